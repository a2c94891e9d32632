// The one way a test waits for something another thread does: poll a condition until it
// holds, or fail after a timeout long enough that only a real failure reaches it.
#pragma once

#include <chrono>
#include <cstdlib>
#include <thread>

namespace rilbed::testing {

/// How long eventually() waits before it gives up: 20 s, times RILBED_TEST_TIME_SCALE when
/// that is set (a slow machine, a sanitizer build). What a test waits for takes
/// milliseconds; the timeout only bounds a failing test, so it is generous.
inline std::chrono::milliseconds eventually_timeout() {
  double scale = 1.0;
  if (const char* s = std::getenv("RILBED_TEST_TIME_SCALE")) {
    const double v = std::atof(s);
    if (v > 0.0) scale = v;
  }
  return std::chrono::milliseconds(static_cast<long long>(20'000 * scale));
}

/// Polls `condition` every millisecond until it holds (true) or eventually_timeout()
/// passes (false). Never use it to show that something does not happen: wait for a later
/// event that proves the earlier one would have been seen.
template <typename Condition>
bool eventually(Condition condition) {
  const auto give_up = std::chrono::steady_clock::now() + eventually_timeout();
  while (!condition()) {
    if (std::chrono::steady_clock::now() > give_up) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

}  // namespace rilbed::testing

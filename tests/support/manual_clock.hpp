// A clock that moves only when a test moves it, for the parts of rilbed that take one
// (the Khepera emulator, the web panel's manual driving): what they do over a span of
// time is then exact, whatever the machine's load.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>

namespace rilbed::testing {

/// Starts at steady_clock's now and stands still until advance(). Thread-safe.
class ManualClock {
 public:
  using Clock = std::chrono::steady_clock;
  ManualClock() : ns_(Clock::now().time_since_epoch().count()) {}
  Clock::time_point now() const { return Clock::time_point(Clock::duration(ns_.load())); }
  void advance(Clock::duration d) { ns_.fetch_add(d.count()); }
  /// As the parts that take a clock want it. The clock must outlive what it is given to.
  std::function<Clock::time_point()> function() const {
    return [this] { return now(); };
  }

 private:
  std::atomic<Clock::rep> ns_;
};

}  // namespace rilbed::testing

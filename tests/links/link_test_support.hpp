// Helpers shared by the link tests: waiting for something a link's thread does, and
// keeping the link's messages to show when a test fails.
#pragma once

#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "links/khepera_link.hpp"

namespace rilbed::links::testing {

/// Polls `predicate` until it holds (true) or `timeout` passes (false).
template <typename Predicate>
bool eventually(Predicate predicate, std::chrono::milliseconds timeout = std::chrono::milliseconds(3000)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!predicate()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

/// Collects the link's messages so a failing test can show them.
struct LogSink {
  std::mutex mutex;
  std::vector<std::string> messages;
  LogCallback callback() {
    return [this](LogLevel, const std::string& message) {
      std::lock_guard lock(mutex);
      messages.push_back(message);
    };
  }
  std::string text() {
    std::lock_guard lock(mutex);
    std::string all;
    for (const auto& m : messages) all += m + "\n";
    return all;
  }
};

}  // namespace rilbed::links::testing

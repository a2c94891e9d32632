// What the link tests share: eventually(), and the link's messages kept to show when a
// test fails.
#pragma once

#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "serial/khepera_link.hpp"
#include "support/eventually.hpp"

namespace rilbed::testing {

/// Collects the link's messages so a failing test can show them.
struct LogSink {
  std::mutex mutex;
  std::vector<std::string> messages;
  serial::LogCallback callback() {
    return [this](serial::LogLevel, const std::string& message) {
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

}  // namespace rilbed::testing

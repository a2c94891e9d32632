// An LCM log read with every length checked.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace rilbed::bus {

/// Reads an LCM log (the format lcm-logger and `rilbed run --record` write) with every
/// length checked against the file, where liblcm's reader trusts them (a data length of
/// 0x7fffffff makes it write through a null pointer). Bytes that are not an event are
/// skipped up to the next event's sync word, as liblcm does; an event cut short ends it.
class LcmLogReader {
 public:
  struct Event {
    std::int64_t eventnum = 0;
    std::int64_t timestamp_us = 0;  ///< when it was logged, microseconds since the epoch
    std::string channel;
    std::vector<std::uint8_t> data;
  };
  /// Opens `path`; good() says whether it could.
  explicit LcmLogReader(const std::string& path);
  bool good() const { return good_; }
  /// The next event, or nullopt at the end (then truncated() says whether the last one was cut short).
  std::optional<Event> next();
  bool truncated() const { return truncated_; }
  /// Bytes skipped because they were not an event.
  std::uint64_t skipped_bytes() const { return skipped_; }

 private:
  std::vector<std::uint8_t> bytes_;
  std::size_t pos_ = 0;
  bool good_ = false;
  bool truncated_ = false;
  std::uint64_t skipped_ = 0;
};

}  // namespace rilbed::bus

#include "bus/lcm_log_reader.hpp"

#include "bus/lcm_checked.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <type_traits>
#include <utility>

namespace rilbed::bus {

LcmLogReader::LcmLogReader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return;
  bytes_.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  good_ = !in.bad();
}

std::optional<LcmLogReader::Event> LcmLogReader::next() {
  constexpr std::uint32_t kSync = 0xEDA1DA01;
  constexpr std::size_t kHeader = 4 + 8 + 8 + 4 + 4;
  auto u32 = [this](std::size_t at) {
    return (std::uint32_t{bytes_[at]} << 24) | (std::uint32_t{bytes_[at + 1]} << 16) |
           (std::uint32_t{bytes_[at + 2]} << 8) | std::uint32_t{bytes_[at + 3]};
  };
  auto u64 = [&](std::size_t at) { return (std::uint64_t{u32(at)} << 32) | u32(at + 4); };
  while (pos_ + 4 <= bytes_.size()) {
    if (u32(pos_) != kSync) {  // not an event here: look for the next one
      ++pos_;
      ++skipped_;
      continue;
    }
    if (pos_ + kHeader > bytes_.size()) break;
    const auto channel_length = static_cast<std::int32_t>(u32(pos_ + 20));
    const auto data_length = static_cast<std::int32_t>(u32(pos_ + 24));
    const std::size_t left = bytes_.size() - pos_ - kHeader;
    if (channel_length < 1 || channel_length > 255 || data_length < 0) {  // a sync word by chance: go on looking
      ++pos_;
      ++skipped_;
      continue;
    }
    if (static_cast<std::size_t>(channel_length) + static_cast<std::size_t>(data_length) > left) break;  // cut short
    Event e;
    e.eventnum = static_cast<std::int64_t>(u64(pos_ + 4));
    e.timestamp_us = static_cast<std::int64_t>(u64(pos_ + 12));
    const std::size_t channel_at = pos_ + kHeader;
    e.channel.assign(reinterpret_cast<const char*>(&bytes_[channel_at]), static_cast<std::size_t>(channel_length));
    const std::size_t data_at = channel_at + static_cast<std::size_t>(channel_length);
    e.data.assign(bytes_.begin() + static_cast<std::ptrdiff_t>(data_at),
                  bytes_.begin() + static_cast<std::ptrdiff_t>(data_at + static_cast<std::size_t>(data_length)));
    pos_ = data_at + static_cast<std::size_t>(data_length);
    return e;
  }
  truncated_ = pos_ < bytes_.size();
  if (truncated_) skipped_ += bytes_.size() - pos_;
  pos_ = bytes_.size();
  return std::nullopt;
}

}  // namespace rilbed::bus

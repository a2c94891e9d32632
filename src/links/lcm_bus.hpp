// A run on an LCM bus: the channels, the conversion of what a run reports into the LCM
// types of src/links/msgs (package `rilbed`), and the publisher that the run reports
// through (agents::RunObserver). Other programs decode these channels with types that
// lcm-gen makes from the same .lcm files in any language.
#pragma once

#include <lcm/lcm-cpp.hpp>
#include <lcm/lcm.h>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "agents/run_observer.hpp"
#include "rilbed/event_t.hpp"
#include "rilbed/poses_t.hpp"
#include "rilbed/status_t.hpp"
#include "rilbed/summary_t.hpp"
#include "rilbed/world_t.hpp"

namespace rilbed::links {

/// A subscription through LCM's C API: `handler(channel, data, size)` for every message on
/// `channel` (a regular expression, as LCM takes it), on the thread that handles `lcm`.
/// LCM 1.3's C++ subscription templates misbehave under UBSan (their callback is handed a
/// wrong object), and rilbed decodes every message itself anyway (decode_checked).
/// Unsubscribes when destroyed; `lcm` must outlive it.
class LcmSubscription {
 public:
  using Handler = std::function<void(const std::string& channel, const void* data, std::size_t size)>;
  LcmSubscription(lcm::LCM& lcm, const std::string& channel, Handler handler);
  ~LcmSubscription();
  LcmSubscription(const LcmSubscription&) = delete;
  LcmSubscription& operator=(const LcmSubscription&) = delete;

 private:
  static void dispatch(const lcm_recv_buf_t* rbuf, const char* channel, void* self);
  lcm_t* lcm_;
  lcm_subscription_t* subscription_ = nullptr;
  Handler handler_;
};

/// The channel names of a run; `prefix` (e.g. "LAB2_") lets two runs share a network.
struct Channels {
  std::string poses = "RILBED_POSES";    ///< rilbed::poses_t, every control step
  std::string events = "RILBED_EVENTS";  ///< rilbed::event_t, each event
  std::string status = "RILBED_STATUS";  ///< rilbed::status_t, every simulated second and at the end
  std::string world = "RILBED_WORLD";    ///< rilbed::world_t, at the start and every simulated second
  std::string summary = "RILBED_SUMMARY";  ///< rilbed::summary_t, once when the run ends
  std::string console = "RILBED_CONSOLE";  ///< rilbed::console_command_t, from consoles
  std::string console_reply = "RILBED_CONSOLE_REPLY";  ///< rilbed::console_reply_t, the run's answers
  /// The same names behind `prefix`.
  static Channels with_prefix(const std::string& prefix);
};

/// A channel prefix is letters, digits and '_' (LCM channel names are at most 63 bytes);
/// returns the reason when `prefix` is not one.
std::optional<std::string> check_channel_prefix(const std::string& prefix);

/// Opens an LCM instance on `url` ("memq://", "udpm://239.255.76.67:7667?ttl=0", ...).
/// Returns nullptr and the reason when LCM cannot use it.
std::unique_ptr<lcm::LCM> open_lcm(const std::string& url, std::string& error);

/// What a run reports, as LCM messages.
rilbed::poses_t to_lcm(TimeUs t_us, std::span<const agents::PoseReport> poses);
/// The same into `message`, reusing its storage (a publisher keeps one between steps).
void fill(rilbed::poses_t& message, TimeUs t_us, std::span<const agents::PoseReport> poses);
rilbed::event_t to_lcm(const agents::RunEvent& event);
rilbed::status_t to_lcm(const agents::StatusReport& status);
rilbed::world_t to_lcm(TimeUs t_us, const agents::WorldReport& world);
rilbed::summary_t to_lcm(TimeUs t_us, const nlohmann::json& summary);

/// Hands the messages of a run's channels, as raw bytes from a bus or a log, to a
/// RunObserver as the run reported them. Messages on other channels are ignored.
class RunReportDecoder {
 public:
  RunReportDecoder(Channels channels, agents::RunObserver& observer);
  /// Decodes one message of `channel`; returns the reason when its bytes are not a
  /// message of that channel's type (the message is then skipped).
  std::optional<std::string> decode(const std::string& channel, const void* data, std::size_t size);
  /// Whether the run's summary (its last message) has come.
  bool summary_seen() const { return summary_seen_; }
  /// The last status decoded, if any.
  const std::optional<rilbed::status_t>& last_status() const { return last_status_; }
  /// The summary a recording cut short gets (no RILBED_SUMMARY came): {"truncated": true}
  /// and what its last status said of the run.
  nlohmann::json cut_short_summary() const;

 private:
  Channels channels_;
  agents::RunObserver& observer_;
  std::vector<agents::PoseReport> poses_;
  bool summary_seen_ = false;
  std::optional<rilbed::status_t> last_status_;
};

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

/// Messages and bytes sent on one channel, and publishes that failed.
struct ChannelCount {
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;
  std::uint64_t failures = 0;  ///< lcm publish returned an error (e.g. EPERM from a firewall): the message is lost
};

/// Publishes what a run reports on `lcm` (which must outlive it), and writes every
/// message to `log` too when given (a standard LCM log, as lcm-logger writes). A failed
/// publish is counted and the run goes on. On an in-process bus (memq://) it also delivers
/// the messages to the in-process subscribers after each publish, so nothing piles up.
class LcmRunPublisher final : public agents::RunObserver {
 public:
  LcmRunPublisher(lcm::LCM& lcm, Channels channels, bool in_process, lcm::LogFile* log = nullptr);
  void on_world(TimeUs t_us, const agents::WorldReport& world) override;
  void on_poses(TimeUs t_us, std::span<const agents::PoseReport> poses) override;
  void on_event(const agents::RunEvent& event) override;
  void on_status(const agents::StatusReport& status) override;
  void on_summary(TimeUs t_us, const nlohmann::json& summary) override;
  /// Counts per channel name so far.
  std::map<std::string, ChannelCount> counts() const;

 private:
  template <typename Message>
  void publish(const std::string& channel, const Message& message);

  lcm::LCM& lcm_;
  Channels channels_;
  bool in_process_;
  lcm::LogFile* log_;
  std::int64_t log_events_ = 0;
  std::vector<std::uint8_t> buffer_;
  rilbed::poses_t poses_message_;  // kept between steps (on_poses is called from the run's thread only)
  mutable std::mutex mutex_;
  std::map<std::string, ChannelCount> counts_;
};

}  // namespace rilbed::links

// The publisher a run reports through (a run::RunObserver): every report encoded once,
// sent on the bus and into a recording, and decoded from the same bytes for the run's
// local subscribers.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "bus/lcm_bus.hpp"
#include "bus/lcm_conversion.hpp"
#include "bus/report_decoder.hpp"
#include "run/run_observer.hpp"

namespace rilbed::bus {

/// Messages and bytes sent on one channel, and publishes that failed.
struct ChannelCount {
  std::uint64_t messages = 0;  ///< published, including those the bus refused (also counted in failures)
  std::uint64_t bytes = 0;
  std::uint64_t failures = 0;  ///< lcm publish returned an error (e.g. EPERM from a firewall): the message is lost
};

/// Publishes what a run reports on `lcm` (which must outlive it), and writes every
/// message to `log` too when given (a standard LCM log, as lcm-logger writes). A failed
/// publish is counted and the run goes on.
///
/// In-process subscribers (add_local_subscriber: the run folder, the terminal status line)
/// get the very bytes that went on the bus, decoded, synchronously: they never miss a
/// message, whatever the bus loses. On the in-process bus (memq://) the messages are
/// published only when something in the process subscribed to it (subscribe()), and when
/// nothing at all wants them (no subscriber, no log) they are not even encoded: a plain
/// run pays nothing for its bus.
class LcmRunPublisher final : public run::RunObserver {
 public:
  struct Options {
    bool in_process = false;      ///< the bus is memq://
    lcm::LogFile* log = nullptr;  ///< also write every message here (not owned)
    bool frames = false;          ///< publish the camera frames themselves (RILBED_FRAMES, JPEG)
    int jpeg_quality = 90;        ///< of those frames; higher is larger and closer to the camera's
    /// Hand the local subscribers that want them (a web panel) a frame at most this often,
    /// wall milliseconds, without putting it on the bus or in the log; 0: never. Each
    /// costs a JPEG encoding (about 2 ms for 640 x 480).
    int local_frame_period_ms = 0;
  };
  LcmRunPublisher(lcm::LCM& lcm, Channels channels, Options options);
  ~LcmRunPublisher() override;
  /// The pre-options form: `in_process` is memq://.
  LcmRunPublisher(lcm::LCM& lcm, Channels channels, bool in_process, lcm::LogFile* log = nullptr)
      : LcmRunPublisher(lcm, std::move(channels), Options{in_process, log}) {}
  /// Hands `observer` every message published from now on, decoded from its bytes, on the
  /// publishing thread. `observer` must outlive the publisher. Not thread-safe: add
  /// subscribers before the run starts.
  void add_local_subscriber(run::RunObserver& observer);
  /// Subscribes `handler` to `channel` on the publisher's bus and, on memq://, makes the
  /// publisher publish there (it does only once something subscribed). The subscription
  /// must not outlive the bus.
  std::unique_ptr<LcmSubscription> subscribe(const std::string& channel, LcmSubscription::Handler handler);
  /// Publishes the last world and status again (a paused run does, every second, for
  /// viewers that join while it is paused). Thread-safe.
  void republish_world_and_status();
  /// Publishes the run's last status and its summary again, on the bus only (not to the
  /// log or the local subscribers): each goes out once, and a watcher on a lossy network
  /// that missed it would not learn that the run ended. Thread-safe.
  void repeat_end();

  bool wants_steps() const override { return heard(); }
  void on_world(TimeUs t_us, const run::WorldReport& world) override;
  void on_poses(TimeUs t_us, std::span<const run::PoseReport> poses) override;
  void on_wheels(TimeUs t_us, std::span<const run::WheelReport> wheels) override;
  void on_sensors(TimeUs t_us, std::span<const run::SensorReport> sensors) override;
  void on_detections(const run::FrameReport& frame) override;
  bool wants_frame_images() const override { return options_.frames || options_.local_frame_period_ms > 0; }
  void on_frame_image(TimeUs t_us, std::int64_t frame, const cv::Mat& image) override;
  void on_event(const run::RunEvent& event) override;
  void on_status(const run::StatusReport& status) override;
  void on_summary(TimeUs t_us, const nlohmann::json& summary) override;
  /// Counts per channel name so far.
  std::map<std::string, ChannelCount> counts() const;

 private:
  class Fanout;
  // Whether a message would reach anyone: a subscriber in the process, the log, or a bus
  // other processes may listen on.
  bool heard() const { return !options_.in_process || bus_subscribers_ > 0 || options_.log || fanout_; }
  template <typename Message>
  void publish(const std::string& channel, const Message& message, bool local_only = false);

  lcm::LCM& lcm_;
  Channels channels_;
  Options options_;
  std::int64_t log_events_ = 0;
  std::vector<std::uint8_t> buffer_;
  // Kept between steps (their on_ calls come from the run's thread only), so that a step
  // of 10,000 robots does not allocate their strings and arrays anew.
  rilbed::poses_t poses_message_;
  rilbed::wheels_t wheels_message_;
  rilbed::sensors_t sensors_message_;
  rilbed::sensor_models_t models_message_;
  std::unique_ptr<Fanout> fanout_;  // the local subscribers
  std::unique_ptr<RunReportDecoder> local_decoder_;
  std::atomic<int> bus_subscribers_{0};
  std::vector<std::uint8_t> last_world_, last_status_, last_summary_;  // their bytes, to publish again
  std::chrono::steady_clock::time_point next_local_frame_{};
  mutable std::mutex mutex_;
  std::map<std::string, ChannelCount> counts_;
};

}  // namespace rilbed::bus

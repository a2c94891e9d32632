// A run on an LCM bus: the channels, the conversion of what a run reports into the LCM
// types of src/bus/msgs (package `rilbed`), and the publisher that the run reports
// through (agents::RunObserver). Other programs decode these channels with types that
// lcm-gen makes from the same .lcm files in any language.
#pragma once

#include <lcm/lcm.h>
#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "rilbed/camera_t.hpp"
#include "rilbed/detections_t.hpp"
#include "rilbed/event_t.hpp"
#include "rilbed/frame_t.hpp"
#include "rilbed/poses_t.hpp"
#include "rilbed/sensor_layout_t.hpp"
#include "rilbed/sensors_t.hpp"
#include "rilbed/status_t.hpp"
#include "rilbed/summary_t.hpp"
#include "rilbed/vision_settings_t.hpp"
#include "rilbed/wheels_t.hpp"
#include "rilbed/world_t.hpp"
#include "run/run_observer.hpp"

namespace rilbed::bus {

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
  std::string poses = "RILBED_POSES";            ///< rilbed::poses_t, every control step
  std::string events = "RILBED_EVENTS";          ///< rilbed::event_t, each event
  std::string status = "RILBED_STATUS";          ///< rilbed::status_t, every simulated second and at the end
  std::string world = "RILBED_WORLD";            ///< rilbed::world_t, at the start and every simulated second
  std::string summary = "RILBED_SUMMARY";        ///< rilbed::summary_t, once when the run ends
  std::string wheels = "RILBED_WHEELS";          ///< rilbed::wheels_t, every control step
  std::string sensors = "RILBED_SENSORS";        ///< rilbed::sensors_t, every control step
  std::string detections = "RILBED_DETECTIONS";  ///< rilbed::detections_t, every camera frame
  std::string frames = "RILBED_FRAMES";          ///< rilbed::frame_t (JPEG), every camera frame, only when asked for
  std::string camera = "RILBED_CAMERA";          ///< rilbed::camera_t, before each world_t of a run with a camera
  std::string sensor_layout = "RILBED_SENSOR_LAYOUT";  ///< rilbed::sensor_layout_t, before each world_t
  std::string vision = "RILBED_VISION";    ///< rilbed::vision_settings_t, before each status_t of a run with a camera
  std::string console = "RILBED_CONSOLE";  ///< rilbed::console_command_t, from consoles
  std::string console_reply = "RILBED_CONSOLE_REPLY";  ///< rilbed::console_reply_t, the run's answers
  std::string agent_hello = "RILBED_AGENT_HELLO";      ///< rilbed::agent_hello_t, from agent processes (issue 18)
  std::string quantum = "RILBED_QUANTUM";              ///< rilbed::quantum_t, the run's quanta to agent processes
  std::string quantum_reply = "RILBED_QUANTUM_REPLY";  ///< rilbed::quantum_reply_t, their answers
  /// The same names behind `prefix`.
  static Channels with_prefix(const std::string& prefix);
};

/// A channel prefix is letters, digits and '_' (LCM channel names are at most 63 bytes);
/// returns the reason when `prefix` is not one.
std::optional<std::string> check_channel_prefix(const std::string& prefix);

/// The bus an agent exchange's answers and announcements travel on, for a run whose quanta
/// go on `url`: with udpm, the same group on the next port (so that an agent process's
/// socket receives quanta only, not every other process's answers: with P processes a step
/// would wake every process P times); any other URL is its own answer bus.
std::string agent_reply_url(const std::string& url);

/// Opens an LCM instance on `url` ("memq://", "udpm://239.255.76.67:7667?ttl=0", ...).
/// Returns nullptr and the reason when LCM cannot use it.
std::unique_ptr<lcm::LCM> open_lcm(const std::string& url, std::string& error);

/// What a run reports, as LCM messages.
rilbed::poses_t to_lcm(TimeUs t_us, std::span<const run::PoseReport> poses);
/// The same into `message`, reusing its storage (a publisher keeps one between steps).
void fill(rilbed::poses_t& message, TimeUs t_us, std::span<const run::PoseReport> poses);
rilbed::event_t to_lcm(const run::RunEvent& event);
rilbed::status_t to_lcm(const run::StatusReport& status);
rilbed::world_t to_lcm(TimeUs t_us, const run::WorldReport& world);
rilbed::summary_t to_lcm(TimeUs t_us, const nlohmann::json& summary);
void fill(rilbed::wheels_t& message, TimeUs t_us, std::span<const run::WheelReport> wheels);
void fill(rilbed::sensors_t& message, TimeUs t_us, std::span<const run::SensorReport> sensors);
/// One robot's readings (counts beyond the wire's int8/int16 are cut; a robot carries a
/// handful of each sensor).
void fill(rilbed::robot_sensors_t& message, int id, const environment::SensorReadings& readings);
/// The readings back, taken at `t_us` (a proximity array of another length than 8 is left out).
environment::SensorReadings from_lcm(const rilbed::robot_sensors_t& message, TimeUs t_us);
rilbed::detections_t to_lcm(const run::FrameReport& frame);
/// A camera frame as JPEG of `quality` (1..100); an empty image gives size 0.
rilbed::frame_t to_lcm(TimeUs t_us, std::int64_t frame, const cv::Mat& image, int quality);
/// The camera's mapping onto the field.
rilbed::camera_t to_lcm(TimeUs t_us, const run::CameraReport& camera);
/// The camera's vision settings, and back (unchecked: see vision::check_vision_settings).
rilbed::vision_settings_t to_lcm(TimeUs t_us, const vision::VisionSettings& settings);
vision::VisionSettings from_lcm(const rilbed::vision_settings_t& message);
/// The robots' sensor geometry (from a world's sensor_geometries and sensor_geometry_of).
rilbed::sensor_layout_t sensor_layout(TimeUs t_us, const run::WorldReport& world);

/// Hands the messages of a run's channels, as raw bytes from a bus or a log, to a
/// RunObserver as the run reported them. Messages on other channels are ignored.
class RunReportDecoder {
 public:
  RunReportDecoder(Channels channels, run::RunObserver& observer);
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
  run::RunObserver& observer_;
  std::vector<run::PoseReport> poses_;
  std::vector<run::WheelReport> wheels_;
  std::vector<environment::SensorReadings> readings_;
  std::vector<run::SensorReport> sensors_;
  std::vector<run::DetectionReport> detections_;
  bool summary_seen_ = false;
  std::optional<rilbed::status_t> last_status_;
  std::optional<run::CameraReport> camera_;             // the last camera_t, for the next world_t
  std::vector<run::SensorGeometry> sensor_geometries_;  // the last sensor_layout_t, for the next world_t
  std::map<int, int> sensor_geometry_of_;
  std::optional<vision::VisionSettings> vision_;  // the last vision_settings_t, for the next status_t
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
  std::unique_ptr<Fanout> fanout_;  // the local subscribers
  std::unique_ptr<RunReportDecoder> local_decoder_;
  std::atomic<int> bus_subscribers_{0};
  std::vector<std::uint8_t> last_world_, last_status_, last_summary_;  // their bytes, to publish again
  std::chrono::steady_clock::time_point next_local_frame_{};
  mutable std::mutex mutex_;
  std::map<std::string, ChannelCount> counts_;
};

}  // namespace rilbed::bus

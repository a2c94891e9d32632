// A run on an LCM bus: opening the bus, the run's channel names, subscriptions through
// LCM's C API. The messages (src/bus/msgs, package `rilbed`) are public: other programs
// decode these channels with types that lcm-gen makes from the same .lcm files in any
// language. lcm_conversion.hpp turns what a run reports into them and back,
// run_publisher.hpp publishes a run, report_decoder.hpp hands the messages back to a
// RunObserver, lcm_log_reader.hpp reads a recording.
#pragma once

#include <lcm/lcm.h>
#include <lcm/lcm-cpp.hpp>

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
  std::string robot_bodies = "RILBED_ROBOT_BODIES";    ///< rilbed::robot_bodies_t, before each world_t
  /// rilbed::sensor_models_t, before a control step's sensors_t when a robot's sensor
  /// models read or drew something
  std::string sensor_models = "RILBED_SENSOR_MODELS";
  std::string vision = "RILBED_VISION";    ///< rilbed::vision_settings_t, before each status_t of a run with a camera
  std::string console = "RILBED_CONSOLE";  ///< rilbed::console_command_t, from consoles
  std::string console_reply = "RILBED_CONSOLE_REPLY";  ///< rilbed::console_reply_t, the run's answers
  std::string agent_hello = "RILBED_AGENT_HELLO";      ///< rilbed::agent_hello_t, from agent processes
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

}  // namespace rilbed::bus

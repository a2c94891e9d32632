// A run as the web server's channels: what a run reports (agents::RunObserver, decoded from
// its LCM messages) as JSON messages on Foxglove channels, with their JSON Schemas, for
// rilbed's page and for Foxglove Studio or Lichtblick. Topics:
//   /rilbed/world, /rilbed/status, /rilbed/poses, /rilbed/wheels, /rilbed/sensors,
//   /rilbed/detections, /rilbed/events  (rilbed.* schemas, the LCM messages' fields)
//   /rilbed/scene       (foxglove.SceneUpdate: the field and every robot, frame "field")
//   /rilbed/console_reply  (the run's answers to console commands sent from a browser)
//   /rilbed/camera      (foxglove.CompressedImage: the camera's frames, JPEG, frame "camera")
//   /rilbed/camera_calibration  (rilbed.camera: frame size, image_to_field and
//                        field_to_image homographies, row-major)
// The world, status, poses, scene and camera calibration are latched: a viewer that joins gets the
// last of each at once (a paused run sends nothing new).
// A message nobody subscribes to is not built (JSON for 100 robots' scene is milliseconds of
// the run's thread each step): the poses and the scene are built for a viewer who
// subscribes from the last ones reported (WebServer::set_latch_source), the step
// channels (wheels, sensors, detections) simply skipped. What is built is built on a thread
// of its own, in the order reported, from copies: the run's thread only copies (a viewer
// must not slow the control loop). A step's message not yet built when the next comes is
// dropped (newest state wins).
// Times are simulated seconds (t_s); the binary header's time is the same in nanoseconds.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "gui_web/web_server.hpp"
#include "run/run_observer.hpp"

namespace rilbed::gui_web {

/// Publishes a run's reports on `server` (which must outlive it). Each on_ call converts
/// and queues (WebServer::publish never blocks); call from one thread (the server's thread
/// builds the latest poses and scene for a new subscriber, under a mutex).
class RunChannels final : public run::RunObserver {
 public:
  explicit RunChannels(WebServer& server);
  /// Builds and publishes what was handed over, then stops its thread.
  ~RunChannels() override;
  RunChannels(const RunChannels&) = delete;
  RunChannels& operator=(const RunChannels&) = delete;
  /// Waits until everything reported so far has been published on the server (not yet
  /// written to the clients: see WebServer::flush), at most `timeout`; returns whether it was.
  bool flush(std::chrono::milliseconds timeout);
  void on_world(TimeUs t_us, const run::WorldReport& world) override;
  void on_poses(TimeUs t_us, std::span<const run::PoseReport> poses) override;
  void on_wheels(TimeUs t_us, std::span<const run::WheelReport> wheels) override;
  void on_sensors(TimeUs t_us, std::span<const run::SensorReport> sensors) override;
  void on_detections(const run::FrameReport& frame) override;
  void on_event(const run::RunEvent& event) override;
  void on_status(const run::StatusReport& status) override;
  void on_summary(TimeUs t_us, const nlohmann::json& summary) override;
  /// A camera frame (JPEG) as foxglove.CompressedImage on /rilbed/camera. Call at the rate
  /// viewers should get them: each is base64 text of about 4/3 of the JPEG's size.
  void camera_frame(TimeUs t_us, std::span<const std::uint8_t> jpeg);
  /// The run's answer to a console command from a client (accepted, and why or what).
  void console_reply(TimeUs t_us, bool accepted, const std::string& reason, const std::string& client);

  /// The JSON messages, for tests and other servers.
  static nlohmann::json world_json(TimeUs t_us, const run::WorldReport& world);
  static nlohmann::json poses_json(TimeUs t_us, std::span<const run::PoseReport> poses);
  static nlohmann::json status_json(const run::StatusReport& status);
  /// foxglove.SceneUpdate: every robot as a disc (virtual red, real blue) with its ID and
  /// behaviour and the marks its sensor models drew (by robot ID, robot frame; drawn as
  /// lines in the field frame, a circle as a loop of 16 points), and the field's boundary,
  /// obstacles and tracks as lines.
  static nlohmann::json scene_json(TimeUs t_us, std::span<const run::PoseReport> poses,
                                   const std::optional<run::WorldReport>& world,
                                   const std::map<int, std::vector<environment::SensorMark>>& marks = {});
  /// A robot's sensor-model readings as the sensors channel carries them: [{name, values}].
  static nlohmann::json models_json(const environment::SensorReadings& s);
  /// Its sensor models' marks, robot frame: [{shape, x_m, y_m, radius_m, x2_m, y2_m, rgba}].
  static nlohmann::json marks_json(const environment::SensorReadings& s);

 private:
  // The latest marks of each robot, for the scene (only while someone watches it).
  void keep_marks(std::span<const run::SensorReport> sensors);
  // Something to build and publish on the channels' thread.
  struct Job {
    std::uint32_t channel = 0;
    bool step = false;  // a step's message: a newer one replaces it while it waits
    std::function<void()> build;
  };
  void post(std::uint32_t channel, bool step, std::function<void()> build);
  void work();
  void send(std::uint32_t channel, TimeUs t_us, const nlohmann::json& message);

  // Pose reports whose strings it owns: the run's own behaviour names are static, but
  // those a bus decoder hands over live only during the call (`rilbed gui --lcm`), and
  // these are kept for later. Not copyable: the reports view its own strings.
  struct OwnedPoses {
    std::vector<run::PoseReport> poses;
    std::vector<std::string> strings;  // reserved up front, so that the views stay put
    OwnedPoses() = default;
    OwnedPoses(const OwnedPoses&) = delete;
    OwnedPoses& operator=(const OwnedPoses&) = delete;
    void assign(std::span<const run::PoseReport> from);
  };

  // What the poses and scene channels' latch sources build from; shared with them (they
  // run on the server's thread, which may outlive this object).
  struct Latest {
    std::mutex mutex;  // guards all of it
    std::optional<run::WorldReport> world;
    TimeUs poses_t_us = 0;
    OwnedPoses poses;
    bool poses_unsent = false, scene_unsent = false;            // the last poses were not published on the channel
    std::map<int, std::vector<environment::SensorMark>> marks;  // each robot's latest sensor marks
    // The latest poses or scene message, or null when what was published last is the latest.
    std::shared_ptr<const std::string> build(bool scene, std::uint64_t& t_ns);
  };

  WebServer& server_;
  std::uint32_t world_, status_, poses_, wheels_, sensors_, detections_, events_, scene_, console_reply_, summary_;
  std::uint32_t camera_ = 0, camera_calibration_ = 0;
  std::shared_ptr<Latest> latest_ = std::make_shared<Latest>();
  std::mutex jobs_mutex_;
  std::condition_variable jobs_changed_;
  std::deque<Job> jobs_;
  bool building_ = false;
  bool stopping_ = false;
  std::thread worker_;  // last: started once everything else is
};

}  // namespace rilbed::gui_web

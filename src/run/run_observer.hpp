// What a run tells whoever watches it while it runs: the world it takes place in, every
// robot's pose at every control step, its events, and its status. The run calls an
// observer from its own thread; the links module publishes these on the LCM bus
// (LcmRunPublisher), tests record them. The run never waits for a watcher: an observer
// must return quickly (publishing is a send, never a wait for a receiver).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include <opencv2/core/mat.hpp>

#include "agents/controller.hpp"
#include "core/geometry.hpp"
#include "core/time.hpp"
#include "environment/sensor_readings.hpp"
#include "run/run_recorder.hpp"
#include "vision/vision_settings.hpp"

namespace rilbed::run {

/// One robot at one control step, as the test bed knows it.
struct PoseReport {
  int id = 0;
  bool real = false;  ///< a real robot: its pose is the camera's
  bool seen = true;   ///< false: a real robot the camera has not seen recently (pose is its last)
  Pose2 pose;         ///< field frame
  /// Valid during the call that hands the report over: the run's own are static, but a
  /// bus decoder's (bus::RunReportDecoder) view the message being decoded. An observer
  /// that keeps a report keeps a copy of its strings.
  std::string_view behaviour;
  std::string_view health;  ///< "ok", "unseen", ...; valid as `behaviour` is
};

/// One robot's wheel command at one control step.
struct WheelReport {
  int id = 0;
  agents::WheelCommand wheels;  ///< Khepera units (+-127, 8 mm/s each)
};

/// One robot's sensor readings at one control step. `readings` is a view, valid during
/// the call it is handed to.
struct SensorReport {
  int id = 0;
  const environment::SensorReadings* readings = nullptr;
};

/// One marker the overhead camera found in a frame.
struct DetectionReport {
  int id = 0;
  double u_px = 0.0, v_px = 0.0;  ///< centre in the image, pixels
  double heading_deg = 0.0;       ///< on screen, counter-clockwise from +u, [0, 360)
  double score = 0.0;             ///< circular cross-covariance, [-1, 1]
  double diameter_px = 0.0;
  Pose2 pose;  ///< the same in the field frame
};

/// What the overhead camera found in one frame.
struct FrameReport {
  TimeUs t_us = 0;          ///< when the frame was taken (simulated time)
  std::int64_t frame = 0;   ///< frame number, from 1
  double process_ms = 0.0;  ///< wall time the vision pipeline took on it
  std::span<const DetectionReport> detections;
};

/// The overhead camera of a run with real robots: how its frames map onto the field.
struct CameraReport {
  int width_px = 0;  ///< frame size
  int height_px = 0;
  /// Homogeneous undistorted pixels (u, v, 1) to homogeneous field metres, row-major.
  std::array<double, 9> image_to_field{1, 0, 0, 0, 1, 0, 0, 0, 1};
  bool lens_distortion = false;  ///< frames are distorted (the homography applies after undistortion)
  std::string source;            ///< "emulated", "device 0", or the footage's path
};

/// One robot's sensors as a viewer draws them; robot frame (x forward, y left), metres,
/// angles counter-clockwise from forward.
struct SensorGeometry {
  double ir_range_m = 0.0;  ///< the IR ring's reach; 0: none
  struct Range {
    double mount_rad = 0.0, opening_rad = 0.0, max_m = 0.0;
    bool operator==(const Range&) const = default;
  };
  std::vector<Range> ranges;  ///< ultrasonic, in reading order
  bool beacon_finder = false;
  double beacon_fov_rad = 0.0;
  /// Each track sensor's floor segments (their centres), in reading order.
  std::vector<std::vector<Vec2>> track_points_m;
  bool operator==(const SensorGeometry&) const = default;
};

/// A robot's body as viewers draw it: its disc, or its convex outline (robot frame: x
/// forward, y left, metres, counter-clockwise), and its wheels.
struct BodyDrawing {
  std::string name = "khepera2";  ///< the robot model's name
  double radius_m = 0.0275;       ///< the disc (when outline_m is empty)
  std::vector<Vec2> outline_m;    ///< empty: the disc
  double wheel_base_m = 0.053;
  double wheel_radius_m = 0.00764;
  bool operator==(const BodyDrawing&) const = default;
};

/// The world a run takes place in.
struct WorldReport {
  std::optional<CameraReport> camera;  ///< runs with a camera
  /// Distinct sensor geometries, and each robot's (robot ID -> index); may be empty (a
  /// recording from before they were published).
  std::vector<SensorGeometry> sensor_geometries;
  std::map<int, int> sensor_geometry_of;
  std::string scenario;
  FieldDrawing field;          ///< size, obstacles, tracks, beacons, which robots are real
  bool walls = true;           ///< the field's edges are walls
  std::vector<int> robot_ids;  ///< every robot, in ID order
  /// Distinct bodies, and each robot's (robot ID -> index); may be empty (a recording or
  /// a publisher from before bodies were published: draw Kheperas).
  std::vector<BodyDrawing> bodies;
  std::map<int, int> body_of;
};

/// The run's state.
struct StatusReport {
  TimeUs t_us = 0;      ///< simulated time
  double wall_s = 0.0;  ///< wall-clock time since the run started
  std::string scenario;
  std::uint64_t seed = 0;
  std::string mode;  ///< "distributed" or "central"
  bool realtime = false;
  double rt_factor = 1.0;
  std::string state;     ///< "running" or "ended"
  std::string ended_by;  ///< when ended (RunResult::ended_by)
  int robots = 0;
  int real_robots = 0;
  bool formed = false;
  std::optional<double> formation_time_s;
  int collisions = 0;
  double loop_latency_ms = 0.0;  ///< realtime: the most the control loop fell behind the wall clock in the last second
  double camera_fps = 0.0;       ///< camera frames processed per wall second over the last second
  std::int64_t frames = 0;       ///< camera frames processed so far
  /// The camera's vision settings now; none for a run without a camera.
  std::optional<vision::VisionSettings> vision;
};

/// Receives what a run reports. Every member has an empty default. A run reports each
/// control step in this order: on_world (before the first instant and on a new second), on_poses, on_wheels,
/// on_sensors, on_status (on a new second); events and camera frames as they happen.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  /// Whether anything comes of the step reports (on_poses, on_wheels, on_sensors) now: a
  /// run builds them only when it does (10,000 robots' reports every step cost ~2 ms).
  virtual bool wants_steps() const { return true; }
  /// Before the run's first instant (even one the console ends at once), then once per
  /// simulated second.
  virtual void on_world(TimeUs /*t_us*/, const WorldReport& /*world*/) {}
  /// After every control step: every robot with a known pose.
  virtual void on_poses(TimeUs /*t_us*/, std::span<const PoseReport> /*poses*/) {}
  /// After every control step: every robot's wheel command (what drove it during the step).
  virtual void on_wheels(TimeUs /*t_us*/, std::span<const WheelReport> /*wheels*/) {}
  /// After every control step: every robot's sensor readings, as its controller read them.
  virtual void on_sensors(TimeUs /*t_us*/, std::span<const SensorReport> /*sensors*/) {}
  /// After every camera frame: what the vision pipeline found in it.
  virtual void on_detections(const FrameReport& /*frame*/) {}
  /// Whether it wants the camera's frames themselves (on_frame_image); asked once, when
  /// the run starts. Handing over a frame costs a copy of the image.
  virtual bool wants_frame_images() const { return false; }
  /// Every camera frame, 8-bit grey or BGR, when wants_frame_images(); valid during the call.
  virtual void on_frame_image(TimeUs /*t_us*/, std::int64_t /*frame*/, const cv::Mat& /*image*/) {}
  /// Whether it wants the camera's frames as JPEG bytes (on_frame_jpeg) when they come
  /// that way (from a bus, or a publisher's local subscribers): no decoding, no copy.
  virtual bool wants_frame_jpegs() const { return false; }
  /// A camera frame as JPEG, when wants_frame_jpegs(); `jpeg` is valid during the call.
  virtual void on_frame_jpeg(TimeUs /*t_us*/, std::int64_t /*frame*/, int /*width_px*/, int /*height_px*/,
                             std::span<const std::uint8_t> /*jpeg*/) {}
  /// Each event as it is recorded (the rows of events.csv).
  virtual void on_event(const RunEvent& /*event*/) {}
  /// At the start, once per simulated second, and when the run ends (state "ended").
  virtual void on_status(const StatusReport& /*status*/) {}
  /// Once, last: summary.json's object.
  virtual void on_summary(TimeUs /*t_us*/, const nlohmann::json& /*summary*/) {}
};

}  // namespace rilbed::run

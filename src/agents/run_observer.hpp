// What a run tells whoever watches it while it runs: the world it takes place in, every
// robot's pose at every control step, its events, and its status. The run calls an
// observer from its own thread; the links module publishes these on the LCM bus
// (LcmRunPublisher), tests record them. The run never waits for a watcher: an observer
// must return quickly (publishing is a send, never a wait for a receiver).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "agents/run_recorder.hpp"
#include "core/geometry.hpp"
#include "core/time.hpp"

namespace rilbed::agents {

/// One robot at one control step, as the test bed knows it.
struct PoseReport {
  int id = 0;
  bool real = false;  ///< a real robot: its pose is the camera's
  bool seen = true;   ///< false: a real robot the camera has not seen recently (pose is its last)
  Pose2 pose;         ///< field frame
  std::string_view behaviour;  ///< a static string
  std::string_view health;     ///< a static string: "ok", "unseen", ...
};

/// The world a run takes place in.
struct WorldReport {
  std::string scenario;
  FieldDrawing field;          ///< size, obstacles, tracks, beacons, which robots are real
  bool walls = true;           ///< the field's edges are walls
  std::vector<int> robot_ids;  ///< every robot, in ID order
};

/// The run's state.
struct StatusReport {
  TimeUs t_us = 0;          ///< simulated time
  double wall_s = 0.0;      ///< wall-clock time since the run started
  std::string scenario;
  std::uint64_t seed = 0;
  std::string mode;         ///< "distributed" or "central"
  bool realtime = false;
  double rt_factor = 1.0;
  std::string state;        ///< "running" or "ended"
  std::string ended_by;     ///< when ended (RunResult::ended_by)
  int robots = 0;
  int real_robots = 0;
  bool formed = false;
  std::optional<double> formation_time_s;
  int collisions = 0;
};

/// Receives what a run reports. Every member has an empty default.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  /// At the start, then once per simulated second.
  virtual void on_world(TimeUs /*t_us*/, const WorldReport& /*world*/) {}
  /// After every control step: every robot with a known pose.
  virtual void on_poses(TimeUs /*t_us*/, std::span<const PoseReport> /*poses*/) {}
  /// Each event as it is recorded (the rows of events.csv).
  virtual void on_event(const RunEvent& /*event*/) {}
  /// At the start, once per simulated second, and when the run ends (state "ended").
  virtual void on_status(const StatusReport& /*status*/) {}
  /// Once, last: summary.json's object.
  virtual void on_summary(TimeUs /*t_us*/, const nlohmann::json& /*summary*/) {}
};

}  // namespace rilbed::agents

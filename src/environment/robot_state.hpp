// One robot as the world knows it: identity, kind, pose, body, wheel commands, wheel
// counters and the sensors it carries.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/time.hpp"
#include "environment/drive_model.hpp"
#include "environment/kinematics.hpp"
#include "environment/sensor_suite.hpp"

namespace rilbed::environment {

/// Virtual robots live only in the world: the world drives them from their wheel
/// commands. Real robots are driven by the real world: the world takes their pose from
/// outside (the camera) and never moves them.
enum class RobotKind { kVirtual, kReal };

/// "virtual" or "real".
std::string_view to_string(RobotKind kind);

/// A robot to add to the world.
struct RobotConfig {
  int id = 0;                            ///< unique within the world
  RobotKind kind = RobotKind::kVirtual;  ///< virtual (driven here) or real (observed)
  Pose2 pose;                            ///< initial pose, field frame
  double radius_m = kKheperaRadius_m;    ///< the body is a disc of this radius (when outline_m is empty)
  /// A convex outline instead of the disc: robot frame (x forward, y left), metres, the
  /// centre strictly inside, 3 to kMaxOutlineVertices vertices; empty: the disc.
  std::vector<Vec2> outline_m;
  double wheel_base_m = kKheperaWheelBase_m;  ///< between the wheels
  WheelNoiseConfig noise;                     ///< virtual robots only
  SensorSuiteConfig sensors;                  ///< virtual sensors (fed by the world for either kind)
  /// Virtual robots: how the wheels move (a plug-in's); null: the differential drive with `noise`.
  std::shared_ptr<const DriveModelFactory> drive;
};

/// A robot's wheel commands, pulses per 10 ms (1 unit = 8 mm/s), in [-127, 127].
struct WheelUnits {
  int left = 0;
  int right = 0;
  bool operator==(const WheelUnits&) const = default;
};

/// The world's record of one robot. Values; the World owns them. A record is two cache
/// lines, all of it read by a step, and starts a line of its own: threads never write
/// the same line. The wheel commands are
/// kept apart (World::wheel_speeds), in the agents' order, since agents write them.
struct alignas(64) RobotState {
  int id = 0;                            ///< as configured
  RobotKind kind = RobotKind::kVirtual;  ///< as configured
  Pose2 pose;                            ///< current pose, heading in [-pi, pi)
  TimeUs pose_t_us = 0;                  ///< when pose was last set (step end or observation)
  /// Real robots: whether the camera has placed it at least once (until then `pose` is
  /// only where the scenario put it).
  bool observed = false;
  double radius_m = kKheperaRadius_m;         ///< body disc (with an outline: its bounding radius)
  double wheel_base_m = kKheperaWheelBase_m;  ///< between the wheels
  /// Wheel travel counted by the encoders since the counters were last set, metres
  /// (kept in metres so that fractions of a pulse are not lost between steps).
  double left_wheel_travel_m = 0.0;
  double right_wheel_travel_m = 0.0;
  WheelNoiseConfig noise;  ///< as configured
  // (Its sensors' configuration is World::sensor_config(id): kept out of this record,
  // which every step reads four times, so that a record is two cache lines, not five.)

  /// The wheel counters, as the Khepera's `H` command would report them: whole pulses of
  /// 0.08 mm, rounded towards minus infinity.
  OdometryReading odometer() const;
};
static_assert(sizeof(RobotState) == 128, "two cache lines a robot (see above)");

}  // namespace rilbed::environment

// How a virtual robot's wheels turn its commands into motion, when not the built-in
// differential drive with slip: a model from outside the module (a plug-in library's,
// agents::library_actuator_models). The world asks it for the wheels' ground speeds of
// each step and drives the exact arc they make.
#pragma once

#include <memory>

#include "core/geometry.hpp"
#include "core/time.hpp"
#include "environment/random.hpp"

namespace rilbed::environment {

/// One step of one robot, as its drive model sees it.
struct DriveCall {
  TimeUs t_us = 0;  ///< the step's start
  int robot_id = 0;
  Pose2 pose;
  double dt_s = 0.0;
  int left_units = 0, right_units = 0;  ///< the commands, Khepera units
  Vec2 command_mps;                     ///< the same in m/s (left, right)
  NoiseRng& rng;                        ///< the robot's wheel-noise stream at this step
};

/// What the wheels do over the step: ground speeds and what the counters count (left, right, m/s).
struct DriveOutput {
  Vec2 ground_mps;
  Vec2 counted_mps;
};

/// One robot's drive: may keep that robot's state.
class DriveModel {
 public:
  virtual ~DriveModel() = default;
  /// The step's wheel speeds. Throws std::runtime_error, naming the model and the robot, when it fails.
  virtual DriveOutput drive(const DriveCall& call) = 0;
};

/// Makes each robot's DriveModel (a scenario's `actuator:`), shared by the robots of an entry.
class DriveModelFactory {
 public:
  virtual ~DriveModelFactory() = default;
  /// The drive of robot `robot_id` with `wheel_base_m`. Throws std::invalid_argument
  /// (naming the model and the robot) when the model refuses.
  virtual std::unique_ptr<DriveModel> make(int robot_id, double wheel_base_m) const = 0;
  /// Whether two robots' drives may run at once.
  virtual bool concurrent() const = 0;
};

}  // namespace rilbed::environment

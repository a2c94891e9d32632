// The controller API: what a robot's controller sees (sensor readings, its pose as the
// test bed knows it, team messages) and what it commands (wheel speeds). A controller
// never learns whether its body is virtual or a real Khepera (ARGoS's rule).
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/geometry.hpp"
#include "core/time.hpp"
#include "environment/sensor_readings.hpp"

namespace rilbed::agents {

/// Khepera wheel speed units: pulses per 10 ms; 1 unit = 8 mm/s; the firmware takes ±127.
inline constexpr double kMetresPerSecondPerUnit = 0.008;
/// Largest wheel speed the Khepera's `D` command accepts, in its units.
inline constexpr int kMaxWheelUnits = 127;
/// Distance between the Khepera's wheels, metres.
inline constexpr double kWheelBase_m = 0.053;

/// Wheel speeds in Khepera units (pulses per 10 ms, ±127), as the `D` command sends them.
struct WheelCommand {
  int left = 0;
  int right = 0;
  bool operator==(const WheelCommand&) const = default;
};

/// Forward speed (m/s) and turn rate (rad/s, counter-clockwise) to wheel units, rounded
/// and clamped to ±127. When a wheel would exceed the limit both are scaled down together,
/// so the curvature is kept.
inline WheelCommand wheels_from_twist(double speed_mps, double turn_rate_radps) {
  double left = (speed_mps - 0.5 * turn_rate_radps * kWheelBase_m) / kMetresPerSecondPerUnit;
  double right = (speed_mps + 0.5 * turn_rate_radps * kWheelBase_m) / kMetresPerSecondPerUnit;
  const double biggest = std::max(std::abs(left), std::abs(right));
  if (biggest > kMaxWheelUnits) {
    left *= kMaxWheelUnits / biggest;
    right *= kMaxWheelUnits / biggest;
  }
  return {static_cast<int>(std::lround(left)), static_cast<int>(std::lround(right))};
}

/// What a robot of the team tells the others (broadcast over the team channel): who, where
/// and what it is doing. In distributed mode it is an agent's only knowledge of the others.
struct TeamMessage {
  int id = 0;
  Pose2 pose;                  ///< field frame
  std::string_view behaviour;  ///< its active behaviour ("follow", ...); points to a static string
  TimeUs t_us = 0;             ///< when the pose was true
};

/// Everything a controller gets at one control step.
struct ControlInput {
  TimeUs t_us = 0;                      ///< simulated time of this step
  int robot_id = 0;                     ///< the robot being controlled
  environment::SensorReadings sensors;  ///< its sensors (virtual, real or combined)
  std::optional<Pose2> pose;            ///< its pose from localisation (world or camera); nullopt if unknown
  /// The latest team broadcast (every member, possibly this robot too); empty unless the
  /// controller wants_team(). Valid only during the step() call it is passed to.
  std::span<const TeamMessage> team;
};

/// What a controller decides at one control step.
struct ControlOutput {
  WheelCommand wheels;
  /// The active behaviour, part of the agent's visible state (written to the trajectories);
  /// must point to a string that lives as long as the program (a literal).
  std::string_view behaviour = "idle";
};

/// Something a controller reports as it learns (a node of the track network it explores):
/// it becomes an event of the run (events.csv, the bus, the panel, a replay), with the
/// robot's ID, at the control instant after the step that made it.
struct ControllerEvent {
  std::string kind;    ///< what happened, lower case with underscores ("track_node")
  int other = 0;       ///< a number the kind gives meaning to (a node's ID)
  std::string detail;  ///< the rest, free text (JSON for the track events)
};

/// A controller failed at a step: its own code raised an error, or it answered what rilbed
/// cannot use. The message names the controller, where it comes from and the robot, and
/// holds the cause (a Python traceback, for one). The run then stops the robot (or every
/// robot, and ends; RunOptions::on_controller_error).
class ControllerError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ControllerGroup;

/// A robot controller: called once per control period with the latest input.
/// Implementations keep their own state between calls; one instance per robot.
class Controller {
 public:
  virtual ~Controller() = default;
  /// One control step.
  virtual ControlOutput step(const ControlInput& input) = 0;
  /// Called once when the run ends (normally or not), after the last step.
  virtual void finish() {}
  /// Whether it reads ControlInput::team. Only such agents are sent the team broadcast,
  /// which costs a copy of every member's message per agent.
  virtual bool wants_team() const { return false; }
  /// Whether it has reached its goal (a controller with a goal, e.g. going to a pose);
  /// a run with RunOptions::stop_when_done ends once every controller is done.
  virtual bool done() const { return false; }
  /// Whether it reports events (take_events); asked once, so that a swarm's run does not
  /// ask 100,000 controllers every step.
  virtual bool reports_events() const { return false; }
  /// Moves the events made since the last call to the end of `out`. Called on the run's
  /// thread after each step of a controller that reports_events().
  virtual void take_events(std::vector<ControllerEvent>& out) { (void)out; }
  /// Whether its step may run at the same time as other robots' controllers' steps (a
  /// run on `--threads N`): it shares no mutable state with them. Asked once. Default
  /// true; a controller that keeps state shared between robots must say false.
  virtual bool concurrent() const { return true; }
  /// The group it decides with, when its robot is stepped together with others in one
  /// call (a vectorised Python class); null for a controller that decides alone. A run
  /// steps a group's members through the group (gather, then step_gathered) rather than
  /// one by one; step() still works alone, as a group of one. Owned by the run's groups.
  virtual ControllerGroup* group() { return nullptr; }
};

}  // namespace rilbed::agents

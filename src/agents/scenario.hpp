// Scenario files (YAML) for `rilbed run`: the field, its walls, obstacles, tracks,
// beacons and moving obstacles, the robots with their poses, sensors and controllers,
// and the convoy's mode. scenarios/README.md documents every key. Parsing is strict:
// an unknown key, a wrong type or a bad value is an error naming the file, line and key.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "agents/convoy.hpp"
#include "core/geometry.hpp"
#include "core/time.hpp"
#include "environment/kinematics.hpp"
#include "environment/moving_obstacle.hpp"
#include "environment/robot_state.hpp"
#include "environment/sensor_suite.hpp"
#include "environment/static_map.hpp"

namespace rilbed::agents {

/// A scenario that cannot be used; what() is "FILE:LINE: KEY: problem".
class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Who decides for the convoy (paper 001 §5).
enum class ConvoyMode { kDistributed, kCentral };

/// How a real robot is reached (used by runs with real robots).
struct LinkSpec {
  std::string port;            ///< serial device, e.g. /dev/ttyUSB0; empty when emulated
  int baud = 38400;
  std::string model = "khepera2";  ///< protocol variant: khepera2 | epuck
  bool emulate = false;        ///< start an emulated Khepera on a pseudo-terminal instead
};

/// A robot's controller and its knobs.
struct ControllerSpec {
  /// "convoy", "wander", "track_follow", "beacon_homing", "c:<name>" (a built-in C
  /// controller) or "none" (stands still).
  std::string name = "convoy";
  std::map<std::string, double> params;  ///< controller-specific numbers, checked by the run
};

/// One robot of a scenario.
struct RobotSpec {
  int id = 0;
  environment::RobotKind kind = environment::RobotKind::Virtual;
  std::optional<Pose2> pose;  ///< nullopt: a random free pose drawn from the run's seed
  ControllerSpec controller;
  environment::WheelNoiseConfig noise;
  environment::SensorSuiteConfig sensors;
  std::optional<LinkSpec> link;  ///< real robots only
  int line = 0;                  ///< where it was defined, for messages
};

/// A whole scenario.
struct Scenario {
  std::string name;                 ///< the file's `name`, else its stem
  std::filesystem::path source;     ///< the file it came from
  ConvoyMode mode = ConvoyMode::kDistributed;
  environment::StaticMapConfig map;
  std::vector<environment::MovingObstacleConfig> moving_obstacles;
  TimeUs physics_step_us = 20'000;     ///< world integration step
  TimeUs control_period_us = 100'000;  ///< controllers run this often
  TimeUs broadcast_period_us = 100'000;  ///< team broadcast (distributed mode)
  double duration_s = 120.0;        ///< default run length
  ConvoyConfig convoy;              ///< the convoy's knobs (the `convoy:` block)
  std::vector<RobotSpec> robots;    ///< sorted by ID
};

/// Reads and checks a scenario file. Throws ScenarioError.
Scenario load_scenario(const std::filesystem::path& path);
/// Parses scenario text (`source_name` is used in messages). Throws ScenarioError.
Scenario parse_scenario(const std::string& yaml_text, const std::string& source_name);

/// Poses for the robots without one: uniformly random in the field, at least
/// `clearance_m` from walls, obstacles and every other robot, random heading; fixed poses
/// are kept. Deterministic for a given seed. Throws ScenarioError if the field is too
/// crowded to place them.
std::vector<Pose2> draw_initial_poses(const Scenario& scenario, std::mt19937_64& rng, double clearance_m = 0.02);

}  // namespace rilbed::agents

// A robot described by its parts: the robot model file (robots/*.yaml) a scenario's robot
// names with `model:`, and the overrides of its parts in the scenario's robot entry.
//
// A robot model file:
//   name: e-puck                       # for displays; default: the file's stem
//   body: {radius_m: 0.035}            # a disc, or {outline_m: [[x, y], ...]} (convex, robot frame)
//   wheels: {base_m: 0.053, radius_m: 0.0205}
//   link: {model: epuck, speed_unit_mps: 0.000129, counter_pulse_m: 0.000129}
//   sensors: {...}                     # as a scenario robot's `sensors:`
// Every key is optional; what a file leaves out is the Khepera II's.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry.hpp"
#include "core/result.hpp"
#include "environment/kinematics.hpp"
#include "environment/sensor_suite.hpp"

namespace rilbed::run {

namespace yaml_detail {
class Reader;
}

/// Khepera II's wheel radius: 600 counter pulses of 0.08 mm make one turn of the wheel
/// (48 mm around: 7.64 mm, as robots/khepera2.yaml gives it).
inline constexpr double kKheperaWheelRadius_m = 0.00764;

/// A robot's body and wheels, as the world and the displays use them. A value.
struct RobotBody {
  std::string name = "khepera2";                    ///< the model's name (for displays)
  std::string file;                                 ///< the model file, absolute; empty: built in
  double radius_m = environment::kKheperaRadius_m;  ///< the disc; with an outline, its bounding radius
  std::vector<Vec2> outline_m;  ///< convex outline, robot frame (x forward, y left); empty: the disc
  double wheel_base_m = environment::kKheperaWheelBase_m;  ///< between the wheels' contact points
  double wheel_radius_m = kKheperaWheelRadius_m;           ///< drawn by the displays
  bool operator==(const RobotBody&) const = default;
};

/// What a model file says of its link, as defaults for the scenario's `link:` (a real
/// robot's): the protocol and its speed units, when they differ from the protocol's own.
struct LinkDefaults {
  std::optional<std::string> model;       ///< protocol: khepera2 | epuck
  std::optional<double> speed_unit_mps;   ///< ground speed of one firmware speed unit
  std::optional<double> counter_pulse_m;  ///< wheel travel of one counter pulse
};

/// A whole robot model file.
struct RobotDescription {
  RobotBody body;
  LinkDefaults link;
  /// Its sensors (`sensors:`); none: the robot entry's own, or the default IR ring.
  std::optional<environment::SensorSuiteConfig> sensors;
};

/// Where the robot models shipped with rilbed are: $RILBED_ROBOT_DIR, else `robots/`
/// beside the executable (the build copies the repository's robots/ there).
std::filesystem::path robot_model_directory();

/// The file a scenario's `model:` names: a path relative to the scenario's folder, else
/// relative to robot_model_directory(); a bare name ("epuck") is robot_model_directory()'s
/// NAME.yaml. The error lists where it looked.
core::Result<std::filesystem::path> find_robot_model(const std::string& name,
                                                     const std::filesystem::path& scenario_dir);

/// Reads the `body:` and `wheels:` blocks of `r` (a model file's top level, or a
/// scenario's robot entry) over `body`: only what they give changes. Throws ScenarioError
/// naming the file, the line and the key (an outline that is not convex, say).
void read_body_parts(const yaml_detail::Reader& r, RobotBody& body);

/// Reads a robot model file. `read_sensors` reads its `sensors:` block (the scenario's
/// reader, so that the blocks are alike; plug-in paths in it are relative to the model
/// file). Throws ScenarioError naming the file, the line and the key.
RobotDescription read_robot_description(
    const std::filesystem::path& file,
    const std::function<environment::SensorSuiteConfig(const yaml_detail::Reader&)>& read_sensors);

}  // namespace rilbed::run

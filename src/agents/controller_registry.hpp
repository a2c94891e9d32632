// The one list of the controllers a scenario can name: for each, what it does, the
// numbers it takes from a robot's `params` (with unit, default and allowed range), the
// sensors it reads, whether it wants the team broadcast and whether it may step beside
// other robots' controllers, and how to make one. The scenario parser checks `params`
// against it, the run builds controllers from it, `rilbed controllers` prints it and the
// web editor builds its lists and forms from its JSON. rilbed's own controllers are one
// source of entries (builtin_controllers.hpp); an entry carries where it came from, so
// that entries from a lab's libraries or files can be told apart.
#pragma once

#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "agents/controller.hpp"
#include "agents/controller_group.hpp"
#include "agents/convoy.hpp"
#include "environment/sensor_suite.hpp"

namespace rilbed::agents {

/// One number a controller takes from a robot's `params`.
struct ParamSpec {
  std::string name;  ///< the key in `params`; its unit is in it (`speed_mps`, `tolerance_deg`)
  std::string unit;  ///< "m/s", "m", "deg", ... ; empty for a count, an ID or a level
  /// Used when the scenario leaves the parameter out; nullopt: the controller decides
  /// (the summary says how), or the parameter is required.
  std::optional<double> default_value;
  bool required = false;                                  ///< the scenario must give it
  double min = -std::numeric_limits<double>::infinity();  ///< smallest allowed value (inclusive)
  double max = std::numeric_limits<double>::infinity();   ///< largest allowed value (inclusive)
  bool integer = false;                                   ///< only whole numbers
  std::string summary;                                    ///< one line of what it means
};

/// The sensor names an entry can read: the keys of a scenario's `sensors:` block
/// (`proximity`, `range_finders`, `beacon_finder`, `track`, `odometer`) and `pose`, the
/// robot's own pose from localisation (the world or the camera).
const std::vector<std::string>& known_sensor_names();

/// Whether a robot configured with `sensors` has the sensor `name` (one of
/// known_sensor_names(); `pose` always).
bool robot_has_sensor(const environment::SensorSuiteConfig& sensors, std::string_view name);

/// The parameters one robot's controller was given, with the entry's defaults behind them.
class ControllerParams {
 public:
  /// `specs` must outlive this object; `given` holds only names that `specs` lists
  /// (check_params() says so first).
  ControllerParams(const std::vector<ParamSpec>& specs, std::map<std::string, double> given);
  /// Whether the scenario gave `name`.
  bool given(std::string_view name) const;
  /// The value given, else the default. Throws std::out_of_range for a name that was
  /// neither given nor has a default (ask given() first for such a parameter).
  double get(std::string_view name) const;
  /// Every parameter the scenario gave, by name (for an entry with open_params, whose
  /// controller reads names rilbed does not know).
  const std::map<std::string, double, std::less<>>& given_values() const { return given_; }

 private:
  const std::vector<ParamSpec>* specs_;
  std::map<std::string, double, std::less<>> given_;
};

/// Everything a factory gets to make one robot's controller. Valid during the call only.
struct ControllerContext {
  int robot_id = 0;                               ///< the robot it will control
  const ControllerParams& params;                 ///< checked against the entry
  const environment::SensorSuiteConfig& sensors;  ///< the robot's sensors as configured
  const ConvoyConfig& convoy;                     ///< the scenario's `convoy:` block
  /// The run's groups of controllers that step together (ControllerGroup); null: each
  /// controller that would join a group gets one of its own. Owned by the run.
  ControllerGroups* groups = nullptr;
};

/// Makes one robot's controller, or nullptr for a robot that stands still. Throws
/// std::invalid_argument, with a message for the scenario's author, for arguments it
/// cannot use.
using ControllerFactory = std::function<std::unique_ptr<Controller>(const ControllerContext&)>;

/// One controller a scenario can name.
struct ControllerEntry {
  std::string name;                           ///< `controller: <name>` in a scenario
  std::string summary;                        ///< one line of what it does
  std::vector<ParamSpec> params;              ///< what it takes from `params`, in the order shown
  std::vector<std::string> sensors;           ///< what it reads (known_sensor_names())
  std::vector<std::string> required_sensors;  ///< of those, what a robot must have to run it
  bool wants_team = false;                    ///< it reads the team broadcast (Controller::wants_team)
  bool concurrent = true;                     ///< its steps may run beside others' (Controller::concurrent)
  std::string origin = "built in";            ///< where it came from: "built in", a library's or file's path
  /// The plug-in library's absolute path, for a controller a scenario names with
  /// `controller: {library: ..., name: ...}`; empty for one named by its name alone.
  std::string library;
  /// It takes any parameter names, and checks them itself when it is made (a Python
  /// class: its `__init__` gets `params` as a dict); `params` then lists none.
  bool open_params = false;
  /// Its robots form the convoy of paper 001 (robot k follows robot k - 1, IDs 1..N): the
  /// run watches them for formation (summary: formed, formation_time_s), and in central
  /// mode rilbed's coordinator drives them. rilbed's `convoy`; a Python class that sets
  /// `forms_convoy = True`.
  bool forms_convoy = false;
  ControllerFactory make;  ///< makes one; must be set

  /// The entry's parameter `name`, or nullptr.
  const ParamSpec* param(std::string_view name) const;
};

/// A parameter that cannot be used: which one and why.
struct ParamProblem {
  std::string key;      ///< the parameter's name ("" for the whole params block)
  std::string problem;  ///< e.g. "must be between 0 and 1.016 (m/s)"
};

/// Checks `given` against `entry`: every name known, every value a finite number in range
/// (whole where it must be), every required parameter there. The first problem, if any.
std::optional<ParamProblem> check_params(const ControllerEntry& entry, const std::map<std::string, double>& given);

/// The first sensor of entry.required_sensors that `sensors` lacks, if any.
std::optional<std::string> missing_sensor(const ControllerEntry& entry, const environment::SensorSuiteConfig& sensors);

/// The controllers a run can use, by name, in the order they were added. A value: copy it
/// to extend it for one run.
class ControllerRegistry {
 public:
  /// Adds `entry`. Throws std::invalid_argument (naming the entry and its origin) for an
  /// empty or taken name, no factory, a parameter named twice, a default outside its range
  /// or on a required parameter, or a sensor that is not one of known_sensor_names().
  void add(ControllerEntry entry);
  /// The entry called `name`, or nullptr.
  const ControllerEntry* find(std::string_view name) const;
  /// Every entry, in the order added.
  const std::vector<ControllerEntry>& entries() const { return entries_; }
  /// The names, comma-separated ("convoy, wander, ..."), for messages.
  std::string names_text() const;

 private:
  std::vector<ControllerEntry> entries_;
};

/// The registry as `rilbed controllers --json` prints it and the web server serves it: a
/// list of objects with `name`, `summary`, `sensors`, `required_sensors`, `wants_team`,
/// `concurrent`, `origin`, `library` (null unless it comes from a plug-in library) and
/// `params`, each parameter `{name, unit, default, min, max,
/// summary, required, integer}` (`default`, `min`, `max` null where there is none).
nlohmann::ordered_json controllers_json(const ControllerRegistry& registry);

/// The registry as a Markdown table, one row per controller and its parameters, as
/// `rilbed controllers` prints it and scenarios/README.md shows it.
std::string controllers_table(const ControllerRegistry& registry);

}  // namespace rilbed::agents

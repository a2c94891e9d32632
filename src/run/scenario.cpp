#include "run/scenario.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "agents/builtin_controllers.hpp"
#include "agents/library_actuator_models.hpp"
#include "agents/library_controllers.hpp"
#include "agents/library_sensor_models.hpp"
#include "core/id_list.hpp"
#include "environment/body_shape.hpp"
#include "environment/shapes.hpp"
#include "environment/track_layouts.hpp"
#include "python/python_controllers.hpp"
#include "run/robot_description.hpp"
#include "run/sensor_parameters.hpp"
#include "run/yaml_reader.hpp"

namespace rilbed::run {

namespace {

using yaml_detail::Reader;

TimeUs milliseconds(const Reader& r, const std::string& key, TimeUs fallback_us) {
  const double ms = r.positive(key, static_cast<double>(fallback_us) / 1000.0);
  const TimeUs us = static_cast<TimeUs>(std::llround(ms * 1000.0));
  if (us <= 0) r.fail_key(key, "must be at least 0.001 ms");
  return us;
}

// `path` relative to the file `r` reads (a scenario, or a robot model file it names),
// absolute: what a scenario's plug-in libraries, parameter files and Python files are.
std::filesystem::path resolved(const Reader& r, const std::string& path) {
  std::error_code ec;
  return std::filesystem::absolute(std::filesystem::path(r.source()).parent_path() / path, ec).lexically_normal();
}

// The sensor models a scenario's robots mount (`sensors: {models: [...]}`): their libraries
// loaded once each, their parameter files read and checked, each mount made (its model's
// create(), with the scenario's static map and control period) once per robot entry.
class ScenarioSensors {
 public:
  explicit ScenarioSensors(const Scenario& scenario) : scenario_(scenario) {}

  environment::SensorModelMount mount(const Reader& m) {
    m.allow({"library", "name", "parameters", "mount_x_m", "mount_y_m", "mount_yaw_deg", "as"});
    const std::string library = m.text("library", "");
    const std::string name = m.text("name", "");
    if (library.empty()) m.fail_key("library", "give the plug-in library's path, relative to the scenario file");
    if (name.empty()) m.fail_key("name", "give the name of one of the library's sensor models");
    const agents::SensorModelEntry& entry = model(m, resolved(m, library), name);
    ParameterFile file{"(no parameter file)", {}};
    if (m.has("parameters")) {
      const std::filesystem::path path = resolved(m, m.text("parameters", ""));
      core::Result<ParameterFile> read = read_parameter_file(path);
      if (!read) m.fail_key("parameters", read.error());
      file = *read;
    }
    core::Result<std::vector<double>> values = parameter_values(entry, file);
    if (!values) m.fail_key("parameters", values.error());
    agents::SensorMount mount{m.text("as", entry.name),       *values,
                              m.number("mount_x_m", 0.0),     m.number("mount_y_m", 0.0),
                              m.number("mount_yaw_deg", 0.0), m.has("parameters") ? file.source : std::string()};
    core::Result<std::shared_ptr<const environment::SensorModel>> made =
        agents::mount_sensor_model(entry, mount, static_map(m), scenario_.control_period_us);
    if (!made) m.fail_key("name", made.error());
    return {*made};
  }

  // A robot entry's `actuator:`: the model's factory, its parameters checked.
  std::shared_ptr<const environment::DriveModelFactory> actuator(const Reader& a) {
    a.allow({"library", "name", "parameters"});
    const std::string library = a.text("library", "");
    const std::string name = a.text("name", "");
    if (library.empty()) a.fail_key("library", "give the plug-in library's path, relative to the scenario file");
    if (name.empty()) a.fail_key("name", "give the name of one of the library's actuator models");
    const std::filesystem::path path = resolved(a, library);
    auto it = actuators_.find(path.string());
    if (it == actuators_.end()) {
      core::Result<std::vector<agents::ActuatorModelEntry>> loaded = agents::load_library_actuator_models(path);
      if (!loaded) a.fail_key("library", loaded.error());
      it = actuators_.emplace(path.string(), std::move(*loaded)).first;
    }
    const agents::ActuatorModelEntry* entry = nullptr;
    std::string held;
    for (const agents::ActuatorModelEntry& e : it->second) {
      if (e.name == name) entry = &e;
      held += (held.empty() ? "" : ", ") + e.name;
    }
    if (!entry) {
      a.fail_key("name", "plug-in library " + path.string() + " holds no actuator model '" + name + "' (it holds " +
                             (held.empty() ? std::string("none") : held) + ")");
    }
    ParameterFile file{"(no parameter file)", {}};
    if (a.has("parameters")) {
      core::Result<ParameterFile> read = read_parameter_file(resolved(a, a.text("parameters", "")));
      if (!read) a.fail_key("parameters", read.error());
      file = *read;
    }
    core::Result<std::vector<double>> values = parameter_values("actuator model " + entry->name, entry->params, file);
    if (!values) a.fail_key("parameters", values.error());
    return agents::actuator_factory(*entry, *values, static_map(a), scenario_.physics_step_us,
                                    a.has("parameters") ? file.source : std::string());
  }

 private:
  const agents::SensorModelEntry& model(const Reader& m, const std::filesystem::path& path, const std::string& name) {
    auto it = libraries_.find(path.string());
    if (it == libraries_.end()) {
      core::Result<std::vector<agents::SensorModelEntry>> loaded = agents::load_library_sensor_models(path);
      if (!loaded) m.fail_key("library", loaded.error());
      it = libraries_.emplace(path.string(), std::move(*loaded)).first;
    }
    std::string held;
    for (const agents::SensorModelEntry& e : it->second) {
      if (e.name == name) return e;
      held += (held.empty() ? "" : ", ") + e.name;
    }
    m.fail_key("name", "plug-in library " + path.string() + " holds no sensor model '" + name + "' (it holds " +
                           (held.empty() ? std::string("none") : held) + ")");
  }

  // The scenario's static map as the models' create() sees it, made once.
  const environment::StaticMap& static_map(const Reader& m) {
    if (!map_) {
      try {
        map_.emplace(scenario_.map);
      } catch (const std::invalid_argument& e) {
        m.fail_key("name", std::string("the scenario's map is not usable: ") + e.what());
      }
    }
    return *map_;
  }

  const Scenario& scenario_;
  std::map<std::string, std::vector<agents::SensorModelEntry>> libraries_;
  std::map<std::string, std::vector<agents::ActuatorModelEntry>> actuators_;
  std::optional<environment::StaticMap> map_;
};

environment::SensorSuiteConfig read_sensors(const Reader& r, ScenarioSensors& models) {
  environment::SensorSuiteConfig s;
  r.allow({"proximity", "range_finders", "beacon_finder", "track", "odometer", "models"});
  if (r.has("proximity")) {
    const YAML::Node n = r.get("proximity");
    if (n.IsScalar()) {
      if (r.boolean("proximity", true)) {
        s.proximity = environment::ProximityConfig{};
      } else {
        s.proximity.reset();
      }
    } else {
      const Reader p = r.child("proximity");
      p.allow({"range_m", "falloff_m", "half_angle_deg", "noise_sd"});
      environment::ProximityConfig c;
      c.range_m = p.positive("range_m", c.range_m);
      c.falloff_m = p.positive("falloff_m", c.falloff_m);
      c.half_angle_rad = deg_to_rad(p.positive("half_angle_deg", rad_to_deg(c.half_angle_rad)));
      c.noise_sd = p.non_negative("noise_sd", c.noise_sd);
      s.proximity = c;
    }
  }
  if (r.has("range_finders")) {
    const YAML::Node list = r.get("range_finders");
    if (!list.IsSequence()) r.fail_key("range_finders", "must be a list");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Reader f(list[i], r.source(), r.join("range_finders") + "[" + std::to_string(i) + "]");
      f.allow({"mount_deg", "opening_deg", "max_range_m", "noise_sd_m"});
      environment::RangeFinderConfig c;
      c.mount_angle_rad = deg_to_rad(f.number("mount_deg", 0.0));
      c.opening_angle_rad = deg_to_rad(f.positive("opening_deg", rad_to_deg(c.opening_angle_rad)));
      c.max_range_m = f.positive("max_range_m", c.max_range_m);
      c.noise_sd_m = f.non_negative("noise_sd_m", c.noise_sd_m);
      s.range_finders.push_back(c);
    }
  }
  if (r.has("beacon_finder")) {
    const Reader b = r.child("beacon_finder");
    b.allow({"field_of_view_deg", "bearing_noise_deg"});
    environment::BeaconFinderConfig c;
    c.field_of_view_rad = deg_to_rad(b.positive("field_of_view_deg", 360.0));
    c.bearing_noise_sd_rad = deg_to_rad(b.non_negative("bearing_noise_deg", 0.0));
    s.beacon_finder = c;
  }
  if (r.has("track")) {
    const YAML::Node list = r.get("track");
    if (!list.IsSequence()) r.fail_key("track", "must be a list of track sensor elements");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Reader t(list[i], r.source(), r.join("track") + "[" + std::to_string(i) + "]");
      // One key per parameter of paper 000 §8.2's configuration block, plus the mount.
      t.allow({"mount_x_m", "mount_y_m", "mount_yaw_deg", "height_mm", "inclination_deg", "cone_angle_deg", "precision",
               "coverage_percent", "max_value", "error_level_percent", "graded"});
      environment::TrackSensorConfig c;
      c.mount_x_m = t.number("mount_x_m", c.mount_x_m);
      c.mount_y_m = t.number("mount_y_m", c.mount_y_m);
      c.mount_yaw_deg = t.number("mount_yaw_deg", c.mount_yaw_deg);
      c.height_mm = t.positive("height_mm", c.height_mm);
      c.inclination_deg = t.number("inclination_deg", c.inclination_deg);
      c.cone_angle_deg = t.positive("cone_angle_deg", c.cone_angle_deg);
      c.precision = t.integer("precision", c.precision);
      c.coverage_percent = t.non_negative("coverage_percent", c.coverage_percent);
      c.max_value = t.integer("max_value", c.max_value);
      c.error_level_percent = t.non_negative("error_level_percent", c.error_level_percent);
      c.graded = t.boolean("graded", c.graded);
      s.track_sensors.push_back(c);
    }
  }
  s.odometer = r.boolean("odometer", s.odometer);
  if (r.has("models")) {
    const YAML::Node list = r.get("models");
    if (!list.IsSequence()) r.fail_key("models", "must be a list of sensor model mounts");
    std::set<std::string> names;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Reader m(list[i], r.source(), r.join("models") + "[" + std::to_string(i) + "]");
      s.models.push_back(models.mount(m));
      const environment::SensorModel& model = *s.models.back().model;
      if (!model.provides_track() && !names.insert(model.name()).second) {
        m.fail_key("name", "a second mount called '" + model.name() + "' on this robot: give one `as: OTHER_NAME`");
      }
    }
  }
  return s;
}

// The robot IDs of one entry: `id: 3` or `ids: 1-8`.
std::vector<int> read_robot_ids(const Reader& r, const YAML::Node& entry) {
  std::vector<int> ids;
  if (r.has("id") == r.has("ids")) r.fail(entry, "give exactly one of `id` (one robot) or `ids` (e.g. 1-8)");
  if (r.has("id")) {
    ids.push_back(r.integer("id", 0));
  } else {
    const auto parsed = parse_id_list(r.text("ids", ""), 1, 100000);
    if (!parsed.ok()) r.fail_key("ids", parsed.error);
    ids = parsed.ids;
  }
  return ids;
}

environment::RobotKind read_kind(const Reader& r) {
  const std::string kind = r.text("kind", "virtual");
  if (kind == "real") return environment::RobotKind::kReal;
  if (kind != "virtual") r.fail_key("kind", "must be virtual or real, not '" + kind + "'");
  return environment::RobotKind::kVirtual;
}

// `pose: random` (nullopt) or [x_m, y_m, theta_deg]; one pose places one robot only.
std::optional<Pose2> read_pose(const Reader& r, std::size_t robots) {
  if (!r.has("pose")) return std::nullopt;
  const YAML::Node p = r.get("pose");
  if (p.IsScalar() && p.as<std::string>() == "random") return std::nullopt;
  if (!p.IsSequence() || p.size() != 3) r.fail_key("pose", "must be `random` or [x_m, y_m, theta_deg]");
  double v[3];
  for (int k = 0; k < 3; ++k) {
    try {
      v[k] = p[k].as<double>();
    } catch (const YAML::Exception&) {
      r.fail_key("pose", "must be `random` or [x_m, y_m, theta_deg]");
    }
    if (!std::isfinite(v[k])) r.fail_key("pose", "must hold finite numbers");
  }
  if (robots > 1) r.fail_key("pose", "one pose cannot place several robots; use `random` or one entry per robot");
  return Pose2{{v[0], v[1]}, deg_to_rad(v[2])};
}

// The registry a scenario's robots are read against: the one given, and the controllers
// of the plug-in libraries its robots name (`controller: {library: ..., name: ...}`),
// added to a copy of it the first time each library is met.
class ScenarioControllers {
 public:
  explicit ScenarioControllers(std::shared_ptr<const agents::ControllerRegistry> base) : base_(std::move(base)) {}
  const agents::ControllerRegistry& registry() const { return extended_ ? *extended_ : *base_; }
  // The registry with every library's controllers, for the scenario to carry.
  std::shared_ptr<const agents::ControllerRegistry> result() const {
    return extended_ ? std::make_shared<const agents::ControllerRegistry>(*extended_) : base_;
  }
  // The entry `name` of the library at `path` (already absolute), loading the library the
  // first time; a problem is reported against `r`'s `controller` key.
  const agents::ControllerEntry& from_library(const Reader& r, const std::filesystem::path& path,
                                              const std::string& name) {
    if (loaded_.insert(path.string()).second) add_library(r, path);
    const agents::ControllerEntry* entry = registry().find(name);
    if (!entry || entry->library != path.string()) {
      std::vector<std::string> held;
      for (const agents::ControllerEntry& e : registry().entries()) {
        if (e.library == path.string()) held.push_back(e.name);
      }
      std::string list;
      for (const std::string& h : held) list += (list.empty() ? "" : ", ") + h;
      r.fail_key("controller", "plug-in library " + path.string() + " holds no controller '" + name + "' (it holds " +
                                   (list.empty() ? std::string("none") : list) + ")");
    }
    return *entry;
  }

  // The entry of class `class_name` of the Python file at `path` (absolute), imported the
  // first time; a problem is reported against `r`'s `controller` key.
  const agents::ControllerEntry& from_python(const Reader& r, const std::filesystem::path& path,
                                             const std::string& class_name) {
    const std::string key = path.string() + "\n" + class_name;
    if (const auto it = python_.find(key); it != python_.end()) return *registry().find(it->second);
    core::Result<agents::ControllerEntry> entry = python::load_python_controller(path, class_name);
    if (!entry) r.fail_key("controller", entry.error());
    if (!extended_) extended_ = *base_;
    const std::string name = entry->name;
    if (const agents::ControllerEntry* taken = extended_->find(name)) {
      r.fail_key("controller", "the Python class " + name + " of " + path.string() +
                                   " has the name of the controller from " + taken->origin +
                                   "; rename the file or the class");
    }
    extended_->add(std::move(*entry));
    python_.emplace(key, name);
    return *registry().find(name);
  }

 private:
  void add_library(const Reader& r, const std::filesystem::path& path) {
    core::Result<std::vector<agents::ControllerEntry>> entries = agents::load_library_controllers(path);
    if (!entries) r.fail_key("controller", entries.error());
    if (!extended_) extended_ = *base_;
    for (agents::ControllerEntry& e : *entries) {
      try {
        extended_->add(std::move(e));
      } catch (const std::invalid_argument& error) {
        r.fail_key("controller", error.what());
      }
    }
  }

  std::shared_ptr<const agents::ControllerRegistry> base_;
  std::optional<agents::ControllerRegistry> extended_;
  std::set<std::string> loaded_;
  std::map<std::string, std::string> python_;  // file and class -> the entry's name
};

// The entry a robot's `controller` names: a name of the registry, or a plug-in library's
// controller, `{library: PATH, name: NAME}` with PATH relative to the scenario file.
const agents::ControllerEntry& read_controller_name(const Reader& r, ScenarioControllers& controllers,
                                                    ControllerSpec& spec) {
  const bool python = r.has("controller") && [&] {
    const YAML::Node c = r.get("controller");
    return c.IsMap() && c["python"];
  }();
  if (python) {
    const Reader c = r.child("controller");
    c.allow({"python", "class"});
    const std::string file = c.text("python", "");
    const std::string class_name = c.text("class", "");
    if (file.empty()) c.fail_key("python", "give the Python file's path, relative to the scenario file");
    if (class_name.empty())
      c.fail_key("class", "give the name of a class of the file that subclasses rilbed.Controller");
    const std::filesystem::path path = resolved(r, file);
    const agents::ControllerEntry& entry = controllers.from_python(r, path, class_name);
    spec.name = entry.name;
    spec.library = path.string();
    return entry;
  }
  if (r.has("controller") && r.get("controller").IsMap()) {
    const Reader c = r.child("controller");
    c.allow({"library", "name"});
    const std::string library = c.text("library", "");
    spec.name = c.text("name", "");
    if (library.empty()) c.fail_key("library", "give the plug-in library's path, relative to the scenario file");
    if (spec.name.empty()) c.fail_key("name", "give the name of one of the library's controllers");
    const std::filesystem::path path = resolved(r, library);
    spec.library = path.string();
    return controllers.from_library(r, path, spec.name);
  }
  spec.name = r.text("controller", "convoy");
  const agents::ControllerEntry* controller = controllers.registry().find(spec.name);
  if (!controller) {
    r.fail_key("controller",
               "unknown controller '" + spec.name + "' (known: " + controllers.registry().names_text() +
                   "; `rilbed controllers` lists them; a plug-in library's: {library: PATH, name: NAME}; a Python "
                   "class: {python: FILE, class: NAME})");
  }
  if (!controller->library.empty() && controller->open_params) {
    r.fail_key("controller", "'" + spec.name + "' is a Python class of " + controller->library +
                                 ": name it as {python: FILE, class: NAME}");
  }
  if (!controller->library.empty()) {
    r.fail_key("controller", "'" + spec.name + "' comes from the plug-in library " + controller->library +
                                 ": name it as {library: PATH, name: " + spec.name + "}");
  }
  return *controller;
}

// `controller` and `params`, checked against the controller's registry entry; the entry,
// for the robot's sensors to be checked against.
const agents::ControllerEntry& read_controller(const Reader& r, ScenarioControllers& controllers,
                                               ControllerSpec& spec) {
  const agents::ControllerEntry& controller = read_controller_name(r, controllers, spec);
  if (!r.has("params")) {
    if (const auto problem = agents::check_params(controller, {})) r.fail_key("controller", problem->problem);
    return controller;
  }
  const Reader p = r.child("params");
  for (const auto& kv : r.get("params")) {
    const std::string key = kv.first.as<std::string>();
    spec.params[key] = p.number(key, 0.0);
  }
  if (const auto problem = agents::check_params(controller, spec.params)) {
    if (problem->key.empty()) r.fail_key("params", problem->problem);
    p.fail_key(problem->key, problem->problem);
  }
  return controller;
}

environment::WheelNoiseConfig read_noise(const Reader& n) {
  n.allow({"slip_sd", "left_bias", "right_bias", "odometer_counts_slip"});
  environment::WheelNoiseConfig noise;
  noise.slip_sd = n.non_negative("slip_sd", 0.0);
  noise.left_bias = n.number("left_bias", 0.0);
  noise.right_bias = n.number("right_bias", 0.0);
  noise.odometer_counts_slip = n.boolean("odometer_counts_slip", true);
  return noise;
}

// An emulated robot's `faults:`.
serial::EmulatorFaults read_faults(const Reader& f) {
  f.allow({"reply_delay_ms", "drop", "garbage", "corrupt", "disconnect_after_s", "replug_after_s"});
  serial::EmulatorFaults faults;
  faults.reply_delay_ms = f.integer("reply_delay_ms", 0);
  if (faults.reply_delay_ms < 0) f.fail_key("reply_delay_ms", "must not be negative");
  for (auto [key, value] : {std::pair{"drop", &faults.drop_probability},
                            {"garbage", &faults.garbage_probability},
                            {"corrupt", &faults.corrupt_probability}}) {
    *value = f.non_negative(key, 0.0);
    if (*value > 1.0) f.fail_key(key, "is a probability, at most 1");
  }
  faults.disconnect_after_s = f.non_negative("disconnect_after_s", 0.0);
  faults.replug_after_s = f.non_negative("replug_after_s", 0.0);
  return faults;
}

LinkSpec read_link(const Reader& l, const YAML::Node& at) {
  l.allow(
      {"port", "baud", "model", "emulate", "placement", "faults", "reply_timeout_ms", "retries", "counters_period_ms"});
  LinkSpec link;
  link.port = l.text("port", "");
  link.baud = l.integer("baud", link.baud);
  link.model = l.text("model", link.model);
  // Checked here, not when the robot is connected; the firmware's other spellings too.
  if (link.model == "khepera") link.model = "khepera2";
  if (link.model == "e-puck") link.model = "epuck";
  if (link.model != "khepera2" && link.model != "epuck")
    l.fail_key("model", "is khepera2 or epuck, not '" + link.model + "'");
  link.emulate = l.boolean("emulate", false);
  link.reply_timeout_ms = l.integer("reply_timeout_ms", link.reply_timeout_ms);
  if (link.reply_timeout_ms <= 0) l.fail_key("reply_timeout_ms", "must be greater than 0");
  link.retries = l.integer("retries", link.retries);
  if (link.retries < 0) l.fail_key("retries", "must not be negative");
  link.counters_period_ms = l.integer("counters_period_ms", link.counters_period_ms);
  if (link.counters_period_ms < 0) l.fail_key("counters_period_ms", "must not be negative");
  if (link.port.empty() == !link.emulate) l.fail(at, "give either `port` or `emulate: true`");
  const std::string placement = l.text("placement", link.emulate ? "teleport" : "drive");
  if (placement == "drive") {
    link.placement = Placement::kDrive;
  } else if (placement == "teleport") {
    if (!link.emulate)
      l.fail_key("placement", "only an emulated robot can be put in place by rilbed (a real one is driven there)");
    link.placement = Placement::kTeleport;
  } else {
    l.fail_key("placement", "is drive or teleport, not '" + placement + "'");
  }
  if (l.has("faults")) {
    if (!link.emulate) l.fail_key("faults", "only an emulated robot injects faults");
    link.faults = read_faults(l.child("faults"));
  }
  return link;
}

// The robot model file a robot entry names (`model:`), or the built-in Khepera II. Its
// errors are the model file's, after where the scenario named it.
RobotDescription read_model(const Reader& r, ScenarioSensors& sensors) {
  if (!r.has("model")) return {};
  const std::string name = r.text("model", "");
  core::Result<std::filesystem::path> file = find_robot_model(name, std::filesystem::path(r.source()).parent_path());
  if (!file) r.fail_key("model", file.error());
  try {
    return read_robot_description(*file, [&](const Reader& block) { return read_sensors(block, sensors); });
  } catch (const ScenarioError& e) {
    r.fail_key("model", e.what());
  }
}

// Every robot entry, each of one robot (`id`) or several alike (`ids`), sorted by ID.
std::vector<RobotSpec> read_robots(const Reader& top, ScenarioControllers& controllers, ScenarioSensors& sensors) {
  const YAML::Node list = top.get("robots");
  if (!list || !list.IsSequence() || list.size() == 0) top.fail_key("robots", "must be a non-empty list of robots");
  std::vector<RobotSpec> robots;
  std::set<int> seen;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const Reader r(list[i], top.source(), "robots[" + std::to_string(i) + "]");
    r.allow({"id", "ids", "kind", "pose", "model", "body", "wheels", "controller", "params", "noise", "sensors", "link",
             "actuator"});
    RobotSpec base;
    base.line = list[i].Mark().line + 1;
    const RobotDescription model = read_model(r, sensors);
    base.body = model.body;
    if (model.sensors) base.sensors = *model.sensors;
    read_body_parts(r, base.body);
    const std::vector<int> ids = read_robot_ids(r, list[i]);
    base.kind = read_kind(r);
    base.pose = read_pose(r, ids.size());
    const agents::ControllerEntry& controller = read_controller(r, controllers, base.controller);
    if (r.has("noise")) base.noise = read_noise(r.child("noise"));
    if (r.has("actuator")) {
      if (base.kind == environment::RobotKind::kReal)
        r.fail_key("actuator", "a real robot's wheels are its own: only a virtual robot takes an actuator model");
      if (r.has("noise")) r.fail_key("actuator", "give either `noise` (the built-in drive's) or `actuator`, not both");
      base.drive = sensors.actuator(r.child("actuator"));
    }
    if (r.has("sensors")) base.sensors = read_sensors(r.child("sensors"), sensors);
    if (const auto sensor = agents::missing_sensor(controller, base.sensors)) {
      r.fail_key(r.has("sensors") ? "sensors" : "controller",
                 base.controller.name + " needs `sensors: " + *sensor + ":` (see scenarios/README.md)");
    }
    if (r.has("link")) {
      if (base.kind != environment::RobotKind::kReal) r.fail_key("link", "only a robot of kind real has a link");
      base.link = read_link(r.child("link"), r.get("link"));
      if (!r.child("link").has("model") && model.link.model) base.link->model = *model.link.model;
      // The model's units are its protocol's: a link that speaks another keeps that one's own.
      if (!model.link.model || *model.link.model == base.link->model) {
        base.link->speed_unit_mps = model.link.speed_unit_mps;
        base.link->counter_pulse_m = model.link.counter_pulse_m;
      }
    } else if (base.kind == environment::RobotKind::kReal) {
      r.fail(list[i], "a robot of kind real needs a `link` ({port: /dev/ttyUSB0, baud: 38400} or {emulate: true})");
    }
    for (int id : ids) {
      if (id < 1) r.fail(list[i], "robot IDs start at 1");
      if (!seen.insert(id).second) r.fail(list[i], "robot " + std::to_string(id) + " is defined twice");
      RobotSpec spec = base;
      spec.id = id;
      robots.push_back(spec);
    }
  }
  std::sort(robots.begin(), robots.end(), [](const RobotSpec& a, const RobotSpec& b) { return a.id < b.id; });
  return robots;
}

// `mode`, `field` and `timing`.
void read_mode_field_and_timing(const Reader& top, Scenario& s) {
  const std::string mode = top.text("mode", "distributed");
  if (mode == "distributed") {
    s.mode = ConvoyMode::kDistributed;
  } else if (mode == "central") {
    s.mode = ConvoyMode::kCentral;
  } else {
    top.fail_key("mode", "must be central or distributed, not '" + mode + "'");
  }
  if (top.has("field")) {
    const Reader f = top.child("field");
    f.allow({"width_m", "height_m", "walls"});
    s.map.field.width_m = f.positive("width_m", s.map.field.width_m);
    s.map.field.height_m = f.positive("height_m", s.map.field.height_m);
    s.map.field.boundary_walls = f.boolean("walls", true);
  }
  if (top.has("timing")) {
    const Reader t = top.child("timing");
    t.allow({"physics_step_ms", "control_period_ms", "broadcast_period_ms"});
    s.physics_step_us = milliseconds(t, "physics_step_ms", s.physics_step_us);
    s.control_period_us = milliseconds(t, "control_period_ms", s.control_period_us);
    s.broadcast_period_us = milliseconds(t, "broadcast_period_ms", s.broadcast_period_us);
  }
}

// The convoy's knobs (`convoy:`).
void read_convoy(const Reader& top, Scenario& s) {
  if (!top.has("convoy")) return;
  const Reader c = top.child("convoy");
  c.allow({"standoff_m", "engage_m", "max_speed_mps", "avoid_low", "avoid_high"});
  s.convoy.standoff_m = c.positive("standoff_m", s.convoy.standoff_m);
  s.convoy.engage_m = c.positive("engage_m", s.convoy.engage_m);
  s.convoy.steering.max_speed_mps = c.positive("max_speed_mps", s.convoy.steering.max_speed_mps);
  s.convoy.avoid_low = c.non_negative("avoid_low", s.convoy.avoid_low);
  s.convoy.avoid_high = c.positive("avoid_high", s.convoy.avoid_high);
  if (s.convoy.avoid_high <= s.convoy.avoid_low) c.fail_key("avoid_high", "must be above avoid_low");
}

// The field's contents: `obstacles`, `tracks`, `beacons` and `moving_obstacles`.
void read_map_lists(const Reader& top, const std::string& source, Scenario& s) {
  auto each = [&](const char* key, auto&& read) {
    if (!top.has(key)) return;
    const YAML::Node list = top.get(key);
    if (!list.IsSequence()) top.fail_key(key, "must be a list");
    for (std::size_t i = 0; i < list.size(); ++i)
      read(Reader(list[i], source, std::string(key) + "[" + std::to_string(i) + "]"));
  };
  each("obstacles", [&](const Reader& o) {
    o.allow({"name", "polygon"});
    s.map.obstacles.push_back({o.points("polygon"), o.text("name", "")});
  });
  each("tracks", [&](const Reader& t) {
    t.allow({"name", "points", "width_m", "closed"});
    environment::TrackConfig c;
    c.points_m = t.points("points");
    c.width_m = t.positive("width_m", c.width_m);
    c.closed = t.boolean("closed", false);
    c.name = t.text("name", "");
    s.map.tracks.push_back(c);
  });
  if (top.has("track_layout")) {
    // A random tape network drawn from a seed (grid, tree or loop with spurs), added to
    // the listed tracks: networks nobody designed the controller for.
    const Reader l = top.child("track_layout");
    l.allow({"kind", "seed", "tape_width_m", "margin_m"});
    const std::string kind = l.text("kind", "grid");
    environment::TrackLayoutKind k = environment::TrackLayoutKind::kGrid;
    if (kind == "tree") {
      k = environment::TrackLayoutKind::kTree;
    } else if (kind == "loop") {
      k = environment::TrackLayoutKind::kLoopWithSpurs;
    } else if (kind != "grid") {
      l.fail_key("kind", "must be grid, tree or loop");
    }
    environment::TrackLayoutOptions options;
    options.field_width_m = s.map.field.width_m;
    options.field_height_m = s.map.field.height_m;
    options.tape_width_m = l.positive("tape_width_m", options.tape_width_m);
    options.margin_m = l.non_negative("margin_m", options.margin_m);
    const int seed = l.integer("seed", 1);
    if (seed < 0) l.fail_key("seed", "must be 0 or more");
    try {
      for (auto& t : environment::make_track_layout(static_cast<std::uint64_t>(seed), k, options))
        s.map.tracks.push_back(std::move(t));
    } catch (const std::invalid_argument& e) {
      l.fail_key("margin_m", e.what());
    }
  }
  each("beacons", [&](const Reader& b) {
    b.allow({"id", "position", "facing_deg", "aperture_deg", "range_m"});
    environment::BeaconConfig c;
    c.id = b.integer("id", 0);
    if (!b.has("position")) b.fail_key("position", "is required");
    c.position_m = b.point(b.get("position"), "position");
    c.facing_rad = deg_to_rad(b.number("facing_deg", 0.0));
    c.aperture_rad = deg_to_rad(b.positive("aperture_deg", 360.0));
    c.range_m = b.positive("range_m", c.range_m);
    s.map.beacons.push_back(c);
  });
  each("moving_obstacles", [&](const Reader& m) {
    m.allow({"name", "shape", "radius_m", "vertices", "position", "velocity_mps"});
    environment::MovingObstacleConfig c;
    const std::string shape = m.text("shape", "disc");
    if (shape == "disc") {
      c.shape = environment::MovingShape::kDisc;
      c.radius_m = m.positive("radius_m", c.radius_m);
    } else if (shape == "polygon") {
      c.shape = environment::MovingShape::kPolygon;
      c.vertices_m = m.points("vertices");
    } else {
      m.fail_key("shape", "must be disc or polygon");
    }
    if (!m.has("position")) m.fail_key("position", "is required");
    c.position_m = m.point(m.get("position"), "position");
    c.velocity_mps = m.has("velocity_mps") ? m.point(m.get("velocity_mps"), "velocity_mps") : Vec2{};
    c.name = m.text("name", "");
    s.moving_obstacles.push_back(c);
  });
}

// The overhead camera of a scenario with real robots (`camera:`).
CameraSpec read_camera(const Reader& top) {
  const Reader c = top.child("camera");
  c.allow({"emulate", "device", "file", "calibration", "fps", "marker_diameter_m", "family", "vision"});
  CameraSpec cam;
  cam.line = top.line_of("camera");
  cam.emulate = c.boolean("emulate", false);
  if (c.has("device")) cam.device = c.integer("device", 0);
  cam.file = c.text("file", "");
  cam.calibration = c.text("calibration", "");
  cam.fps = c.positive("fps", cam.fps);
  cam.marker_diameter_m = c.positive("marker_diameter_m", cam.marker_diameter_m);
  cam.family = c.text("family", cam.family);
  if (c.has("vision")) {
    const Reader v = c.child("vision");
    v.allow({"brightness", "contrast", "threshold", "min_diameter_px", "max_diameter_px", "min_score"});
    for (const std::string_view setting : vision::kVisionSettingNames) {
      const std::string name(setting);
      if (!v.has(name)) continue;
      if (auto why = vision::set_vision_setting(cam.vision, name, v.number(name, 0.0))) v.fail_key(name, *why);
    }
    if (auto why = vision::check_vision_settings(cam.vision)) c.fail_key("vision", *why);
  }
  const int sources = (cam.emulate ? 1 : 0) + (cam.device ? 1 : 0) + (cam.file.empty() ? 0 : 1);
  if (sources != 1) top.fail_key("camera", "give exactly one of `emulate: true`, `device: N` or `file: PATH`");
  if (!cam.emulate && cam.calibration.empty())
    c.fail_key("calibration", "a real camera needs its field calibration file");
  return cam;
}

// Where the robots' controllers run (`agents:`), checked against the robots.
AgentsSpec read_agents(const Reader& top, const std::vector<RobotSpec>& robots) {
  const Reader a = top.child("agents");
  a.allow({"processes", "ids", "announce_timeout_s", "resend_ms", "dead_after_ms", "deadline_ms", "hosts", "launch",
           "remote_rilbed"});
  AgentsSpec spec;
  if (a.has("hosts")) spec.hosts = a.words("hosts");
  for (const std::string& host : spec.hosts) {
    // A host is one argument of the launch command: one starting with '-' would be taken
    // for an option of ssh (e.g. -oProxyCommand=...), not a machine.
    if (host.empty() || host.front() == '-' || host.find_first_of(" \t\r\n") != std::string::npos) {
      a.fail_key("hosts", "'" + host + "' is not a host name (no spaces, not starting with '-')");
    }
  }
  spec.processes = a.integer("processes", static_cast<int>(spec.hosts.size()));
  if (spec.processes < 0 || spec.processes > 64) a.fail_key("processes", "must be 0 to 64");
  if (!spec.hosts.empty() && spec.processes < 1) a.fail_key("processes", "the hosts need at least one process");
  if (a.has("launch")) {
    spec.launch = a.words("launch");
    if (spec.launch.empty() || spec.launch.front().empty()) a.fail_key("launch", "must name a program to start");
    if (std::none_of(spec.launch.begin(), spec.launch.end(),
                     [](const std::string& w) { return w.find("{command}") != std::string::npos; })) {
      a.fail_key("launch", "must have a {command} item (the agent's command line)");
    }
  }
  spec.remote_rilbed = a.text("remote_rilbed", "");
  if (a.has("ids")) {
    const auto parsed = parse_id_list(a.text("ids", ""), 1, 100000);
    if (!parsed.ok()) a.fail_key("ids", parsed.error);
    for (const int id : parsed.ids) {
      const auto robot = std::find_if(robots.begin(), robots.end(), [&](const RobotSpec& r) { return r.id == id; });
      if (robot == robots.end()) a.fail_key("ids", "there is no robot " + std::to_string(id));
      if (robot->controller.name == "none") a.fail_key("ids", "robot " + std::to_string(id) + " has no controller");
    }
    spec.ids = parsed.ids;
  } else {
    for (const RobotSpec& r : robots) {
      if (r.controller.name != "none") spec.ids.push_back(r.id);
    }
  }
  if (spec.ids.empty()) a.fail_key("ids", "no robot has a controller to run elsewhere");
  if (spec.processes > static_cast<int>(spec.ids.size())) {
    a.fail_key("processes", "more processes than robots to run (" + std::to_string(spec.ids.size()) + ")");
  }
  spec.announce_timeout_s = a.positive("announce_timeout_s", spec.announce_timeout_s);
  spec.resend_ms = a.integer("resend_ms", spec.resend_ms);
  if (spec.resend_ms < 1) a.fail_key("resend_ms", "must be at least 1");
  spec.dead_after_ms = a.integer("dead_after_ms", spec.dead_after_ms);
  if (spec.dead_after_ms <= spec.resend_ms) a.fail_key("dead_after_ms", "must be longer than resend_ms");
  spec.deadline_ms = a.integer("deadline_ms", spec.deadline_ms);
  if (spec.deadline_ms < 1) a.fail_key("deadline_ms", "must be at least 1");
  return spec;
}

Scenario read_scenario(const YAML::Node& root, const std::string& source, ScenarioControllers& controllers) {
  Scenario s;
  const Reader top(root, source, "");
  top.allow({"name", "description", "mode", "field", "timing", "duration_s", "convoy", "obstacles", "tracks",
             "track_layout", "beacons", "moving_obstacles", "robots", "camera", "safety", "agents"});
  s.name = top.text("name", std::filesystem::path(source).stem().string());
  read_mode_field_and_timing(top, s);
  s.duration_s = top.positive("duration_s", s.duration_s);
  read_convoy(top, s);
  read_map_lists(top, source, s);
  ScenarioSensors sensors(s);
  s.robots = read_robots(top, controllers, sensors);
  if (top.has("camera")) s.camera = read_camera(top);
  if (top.has("safety")) {
    const Reader f = top.child("safety");
    f.allow({"lost_timeout_ms", "geofence_margin_m"});
    s.lost_timeout_ms = f.integer("lost_timeout_ms", s.lost_timeout_ms);
    if (s.lost_timeout_ms <= 0) f.fail_key("lost_timeout_ms", "must be greater than 0");
    s.geofence_margin_m = f.non_negative("geofence_margin_m", s.geofence_margin_m);
  }
  if (top.has("agents")) s.agents = read_agents(top, s.robots);
  const bool any_real = std::any_of(s.robots.begin(), s.robots.end(),
                                    [](const RobotSpec& r) { return r.kind == environment::RobotKind::kReal; });
  if (any_real && !s.camera) top.fail_key("camera", "a scenario with real robots needs a `camera` to see them");
  // The static map validates its own geometry; report its complaint against the file.
  try {
    environment::StaticMap check(s.map);
  } catch (const std::invalid_argument& e) {
    throw ScenarioError(source + ": " + e.what());
  }
  return s;
}

}  // namespace

Scenario parse_scenario(const std::string& yaml_text, const std::string& source_name,
                        std::shared_ptr<const agents::ControllerRegistry> controllers) {
  if (!controllers) controllers = agents::default_controllers();
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw ScenarioError(source_name + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
  if (!root || root.IsNull()) throw ScenarioError(source_name + ": the scenario is empty");
  try {
    ScenarioControllers registry(std::move(controllers));
    Scenario scenario = read_scenario(root, source_name, registry);
    scenario.controllers = registry.result();
    return scenario;
  } catch (const YAML::Exception& e) {
    throw ScenarioError(source_name + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

Scenario load_scenario(const std::filesystem::path& path,
                       std::shared_ptr<const agents::ControllerRegistry> controllers) {
  std::ifstream in(path);
  if (!in) throw ScenarioError(path.string() + ": cannot open the scenario file");
  std::stringstream text;
  text << in.rdbuf();
  Scenario s = parse_scenario(text.str(), path.string(), std::move(controllers));
  s.source = path;
  return s;
}

namespace {

// Points hashed in a uniform grid of cells at least `spacing_m` wide, so that whether a new
// point comes nearer than that to one of them looks at 3 x 3 cells, not at every point:
// placing 100,000 robots took 14 s with a list. At most about 2^20 cells (wider ones on a
// huge field); points off the field go to its edge cells.
class PlacedPoints {
 public:
  PlacedPoints(double width_m, double height_m, double spacing_m)
      // A hair wider than the spacing: two points nearer than it never round two cells apart.
      : cell_m_(std::max(spacing_m, std::sqrt(std::max(width_m * height_m, 1e-12) / double(1 << 20))) * (1.0 + 1e-9)),
        nx_(cells_along(width_m)),
        ny_(cells_along(height_m)),
        head_(static_cast<std::size_t>(nx_) * ny_, -1) {}
  void add(Vec2 p) {
    const std::size_t c = cell(index_x(p.x), index_y(p.y));
    next_.push_back(head_[c]);
    head_[c] = static_cast<int>(points_.size());
    points_.push_back(p);
  }
  // Whether a point lies strictly nearer than `distance_m` (at most the spacing) to p.
  bool any_nearer(Vec2 p, double distance_m) const {
    const int cx = index_x(p.x), cy = index_y(p.y);
    for (int y = std::max(0, cy - 1); y <= std::min(ny_ - 1, cy + 1); ++y) {
      for (int x = std::max(0, cx - 1); x <= std::min(nx_ - 1, cx + 1); ++x) {
        for (int k = head_[cell(x, y)]; k >= 0; k = next_[static_cast<std::size_t>(k)]) {
          if (environment::distance_sq(p, points_[static_cast<std::size_t>(k)]) < distance_m * distance_m) return true;
        }
      }
    }
    return false;
  }

 private:
  int cells_along(double length_m) const {
    return static_cast<int>(std::clamp(std::ceil(length_m / cell_m_), 1.0, double(1 << 20)));
  }
  // Clamped before the cast: a fixed pose far off the field must not overflow an int.
  int index_x(double x) const { return static_cast<int>(std::clamp(std::floor(x / cell_m_), 0.0, double(nx_ - 1))); }
  int index_y(double y) const { return static_cast<int>(std::clamp(std::floor(y / cell_m_), 0.0, double(ny_ - 1))); }
  std::size_t cell(int x, int y) const { return static_cast<std::size_t>(y) * nx_ + x; }
  double cell_m_;
  int nx_, ny_;
  std::vector<int> head_, next_;
  std::vector<Vec2> points_;
};

}  // namespace

std::vector<Pose2> draw_initial_poses(const Scenario& scenario, std::mt19937_64& rng, double clearance_m) {
  const environment::FieldConfig& field = scenario.map.field;
  // Apart by the largest body's bounding disc (a Khepera's, in a swarm of Kheperas).
  double radius = 0.0;
  for (const RobotSpec& r : scenario.robots)
    radius = std::max(
        radius, r.body.outline_m.empty() ? r.body.radius_m : environment::outline_bounding_radius_m(r.body.outline_m));
  const double margin = radius + clearance_m;
  std::vector<Pose2> poses(scenario.robots.size());
  const double spacing_m = 2 * radius + clearance_m;
  PlacedPoints placed(field.width_m, field.height_m, spacing_m);
  for (std::size_t i = 0; i < scenario.robots.size(); ++i) {
    if (scenario.robots[i].pose) {
      poses[i] = *scenario.robots[i].pose;
      placed.add(poses[i].position_m);
    }
  }
  auto free = [&](Vec2 p) {
    if (placed.any_nearer(p, spacing_m)) return false;
    for (const auto& o : scenario.map.obstacles) {
      if (environment::point_in_polygon(p, o.vertices_m)) return false;
      for (std::size_t k = 0; k < o.vertices_m.size(); ++k) {
        const Vec2 a = o.vertices_m[k], b = o.vertices_m[(k + 1) % o.vertices_m.size()];
        if (environment::distance_sq_to_segment(p, a, b) < margin * margin) return false;
      }
    }
    // A moving obstacle where it starts, by its bounding circle (a polygon's vertices are
    // relative to its position).
    for (const auto& m : scenario.moving_obstacles) {
      double reach_m = m.shape == environment::MovingShape::kDisc ? m.radius_m : 0.0;
      for (const Vec2& v : m.vertices_m) reach_m = std::max(reach_m, std::hypot(v.x, v.y));
      if (environment::distance_sq(p, m.position_m) < (reach_m + margin) * (reach_m + margin)) return false;
    }
    return true;
  };
  std::uniform_real_distribution<double> ux(margin, field.width_m - margin), uy(margin, field.height_m - margin);
  std::uniform_real_distribution<double> heading(-kPi, kPi);
  if (field.width_m <= 2 * margin || field.height_m <= 2 * margin) {
    throw ScenarioError(scenario.source.string() + ": the field is too small for a robot");
  }
  for (std::size_t i = 0; i < scenario.robots.size(); ++i) {
    if (scenario.robots[i].pose) continue;
    bool done = false;
    for (int attempt = 0; attempt < 10000 && !done; ++attempt) {
      const Vec2 p{ux(rng), uy(rng)};
      if (!free(p)) continue;
      poses[i] = {p, heading(rng)};
      placed.add(p);
      done = true;
    }
    if (!done) {
      throw ScenarioError(scenario.source.string() + ":" + std::to_string(scenario.robots[i].line) +
                          ": no free place for robot " + std::to_string(scenario.robots[i].id) +
                          " after 10000 tries: the field is too crowded");
    }
  }
  return poses;
}

std::vector<int> real_robot_ids(const Scenario& scenario) {
  std::vector<int> ids;
  for (const RobotSpec& r : scenario.robots) {
    if (r.kind == environment::RobotKind::kReal) ids.push_back(r.id);
  }
  return ids;
}

Scenario wandering_scenario(int robots, double seconds, double physics_step_ms, double density_per_m2) {
  Scenario s;
  s.name = "wander-" + std::to_string(robots);
  s.source = "(benchmark)";
  s.controllers = agents::default_controllers();
  const double area_m2 = robots / density_per_m2;
  s.map.field.width_m = std::sqrt(area_m2 * 1.25);
  s.map.field.height_m = area_m2 / s.map.field.width_m;
  s.physics_step_us = static_cast<TimeUs>(std::llround(physics_step_ms * 1000));
  s.control_period_us = 100'000;
  s.duration_s = seconds;
  for (int id = 1; id <= robots; ++id) {
    RobotSpec r;
    r.id = id;
    r.controller.name = "wander";
    r.noise.slip_sd = 0.02;
    r.sensors.proximity = environment::ProximityConfig{};
    s.robots.push_back(r);
  }
  return s;
}

}  // namespace rilbed::run

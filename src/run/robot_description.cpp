#include "run/robot_description.hpp"

#include <cstdlib>
#include <stdexcept>

#include "core/beside_executable.hpp"
#include "environment/body_shape.hpp"
#include "run/yaml_reader.hpp"

namespace rilbed::run {

using yaml_detail::Reader;

std::filesystem::path robot_model_directory() { return core::beside_executable("robots", "RILBED_ROBOT_DIR"); }

core::Result<std::filesystem::path> find_robot_model(const std::string& name,
                                                     const std::filesystem::path& scenario_dir) {
  if (name.empty()) return core::Failure{"give a robot model file (robots/epuck.yaml) or a shipped model's name"};
  std::vector<std::filesystem::path> tried;
  const bool bare = name.find('/') == std::string::npos && std::filesystem::path(name).extension() != ".yaml";
  if (bare) {
    tried.push_back(robot_model_directory() / (name + ".yaml"));
  } else {
    tried.push_back(scenario_dir / name);
    if (std::filesystem::path(name).is_relative()) {
      // "robots/epuck.yaml" from a scenario anywhere: the shipped folder holds robots/'s files.
      const std::filesystem::path p(name);
      tried.push_back(robot_model_directory() / (*p.begin() == "robots" ? p.lexically_relative("robots") : p));
    }
  }
  std::string looked;
  for (const std::filesystem::path& t : tried) {
    std::error_code ec;
    const std::filesystem::path abs = std::filesystem::absolute(t, ec).lexically_normal();
    if (std::filesystem::is_regular_file(abs, ec)) return abs;
    looked += (looked.empty() ? "" : ", ") + abs.string();
  }
  return core::Failure{"no robot model file '" + name + "' (looked for " + looked + ")"};
}

namespace {

void read_outline(const Reader& b, RobotBody& body) {
  std::vector<Vec2> outline = b.points("outline_m");
  try {
    body.outline_m = environment::checked_outline(std::move(outline), "the body");
  } catch (const std::invalid_argument& e) {
    b.fail_key("outline_m", e.what());
  }
}

}  // namespace

void read_body_parts(const Reader& r, RobotBody& body) {
  if (r.has("body")) {
    const Reader b = r.child("body");
    b.allow({"radius_m", "outline_m"});
    if (b.has("radius_m") && b.has("outline_m")) b.fail_key("outline_m", "give either radius_m (a disc) or outline_m");
    if (b.has("radius_m")) {
      body.radius_m = b.positive("radius_m", body.radius_m);
      if (body.radius_m > 1.0) b.fail_key("radius_m", "is at most 1 m (a robot on a lab's table)");
      body.outline_m.clear();
    }
    if (b.has("outline_m")) {
      read_outline(b, body);
      body.radius_m = environment::outline_bounding_radius_m(body.outline_m);
    }
    if (!body.outline_m.empty() && environment::outline_bounding_radius_m(body.outline_m) > 1.0)
      b.fail_key("outline_m", "reaches more than 1 m from the centre (a robot on a lab's table)");
  }
  if (r.has("wheels")) {
    const Reader w = r.child("wheels");
    w.allow({"base_m", "radius_m"});
    body.wheel_base_m = w.positive("base_m", body.wheel_base_m);
    body.wheel_radius_m = w.positive("radius_m", body.wheel_radius_m);
    if (body.wheel_base_m > 2.0) w.fail_key("base_m", "is at most 2 m");
    if (body.wheel_radius_m > 0.5) w.fail_key("radius_m", "is at most 0.5 m");
  }
}

RobotDescription read_robot_description(
    const std::filesystem::path& file,
    const std::function<environment::SensorSuiteConfig(const Reader&)>& read_sensors) {
  const std::string source = file.string();
  YAML::Node root;
  try {
    root = YAML::LoadFile(source);
  } catch (const YAML::BadFile&) {
    throw ScenarioError(source + ": cannot read the robot model file");
  } catch (const YAML::Exception& e) {
    throw ScenarioError(source + ":" + std::to_string(e.mark.line + 1) + ": not YAML: " + e.msg);
  }
  if (!root || root.IsNull()) throw ScenarioError(source + ":1: the robot model file is empty");
  const Reader top(root, source, "");
  top.allow({"name", "body", "wheels", "link", "sensors"});
  RobotDescription d;
  d.body.name = top.text("name", file.stem().string());
  d.body.file = source;
  read_body_parts(top, d.body);
  if (top.has("link")) {
    const Reader l = top.child("link");
    l.allow({"model", "speed_unit_mps", "counter_pulse_m"});
    if (l.has("model")) {
      const std::string model = l.text("model", "");
      if (model != "khepera2" && model != "epuck") l.fail_key("model", "is khepera2 or epuck, not '" + model + "'");
      d.link.model = model;
    }
    if (l.has("speed_unit_mps")) d.link.speed_unit_mps = l.positive("speed_unit_mps", 0.0);
    if (l.has("counter_pulse_m")) d.link.counter_pulse_m = l.positive("counter_pulse_m", 0.0);
  }
  if (top.has("sensors")) d.sensors = read_sensors(top.child("sensors"));
  return d;
}

}  // namespace rilbed::run

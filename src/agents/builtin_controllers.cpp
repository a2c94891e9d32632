#include "agents/builtin_controllers.hpp"

#include <filesystem>
#include <stdexcept>

#include "agents/basic_controllers.hpp"
#include "agents/convoy.hpp"
#include "agents/library_controllers.hpp"
#include "agents/track_explore.hpp"

namespace rilbed::agents {

namespace {

// The fastest a Khepera drives, m/s (127 units of 8 mm/s).
constexpr double kTopSpeed_mps = kMaxWheelUnits * kMetresPerSecondPerUnit;

ParamSpec speed(double default_mps, const char* summary) {
  return {"speed_mps", "m/s", default_mps, false, 0.0, kTopSpeed_mps, false, summary};
}

ControllerEntry convoy_entry() {
  ControllerEntry e;
  e.name = "convoy";
  e.summary =
      "paper 001's convoy: robot k follows robot k-1 (robot 1 leads) through a behaviour network of search, follow, "
      "wait and avoid; its numbers are the scenario's `convoy:` block, and `mode: central` drives it from one "
      "coordinator instead";
  e.sensors = {"proximity", "pose"};
  e.wants_team = true;
  e.forms_convoy = true;
  e.make = [](const ControllerContext& c) { return std::make_unique<ConvoyController>(c.robot_id, c.convoy); };
  return e;
}

ControllerEntry wander_entry() {
  ControllerEntry e;
  e.name = "wander";
  e.summary = "a Braitenberg wanderer: straight ahead in the open, turning away from what its IR sensors see";
  e.params = {speed(WanderConfig{}.speed_mps, "cruising speed in the open")};
  e.sensors = {"proximity"};
  e.make = [](const ControllerContext& c) {
    WanderConfig config;
    config.speed_mps = c.params.get("speed_mps");
    return std::make_unique<WanderController>(config);
  };
  return e;
}

ControllerEntry track_follow_entry() {
  ControllerEntry e;
  e.name = "track_follow";
  e.summary =
      "follows a floor track with two or more track sensors ordered left to right (paper 000 section 8), arcing in "
      "search of it when none sees it, avoiding obstacles first";
  e.params = {speed(TrackFollowConfig{}.speed_mps, "speed along the track"),
              {"max_value", "", std::nullopt, false, 1.0, 1e6, true,
               "the track sensors' full scale; default: the robot's first track sensor's max_value"}};
  e.sensors = {"track", "proximity"};
  e.required_sensors = {"track"};
  e.make = [](const ControllerContext& c) {
    TrackFollowConfig config;
    config.speed_mps = c.params.get("speed_mps");
    if (!c.sensors.track_sensors.empty()) config.max_value = c.sensors.track_sensors.front().max_value;
    if (c.params.given("max_value")) config.max_value = static_cast<int>(c.params.get("max_value"));
    return std::make_unique<TrackFollowController>(config);
  };
  return e;
}

ControllerEntry track_explore_entry() {
  ControllerEntry e;
  e.name = "track_explore";
  e.summary =
      "finds a floor tape from anywhere and visits every edge of the tape network with its track sensors and wheel "
      "counters only (paper 000 section 9), turning once on the spot at each node to tell its kind; records each "
      "node (track_node) and edge (track_edge) and is done when no way is left untaken; the run folder gets "
      "track_map.json";
  const TrackExploreConfig d;
  e.params = {speed(d.speed_mps, "speed along the tape"),
              {"tape_width_m", "m", d.reading.tape_width_m, false, 0.003, 0.1, false,
               "the tape's width: decides which track sensors can see a side arm"},
              {"scan_turn_radps", "rad/s", d.scan_turn_radps, false, 0.2, 6.0, false,
               "turn rate of the look round at a node (slower resolves ways better)"},
              {"match_radius_m", "m", d.match_radius_m, false, 0.01, 0.5, false,
               "a node found within this of a known one is that node"},
              {"time_limit_s", "s", 0.0, false, 0.0, 1e6, false, "done after this long, with what it has; 0: never"},
              {"correct_odometry", "", 0.0, false, 0.0, 1.0, true,
               "1: correct the odometry from the map it builds (experimental: not yet better under wheel slip); "
               "0: the map is dead reckoning alone"},
              {"max_value", "", std::nullopt, false, 1.0, 1e6, true,
               "the track sensors' full scale; default: the robot's first track sensor's max_value"}};
  e.sensors = {"track", "odometer", "proximity", "pose"};
  e.required_sensors = {"track", "odometer"};
  e.make = [](const ControllerContext& c) {
    TrackExploreConfig config;
    config.speed_mps = c.params.get("speed_mps");
    config.reading.tape_width_m = c.params.get("tape_width_m");
    config.scan_turn_radps = c.params.get("scan_turn_radps");
    config.match_radius_m = c.params.get("match_radius_m");
    config.time_limit_s = c.params.get("time_limit_s");
    config.correct_odometry = c.params.get("correct_odometry") != 0.0;
    if (!c.sensors.track_sensors.empty()) config.reading.max_value = c.sensors.track_sensors.front().max_value;
    if (c.params.given("max_value")) config.reading.max_value = static_cast<int>(c.params.get("max_value"));
    if (c.sensors.track_sensors.size() < 3)
      throw std::invalid_argument("track_explore needs at least three track sensors across the robot's front");
    return std::make_unique<TrackExploreController>(TrackArray::of(c.sensors.track_sensors), config);
  };
  return e;
}

ControllerEntry beacon_homing_entry() {
  ControllerEntry e;
  e.name = "beacon_homing";
  e.summary =
      "turns towards a beacon's bearing and drives to it (paper 000 section 6.10), turning on the spot while none is "
      "in view, and stops at its base";
  e.params = {{"beacon_id", "", std::nullopt, false, 0.0, 1e6, true, "the beacon to home on; default: the first seen"},
              speed(BeaconHomingConfig{}.speed_mps, "speed towards the beacon")};
  e.sensors = {"beacon_finder", "proximity"};
  e.required_sensors = {"beacon_finder"};
  e.make = [](const ControllerContext& c) {
    BeaconHomingConfig config;
    if (c.params.given("beacon_id")) config.beacon_id = static_cast<int>(c.params.get("beacon_id"));
    config.speed_mps = c.params.get("speed_mps");
    return std::make_unique<BeaconHomingController>(config);
  };
  return e;
}

ControllerEntry goto_entry() {
  const GoToPoseConfig defaults{};
  ControllerEntry e;
  e.name = "goto";
  e.summary =
      "drives slowly to a pose and holds it, yielding to lower IDs ahead and steering around higher ones: what places "
      "real robots before a run";
  e.params = {
      {"x_m", "m", std::nullopt, true, -1e6, 1e6, false, "the target's x in the field frame"},
      {"y_m", "m", std::nullopt, true, -1e6, 1e6, false, "the target's y in the field frame"},
      {"theta_deg", "deg", 0.0, false, -360.0, 360.0, false, "the target heading, counter-clockwise from +x"},
      speed(defaults.speed_mps, "top speed (slow, so that the camera keeps up and a bump is harmless)"),
      {"tolerance_m", "m", defaults.position_tolerance_m, false, 0.0005, 1.0, false, "close enough to the target"},
      {"tolerance_deg", "deg", rad_to_deg(defaults.heading_tolerance_rad), false, 0.05, 180.0, false,
       "close enough to the target heading"},
  };
  e.sensors = {"pose"};
  e.wants_team = true;
  e.make = [](const ControllerContext& c) {
    GoToPoseConfig config;
    config.target = Pose2{{c.params.get("x_m"), c.params.get("y_m")}, deg_to_rad(c.params.get("theta_deg"))};
    config.speed_mps = c.params.get("speed_mps");
    config.position_tolerance_m = c.params.get("tolerance_m");
    config.heading_tolerance_rad = deg_to_rad(c.params.get("tolerance_deg"));
    return std::make_unique<GoToPoseController>(config);
  };
  return e;
}

// rilbed's own C controller, a plug-in library built beside rilbed from the example that
// docs/write-a-controller.md shows; loaded the first time a robot needs it.
ControllerEntry braitenberg_entry() {
  ControllerEntry e;
  e.name = "c:braitenberg";
  e.summary =
      "a Braitenberg wanderer written in C against rilbed_controller.h's register map "
      "(examples/controllers/braitenberg_c, the plug-in library plugins/braitenberg.so beside rilbed)";
  e.sensors = {"proximity", "odometer", "range_finders", "track", "beacon_finder", "pose"};
  e.concurrent = false;
  e.make = [](const ControllerContext& context) {
    static const core::Result<ControllerEntry> loaded = []() -> core::Result<ControllerEntry> {
      const std::filesystem::path path = builtin_plugin_directory() / "braitenberg.so";
      core::Result<std::vector<ControllerEntry>> entries = load_library_controllers(path);
      if (!entries) return core::Failure{entries.error()};
      for (ControllerEntry& entry : *entries) {
        if (entry.name == "braitenberg") return std::move(entry);
      }
      return core::Failure{"plug-in library " + path.string() + " holds no controller 'braitenberg'"};
    }();
    if (!loaded) throw std::invalid_argument(loaded.error());
    return loaded->make(context);
  };
  return e;
}

ControllerEntry none_entry() {
  ControllerEntry e;
  e.name = "none";
  e.summary = "no controller: the robot stands still, an obstacle the others sense";
  e.make = [](const ControllerContext&) { return std::unique_ptr<Controller>(); };
  return e;
}

}  // namespace

ControllerRegistry builtin_controllers() {
  ControllerRegistry r;
  r.add(convoy_entry());
  r.add(wander_entry());
  r.add(track_follow_entry());
  r.add(track_explore_entry());
  r.add(beacon_homing_entry());
  r.add(goto_entry());
  r.add(braitenberg_entry());
  r.add(none_entry());
  return r;
}

std::shared_ptr<const ControllerRegistry> default_controllers() {
  static const auto registry = std::make_shared<const ControllerRegistry>(builtin_controllers());
  return registry;
}

}  // namespace rilbed::agents

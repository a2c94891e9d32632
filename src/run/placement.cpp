#include "run/placement.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "core/id_list.hpp"
#include "run/simulation.hpp"

namespace rilbed::run {

namespace {

std::string pose_text(const Pose2& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.3f m, %.3f m, %.0f deg)", p.position_m.x, p.position_m.y,
                wrap_deg_360(rad_to_deg(p.heading_rad)));
  return buf;
}

// The scenario of the placing run: the same field and camera, only the real robots; each
// to be driven gets the goto controller with its target, the others stand still (they
// are still there for the others to avoid).
run::Scenario placing_scenario(const run::Scenario& scenario, const std::map<int, Pose2>& targets,
                               const std::vector<int>& drive_ids, const PlacementOptions& options) {
  run::Scenario s = scenario;
  s.name = scenario.name + " (placing the real robots)";
  s.moving_obstacles.clear();
  s.robots.clear();
  for (const run::RobotSpec& r : scenario.robots) {
    if (r.kind != environment::RobotKind::kReal) continue;
    run::RobotSpec spec = r;
    const auto target = targets.find(r.id);
    spec.pose = target != targets.end() ? target->second : Pose2{};
    spec.controller = {};
    spec.controller.name = "none";
    if (std::find(drive_ids.begin(), drive_ids.end(), r.id) != drive_ids.end()) {
      spec.controller.name = "goto";
      spec.controller.params = {{"x_m", target->second.position_m.x},
                                {"y_m", target->second.position_m.y},
                                {"theta_deg", rad_to_deg(target->second.heading_rad)},
                                {"speed_mps", options.speed_mps},
                                {"tolerance_m", options.tolerance_m},
                                {"tolerance_deg", options.tolerance_deg}};
    }
    s.robots.push_back(spec);
  }
  return s;
}

// Each robot's last pose in a run kept in memory.
std::map<int, Pose2> last_poses(const run::RunResult& r) {
  std::map<int, Pose2> last;
  for (const run::TrajectorySample& s : r.trajectory) last[s.id] = s.pose;
  return last;
}

}  // namespace

PlacementResult place_real_robots(RealRobots& robots, const std::map<int, Pose2>& targets,
                                  const PlacementOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const run::Scenario& scenario = robots.scenario();
  PlacementResult result;
  auto log = [&](serial::LogLevel level, const std::string& message) {
    if (options.log) options.log(level, message);
  };
  std::vector<int> drive_ids;
  for (const run::RobotSpec& r : scenario.robots) {
    const auto target = targets.find(r.id);
    if (r.kind != environment::RobotKind::kReal || target == targets.end()) continue;
    const bool is_new = robots.emulator(r.id) == nullptr && r.link && r.link->emulate;
    robots.connect(r, target->second);  // a new emulated robot starts at its target
    if (is_new) continue;
    if (r.link->placement == run::Placement::kTeleport) {
      robots.emulator(r.id)->place(target->second);
    } else {
      drive_ids.push_back(r.id);
    }
  }
  if (drive_ids.empty()) {
    result.ok = true;
    return result;
  }
  log(serial::LogLevel::kInfo, "driving robots " + id_list_text(drive_ids) + " to their start poses");
  const run::Scenario placing = placing_scenario(scenario, targets, drive_ids, options);
  run::RunOptions run;
  run.realtime = true;
  run.duration_s = options.timeout_s;
  run.stop_when_done = true;
  run.keep_in_memory = true;
  run.interrupt = options.interrupt;
  run.emulated_markers = [&robots] { return robots.emulated_markers(); };
  const run::RunResult r = run::run_scenario(placing, run, robots.body_factory());
  const std::map<int, Pose2> last = last_poses(r);
  for (const int id : drive_ids) {
    const auto seen = last.find(id);
    if (seen != last.end()) result.offset_m[id] = (seen->second.position_m - targets.at(id).position_m).norm();
  }
  if (r.ended_by == "interrupt") {
    result.error = "interrupted while placing robots " + id_list_text(drive_ids);
  } else if (!r.not_done.empty()) {
    char within[32];
    std::snprintf(within, sizeof within, "%g s", options.timeout_s);
    std::string message = "robots " + id_list_text(r.not_done) + " did not reach their start poses within " + within +
                          "; place them by hand:";
    for (const int id : r.not_done) {
      const auto seen = last.find(id);
      message += "\n  robot " + std::to_string(id) + " to " + pose_text(targets.at(id)) +
                 (seen != last.end() ? " (the camera sees it at " + pose_text(seen->second) + ")"
                                     : " (the camera does not see it)");
    }
    if (!options.ask_operator) log(serial::LogLevel::kWarning, message);
    if (!options.ask_operator || !options.ask_operator(message)) {
      result.error = "robots " + id_list_text(r.not_done) + " are not at their start poses and nobody placed them";
    } else {
      for (const int id : r.not_done) {
        // An emulated robot is placed by the hand the operator lends it.
        if (serial::KheperaEmulator* e = robots.emulator(id)) e->place(targets.at(id));
        result.placed_by_operator.push_back(id);
        result.offset_m.erase(id);  // measured before the operator's hand moved it
      }
    }
  }
  result.ok = result.error.empty();
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace rilbed::run

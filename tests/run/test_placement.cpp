// Placing real robots at a run's start poses: emulated robots (through the real serial
// link, seen by the emulated camera and the real detector) driven across each other's
// paths to their poses; the operator asked, by name, when driving runs out of time; an
// emulated robot put in place when its link says so. Real time: each takes seconds.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

#include "run/placement.hpp"
#include "run/real_robots.hpp"
#include "run/simulation.hpp"

namespace rilbed::run {
namespace {

run::Scenario two_real_robots(const std::string& placement) {
  return run::parse_scenario(
      "name: placing\n"
      "field: {width_m: 1.5, height_m: 1.2, walls: true}\n"
      "camera: {emulate: true, fps: 30}\n"
      "safety: {lost_timeout_ms: 500, geofence_margin_m: 0.03}\n"
      "robots:\n"
      "  - ids: 1-2\n"
      "    kind: real\n"
      "    link: {emulate: true, placement: " +
          placement +
          "}\n"
          "    pose: random\n"
          "    controller: none\n"
          "  - id: 3\n"
          "    pose: [0.75, 0.6, 0]\n"
          "    controller: none\n",
      "placing.yaml");
}

double heading_error_deg(const Pose2& a, const Pose2& b) {
  return std::abs(rad_to_deg(wrap_rad_pi(a.heading_rad - b.heading_rad)));
}

TEST(Placement, DrivesRobotsAcrossEachOthersPathsToTheirPoses) {
  const run::Scenario scenario = two_real_robots("drive");
  RealRobots robots(scenario, {});
  // They start facing each other on one line and must swap sides (and turn round).
  const std::map<int, Pose2> start = {{1, Pose2{{0.45, 0.6}, 0.0}}, {2, Pose2{{0.85, 0.6}, M_PI}}};
  PlacementOptions options;
  options.timeout_s = 60.0;
  PlacementResult r = place_real_robots(robots, start, options);  // new emulated robots start there
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_TRUE(r.offset_m.empty());
  const std::map<int, Pose2> swapped = {{1, Pose2{{0.85, 0.62}, M_PI / 2}}, {2, Pose2{{0.45, 0.58}, -M_PI / 2}}};
  bool asked = false;
  options.ask_operator = [&](const std::string&) { return asked = true; };
  r = place_real_robots(robots, swapped, options);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_FALSE(asked);
  ASSERT_EQ(r.offset_m.size(), 2u);
  for (const auto& [id, target] : swapped) {
    const Pose2 truth = robots.emulator(id)->true_pose();
    // The camera's tolerance plus what the detector and the last step may add.
    EXPECT_LT((truth.position_m - target.position_m).norm(), 0.008) << "robot " << id;
    EXPECT_LT(heading_error_deg(truth, target), 5.0) << "robot " << id;
    EXPECT_LE(r.offset_m.at(id), options.tolerance_m + 1e-9) << "robot " << id;
    // Stopped, and stopped for good: nothing drives it after placing.
    EXPECT_EQ(robots.emulator(id)->last_speeds(), (serial::WheelSpeeds{0, 0}));
  }
}

TEST(Placement, AsksTheOperatorByNameWhenDrivingRunsOutOfTime) {
  const run::Scenario scenario = two_real_robots("drive");
  RealRobots robots(scenario, {});
  PlacementOptions options;
  ASSERT_TRUE(place_real_robots(robots, {{1, Pose2{{0.3, 0.3}, 0.0}}, {2, Pose2{{1.2, 0.9}, 0.0}}}, options).ok);
  const std::map<int, Pose2> far = {{1, Pose2{{1.2, 0.3}, 1.0}}, {2, Pose2{{0.3, 0.9}, 2.0}}};
  options.timeout_s = 0.5;  // far too short for 0.9 m at 4 cm/s
  std::string asked;
  options.ask_operator = [&](const std::string& message) {
    asked = message;
    return true;  // "placed by hand": an emulated robot is put there
  };
  PlacementResult r = place_real_robots(robots, far, options);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_NE(asked.find("robots 1, 2 did not reach their start poses"), std::string::npos) << asked;
  EXPECT_NE(asked.find("robot 1 to (1.200 m, 0.300 m, 57 deg)"), std::string::npos) << asked;
  EXPECT_EQ(r.placed_by_operator, (std::vector<int>{1, 2}));
  for (const auto& [id, target] : far) {
    EXPECT_LT((robots.emulator(id)->true_pose().position_m - target.position_m).norm(), 1e-9);
  }
  // An operator who gives up (or is not there) ends it with a reason.
  options.ask_operator = [](const std::string&) { return false; };
  r = place_real_robots(robots, {{1, Pose2{{0.3, 0.3}, 0.0}}, {2, Pose2{{1.2, 0.9}, 0.0}}}, options);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("robots 1, 2 are not at their start poses and nobody placed them"), std::string::npos)
      << r.error;
  // With nobody to ask, it fails too. (Towards poses nearly a metre from where the robots
  // stand: the call above drove them towards these for at most 0.5 s, so a slow machine
  // cannot leave them already in place.)
  options.ask_operator = {};
  EXPECT_FALSE(place_real_robots(robots, {{1, Pose2{{0.3, 0.3}, 0.0}}, {2, Pose2{{1.2, 0.9}, 0.0}}}, options).ok);
}

TEST(Placement, PutsEmulatedRobotsInPlaceWhenTheirLinkSaysSo) {
  const run::Scenario scenario = two_real_robots("teleport");
  RealRobots robots(scenario, {});
  PlacementOptions options;
  ASSERT_TRUE(place_real_robots(robots, {{1, Pose2{{0.3, 0.3}, 0.0}}, {2, Pose2{{1.2, 0.9}, 0.0}}}, options).ok);
  const std::map<int, Pose2> next = {{1, Pose2{{1.0, 0.2}, 1.0}}, {2, Pose2{{0.2, 1.0}, -1.0}}};
  const PlacementResult r = place_real_robots(robots, next, options);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_TRUE(r.offset_m.empty());  // nothing was driven
  for (const auto& [id, target] : next) {
    EXPECT_LT((robots.emulator(id)->true_pose().position_m - target.position_m).norm(), 1e-9);
    EXPECT_LT(heading_error_deg(robots.emulator(id)->true_pose(), target), 1e-6);
  }
}

TEST(Placement, TheStartPosesAreTheRunsOwn) {
  // What a batch places the robots at is exactly where the run (and its all-virtual twin)
  // starts them.
  const run::Scenario scenario = two_real_robots("teleport");
  for (std::uint64_t seed : {1u, 7u, 42u}) {
    run::Scenario all_virtual = scenario;
    for (auto& r : all_virtual.robots) {
      r.kind = environment::RobotKind::kVirtual;
      r.link.reset();
    }
    all_virtual.camera.reset();
    run::RunOptions o;
    o.seed = seed;
    o.duration_s = 0.1;
    o.keep_in_memory = true;
    const run::RunResult run = run::run_scenario(all_virtual, o);
    const std::vector<Pose2> poses = run::start_poses(scenario, seed);
    ASSERT_EQ(poses.size(), 3u);
    for (const auto& sample : run.trajectory) {
      if (sample.t_us != 0) continue;
      EXPECT_LT((sample.pose.position_m - poses[sample.id - 1].position_m).norm(), 1e-12) << "seed " << seed;
    }
  }
}

}  // namespace
}  // namespace rilbed::run

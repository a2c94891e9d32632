// What a robot's track sensor array tells about a tape network on board: the array's
// reading (on the tape, where across it, side arms) and the turn on the spot at a node
// (its kind, its ways, where it is). The readings come from the world's own track sensor
// (paper 000's element model) over real tapes, not from made-up values.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "agents/c_controller.hpp"
#include "agents/dead_reckoning.hpp"
#include "agents/track_explore.hpp"
#include "agents/track_features.hpp"
#include "environment/world.hpp"

using namespace rilbed;
using namespace rilbed::agents;

namespace {

// Paper 000's element block, noise-free, `count` elements `spacing_m` apart across the
// front, 20 mm ahead, left to right.
std::vector<environment::TrackSensorConfig> array_block(int count, double spacing_m) {
  std::vector<environment::TrackSensorConfig> elements;
  for (int k = 0; k < count; ++k) {
    environment::TrackSensorConfig c;
    c.mount_x_m = 0.02;
    c.mount_y_m = (0.5 * (count - 1) - k) * spacing_m;
    c.inclination_deg = 0.0;
    c.error_level_percent = 0.0;
    elements.push_back(c);
  }
  return elements;
}

// The track values a robot at `pose` reads over `tapes` (each a 2-point polyline).
std::vector<int> read_at(const std::vector<environment::TrackConfig>& tapes, Pose2 pose,
                         const std::vector<environment::TrackSensorConfig>& elements) {
  environment::StaticMapConfig map;
  map.field.width_m = 1.0;
  map.field.height_m = 1.0;
  map.tracks = tapes;
  environment::World world(map);
  environment::RobotConfig robot;
  robot.id = 1;
  robot.pose = pose;
  robot.sensors.proximity.reset();
  robot.sensors.track_sensors = elements;
  world.add_robot(robot);
  environment::NoiseRng rng(1);
  return world.sense(1, 0, rng).track;
}

environment::TrackConfig tape(Vec2 a, Vec2 b, double width_m = 0.02) { return {{a, b}, width_m, false, ""}; }

// One turn on the spot at `centre`, arriving with `heading_rad`, 4 degrees a step.
ScanResult scan(const std::vector<environment::TrackConfig>& tapes, Vec2 centre, double heading_rad, int count = 5,
                double spacing_m = 0.012) {
  const auto elements = array_block(count, spacing_m);
  TrackReadingConfig reading;
  BranchScan scanner(TrackArray::of(elements), reading);
  scanner.start({centre, heading_rad}, heading_rad);
  for (int step = 0; !scanner.complete(); ++step) {
    const Pose2 pose{centre, wrap_rad_pi(heading_rad + deg_to_rad(4.0 * step))};
    scanner.add(pose, read_at(tapes, pose, elements));
  }
  return scanner.result();
}

double angle_error_deg(double a_rad, double b_deg) { return std::abs(wrap_deg_180(rad_to_deg(a_rad) - b_deg)); }

// Whether `ways` has one direction within `tolerance_deg` of each of `expected_deg`.
void expect_ways(const ScanResult& r, std::vector<double> expected_deg, double tolerance_deg) {
  ASSERT_EQ(r.ways_rad.size(), expected_deg.size());
  for (double e : expected_deg) {
    bool seen = false;
    for (double w : r.ways_rad) seen = seen || angle_error_deg(w, e) <= tolerance_deg;
    EXPECT_TRUE(seen) << "no way near " << e << " degrees";
  }
}

const Vec2 kNode{0.5, 0.5};

}  // namespace

TEST(TrackArrayReading, SeesTheTapeAndWhereItLies) {
  const auto elements = array_block(5, 0.012);
  const TrackArray array = TrackArray::of(elements);
  TrackReadingConfig config;
  const auto sides = arm_sides(array, config);
  // 24 mm out, beyond a 20 mm tape's edge and the footprint: those two can see arms.
  EXPECT_EQ(sides, (std::vector<int>{1, 0, 0, 0, -1}));
  EXPECT_EQ(array.centre_element(), 2);
  // A tape along the robot's heading, 6 mm to its left.
  const auto on = read_at({tape({0.2, 0.506}, {0.8, 0.506})}, {{0.4, 0.5}, 0.0}, elements);
  const TrackArrayReading r = read_track_array(array, on, config, sides);
  EXPECT_TRUE(r.on_track);
  EXPECT_GT(r.offset_m, 0.0);
  EXPECT_FALSE(r.arm_left);
  EXPECT_FALSE(r.arm_right);
  // The same tape with a side arm leaving to the right under the array.
  const auto arm = read_at({tape({0.2, 0.5}, {0.8, 0.5}), tape({0.42, 0.5}, {0.42, 0.3})}, {{0.4, 0.5}, 0.0}, elements);
  const TrackArrayReading a = read_track_array(array, arm, config, sides);
  EXPECT_TRUE(a.arm_right);
  EXPECT_FALSE(a.arm_left);
  // Off the tape.
  const auto off = read_at({tape({0.2, 0.7}, {0.8, 0.7})}, {{0.4, 0.5}, 0.0}, elements);
  EXPECT_FALSE(read_track_array(array, off, config, sides).on_track);
}

TEST(TrackArrayReading, FollowsTheRunNearestTheTapeItFollows) {
  // Two tapes under the array, one on each side: the run nearest where the followed tape
  // was is the one reported, whatever the mean of all.
  const auto elements = array_block(5, 0.012);
  const TrackArray array = TrackArray::of(elements);
  TrackReadingConfig config;
  config.tape_width_m = 0.008;
  const auto values = read_at({tape({0.2, 0.524}, {0.8, 0.524}, 0.008), tape({0.2, 0.476}, {0.8, 0.476}, 0.008)},
                              {{0.4, 0.5}, 0.0}, elements);
  const auto sides = arm_sides(array, config);
  EXPECT_NEAR(read_track_array(array, values, config, sides, 0.02).run_offset_m, 0.024, 1e-9);
  EXPECT_NEAR(read_track_array(array, values, config, sides, -0.02).run_offset_m, -0.024, 1e-9);
}

namespace {
void no_step() {}
}  // namespace

TEST(TrackArrayReading, CControllersReadItInRegisters) {
  const auto elements = array_block(5, 0.012);
  const rilbed_c_controller controller{"test", nullptr, no_step, nullptr};
  CControllerAdapter adapter(controller, {}, elements);
  ControlInput input;
  input.robot_id = 1;
  // A tape 6 mm to the left with a side arm leaving to the right.
  input.sensors.track =
      read_at({tape({0.2, 0.506}, {0.8, 0.506}), tape({0.42, 0.506}, {0.42, 0.3})}, {{0.4, 0.5}, 0.0}, elements);
  adapter.step(input);
  const TrackArrayReading expected = read_track_array(TrackArray::of(elements), input.sensors.track,
                                                      TrackReadingConfig{}, arm_sides(TrackArray::of(elements), {}));
  EXPECT_EQ(adapter.registers().peek(RILBED_REG_TRACK_ON), 1);
  EXPECT_EQ(adapter.registers().peek(RILBED_REG_TRACK_OFFSET_UM), std::lround(expected.offset_m * 1e6));
  EXPECT_EQ(adapter.registers().peek(RILBED_REG_TRACK_ARMS), 2);  // right
  // The tape alone, 6 mm to the left: a positive offset, no arms.
  input.sensors.track = read_at({tape({0.2, 0.506}, {0.8, 0.506})}, {{0.4, 0.5}, 0.0}, elements);
  adapter.step(input);
  EXPECT_GT(adapter.registers().peek(RILBED_REG_TRACK_OFFSET_UM), 0);
  EXPECT_EQ(adapter.registers().peek(RILBED_REG_TRACK_ARMS), 0);
  input.sensors.track = read_at({tape({0.2, 0.8}, {0.8, 0.8})}, {{0.4, 0.5}, 0.0}, elements);
  adapter.step(input);
  EXPECT_EQ(adapter.registers().peek(RILBED_REG_TRACK_ON), 0);
  EXPECT_EQ(adapter.registers().peek(RILBED_REG_TRACK_OFFSET_UM), 0);
  EXPECT_EQ(adapter.registers().peek(RILBED_REG_TRACK_ARMS), 0);
}

TEST(BranchScan, TellsEveryKindOfNodeFromItsCentre) {
  // Arriving heading east (0 degrees) at the node.
  const Vec2 n = kNode;
  const auto end = scan({tape(n - Vec2{0.3, 0}, n)}, n, 0.0);
  EXPECT_EQ(end.kind, TrackFeatureKind::kEnd);
  expect_ways(end, {180}, 4);

  const auto corner = scan({tape(n - Vec2{0.3, 0}, n), tape(n, n + Vec2{0, 0.3})}, n, 0.0);
  EXPECT_EQ(corner.kind, TrackFeatureKind::kCornerLeft);
  expect_ways(corner, {180, 90}, 4);
  EXPECT_LT((corner.node_m - n).norm(), 0.005);

  const auto right = scan({tape(n - Vec2{0.3, 0}, n), tape(n, n + Vec2{0.2, -0.2})}, n, 0.0);
  EXPECT_EQ(right.kind, TrackFeatureKind::kCornerRight);
  expect_ways(right, {180, -45}, 5);

  const auto tee = scan({tape(n - Vec2{0.3, 0}, n + Vec2{0.3, 0}), tape(n, n + Vec2{0, 0.3})}, n, 0.0);
  EXPECT_EQ(tee.kind, TrackFeatureKind::kTee);
  expect_ways(tee, {0, 90, 180}, 4);

  const auto cross = scan({tape(n - Vec2{0.3, 0}, n + Vec2{0.3, 0}), tape(n - Vec2{0, 0.3}, n + Vec2{0, 0.3})}, n, 0.0);
  EXPECT_EQ(cross.kind, TrackFeatureKind::kCross);
  expect_ways(cross, {0, 90, 180, -90}, 4);

  const auto plain = scan({tape(n - Vec2{0.3, 0}, n + Vec2{0.3, 0})}, n, 0.0);
  EXPECT_EQ(plain.kind, TrackFeatureKind::kNone);
  expect_ways(plain, {0, 180}, 4);
}

TEST(BranchScan, TellsApartTwoTapesLeavingFortyFiveDegreesApart) {
  // A fork whose two branches run together on the inner elements' circles: the outer
  // elements' arc, twice as wide as one tape's, is two ways.
  const Vec2 n = kNode;
  const auto fork =
      scan({tape(n - Vec2{0.3, 0}, n), tape(n, n + Vec2{0.2, 0.2}), tape(n, n + Vec2{0.2, -0.2})}, n, 0.0);
  EXPECT_EQ(fork.kind, TrackFeatureKind::kTee);
  expect_ways(fork, {180, 45, -45}, 8);
}

TEST(BranchScan, TellsAJunctionSeenFromOffItsCentre) {
  // Turning 1 cm short of a cross, still a cross with its four ways; the place is the
  // turn's own (near the node the inner elements' arcs run into each other and place it
  // no better), which is why track_explore turns again where the ways seem to meet.
  const Vec2 n = kNode;
  const auto cross = scan({tape(n - Vec2{0.3, 0}, n + Vec2{0.3, 0}), tape(n - Vec2{0, 0.3}, n + Vec2{0, 0.3})},
                          n - Vec2{0.01, 0}, 0.0);
  EXPECT_EQ(cross.kind, TrackFeatureKind::kCross);
  expect_ways(cross, {0, 90, 180, -90}, 20);
  EXPECT_LT((cross.node_m - n).norm(), 0.012) << cross.node_m.x << ", " << cross.node_m.y;
  ASSERT_EQ(cross.way_points_m.size(), 4u);
  // Each way's crossing point lies on its tape's centre line.
  for (const Vec2& q : cross.way_points_m)
    EXPECT_LT(std::min(std::abs(q.x - n.x), std::abs(q.y - n.y)), 0.003) << q.x << ", " << q.y;
}

TEST(MeetOfLines, FindsWhereLinesCrossAndRefusesParallelOnes) {
  const std::vector<Vec2> points = {{1, 0}, {0, 2}};
  const std::vector<double> directions = {kPi / 2, 0.0};
  const Vec2 at = meet_of_lines(points, directions, {9, 9});
  EXPECT_NEAR(at.x, 1.0, 1e-12);
  EXPECT_NEAR(at.y, 2.0, 1e-12);
  const std::vector<double> parallel = {0.0, 0.0};
  EXPECT_EQ(meet_of_lines(points, parallel, {9, 9}), (Vec2{9, 9}));
}

TEST(DeadReckoning, IntegratesStraightRunsAndTurns) {
  DeadReckoning odometry(0.053);
  odometry.update({0, 0});        // the first reading is the start
  odometry.update({1250, 1250});  // 1250 pulses of 0.08 mm: 0.1 m straight on
  EXPECT_NEAR(odometry.pose().position_m.x, 0.1, 1e-9);
  EXPECT_NEAR(odometry.pose().position_m.y, 0.0, 1e-9);
  // A quarter turn on the spot: each wheel pi/4 * 0.053 m, opposite ways.
  const auto quarter = static_cast<std::int64_t>(std::lround(kPi / 4 * 0.053 / 0.08e-3));
  odometry.update({1250 - quarter, 1250 + quarter});
  EXPECT_NEAR(rad_to_deg(odometry.pose().heading_rad), 90.0, 0.1);
  EXPECT_NEAR(odometry.pose().position_m.x, 0.1, 1e-9);
  EXPECT_NEAR(odometry.travelled_m(), 0.1, 1e-9);
  odometry.update({1250 - quarter - 500, 1250 + quarter - 500});  // backwards 4 cm
  EXPECT_NEAR(odometry.pose().position_m.y, -0.04, 1e-4);
  EXPECT_NEAR(odometry.signed_travel_m(), 0.06, 1e-9);
  EXPECT_NEAR(odometry.travelled_m(), 0.14, 1e-9);
}

TEST(ExploredTrackMap, RoutesToTheNearestUntakenWayAndWritesTrackMapJson) {
  // 0 --(0.5)-- 1 --(0.2)-- 2(untaken way), and 0 --(0.1)-- 3 with nothing left.
  ExploredTrackMap map;
  auto node = [&](int id, TrackFeatureKind kind, Vec2 at, std::vector<int> edges) {
    ExploredTrackMap::Node n{id, kind, at, {}};
    for (int e : edges) n.ways.push_back({0.0, e, false, {}});
    map.nodes.push_back(n);
  };
  node(0, TrackFeatureKind::kTee, {0, 0}, {0, 2});
  node(1, TrackFeatureKind::kCornerLeft, {0.5, 0}, {0, 1});
  node(2, TrackFeatureKind::kTee, {0.7, 0}, {1, ExploredTrackMap::kUntaken});
  node(3, TrackFeatureKind::kEnd, {0, 0.1}, {2});
  map.edges = {{0, 0, 1, 0, 0.5}, {1, 1, 2, 0, 0.2}, {0, 1, 3, 0, 0.1}};
  ASSERT_TRUE(map.has_untaken_way());
  const auto route = map.route_to_untaken(3);
  ASSERT_EQ(route.size(), 3u);
  EXPECT_EQ(route[0], (std::pair<int, int>{3, 0}));
  EXPECT_EQ(route[1], (std::pair<int, int>{0, 0}));
  EXPECT_EQ(route[2], (std::pair<int, int>{1, 1}));
  EXPECT_TRUE(map.route_to_untaken(2).empty());  // it has one itself
  EXPECT_EQ(map.to_json(),
            "{\"nodes\": [{\"id\": 0, \"kind\": \"tee\", \"x_m\": 0.0000, \"y_m\": 0.0000}, {\"id\": 1, \"kind\": "
            "\"corner\", \"x_m\": 0.5000, \"y_m\": 0.0000}, {\"id\": 2, \"kind\": \"tee\", \"x_m\": 0.7000, \"y_m\": "
            "0.0000}, {\"id\": 3, \"kind\": \"end\", \"x_m\": 0.0000, \"y_m\": 0.1000}], \"edges\": [{\"from\": 0, "
            "\"to\": 1, \"length_m\": 0.5000}, {\"from\": 1, \"to\": 2, \"length_m\": 0.2000}, {\"from\": 0, \"to\": "
            "3, \"length_m\": 0.1000}]}\n");
  map.nodes[2].ways[1].edge = ExploredTrackMap::kNoTape;  // struck off: nothing left
  EXPECT_FALSE(map.has_untaken_way());
}

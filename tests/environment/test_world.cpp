#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "core/worker_pool.hpp"
#include "environment/random.hpp"
#include "environment/world.hpp"
#include "world_fixtures.hpp"

using namespace rilbed;
using namespace rilbed::environment;
using namespace rilbed::environment::testing;

namespace {
constexpr double kR = kKheperaRadius_m;
constexpr TimeUs kTick = 100'000;

// Expects `f` to throw std::invalid_argument whose message contains `needle`.
template <class F>
void expect_invalid(F&& f, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected one mentioning '" << needle << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

// The lab's field with a non-convex obstacle, a box and a moving disc.
StaticMapConfig cluttered_field() {
  StaticMapConfig map = empty_field(1.5, 1.2);
  map.obstacles.push_back({{{0.3, 0.3}, {0.5, 0.3}, {0.5, 0.35}, {0.35, 0.35}, {0.35, 0.5}, {0.3, 0.5}}, "ell"});
  map.obstacles.push_back(rectangle(1.0, 0.7, 1.1, 0.9));
  return map;
}

// Places up to `count` virtual robots on free lattice points of the world.
// A disc-shaped moving obstacle starting at (0.75, 1.1) in cluttered_field(), drifting
// through the crowd at `velocity_mps`.
MovingObstacleConfig drifting_disc(double radius_m, Vec2 velocity_mps) {
  MovingObstacleConfig disc;
  disc.radius_m = radius_m;
  disc.position_m = {0.75, 1.1};
  disc.velocity_mps = velocity_mps;
  return disc;
}

void populate(World& world, int count, std::mt19937_64& rng, double spacing = 0.075) {
  const FieldConfig& f = world.map().field();
  int id = 0;
  for (double y = 0.04; y < f.height_m - 0.04 && id < count; y += spacing) {
    for (double x = 0.04; x < f.width_m - 0.04 && id < count; x += spacing) {
      RobotConfig c;
      c.id = id;
      c.pose = {{x, y}, 2 * kPi * uniform01(rng)};
      c.noise.slip_sd = 0.05;
      try {
        world.add_robot(c);
        ++id;
      } catch (const std::invalid_argument&) {
        // on an obstacle: skip this lattice point
      }
    }
  }
}

// Largest overlap among all robots and with walls and obstacles, by brute force.
double brute_force_overlap(const World& world) {
  double worst = 0.0;
  const auto robots = world.robots();
  const FieldConfig& f = world.map().field();
  for (std::size_t a = 0; a < robots.size(); ++a) {
    const Vec2 p = robots[a].pose.position_m;
    const double r = robots[a].radius_m;
    worst = std::max({worst, r - p.x, r - p.y, p.x + r - f.width_m, p.y + r - f.height_m});
    for (const ObstacleConfig& o : world.map().obstacles()) {
      worst = std::max(worst, r - distance_to_polygon(p, o.vertices_m));
      if (point_in_polygon(p, o.vertices_m)) worst = std::max(worst, r);
    }
    for (std::size_t b = a + 1; b < robots.size(); ++b)
      worst = std::max(worst, r + robots[b].radius_m - (robots[b].pose.position_m - p).norm());
    for (const MovingObstacle& m : world.moving_obstacles())
      worst = std::max(worst, r + m.bounding_radius_m() - (m.position_m() - p).norm());
  }
  return worst;
}
}  // namespace

TEST(WorldValidation, BadMapsAreRejectedNamingTheItem) {
  expect_invalid([] { World w(empty_field(-1, 1)); }, "field: width_m");
  expect_invalid([] { World w(empty_field(1, NAN)); }, "field: height_m");
  StaticMapConfig map = empty_field(1, 1);
  map.obstacles.push_back(rectangle(0.1, 0.1, 0.2, 0.2));
  map.obstacles.push_back({{{0.5, 0.5}, {0.6, NAN}, {0.6, 0.6}}, "pillar"});
  expect_invalid([&] { World w(map); }, "obstacle 1 (pillar): vertex 1 is not finite");
  map.obstacles[1] = {{{0, 0}, {2, 2}, {2, 0}, {0, 1}}, "bow"};
  expect_invalid([&] { World w(map); }, "obstacle 1 (bow): has crossing edges");
  map.obstacles[1] = {{{0, 0}, {1, 1}}, ""};
  expect_invalid([&] { World w(map); }, "obstacle 1: needs at least three");
  map.obstacles.pop_back();
  map.tracks.push_back({{{0, 0}, {1, 1}}, -0.01, false, ""});
  expect_invalid([&] { World w(map); }, "track 0: width_m");
  map.tracks.clear();
  map.beacons.push_back({3, {0.5, 0.5}, 0.0, 0.0, 1.0});
  expect_invalid([&] { World w(map); }, "beacon 0 (id 3): aperture_rad");
  map.beacons[0].aperture_rad = 1.0;
  map.beacons.push_back({3, {0.2, 0.5}, 0.0, 1.0, 1.0});
  expect_invalid([&] { World w(map); }, "beacon 1 (id 3): another beacon has the same id");
  // A repeated closing vertex is fine.
  StaticMapConfig closed = empty_field(1, 1);
  closed.obstacles.push_back({{{0.1, 0.1}, {0.2, 0.1}, {0.2, 0.2}, {0.1, 0.1}}, ""});
  const World ok(closed);
  EXPECT_EQ(ok.map().obstacles()[0].vertices_m.size(), 3u);
  WorldConfig bad;
  bad.collision.max_passes = 0;
  expect_invalid([&] { World w(empty_field(1, 1), bad); }, "max_passes");
}

TEST(WorldValidation, BadRobotsAreRejectedNamingTheRobot) {
  StaticMapConfig map = empty_field(1, 1);
  map.obstacles.push_back(rectangle(0.6, 0.6, 0.8, 0.8));
  World world(map);
  expect_invalid([&] { world.add_robot(quiet_robot(3, 0.01, 0.5, 0.0)); }, "robot 3: placed overlapping the left wall");
  expect_invalid([&] { world.add_robot(quiet_robot(3, 0.5, 0.99, 0.0)); }, "robot 3: placed overlapping the top wall");
  expect_invalid([&] { world.add_robot(quiet_robot(3, 0.7, 0.7, 0.0)); }, "robot 3: placed inside obstacle 0");
  expect_invalid([&] { world.add_robot(quiet_robot(3, 0.58, 0.7, 0.0)); }, "robot 3: placed overlapping obstacle 0");
  expect_invalid([&] { world.add_robot(quiet_robot(3, NAN, 0.5, 0.0)); }, "robot 3: pose is not finite");
  RobotConfig c = quiet_robot(3, 0.3, 0.3, 0.0);
  c.radius_m = 0.0;
  expect_invalid([&] { world.add_robot(c); }, "robot 3: radius_m");
  c = quiet_robot(3, 0.3, 0.3, 0.0);
  c.noise.slip_sd = -1;
  expect_invalid([&] { world.add_robot(c); }, "robot 3: noise.slip_sd");
  c = quiet_robot(3, 0.3, 0.3, 0.0);
  c.sensors.proximity->half_angle_rad = 2.0;
  expect_invalid([&] { world.add_robot(c); }, "robot 3: proximity: half_angle_rad");
  world.add_robot(quiet_robot(3, 0.3, 0.3, 0.0));
  expect_invalid([&] { world.add_robot(quiet_robot(3, 0.1, 0.1, 0.0)); }, "robot 3: another robot has this id");
  expect_invalid([&] { world.add_robot(quiet_robot(4, 0.33, 0.3, 0.0)); }, "robot 4: placed overlapping robot 3");
  expect_invalid([&] { world.robot(99); }, "no robot with id 99");
  expect_invalid(
      [&] {
        world.set_observed_pose(3, {{0.5, 0.5}, 0.0}, 0);
      },
      "robot 3: set_observed_pose is for real robots");
  expect_invalid([&] { world.step(-1); }, "dt_us");
  // A real robot may be seen anywhere, even overlapping a virtual one.
  RobotConfig real = quiet_robot(5, 0.32, 0.3, 0.0);
  real.kind = RobotKind::kReal;
  world.add_robot(real);
  expect_invalid(
      [&] {
        world.set_observed_pose(5, {{INFINITY, 0.5}, 0.0}, 0);
      },
      "robot 5: observed pose is not finite");
  EXPECT_EQ(world.robots().size(), 2u);
}

TEST(WorldValidation, BadMovingObstaclesAreRejected) {
  World world(empty_field(1, 1));
  MovingObstacleConfig m;
  m.radius_m = -1;
  expect_invalid([&] { world.add_moving_obstacle(m); }, "moving obstacle 0: radius_m");
  m.radius_m = 0.1;
  m.position_m = {0.05, 0.5};
  expect_invalid([&] { world.add_moving_obstacle(m); }, "moving obstacle 0: placed overlapping wall 3 (left)");
  MovingObstacleConfig ell;
  ell.shape = MovingShape::kPolygon;
  ell.position_m = {0.5, 0.5};
  ell.vertices_m = {{-0.1, -0.1}, {0.1, -0.1}, {0.1, 0.0}, {0.0, 0.0}, {0.0, 0.1}, {-0.1, 0.1}};
  expect_invalid([&] { world.add_moving_obstacle(ell); }, "must be convex");
  EXPECT_TRUE(world.moving_obstacles().empty());
}

TEST(World, AddRemoveAndLookUpRobots) {
  World world(empty_field(1, 1));
  world.add_robot(quiet_robot(10, 0.2, 0.2, 0.0));
  world.add_robot(quiet_robot(20, 0.4, 0.2, 7.0));  // heading wrapped
  world.add_robot(quiet_robot(30, 0.6, 0.2, 0.0));
  EXPECT_NEAR(world.robot(20).pose.heading_rad, 7.0 - 2 * kPi, 1e-12);
  world.remove_robot(10);
  EXPECT_FALSE(world.has_robot(10));
  ASSERT_EQ(world.robots().size(), 2u);
  EXPECT_EQ(world.robot(30).pose.position_m, (Vec2{0.6, 0.2}));
  EXPECT_EQ(world.robot(20).pose.position_m, (Vec2{0.4, 0.2}));
  // The freed place can be taken again, and the grid still sees the moved robot.
  world.add_robot(quiet_robot(10, 0.2, 0.2, 0.0));
  expect_invalid([&] { world.add_robot(quiet_robot(11, 0.62, 0.21, 0.0)); }, "overlapping robot 30");
  expect_invalid([&] { world.remove_robot(99); }, "no robot with id 99");
}

TEST(World, SnapshotCopiesTheMovingState) {
  World world(empty_field(1, 1));
  world.add_robot(quiet_robot(1, 0.95, 0.5, 0.0));
  world.set_wheel_speeds(1, 40, 40);  // 32 mm per tick: reaches the wall
  MovingObstacleConfig m;
  m.radius_m = 0.05;
  m.position_m = {0.2, 0.2};
  m.velocity_mps = {0.1, 0.0};
  world.add_moving_obstacle(m);
  world.step(kTick);
  const WorldSnapshot s = world.snapshot();
  EXPECT_EQ(s.t_us, kTick);
  ASSERT_EQ(s.robots.size(), 1u);
  EXPECT_EQ(s.robots[0].id, 1);
  EXPECT_EQ(s.robots[0].left_speed_units, 40);
  EXPECT_NEAR(s.robots[0].pose.position_m.x, 1.0 - kR, 1e-12);
  ASSERT_EQ(s.moving_obstacles.size(), 1u);
  EXPECT_NEAR(s.moving_obstacles[0].position_m.x, 0.21, 1e-12);
  ASSERT_EQ(s.collisions.size(), 1u);
  EXPECT_EQ(to_string(s.collisions[0].second), "wall 1 (right)");
}

TEST(World, SameSeedSameWorldDifferentSeedDifferentWorld) {
  auto run_world = [](std::uint64_t seed) {
    WorldConfig config;
    config.noise_seed = seed;
    World world(cluttered_field(), config);
    std::mt19937_64 rng(seed);
    populate(world, 60, rng);
    std::vector<SensorReadings> readings;
    std::vector<int> proximity_sums;
    for (int step = 0; step < 100; ++step) {
      if (step % 10 == 0)
        for (const RobotState& r : world.robots())
          world.set_wheel_speeds(r.id, static_cast<int>(uniform01(rng) * 120) - 40,
                                 static_cast<int>(uniform01(rng) * 120) - 40);
      world.step(kTick);
      world.sense_all(world.time_us(), readings);
      int sum = 0;
      for (const SensorReadings& s : readings)
        for (const int v : *s.proximity) sum += v;
      proximity_sums.push_back(sum);
    }
    std::vector<Pose2> poses;
    for (const RobotState& r : world.robots()) poses.push_back(r.pose);
    return std::pair{poses, proximity_sums};
  };
  const auto a = run_world(42), b = run_world(42), c = run_world(43);
  ASSERT_EQ(a.first.size(), b.first.size());
  for (std::size_t i = 0; i < a.first.size(); ++i) {
    EXPECT_EQ(a.first[i].position_m, b.first[i].position_m);
    EXPECT_EQ(a.first[i].heading_rad, b.first[i].heading_rad);
  }
  EXPECT_EQ(a.second, b.second);
  EXPECT_NE(a.second, c.second);
  bool any_different = false;
  for (std::size_t i = 0; i < std::min(a.first.size(), c.first.size()); ++i)
    any_different = any_different || !(a.first[i].position_m == c.first[i].position_m);
  EXPECT_TRUE(any_different);
}

TEST(World, SenseAllMatchesSenseOneByOne) {
  World world(cluttered_field());
  std::mt19937_64 rng(5);
  populate(world, 40, rng, 0.06);
  std::vector<SensorReadings> all;
  world.sense_all(123, all);
  ASSERT_EQ(all.size(), world.robots().size());
  for (std::size_t i = 0; i < all.size(); ++i) {
    const SensorReadings one = world.sense(world.robots()[i].id, 123);
    EXPECT_EQ(one.t_us, 123);
    EXPECT_EQ(*one.proximity, *all[i].proximity);
    EXPECT_EQ(one.odometry->left_pulses, all[i].odometry->left_pulses);
  }
}

TEST(World, RealRobotsGetVirtualSensorsButNoVirtualOdometry) {
  World world(empty_field(1, 1));
  RobotConfig real = quiet_robot(1, 0.5, 0.5, 0.0);
  real.kind = RobotKind::kReal;
  world.add_robot(real);
  world.set_observed_pose(1, {{1.0 - kR - 0.01, 0.5}, 0.0}, 5);
  EXPECT_EQ(world.robot(1).pose_t_us, 5);
  NoiseRng rng(1);
  const SensorReadings s = world.sense(1, 5, rng);
  EXPECT_GT((*s.proximity)[2], 400);  // the virtual wall, 10 mm ahead
  EXPECT_FALSE(s.odometry.has_value());
  // Stepping leaves a real robot where it was seen, whatever its wheel commands.
  world.set_wheel_speeds(1, 100, 100);
  world.step(kTick);
  EXPECT_EQ(world.robot(1).pose.position_m, (Vec2{1.0 - kR - 0.01, 0.5}));
}

TEST(World, LongRandomRunOf200RobotsNeverOverlaps) {
  World world(cluttered_field());
  const MovingObstacleConfig disc = drifting_disc(0.06, {0.23, -0.17});
  std::mt19937_64 rng(2024);
  world.add_moving_obstacle(disc);
  populate(world, 200, rng);
  ASSERT_EQ(world.robots().size(), 200u);
  std::vector<SensorReadings> readings;
  double worst = 0.0;
  int collisions = 0;
  for (int step = 0; step < 600; ++step) {
    if (step % 5 == 0) {
      for (const RobotState& r : world.robots()) {
        // Mostly forward and fast, so that they crowd and shove.
        const int base = static_cast<int>(uniform01(rng) * 160) - 30;
        world.set_wheel_speeds(r.id, base + static_cast<int>(uniform01(rng) * 40) - 20,
                               base + static_cast<int>(uniform01(rng) * 40) - 20);
      }
    }
    collisions += static_cast<int>(world.step(kTick).size());
    world.sense_all(world.time_us(), readings);
    const double overlap = brute_force_overlap(world);
    worst = std::max(worst, overlap);
    ASSERT_LE(overlap, 1e-6) << "at step " << step;
    ASSERT_NEAR(world.max_overlap_m(), std::max(0.0, overlap), 1e-12) << "the grid-based check disagrees";
  }
  EXPECT_GT(collisions, 200) << "the run should be crowded enough to collide a lot";
  RecordProperty("worst_overlap_m", std::to_string(worst));
}

// Gives the same random wheel commands to the robots of two worlds stepped side by side:
// mostly forward and fast (a base speed in [-back, span - back), each wheel +-20), so that
// they crowd and shove.
void command_both(World& a, World& b, std::mt19937_64& commands, int span, int back) {
  for (const RobotState& r : a.robots()) {
    const int base = static_cast<int>(uniform01(commands) * span) - back;
    const int left = base + static_cast<int>(uniform01(commands) * 40) - 20;
    const int right = base + static_cast<int>(uniform01(commands) * 40) - 20;
    a.set_wheel_speeds(r.id, left, right);
    b.set_wheel_speeds(r.id, left, right);
  }
}

// --threads: a crowded world stepped with its robots' motion and contact search spread
// over worker threads moves exactly as on one thread, contacts and readings included.
TEST(World, ThreadsChangeNothing) {
  WorldConfig config;
  config.noise_seed = 77;
  World one(cluttered_field(), config), three(cluttered_field(), config);
  core::WorkerPool pool(3);
  three.set_workers(&pool);
  std::mt19937_64 rng_one(31), rng_three(31);
  populate(one, 200, rng_one);
  populate(three, 200, rng_three);
  const MovingObstacleConfig disc = drifting_disc(0.06, {0.23, -0.17});
  one.add_moving_obstacle(disc);
  three.add_moving_obstacle(disc);
  std::mt19937_64 commands(5);
  std::vector<SensorReadings> readings_one, readings_three;
  int events = 0;
  for (int step = 0; step < 300; ++step) {
    if (step % 5 == 0) command_both(one, three, commands, 160, 30);
    const auto e1 = one.step(kTick);
    const std::vector<CollisionEvent> events_one(e1.begin(), e1.end());
    const auto e3 = three.step(kTick);
    ASSERT_EQ(events_one.size(), e3.size()) << "at step " << step;
    for (std::size_t k = 0; k < e3.size(); ++k) {
      ASSERT_EQ(to_string(events_one[k].first), to_string(e3[k].first));
      ASSERT_EQ(to_string(events_one[k].second), to_string(e3[k].second));
      ASSERT_EQ(events_one[k].t_us, e3[k].t_us);
    }
    events += static_cast<int>(e3.size());
    for (std::size_t i = 0; i < one.robots().size(); ++i) {
      ASSERT_EQ(one.robots()[i].pose.position_m, three.robots()[i].pose.position_m)
          << "robot " << i << " at step " << step;
      ASSERT_EQ(one.robots()[i].pose.heading_rad, three.robots()[i].pose.heading_rad);
    }
    one.sense_all(one.time_us(), readings_one);
    three.sense_all(three.time_us(), readings_three);
    for (std::size_t i = 0; i < readings_one.size(); ++i)
      ASSERT_EQ(*readings_one[i].proximity, *readings_three[i].proximity);
  }
  EXPECT_GT(events, 100) << "crowded enough to collide";
}

// Each robot's noise comes from its own stream: what it reads does not depend on who
// read before it, and reading again at the same instant gives the same values.
TEST(World, ARobotsNoiseDoesNotDependOnWhoSensedFirst) {
  WorldConfig config;
  config.noise_seed = 3;
  World world(cluttered_field(), config);
  std::mt19937_64 rng(8);
  populate(world, 30, rng, 0.06);
  const SensorReadings first = world.sense(7, 500'000);
  for (const RobotState& r : world.robots()) world.sense(r.id, 500'000);
  EXPECT_EQ(*world.sense(7, 500'000).proximity, *first.proximity);
  // Another instant draws other noise.
  bool differs = false;
  for (int k = 1; k < 20 && !differs; ++k) differs = *world.sense(7, 500'000 + k).proximity != *first.proximity;
  EXPECT_TRUE(differs);
}

// The sensor sweep (sense_ahead) stores the readings that sense() would compute, and a
// change to the world makes sense() compute afresh.
TEST(World, TheSensorSweepGivesTheReadingsOfOneByOne) {
  for (const int threads : {1, 3}) {
    WorldConfig config;
    config.noise_seed = 12;
    config.reorder_every_steps = 3;
    World world(cluttered_field(), config);
    core::WorkerPool pool(threads);
    world.set_workers(&pool);
    std::mt19937_64 rng(4);
    populate(world, 150, rng, 0.06);
    for (const RobotState& r : world.robots()) world.set_wheel_speeds(r.id, 60, 50);
    std::vector<SensorReadings> fresh;
    for (int step = 0; step < 8; ++step) {
      world.step(kTick);
      const TimeUs t = world.time_us();
      world.sense_all(t, fresh);  // computed robot by robot, never from the store
      world.sense_ahead(t);
      for (std::size_t i = 0; i < fresh.size(); ++i) {
        const SensorReadings stored = world.sense(world.robots()[i].id, t);
        ASSERT_EQ(*stored.proximity, *fresh[i].proximity) << "robot " << world.robots()[i].id << " at step " << step;
        ASSERT_EQ(stored.odometry->left_pulses, fresh[i].odometry->left_pulses);
        ASSERT_EQ(stored.t_us, t);
      }
      // Another instant is computed, not taken from the store.
      EXPECT_EQ(world.sense(world.robots()[0].id, t + 1).t_us, t + 1);
    }
    // A robot moved by hand (a real robot's observed pose) is read where it now is.
    RobotConfig real = quiet_robot(9999, 0.3, 0.3, 0.0);
    real.kind = RobotKind::kReal;
    world.add_robot(real);
    world.sense_ahead(world.time_us());
    world.set_observed_pose(9999, {{1.2, 0.2}, 1.0}, world.time_us());
    world.sense_all(world.time_us(), fresh);
    const SensorReadings after = world.sense(9999, world.time_us());
    EXPECT_EQ(*after.proximity, *fresh.back().proximity);
  }
}

namespace {
// Every field of two readings, lists included.
void expect_same_readings(const SensorReadings& a, const SensorReadings& b, const std::string& where) {
  EXPECT_EQ(a.t_us, b.t_us) << where;
  EXPECT_EQ(a.proximity, b.proximity) << where;
  ASSERT_EQ(a.odometry.has_value(), b.odometry.has_value()) << where;
  if (a.odometry) {
    EXPECT_EQ(a.odometry->left_pulses, b.odometry->left_pulses) << where;
    EXPECT_EQ(a.odometry->right_pulses, b.odometry->right_pulses) << where;
  }
  ASSERT_EQ(a.ranges.size(), b.ranges.size()) << where;
  for (std::size_t k = 0; k < a.ranges.size(); ++k) {
    EXPECT_EQ(a.ranges[k].hit, b.ranges[k].hit) << where;
    EXPECT_EQ(a.ranges[k].distance_m, b.ranges[k].distance_m) << where;
  }
  ASSERT_EQ(a.beacons.size(), b.beacons.size()) << where;
  for (std::size_t k = 0; k < a.beacons.size(); ++k) {
    EXPECT_EQ(a.beacons[k].id, b.beacons[k].id) << where;
    EXPECT_EQ(a.beacons[k].bearing_rad, b.beacons[k].bearing_rad) << where;
  }
  EXPECT_EQ(a.track, b.track) << where;
}
}  // namespace

// The sweep's store keeps every kind of reading: robots without an IR ring or odometer,
// with range finders, a beacon finder or track sensors, among plain Kheperas, read from
// the store exactly what they read one by one (the store packs the IR ring and odometry
// and keeps the lists apart).
TEST(World, TheSensorSweepKeepsEveryKindOfReading) {
  StaticMapConfig map = cluttered_field();
  map.beacons.push_back({4, {0.2, 1.0}, 0.0, 2.0 * kPi, 1.5});
  map.beacons.push_back({6, {1.3, 0.2}, 0.0, 2.0 * kPi, 1.5});
  map.tracks.push_back({{{0.1, 0.6}, {1.4, 0.6}}, 0.03, false, "tape"});
  for (const int threads : {1, 2}) {
    WorldConfig config;
    config.noise_seed = 31;
    World world(map, config);
    core::WorkerPool pool(threads);
    world.set_workers(&pool);
    std::mt19937_64 rng(8);
    int id = 0;
    for (double y = 0.1; y < 1.1; y += 0.12) {
      for (double x = 0.1; x < 1.4; x += 0.12) {
        RobotConfig c;
        c.id = id;
        c.pose = {{x, y}, 2 * kPi * uniform01(rng)};
        switch (id % 5) {
          case 1:  // one ahead, one behind
            c.sensors.range_finders.push_back({});
            c.sensors.range_finders.push_back({});
            c.sensors.range_finders[1].mount_angle_rad = kPi;
            break;
          case 2: c.sensors.beacon_finder = BeaconFinderConfig{}; break;
          case 3: c.sensors.track_sensors.push_back({}); break;
          case 4: c.sensors.proximity.reset(), c.sensors.odometer = false; break;
          default: break;
        }
        try {
          world.add_robot(c);
          EXPECT_EQ(world.sensor_config(c.id), c.sensors);
          ++id;
        } catch (const std::invalid_argument&) {}
      }
    }
    ASSERT_GT(id, 40);
    for (const RobotState& r : world.robots()) world.set_wheel_speeds(r.id, 40, 30);
    std::vector<SensorReadings> fresh;
    int beacons_seen = 0, track_seen = 0, ranges_hit = 0;
    for (int step = 0; step < 6; ++step) {
      world.step(kTick);
      const TimeUs t = world.time_us();
      world.sense_all(t, fresh);
      world.sense_ahead(t);
      for (std::size_t i = 0; i < fresh.size(); ++i) {
        const int robot = world.robots()[i].id;
        const SensorReadings stored = world.sense(robot, t);
        expect_same_readings(stored, fresh[i], "robot " + std::to_string(robot) + " at step " + std::to_string(step));
        beacons_seen += static_cast<int>(stored.beacons.size());
        for (const int v : stored.track) track_seen += v > 0;
        for (const RangeReading& range : stored.ranges) ranges_hit += range.hit;
      }
    }
    // The lists were there to keep (else the test would prove little).
    EXPECT_GT(beacons_seen, 0);
    EXPECT_GT(track_seen, 0);
    EXPECT_GT(ranges_hit, 0);
  }
}

// The collision resolver's first pass visits only robots found near something (or near
// a robot pushed in the pass): the same as visiting them all, in a crowd that shoves.
TEST(World, SearchingContactsAheadChangesNoCollision) {
  for (const std::uint64_t seed : {3ULL, 17ULL, 2026ULL}) {
    WorldConfig ahead, every;
    ahead.noise_seed = every.noise_seed = seed;
    every.collision.search_ahead = false;
    World a(cluttered_field(), ahead), b(cluttered_field(), every);
    std::mt19937_64 ra(seed), rb(seed);
    populate(a, 220, ra, 0.065);
    populate(b, 220, rb, 0.065);
    const MovingObstacleConfig disc = drifting_disc(0.07, {0.25, -0.2});
    a.add_moving_obstacle(disc);
    b.add_moving_obstacle(disc);
    std::mt19937_64 commands(seed + 1);
    int events = 0;
    for (int step = 0; step < 200; ++step) {
      if (step % 4 == 0) command_both(a, b, commands, 180, 40);
      const auto ea = a.step(kTick);
      const std::vector<CollisionEvent> events_a(ea.begin(), ea.end());
      const auto eb = b.step(kTick);
      ASSERT_EQ(events_a.size(), eb.size()) << "seed " << seed << " step " << step;
      for (std::size_t k = 0; k < eb.size(); ++k)
        ASSERT_TRUE(events_a[k] == eb[k]) << "seed " << seed << " step " << step;
      events += static_cast<int>(eb.size());
      for (std::size_t i = 0; i < a.robots().size(); ++i)
        ASSERT_EQ(a.robots()[i].pose.position_m, b.robots()[i].pose.position_m) << "seed " << seed << " step " << step;
    }
    EXPECT_GT(events, 150) << "seed " << seed << ": crowded enough to shove";
  }
}

// The world renumbers its slots by place as robots move (WorldConfig::reorder_every_steps):
// a crowd that shoves moves, collides and senses exactly alike however often that
// happens, and whatever the grid's cell size, compared robot by robot through their ids
// (the slots differ).
TEST(World, NeitherRenumberingTheSlotsNorTheCellSizeChangesAnything) {
  struct Setting {
    int reorder_every_steps;
    double cell_size_m;  // 0: the default
  };
  for (const std::uint64_t seed : {11ULL, 4242ULL}) {
    std::vector<std::unique_ptr<World>> worlds;
    for (const Setting setting :
         {Setting{1, 0.0}, Setting{0, 0.0}, Setting{7, 0.0}, Setting{20, 0.1}, Setting{20, 0.45}}) {
      WorldConfig config;
      config.noise_seed = seed;
      config.reorder_every_steps = setting.reorder_every_steps;
      config.cell_size_m = setting.cell_size_m;
      worlds.push_back(std::make_unique<World>(cluttered_field(), config));
      std::mt19937_64 placement(seed);
      populate(*worlds.back(), 220, placement, 0.065);
      const MovingObstacleConfig disc = drifting_disc(0.07, {0.25, -0.2});
      worlds.back()->add_moving_obstacle(disc);
    }
    const std::vector<int> ids(worlds[0]->ids_in_added_order().begin(), worlds[0]->ids_in_added_order().end());
    std::mt19937_64 commands(seed + 1);
    int events = 0;
    bool slots_differed = false;
    for (int step = 0; step < 200; ++step) {
      if (step % 4 == 0) {
        for (const int id : ids) {
          const int base = static_cast<int>(uniform01(commands) * 180) - 40;
          const int left = base + static_cast<int>(uniform01(commands) * 40) - 20;
          const int right = base + static_cast<int>(uniform01(commands) * 40) - 20;
          for (auto& w : worlds) w->set_wheel_speeds(id, left, right);
        }
      }
      std::vector<std::vector<CollisionEvent>> stepped;
      for (auto& w : worlds) {
        const auto e = w->step(kTick);
        stepped.emplace_back(e.begin(), e.end());
        w->sense_ahead(w->time_us());
      }
      for (std::size_t k = 1; k < worlds.size(); ++k) {
        ASSERT_EQ(stepped[0].size(), stepped[k].size()) << "seed " << seed << " step " << step;
        for (std::size_t e = 0; e < stepped[0].size(); ++e)
          ASSERT_TRUE(stepped[0][e] == stepped[k][e]) << "world " << k << " step " << step << " event " << e;
        for (std::size_t i = 0; i < ids.size(); ++i)
          slots_differed |= worlds[0]->robots()[i].id != worlds[k]->robots()[i].id;
        for (const int id : ids) {
          ASSERT_EQ(worlds[0]->robot(id).pose.position_m, worlds[k]->robot(id).pose.position_m)
              << "seed " << seed << " step " << step << " robot " << id;
          ASSERT_EQ(worlds[0]->robot(id).pose.heading_rad, worlds[k]->robot(id).pose.heading_rad);
          ASSERT_EQ(worlds[k]->pose(id).position_m, worlds[k]->robot(id).pose.position_m);
          ASSERT_EQ(*worlds[0]->sense(id, worlds[0]->time_us()).proximity,
                    *worlds[k]->sense(id, worlds[k]->time_us()).proximity);
        }
      }
      events += static_cast<int>(stepped[0].size());
    }
    EXPECT_TRUE(slots_differed) << "the renumbering periods should give different slots";
    EXPECT_GT(events, 150) << "seed " << seed << ": crowded enough to shove";
  }
}

// Renumbering by place moves robots between slots; lookups by id, the added order, the
// snapshot's order, the stored readings and removal all follow.
TEST(World, RobotsKeepTheirIdsPosesAndAddedOrderWhileTheirSlotsMove) {
  World world(empty_field(2, 2));
  // Added right to left and top to bottom, so that the order by place (grid cells by
  // rows) differs from the added one.
  for (int id = 1; id <= 6; ++id) world.add_robot(quiet_robot(id, 1.9 - 0.3 * id, 1.8 - 0.25 * id, 0.1 * id));
  world.set_wheel_speeds(4, 20, 30);
  world.set_wheel_speeds(6, -15, 25);
  world.step(kTick);
  const std::vector<int> added(world.ids_in_added_order().begin(), world.ids_in_added_order().end());
  EXPECT_EQ(added, (std::vector<int>{1, 2, 3, 4, 5, 6}));
  bool renumbered = false;
  for (std::size_t s = 0; s < world.robots().size(); ++s) renumbered |= world.robots()[s].id != static_cast<int>(s) + 1;
  EXPECT_TRUE(renumbered) << "slots should follow the place, not the order of adding";
  const WorldSnapshot snap = world.snapshot();
  for (std::size_t k = 0; k < snap.robots.size(); ++k) {
    EXPECT_EQ(snap.robots[k].id, static_cast<int>(k) + 1);
    EXPECT_EQ(snap.robots[k].pose.position_m, world.robot(snap.robots[k].id).pose.position_m);
  }
  EXPECT_EQ(snap.robots[3].left_speed_units, 20);
  EXPECT_NE(world.pose(4).position_m, (Vec2{1.9 - 1.2, 1.8 - 1.0}));  // it drove
  world.sense_ahead(world.time_us());
  for (int id = 1; id <= 6; ++id) {
    EXPECT_EQ(world.pose(id).position_m, world.robot(id).pose.position_m);
    EXPECT_EQ(world.sense(id, world.time_us()).odometry.has_value(), true);
  }
  world.remove_robot(2);
  const std::vector<int> after(world.ids_in_added_order().begin(), world.ids_in_added_order().end());
  EXPECT_EQ(after, (std::vector<int>{1, 6, 3, 4, 5}));  // the last added takes the gap
  for (const int id : after) EXPECT_EQ(world.pose(id).position_m, world.robot(id).pose.position_m);
  world.step(kTick);
  world.sense_ahead(world.time_us());
  for (const int id : after) {
    EXPECT_EQ(world.pose(id).position_m, world.robot(id).pose.position_m);
    EXPECT_EQ(world.sense(id, world.time_us()).odometry->left_pulses, world.robot(id).odometer().left_pulses);
  }
  EXPECT_FALSE(world.has_robot(2));
  // The wheel commands stay with their robots (robot 6 took robot 2's place in the order).
  EXPECT_EQ(world.wheel_speeds(4), (WheelUnits{20, 30}));
  EXPECT_EQ(world.wheel_speeds(6), (WheelUnits{-15, 25}));
  EXPECT_EQ(world.wheel_speeds(1), (WheelUnits{0, 0}));
  EXPECT_EQ(world.snapshot().robots[1].right_speed_units, 25);
  EXPECT_THROW(world.wheel_speeds(2), std::invalid_argument);
  EXPECT_THROW(world.set_wheel_speeds(2, 1, 1), std::invalid_argument);
}

// A step turns each robot's sensing direction by rotating it, not by recomputing it from
// the heading: after hours of turning in every way, a robot still senses as one placed
// afresh at its pose (same readings, to the unit).
TEST(World, ARobotThatTurnedForHoursSensesAsOnePlacedAtItsPose) {
  World turning(empty_field(0.5, 0.5));
  turning.add_robot(quiet_robot(1, 0.25, 0.25, 0.3));
  turning.add_robot(quiet_robot(2, 0.25, 0.33, -1.0));  // a neighbour in view
  std::mt19937_64 rng(19);
  for (int step = 0; step < 40'000; ++step) {
    if (step % 10 == 0) {
      const int turn = static_cast<int>(uniform01(rng) * 60) - 30;
      turning.set_wheel_speeds(1, -turn, turn);  // on the spot, either way
    }
    turning.step(kTick);
  }
  const Pose2 end = turning.robot(1).pose;
  EXPECT_NEAR(end.position_m.x, 0.25, 1e-9);
  World fresh(empty_field(0.5, 0.5));
  fresh.add_robot(quiet_robot(1, end.position_m.x, end.position_m.y, end.heading_rad));
  fresh.add_robot(quiet_robot(2, 0.25, 0.33, -1.0));
  const SensorReadings seen = turning.sense(1, turning.time_us());
  const SensorReadings placed = fresh.sense(1, fresh.time_us());
  EXPECT_EQ(*seen.proximity, *placed.proximity);
  int lit = 0;
  for (const int v : *seen.proximity) lit += v > 0 ? 1 : 0;
  EXPECT_GT(lit, 0) << "the neighbour should be in view of some sensor";
}

// Ids far beyond the robot count live in the world's hash map, small ones in its dense
// table: both are found after renumbering moves every slot, and after removals.
TEST(World, SmallAndHugeIdsAreFoundWhileSlotsMove) {
  WorldConfig config;
  config.reorder_every_steps = 1;
  World world(empty_field(3, 3), config);
  const std::vector<int> ids = {3, 2'000'000'000, 7, 123'456'789, 1, 50'000};
  for (std::size_t k = 0; k < ids.size(); ++k)
    world.add_robot(quiet_robot(ids[k], 2.8 - 0.45 * static_cast<double>(k), 0.3 + 0.4 * static_cast<double>(k), 0.0));
  for (const int id : ids) world.set_wheel_speeds(id, 30 + id % 7, 30);
  auto check = [&](const std::vector<int>& present) {
    for (const int id : present) {
      ASSERT_TRUE(world.has_robot(id)) << id;
      EXPECT_EQ(world.robot(id).id, id);
      EXPECT_EQ(world.pose(id).position_m, world.robot(id).pose.position_m) << id;
      EXPECT_EQ(world.wheel_speeds(id).left, 30 + id % 7) << id;
    }
  };
  for (int step = 0; step < 5; ++step) {
    world.step(kTick);
    check(ids);
  }
  world.remove_robot(7);
  world.remove_robot(2'000'000'000);
  const std::vector<int> left = {3, 123'456'789, 1, 50'000};
  for (int step = 0; step < 5; ++step) {
    world.step(kTick);
    check(left);
  }
  EXPECT_FALSE(world.has_robot(7));
  EXPECT_FALSE(world.has_robot(2'000'000'000));
  EXPECT_THROW(world.robot(2'000'000'000), std::invalid_argument);
  world.add_robot(quiet_robot(2'000'000'000, 1.5, 2.8, 0.0));  // the id may come back
  world.set_wheel_speeds(2'000'000'000, 30 + 2'000'000'000 % 7, 30);
  world.step(kTick);
  check({3, 123'456'789, 1, 50'000, 2'000'000'000});
}

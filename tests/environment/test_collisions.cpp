#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "environment/random.hpp"
#include "environment/world.hpp"
#include "world_fixtures.hpp"

using namespace rilbed;
using namespace rilbed::environment;
using namespace rilbed::environment::testing;

namespace {
constexpr double kR = kKheperaRadius_m;
constexpr TimeUs kTick = 100'000;
}  // namespace

TEST(Collisions, RobotDrivingIntoAWallStopsFlushAtItsRadius) {
  World world(empty_field(1, 1));
  world.add_robot(quiet_robot(1, 0.5, 0.5, 0.0));
  world.set_wheel_speeds(1, 127, 127);  // 1.016 m/s: reaches the wall in well under a second
  int wall_events = 0;
  for (int i = 0; i < 20; ++i) {
    for (const CollisionEvent& e : world.step(kTick)) {
      EXPECT_EQ(e.first, (BodyRef{BodyKind::kRobot, 1}));
      EXPECT_EQ(e.second, (BodyRef{BodyKind::kWall, kWallRight}));
      ++wall_events;
    }
  }
  EXPECT_NEAR(world.robot(1).pose.position_m.x, 1.0 - kR, 1e-12);
  EXPECT_NEAR(world.robot(1).pose.position_m.y, 0.5, 1e-12);
  EXPECT_EQ(wall_events, 1) << "one contact episode, however long the robot pushes";
}

TEST(Collisions, EpisodesEndWhenTheRobotBacksOff) {
  World world(empty_field(1, 1));
  world.add_robot(quiet_robot(1, 0.9, 0.5, 0.0));
  auto events_over = [&](int steps) {
    int n = 0;
    for (int i = 0; i < steps; ++i) n += static_cast<int>(world.step(kTick).size());
    return n;
  };
  world.set_wheel_speeds(1, 50, 50);
  EXPECT_EQ(events_over(10), 1);
  world.set_wheel_speeds(1, -50, -50);
  EXPECT_EQ(events_over(3), 0);
  world.set_wheel_speeds(1, 50, 50);
  EXPECT_EQ(events_over(10), 1);
}

TEST(Collisions, HeadOnRobotsSeparateToExactlyTouching) {
  World world(empty_field(1, 1));
  world.add_robot(quiet_robot(1, 0.3, 0.5, 0.0));
  world.add_robot(quiet_robot(2, 0.7, 0.5, kPi));
  world.set_wheel_speeds(1, 50, 50);
  world.set_wheel_speeds(2, 50, 50);
  std::vector<CollisionEvent> events;
  for (int i = 0; i < 20; ++i)
    for (const CollisionEvent& e : world.step(kTick)) events.push_back(e);
  const Vec2 a = world.robot(1).pose.position_m, b = world.robot(2).pose.position_m;
  EXPECT_NEAR((b - a).norm(), 2 * kR, 1e-9);
  EXPECT_NEAR(a.x, 0.5 - kR, 1e-9);
  EXPECT_NEAR(b.x, 0.5 + kR, 1e-9);
  EXPECT_NEAR(a.y, 0.5, 1e-12);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].first, (BodyRef{BodyKind::kRobot, 1}));
  EXPECT_EQ(events[0].second, (BodyRef{BodyKind::kRobot, 2}));
  // They meet after (0.4 - 2R) / (2 * 0.4 m/s) = 0.43125 s, in the step ending at 0.5 s.
  EXPECT_GT(events[0].t_us, 400'000);
  EXPECT_LE(events[0].t_us, 500'000);
}

TEST(Collisions, RobotAgainstAPolygonCorner) {
  StaticMapConfig map = empty_field(1, 1);
  map.obstacles.push_back(rectangle(0.6, 0.6, 0.8, 0.8));
  World world(map);
  // Aimed straight at the corner (0.6, 0.6) along the diagonal: it stops on the
  // diagonal with its rim on the corner.
  world.add_robot(quiet_robot(1, 0.4, 0.4, kPi / 4));
  world.set_wheel_speeds(1, 40, 40);
  bool saw_event = false;
  for (int i = 0; i < 15; ++i) {
    for (const CollisionEvent& e : world.step(kTick)) {
      EXPECT_EQ(e.second, (BodyRef{BodyKind::kObstacle, 0}));
      saw_event = true;
    }
    EXPECT_GE((world.robot(1).pose.position_m - Vec2{0.6, 0.6}).norm(), kR - 1e-9);
  }
  EXPECT_TRUE(saw_event);
  const Vec2 p = world.robot(1).pose.position_m;
  EXPECT_NEAR((p - Vec2{0.6, 0.6}).norm(), kR, 1e-9);
  EXPECT_NEAR(p.x, 0.6 - kR / std::sqrt(2.0), 1e-6);
  EXPECT_NEAR(p.y, 0.6 - kR / std::sqrt(2.0), 1e-6);
}

TEST(Collisions, RobotGlancingOffACornerSlidesAlongTheEdge) {
  StaticMapConfig map = empty_field(1, 1);
  map.obstacles.push_back(rectangle(0.6, 0.6, 0.8, 0.8));
  World world(map);
  // Heading +x at y = 0.59: its disc clips the obstacle's bottom-left corner, then its
  // flank slides along the bottom edge (y = 0.6) until it passes the far corner.
  world.add_robot(quiet_robot(1, 0.4, 0.59, 0.0));
  world.set_wheel_speeds(1, 30, 30);
  for (int i = 0; i < 30; ++i) {
    world.step(kTick);
    EXPECT_LE(world.max_overlap_m(), 1e-9);
    EXPECT_GE(distance_to_polygon(world.robot(1).pose.position_m, map.obstacles[0].vertices_m), kR - 1e-9);
  }
  EXPECT_NEAR(world.robot(1).pose.position_m.y, 0.6 - kR, 1e-9);
  EXPECT_GT(world.robot(1).pose.position_m.x, 0.8);
}

TEST(Collisions, FastRobotDoesNotTunnelThroughAThinWall) {
  StaticMapConfig map = empty_field(2, 1);
  map.obstacles.push_back(rectangle(1.0, 0.2, 1.001, 0.8));  // 1 mm thick
  WorldConfig config;
  config.max_substep_travel_m = 1.0;  // one substep per step: the centre jumps 0.1 m
  World world(map, config);
  world.add_robot(quiet_robot(1, 0.5, 0.5, 0.0));
  world.set_wheel_speeds(1, 127, 127);
  run(world, 20, kTick);
  EXPECT_NEAR(world.robot(1).pose.position_m.x, 1.0 - kR, 1e-12);
}

TEST(Collisions, RealRobotIsNeverPushed) {
  World world(empty_field(1, 1));
  RobotConfig real = quiet_robot(7, 0.5, 0.5, 0.0);
  real.kind = RobotKind::kReal;
  world.add_robot(real);
  world.add_robot(quiet_robot(1, 0.3, 0.5, 0.0));
  world.set_wheel_speeds(1, 60, 60);
  int events = 0;
  for (int i = 0; i < 10; ++i) events += static_cast<int>(world.step(kTick).size());
  EXPECT_EQ(world.robot(7).pose.position_m, (Vec2{0.5, 0.5}));
  EXPECT_NEAR(world.robot(1).pose.position_m.x, 0.5 - 2 * kR, 1e-12);
  EXPECT_EQ(events, 1);

  // The camera then sees the real robot move onto the virtual one: the virtual one
  // makes way, the real one stays where it was seen.
  world.set_wheel_speeds(1, 0, 0);
  world.set_observed_pose(7, {{0.5 - 2 * kR - 0.01, 0.5}, 0.0}, world.time_us());
  world.step(kTick);
  EXPECT_EQ(world.robot(7).pose.position_m, (Vec2{0.5 - 2 * kR - 0.01, 0.5}));
  EXPECT_NEAR((world.robot(1).pose.position_m - world.robot(7).pose.position_m).norm(), 2 * kR, 1e-9);
  EXPECT_LE(world.max_overlap_m(), 1e-9);
}

TEST(Collisions, MovingDiscBouncesOffAWall) {
  World world(empty_field(1, 1));
  MovingObstacleConfig disc;
  disc.radius_m = 0.1;
  disc.position_m = {0.5, 0.5};
  disc.velocity_mps = {1.0, 0.0};
  EXPECT_EQ(world.add_moving_obstacle(disc), 0);
  std::vector<CollisionEvent> events;
  for (int i = 0; i < 10; ++i)
    for (const CollisionEvent& e : world.step(kTick)) events.push_back(e);
  // Touches the right wall at x = 0.9 after 0.4 s, comes back 0.6 m: x = 0.3.
  const MovingObstacle& m = world.moving_obstacles()[0];
  EXPECT_NEAR(m.position_m().x, 0.3, 1e-12);
  EXPECT_NEAR(m.position_m().y, 0.5, 1e-12);
  EXPECT_NEAR(m.velocity_mps().x, -1.0, 1e-12);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].first, (BodyRef{BodyKind::kMovingObstacle, 0}));
  EXPECT_EQ(events[0].second, (BodyRef{BodyKind::kWall, kWallRight}));
}

TEST(Collisions, MovingPolygonBouncesOffAnObstacleAtAnAngle) {
  StaticMapConfig map = empty_field(2, 2);
  map.obstacles.push_back(rectangle(1.5, 0.0, 2.0, 2.0));  // a block along the right side
  World world(map);
  MovingObstacleConfig box;
  box.shape = MovingShape::kPolygon;
  box.vertices_m = {{-0.05, -0.05}, {0.05, -0.05}, {0.05, 0.05}, {-0.05, 0.05}};
  box.position_m = {1.0, 0.5};
  box.velocity_mps = {0.5, 0.5};
  world.add_moving_obstacle(box);
  run(world, 15, kTick);  // reaches x = 1.45 after 0.9 s, then 0.6 s back
  const MovingObstacle& m = world.moving_obstacles()[0];
  EXPECT_NEAR(m.velocity_mps().x, -0.5, 1e-12);
  EXPECT_NEAR(m.velocity_mps().y, 0.5, 1e-12);
  EXPECT_NEAR(m.position_m().x, 1.45 - 0.3, 1e-9);
  EXPECT_NEAR(m.position_m().y, 0.5 + 0.75, 1e-9);
}

TEST(Collisions, MovingObstaclePushesVirtualRobotsAndBouncesOffRealOnes) {
  World world(empty_field(2, 1));
  world.add_robot(quiet_robot(1, 1.0, 0.5, kPi / 2));
  MovingObstacleConfig disc;
  disc.radius_m = 0.05;
  disc.position_m = {0.5, 0.5};
  disc.velocity_mps = {0.2, 0.0};
  world.add_moving_obstacle(disc);
  run(world, 30, kTick);  // the disc would reach x = 1.1: it shoves the robot along
  const double disc_x = world.moving_obstacles()[0].position_m().x;
  EXPECT_NEAR(disc_x, 1.1, 1e-9);
  EXPECT_NEAR(world.robot(1).pose.position_m.x, disc_x + 0.05 + kR, 1e-9);
  EXPECT_LE(world.max_overlap_m(), 1e-9);

  World with_real(empty_field(2, 1));
  RobotConfig real = quiet_robot(2, 1.0, 0.5, 0.0);
  real.kind = RobotKind::kReal;
  with_real.add_robot(real);
  with_real.add_moving_obstacle(disc);
  run(with_real, 30, kTick);
  EXPECT_EQ(with_real.robot(2).pose.position_m, (Vec2{1.0, 0.5}));
  EXPECT_NEAR(with_real.moving_obstacles()[0].velocity_mps().x, -0.2, 1e-12);
  EXPECT_LE(with_real.moving_obstacles()[0].position_m().x, 1.0 - 0.05 - kR + 1e-9);
}

namespace {
void crowd_into_corner(const WorldConfig& config) {
  World world(empty_field(0.6, 0.6), config);
  int id = 0;
  for (int row = 0; row < 7; ++row)
    for (int col = 0; col < 7; ++col) {
      world.add_robot(quiet_robot(id, 0.05 + col * 0.08, 0.05 + row * 0.08, kPi + kPi / 4));
      world.set_wheel_speeds(id, 127, 127);  // all at full speed towards the corner (0, 0)
      ++id;
    }
  for (int i = 0; i < 40; ++i) {
    world.step(kTick);
    const auto robots = world.robots();
    for (std::size_t a = 0; a < robots.size(); ++a) {
      const Vec2 p = robots[a].pose.position_m;
      ASSERT_GE(p.x, kR - 1e-6);
      ASSERT_GE(p.y, kR - 1e-6);
      ASSERT_LE(p.x, 0.6 - kR + 1e-6);
      ASSERT_LE(p.y, 0.6 - kR + 1e-6);
      for (std::size_t b = a + 1; b < robots.size(); ++b)
        ASSERT_GE((robots[b].pose.position_m - p).norm(), 2 * kR - 1e-6) << "robots " << a << " and " << b;
    }
  }
}
}  // namespace

TEST(Collisions, CrowdDrivingIntoACornerNeverOverlaps) { crowd_into_corner(WorldConfig{}); }

TEST(Collisions, CrowdStaysApartEvenWhenThePassesRunOut) {
  // One pass per substep cannot settle a crowd: the fallback (putting overlapping robots
  // back where their substep started) must keep everyone apart on its own.
  WorldConfig config;
  config.collision.max_passes = 1;
  crowd_into_corner(config);
}

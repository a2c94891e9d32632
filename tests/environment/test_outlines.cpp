// Robots with convex outlines: the outline checks, the polygon narrow phase, and a world
// in which square and triangular robots meet walls, obstacles and each other.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "environment/body_shape.hpp"
#include "environment/world.hpp"
#include "world_fixtures.hpp"

using namespace rilbed;
using namespace rilbed::environment;
using namespace rilbed::environment::testing;

namespace {
constexpr TimeUs kTick = 100'000;
constexpr double kHalf = 0.03;  // a 60 mm square robot

std::vector<Vec2> square(double half) { return {{half, half}, {-half, half}, {-half, -half}, {half, -half}}; }

RobotConfig square_robot(int id, double x, double y, double heading_rad) {
  RobotConfig r = quiet_robot(id, x, y, heading_rad);
  r.outline_m = square(kHalf);
  return r;
}

std::string refusal(std::vector<Vec2> outline) {
  try {
    checked_outline(std::move(outline), "robot 7");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}
}  // namespace

TEST(Outline, BadOutlinesAreRefusedNamingTheCause) {
  EXPECT_NE(refusal({{0.1, 0}, {0, 0.1}}).find("robot 7: outline must have 3 to 32 vertices, not 2"),
            std::string::npos);
  EXPECT_NE(refusal({{0.1, 0.1}, {-0.1, 0.1}, {0.0, 0.0}, {-0.1, -0.1}, {0.1, -0.1}}).find("not convex"),
            std::string::npos);
  EXPECT_NE(refusal({{0.1, 0.1}, {-0.1, -0.1}, {-0.1, 0.1}, {0.1, -0.1}}).find("crosses itself"), std::string::npos);
  EXPECT_NE(refusal({{0.1, 0.1}, {0.2, 0.1}, {0.2, 0.2}}).find("centre (0, 0) strictly inside"), std::string::npos);
  EXPECT_NE(refusal({{0.0, 0.0}, {0.1, 0.0}, {0.0, 0.1}}).find("strictly inside"), std::string::npos);
  EXPECT_NE(refusal({{NAN, 0.1}, {-0.1, 0.1}, {0.0, -0.1}}).find("not finite"), std::string::npos);
  EXPECT_EQ(refusal(square(0.02)), "accepted");
}

TEST(Outline, ClockwiseOutlinesAreTurnedCounterClockwise) {
  std::vector<Vec2> cw = square(0.02);
  std::reverse(cw.begin(), cw.end());
  const std::vector<Vec2> out = checked_outline(cw, "robot 1");
  EXPECT_GT(polygon_signed_area(out), 0.0);
  EXPECT_NEAR(outline_bounding_radius_m(out), 0.02 * std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(outline_inner_radius_m(out), 0.02, 1e-15);
}

TEST(Outline, PolygonContactIsTheLeastOverlapAxis) {
  const std::vector<Vec2> a = {{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}};
  std::vector<Vec2> b = {{0.9, 0.2}, {1.9, 0.2}, {1.9, 1.2}, {0.9, 1.2}};
  Contact c = convex_polygon_polygon_contact(a, b);
  EXPECT_NEAR(c.separation_m, -0.1, 1e-12);
  EXPECT_NEAR(c.normal.x, -1.0, 1e-12);  // a must move left, away from b
  for (Vec2& v : b) v.x += 0.15;
  c = convex_polygon_polygon_contact(a, b);
  EXPECT_NEAR(c.separation_m, 0.05, 1e-12);
  // A disc against a polygon through shape_shape_contact: the normal from b towards a.
  const BodyShape disc{{2.1, 0.7}, 0.1, {}};
  const BodyShape poly{{1.5, 0.7}, 0.8, b};
  c = shape_shape_contact(poly, disc);
  EXPECT_NEAR(c.separation_m, -0.05, 1e-12);
  EXPECT_NEAR(c.normal.x, -1.0, 1e-12);
}

TEST(Outline, ASquareDrivesFlushAgainstAWallWhereItsBoundingDiscCouldNot) {
  World world(empty_field(1.0, 1.0));
  world.add_robot(square_robot(1, 0.5, 0.3, 0.0));
  world.add_robot(square_robot(2, 0.5, 0.7, M_PI / 4));
  world.set_wheel_speeds(1, 60, 60);
  world.set_wheel_speeds(2, 60, 60);
  bool hit = false;
  for (int i = 0; i < 20; ++i)
    for (const CollisionEvent& e : world.step(kTick))
      hit = hit || (e.first.id == 1 && e.second.kind == BodyKind::kWall);
  EXPECT_TRUE(hit);
  EXPECT_LE(world.max_overlap_m(), 1e-9);
  // Square on: its front face touches the right wall, 30 mm from its centre (its bounding
  // disc would have stopped it 42 mm away).
  EXPECT_NEAR(world.robot(1).pose.position_m.x, 1.0 - kHalf, 1e-6);
  // Diagonal: the corner leads, half a diagonal ahead of the centre.
  const Pose2 p2 = world.robot(2).pose;
  const double reach = kHalf * (std::abs(std::cos(p2.heading_rad)) + std::abs(std::sin(p2.heading_rad)));
  EXPECT_NEAR(p2.position_m.x, 1.0 - reach, 1e-6);
}

TEST(Outline, PlacementTestsTheOutlineNotItsBoundingDisc) {
  World world(empty_field(1.0, 1.0));
  // Two squares 65 mm apart: 5 mm between their faces, though their bounding discs overlap.
  world.add_robot(square_robot(1, 0.5, 0.5, 0.0));
  EXPECT_NO_THROW(world.add_robot(square_robot(2, 0.565, 0.5, 0.0)));
  // Turned by 45 degrees, a corner reaches into the neighbour.
  try {
    world.add_robot(square_robot(3, 0.5, 0.565, M_PI / 4));
    ADD_FAILURE() << "placed overlapping";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("robot 3: placed overlapping robot 1"), std::string::npos) << e.what();
  }
  // 31 mm from a wall: free square on, overlapping turned.
  EXPECT_NO_THROW(world.add_robot(square_robot(4, 0.969, 0.2, 0.0)));
  try {
    world.add_robot(square_robot(5, 0.969, 0.8, M_PI / 4));
    ADD_FAILURE() << "placed overlapping";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the right wall"), std::string::npos) << e.what();
  }
  ASSERT_EQ(world.outline_m(1).size(), 4u);
  EXPECT_TRUE(world.snapshot().robots[0].outline_m.size() == 4u);
}

TEST(Outline, TwoSquaresPushingEachOtherNeverOverlap) {
  World world(empty_field(1.0, 1.0));
  world.add_robot(square_robot(1, 0.3, 0.5, 0.0));
  world.add_robot(square_robot(2, 0.7, 0.5, M_PI));
  world.set_wheel_speeds(1, 40, 40);
  world.set_wheel_speeds(2, 40, 40);
  bool met = false;
  for (int i = 0; i < 15; ++i) {
    for (const CollisionEvent& e : world.step(kTick))
      met = met || (e.first == BodyRef{BodyKind::kRobot, 1} && e.second == BodyRef{BodyKind::kRobot, 2});
    ASSERT_LE(world.max_overlap_m(), 1e-9) << "step " << i;
  }
  EXPECT_TRUE(met);
  // They met short of their bounding discs' touching distance (85 mm).
  EXPECT_LT((world.robot(1).pose.position_m - world.robot(2).pose.position_m).norm(), 2 * kHalf * std::sqrt(2.0));
}

// Crowded enough that the passes run out and the fallback puts robots back, heading and
// all (put back with their new headings, outlines would overlap: this failed so).
TEST(Outline, AMixedCrowdWithObstaclesStaysFreeOfOverlaps) {
  StaticMapConfig map = empty_field(1.2, 1.0);
  map.obstacles.push_back(rectangle(0.5, 0.4, 0.7, 0.6));
  World world(map);
  MovingObstacleConfig mover;
  mover.shape = MovingShape::kPolygon;
  mover.vertices_m = {{-0.04, -0.03}, {0.04, -0.03}, {0.0, 0.05}};
  mover.position_m = {0.2, 0.8};
  mover.velocity_mps = {0.15, -0.05};
  world.add_moving_obstacle(mover);
  std::mt19937 rng(20261202);
  std::uniform_real_distribution<double> x(0.05, 1.15), y(0.05, 0.95), heading(-M_PI, M_PI);
  std::uniform_int_distribution<int> speed(-80, 80);
  const std::vector<Vec2> triangle = {{0.04, 0.0}, {-0.025, 0.03}, {-0.025, -0.03}};
  int placed = 0;
  for (int id = 1; placed < 40 && id < 2000; ++id) {
    RobotConfig r = quiet_robot(id, x(rng), y(rng), heading(rng));
    if (id % 3 == 1) r.outline_m = square(0.025);
    if (id % 3 == 2) r.outline_m = triangle;
    try {
      world.add_robot(r);
      ++placed;
    } catch (const std::invalid_argument&) {}
  }
  ASSERT_EQ(placed, 40);
  for (int i = 0; i < 300; ++i) {
    if (i % 10 == 0)
      for (const RobotSnapshot& r : world.snapshot().robots) world.set_wheel_speeds(r.id, speed(rng), speed(rng));
    world.step(kTick);
    ASSERT_LE(world.max_overlap_m(), 1e-9) << "step " << i;
  }
}

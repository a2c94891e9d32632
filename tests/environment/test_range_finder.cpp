#include <gtest/gtest.h>

#include <cmath>

#include "environment/world.hpp"
#include "world_fixtures.hpp"

using namespace rilbed;
using namespace rilbed::environment;
using namespace rilbed::environment::testing;

namespace {
constexpr double kR = kKheperaRadius_m;

RobotConfig with_range_finders(RobotConfig c, std::vector<RangeFinderConfig> finders) {
  c.sensors.range_finders = std::move(finders);
  return c;
}

RangeFinderConfig finder(double mount_deg, double opening_deg = 30.0, double max_range_m = 1.0) {
  RangeFinderConfig f;
  f.mount_angle_rad = deg_to_rad(mount_deg);
  f.opening_angle_rad = deg_to_rad(opening_deg);
  f.max_range_m = max_range_m;
  return f;
}

std::vector<RangeReading> ranges_of(const World& world, int id) {
  NoiseRng rng(1);
  return world.sense(id, 0, rng).ranges;
}
}  // namespace

TEST(RangeFinder, WallStraightAheadAndOutOfRange) {
  World world(empty_field(3, 3));
  world.add_robot(with_range_finders(quiet_robot(1, 2.5, 1.5, 0.0), {finder(0), finder(180)}));
  const auto r = ranges_of(world, 1);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_TRUE(r[0].hit);
  EXPECT_NEAR(r[0].distance_m, 0.5 - kR, 1e-12);
  EXPECT_FALSE(r[1].hit);  // the left wall is 2.47 m behind, beyond its 1 m
  EXPECT_EQ(r[1].distance_m, 1.0);
}

TEST(RangeFinder, ObliqueWallIsSeenAlongTheConeEdge) {
  World world(empty_field(3, 3));
  world.add_robot(with_range_finders(quiet_robot(1, 2.5, 1.5, deg_to_rad(30)), {finder(0)}));
  // The cone spans 15..45 degrees; the wall's perpendicular (0 degrees) is outside, so
  // the nearest wall point in the cone lies on the 15-degree edge.
  const double dx = 0.5 - kR * std::cos(deg_to_rad(30));
  const auto r = ranges_of(world, 1);
  EXPECT_TRUE(r[0].hit);
  EXPECT_NEAR(r[0].distance_m, dx / std::cos(deg_to_rad(15)), 1e-12);
}

TEST(RangeFinder, ConeEdges) {
  // A thin bar 0.5 m ahead of the sensor (apex at (1.5 + r, 1.5)), reaching from `from`
  // to 0.4 m left of the axis. The cone's edge passes 0.5 tan 15 = 0.134 m left of the
  // axis there.
  auto bar_range = [](double from_m) {
    StaticMapConfig map = empty_field(3, 3);
    const double x = 1.5 + kR + 0.5;
    map.obstacles.push_back(rectangle(x, 1.5 + from_m, x + 0.001, 1.5 + 0.4));
    World world(map);
    world.add_robot(with_range_finders(quiet_robot(1, 1.5, 1.5, 0.0), {finder(0)}));
    return ranges_of(world, 1)[0];
  };
  const RangeReading inside = bar_range(0.1);  // its lower end is inside the cone
  EXPECT_TRUE(inside.hit);
  EXPECT_NEAR(inside.distance_m, std::sqrt(0.25 + 0.01), 1e-12);
  const RangeReading just_in = bar_range(0.133);
  EXPECT_TRUE(just_in.hit);
  const RangeReading just_out = bar_range(0.135);
  EXPECT_FALSE(just_out.hit);
  EXPECT_FALSE(bar_range(0.2).hit);
}

TEST(RangeFinder, MountAngleTurnsTheCone) {
  World world(empty_field(3, 3));
  world.add_robot(with_range_finders(quiet_robot(1, 1.5, 0.3, 0.0), {finder(-90), finder(90)}));
  const auto r = ranges_of(world, 1);
  EXPECT_TRUE(r[0].hit);  // right side: the bottom wall
  EXPECT_NEAR(r[0].distance_m, 0.3 - kR, 1e-12);
  EXPECT_FALSE(r[1].hit);  // left side: the top wall is 2.67 m away
}

TEST(RangeFinder, SeesRobotsAndReportsNoisyDistances) {
  World world(empty_field(3, 3));
  RangeFinderConfig noisy = finder(0);
  noisy.noise_sd_m = 0.01;
  world.add_robot(with_range_finders(quiet_robot(1, 1.0, 1.5, 0.0), {noisy}));
  world.add_robot(quiet_robot(2, 1.5, 1.5, 0.0));
  NoiseRng rng(3);
  double sum = 0, sum_sq = 0;
  const int n = 2000;
  for (int k = 0; k < n; ++k) {
    const RangeReading r = world.sense(1, 0, rng).ranges[0];
    ASSERT_TRUE(r.hit);
    sum += r.distance_m;
    sum_sq += r.distance_m * r.distance_m;
  }
  const double mean = sum / n;
  EXPECT_NEAR(mean, 0.5 - 2 * kR, 0.001);
  EXPECT_NEAR(std::sqrt(sum_sq / n - mean * mean), 0.01, 0.001);
}

TEST(RangeFinder, BadConfigurationIsRejected) {
  World world(empty_field(3, 3));
  EXPECT_THROW(world.add_robot(with_range_finders(quiet_robot(1, 1, 1, 0), {finder(0, 180)})), std::invalid_argument);
  EXPECT_THROW(world.add_robot(with_range_finders(quiet_robot(1, 1, 1, 0), {finder(0, 30, -1)})),
               std::invalid_argument);
  try {
    world.add_robot(with_range_finders(quiet_robot(4, 1, 1, 0), {finder(0), finder(0, 30, NAN)}));
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("robot 4: range finder 1"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(world.has_robot(1));
}

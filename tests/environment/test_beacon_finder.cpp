#include <gtest/gtest.h>

#include <cmath>

#include "environment/world.hpp"
#include "world_fixtures.hpp"

using namespace rilbed;
using namespace rilbed::environment;
using namespace rilbed::environment::testing;

namespace {
// A beacon at (1, 1) shining along +x through a 90-degree aperture, 1 m far.
StaticMapConfig beacon_field() {
  StaticMapConfig map = empty_field(3, 2);
  map.beacons.push_back({5, {1.0, 1.0}, 0.0, deg_to_rad(90), 1.0});
  return map;
}

RobotConfig with_finder(int id, double x, double y, double heading, BeaconFinderConfig f = {}) {
  RobotConfig c = quiet_robot(id, x, y, heading);
  c.sensors.beacon_finder = f;
  return c;
}

std::vector<BeaconSighting> sightings(const World& world, int id) {
  NoiseRng rng(1);
  return world.sense(id, 0, rng).beacons;
}
}  // namespace

TEST(BeaconFinder, BearingIsRelativeToTheHeading) {
  World world(beacon_field());
  world.add_robot(with_finder(1, 1.5, 1.0, kPi / 2));  // facing up; the beacon is on its left
  world.add_robot(with_finder(2, 1.6, 1.0, kPi));      // facing the beacon
  world.add_robot(with_finder(3, 1.7, 1.0, 0.0));      // back to the beacon
  auto s = sightings(world, 1);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].id, 5);
  EXPECT_NEAR(s[0].bearing_rad, kPi / 2, 1e-12);
  s = sightings(world, 2);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_NEAR(s[0].bearing_rad, 0.0, 1e-12);
  s = sightings(world, 3);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_NEAR(std::abs(s[0].bearing_rad), kPi, 1e-12);
  // An oblique one: robot at (1.4, 1.3) facing +x sees the beacon at atan2(-0.3, -0.4).
  World oblique(beacon_field());
  oblique.add_robot(with_finder(1, 1.4, 1.3, 0.0));
  s = sightings(oblique, 1);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_NEAR(s[0].bearing_rad, std::atan2(-0.3, -0.4), 1e-12);
}

TEST(BeaconFinder, OutOfApertureOrRangeIsNotSeen) {
  World world(beacon_field());
  world.add_robot(with_finder(1, 1.4, 1.38, 0.0));  // 43.5 degrees off the beacon's axis: seen
  world.add_robot(with_finder(2, 1.3, 1.45, 0.0));  // 56 degrees off: outside
  world.add_robot(with_finder(3, 1.98, 0.9, 0.0));  // 0.985 m: in range
  world.add_robot(with_finder(4, 2.01, 1.1, 0.0));  // 1.015 m: out of range
  world.add_robot(with_finder(6, 0.7, 1.0, 0.0));   // behind the beacon
  EXPECT_EQ(sightings(world, 1).size(), 1u);
  EXPECT_TRUE(sightings(world, 2).empty());
  EXPECT_EQ(sightings(world, 3).size(), 1u);
  EXPECT_TRUE(sightings(world, 4).empty());
  EXPECT_TRUE(sightings(world, 6).empty());
}

TEST(BeaconFinder, ObstaclesOccludeRobotsDoNot) {
  StaticMapConfig map = beacon_field();
  map.obstacles.push_back(rectangle(1.2, 0.95, 1.3, 1.05));
  World world(map);
  world.add_robot(with_finder(1, 1.5, 1.0, 0.0));  // straight behind the block
  // The line from (1, 1) to (1.5, 1.2) passes the block at y = 1.08..1.12: clear.
  world.add_robot(with_finder(2, 1.5, 1.2, 0.0));
  // A robot right on the sight line hides nothing.
  world.add_robot(with_finder(3, 1.8, 1.3, 0.0));
  world.add_robot(quiet_robot(4, 1.65, 1.0 + 0.65 * 0.375, 0.0));
  EXPECT_TRUE(sightings(world, 1).empty());
  EXPECT_EQ(sightings(world, 2).size(), 1u);
  EXPECT_EQ(sightings(world, 3).size(), 1u);

  // A moving obstacle hides it too.
  World moving(beacon_field());
  moving.add_robot(with_finder(1, 1.5, 1.0, 0.0));
  MovingObstacleConfig disc;
  disc.radius_m = 0.05;
  disc.position_m = {1.25, 1.0};
  moving.add_moving_obstacle(disc);
  EXPECT_TRUE(sightings(moving, 1).empty());
}

TEST(BeaconFinder, BeaconOnAWallIsNotHiddenByItAndFieldOfViewLimits) {
  StaticMapConfig map = empty_field(2, 2);
  map.beacons.push_back({1, {0.0, 1.0}, 0.0, kPi, 1.5});  // on the left wall, shining in
  map.beacons.push_back({2, {2.0, 1.0}, kPi, kPi, 1.5});  // on the right wall
  World world(map);
  world.add_robot(with_finder(1, 1.0, 1.2, 0.0));
  BeaconFinderConfig narrow;
  narrow.field_of_view_rad = deg_to_rad(120);  // looks ahead only
  world.add_robot(with_finder(2, 1.0, 0.8, 0.0, narrow));
  const auto all = sightings(world, 1);
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].id, 1);  // in the map's order
  EXPECT_EQ(all[1].id, 2);
  const auto ahead = sightings(world, 2);
  ASSERT_EQ(ahead.size(), 1u);
  EXPECT_EQ(ahead[0].id, 2);
}

TEST(BeaconFinder, BearingNoise) {
  World world(beacon_field());
  BeaconFinderConfig f;
  f.bearing_noise_sd_rad = 0.05;
  world.add_robot(with_finder(1, 1.6, 1.0, kPi, f));
  NoiseRng rng(8);
  double sum = 0, sum_sq = 0;
  const int n = 2000;
  for (int k = 0; k < n; ++k) {
    const double b = world.sense(1, 0, rng).beacons.at(0).bearing_rad;
    sum += b;
    sum_sq += b * b;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.005);
  EXPECT_NEAR(std::sqrt(sum_sq / n), 0.05, 0.004);
}

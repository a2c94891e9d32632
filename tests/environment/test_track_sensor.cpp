#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "environment/track_sensor.hpp"
#include "environment/world.hpp"
#include "world_fixtures.hpp"

using namespace rilbed;
using namespace rilbed::environment;
using namespace rilbed::environment::testing;

namespace {
TrackSensorConfig element(double inclination_deg, double coverage_percent = 15.0) {
  TrackSensorConfig c;
  c.inclination_deg = inclination_deg;
  c.coverage_percent = coverage_percent;
  c.error_level_percent = 0.0;
  return c;
}

double centroid_x(const TrackFootprint& f) {
  double sum = 0;
  for (const Vec2 p : f.points_m) sum += p.x;
  return sum / static_cast<double>(f.points_m.size());
}

// A field with one straight track from `a` to `b` and one robot carrying `elements`.
World track_world(Vec2 a, Vec2 b, double width_m, Pose2 robot, std::vector<TrackSensorConfig> elements) {
  StaticMapConfig map = empty_field(1, 1);
  map.tracks.push_back({{a, b}, width_m, false, "tape"});
  World world(map);
  RobotConfig c = quiet_robot(1, robot.position_m.x, robot.position_m.y, robot.heading_rad);
  c.sensors.track_sensors = std::move(elements);
  world.add_robot(c);
  return world;
}

std::vector<int> track_readings(const World& world, std::uint64_t seed = 1) {
  NoiseRng rng(seed);
  return world.sense(1, 0, rng).track;
}
}  // namespace

TEST(TrackFootprint, PaperExampleEllipseEnds) {
  // Height 8 mm, inclination 45, cone 30: the ellipse reaches from 8 tan(45 - 15) to
  // 8 tan(45 + 15) mm, 4.6 to 13.9 mm.
  const TrackFootprint f = track_footprint(TrackSensorConfig{});
  EXPECT_NEAR(f.near_m, 0.008 * std::tan(deg_to_rad(30)), 1e-15);
  EXPECT_NEAR(f.far_m, 0.008 * std::tan(deg_to_rad(60)), 1e-15);
  ASSERT_EQ(f.points_m.size(), 16u);
  for (const Vec2 p : f.points_m) {
    EXPECT_GT(p.x, f.near_m);
    EXPECT_LT(p.x, f.far_m);
  }
}

TEST(TrackFootprint, VerticalElementHasEqualSolidAngleRings) {
  // 16 segments: two rings of 4 and 12 cells (weights 1 and 3), each cell 1/16 of the
  // cone's solid angle; a ring's points sit at its solid-angle middle.
  const TrackFootprint f = track_footprint(element(0.0));
  const double u_max = 1.0 - std::cos(deg_to_rad(15));
  const double r0 = 0.008 * std::tan(std::acos(1.0 - u_max * 2.0 / 16.0));
  const double r1 = 0.008 * std::tan(std::acos(1.0 - u_max * 10.0 / 16.0));
  int inner = 0, outer = 0;
  for (const Vec2 p : f.points_m) {
    if (std::abs(p.norm() - r0) < 1e-12) ++inner;
    if (std::abs(p.norm() - r1) < 1e-12) ++outer;
  }
  EXPECT_EQ(inner, 4);
  EXPECT_EQ(outer, 12);
  EXPECT_NEAR(centroid_x(f), 0.0, 1e-15);
  EXPECT_EQ(track_footprint([] {
              auto c = element(0);
              c.precision = 1;
              return c;
            }())
                .points_m.size(),
            1u);
  EXPECT_EQ(track_footprint([] {
              auto c = element(0);
              c.precision = 100;
              return c;
            }())
                .points_m.size(),
            100u);
}

TEST(TrackFootprint, InclinationShiftsTheEllipseAndCrowdsItsNearEnd) {
  double previous = -1.0;
  for (const double alpha : {0.0, 15.0, 30.0, 45.0, 55.0}) {
    const double c = centroid_x(track_footprint(element(alpha)));
    EXPECT_GT(c, previous) << alpha;
    previous = c;
  }
  // Inclined, the near half of the ellipse gets more light and so more segments.
  const TrackFootprint f = track_footprint(element(45));
  const double middle = 0.5 * (f.near_m + f.far_m);
  const auto near_count = std::count_if(f.points_m.begin(), f.points_m.end(), [&](Vec2 p) { return p.x < middle; });
  EXPECT_GT(near_count, 10);
}

TEST(TrackFootprint, MountPositionAndYaw) {
  TrackSensorConfig c = element(45);
  c.mount_x_m = 0.01;
  c.mount_y_m = 0.005;
  c.mount_yaw_deg = 90;  // leans to the robot's left
  const TrackFootprint f = track_footprint(c);
  for (const Vec2 p : f.points_m) {
    EXPECT_GT(p.y, 0.005 + f.near_m - 1e-12);
    EXPECT_LT(p.y, 0.005 + f.far_m + 1e-12);
    EXPECT_NEAR(p.x, 0.01, 0.005);
  }
}

TEST(TrackSensor, OnAndOffTheTrack) {
  const World on = track_world({0.1, 0.5}, {0.9, 0.5}, 0.02, {{0.5, 0.5}, 0.0}, {element(45)});
  EXPECT_EQ(track_readings(on), std::vector<int>{255});
  const World off = track_world({0.1, 0.5}, {0.9, 0.5}, 0.02, {{0.5, 0.6}, 0.0}, {element(45)});
  EXPECT_EQ(track_readings(off), std::vector<int>{0});
  // Crossing the track at right angles, the element sees it when it is under the
  // footprint; a robot just past it, with the footprint beyond the tape, does not.
  const World crossing = track_world({0.1, 0.5}, {0.9, 0.5}, 0.02, {{0.5, 0.49}, kPi / 2}, {element(45)});
  EXPECT_EQ(track_readings(crossing), std::vector<int>{255});
  const World past = track_world({0.1, 0.5}, {0.9, 0.5}, 0.02, {{0.5, 0.511}, kPi / 2}, {element(45)});
  EXPECT_EQ(track_readings(past), std::vector<int>{0});
}

TEST(TrackSensor, CoverageThreshold) {
  // A wide tape whose edge runs under the robot's centre, along its heading: a vertical
  // element's 16 segments are symmetric about that line, so exactly 8 are on the tape.
  auto reading = [](double coverage, bool graded) {
    TrackSensorConfig c = element(0, coverage);
    c.graded = graded;
    const World w = track_world({0.2, 0.45}, {0.8, 0.45}, 0.1, {{0.5, 0.5}, 0.0}, {c});
    return track_readings(w).at(0);
  };
  EXPECT_EQ(reading(50.0, false), 255);
  EXPECT_EQ(reading(51.0, false), 0);
  EXPECT_EQ(reading(15.0, true), 128);  // 255 * 8 / 16, rounded
  EXPECT_EQ(reading(60.0, true), 0);
  const TrackSensor s(element(0, 50.0), "test");
  EXPECT_EQ(s.required_segments(), 8);
}

TEST(TrackSensor, InclinationDecidesWhetherATrackAheadIsSeen) {
  // A narrow tape across the robot's path, 6..10 mm ahead of the centre: the inclined
  // element (footprint 4.6..13.9 mm ahead) sees it, the vertical one (within 2.2 mm of
  // the centre) does not.
  const Vec2 a{0.5 + 0.008, 0.2}, b{0.5 + 0.008, 0.8};
  const World w = track_world(a, b, 0.004, {{0.5, 0.5}, 0.0}, {element(45, 10), element(0, 10)});
  EXPECT_EQ(track_readings(w), (std::vector<int>{255, 0}));
}

TEST(TrackSensor, ErrorLevelAddsNoiseWithinRange) {
  TrackSensorConfig c = element(45);
  c.error_level_percent = 5.0;  // sd 12.75
  const World on = track_world({0.1, 0.5}, {0.9, 0.5}, 0.02, {{0.5, 0.5}, 0.0}, {c});
  const World off = track_world({0.1, 0.5}, {0.9, 0.5}, 0.02, {{0.5, 0.7}, 0.0}, {c});
  NoiseRng rng(2);
  double sum_on = 0, sum_off = 0;
  int distinct_below_max = 0;
  const int n = 2000;
  for (int k = 0; k < n; ++k) {
    const int v_on = on.sense(1, 0, rng).track[0], v_off = off.sense(1, 0, rng).track[0];
    ASSERT_GE(v_on, 0);
    ASSERT_LE(v_on, 255);
    ASSERT_GE(v_off, 0);
    ASSERT_LE(v_off, 255);
    sum_on += v_on;
    sum_off += v_off;
    if (v_on < 255) ++distinct_below_max;
  }
  // Clamped half-normals: the mean moves by sd / sqrt(2 pi) = 5.09 from the ideal.
  EXPECT_NEAR(sum_on / n, 255 - 12.75 / std::sqrt(2 * kPi), 0.8);
  EXPECT_NEAR(sum_off / n, 12.75 / std::sqrt(2 * kPi), 0.8);
  EXPECT_GT(distinct_below_max, n / 3);
}

TEST(TrackSensor, ConeThatReachesTheHorizonIsRejected) {
  World world(empty_field(1, 1));
  RobotConfig c = quiet_robot(3, 0.5, 0.5, 0.0);
  c.sensors.track_sensors = {element(45), element(80)};
  try {
    world.add_robot(c);
    FAIL() << "accepted an inclination of 80 with a 30-degree cone";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("robot 3: track sensor 1"), std::string::npos) << e.what();
  }
  c.sensors.track_sensors = {element(10)};
  c.sensors.track_sensors[0].precision = 0;
  EXPECT_THROW(world.add_robot(c), std::invalid_argument);
}

#include <gtest/gtest.h>

#include <cmath>

#include "environment/world.hpp"
#include "world_fixtures.hpp"

using namespace rilbed;
using namespace rilbed::environment;
using namespace rilbed::environment::testing;

namespace {
constexpr double kR = kKheperaRadius_m;

// The documented response curve, written out independently of the code under test.
double expected_response(double d_m) {
  if (d_m >= 0.05) return 0.0;
  return 1023.0 * (std::exp(-d_m / 0.0125) - std::exp(-4.0)) / (1.0 - std::exp(-4.0));
}

ProximityValues sense_proximity(const World& world, int id, std::uint64_t seed = 1) {
  NoiseRng rng(seed);
  return *world.sense(id, 0, rng).proximity;
}
}  // namespace

TEST(Proximity, ResponseCurveHandValues) {
  const ProximitySensor sensor(ProximityConfig{}, "test");
  EXPECT_DOUBLE_EQ(sensor.response(0.0), 1023.0);
  EXPECT_NEAR(sensor.response(0.010), 449.16, 0.01);  // 1023 (e^-0.8 - e^-4) / (1 - e^-4)
  EXPECT_NEAR(sensor.response(0.020), 191.3, 0.1);
  EXPECT_NEAR(sensor.response(0.040), 23.4, 0.1);
  EXPECT_EQ(sensor.response(0.050), 0.0);
  EXPECT_EQ(sensor.response(0.2), 0.0);
  for (double d = 0.0; d < 0.05; d += 0.001) EXPECT_GT(sensor.response(d), sensor.response(d + 0.001));
}

TEST(Proximity, WallInFrontOfSensorsTwoAndThree) {
  // Robot heading +x; sensor 2 sits on the rim at +10 degrees, so it is r cos(10 deg)
  // ahead of the centre. Put the right wall 10 mm in front of it.
  const double x = 1.0 - 0.010 - kR * std::cos(deg_to_rad(10));
  World world(empty_field(1, 1));
  world.add_robot(quiet_robot(1, x, 0.5, 0.0));
  const ProximityValues v = sense_proximity(world, 1);
  EXPECT_EQ(v[2], 449);  // the wall's perpendicular foot lies inside its +-30 degree cone
  EXPECT_EQ(v[3], 449);
  // Sensor 1 (45 degrees) sees the wall only along its cone's 15-degree edge.
  const double d1 = (1.0 - x - kR * std::cos(deg_to_rad(45))) / std::cos(deg_to_rad(15));
  EXPECT_EQ(v[1], std::lround(expected_response(d1)));
  EXPECT_EQ(v[4], v[1]);
  // The side and back sensors see nothing.
  EXPECT_EQ(v[0], 0);
  EXPECT_EQ(v[5], 0);
  EXPECT_EQ(v[6], 0);
  EXPECT_EQ(v[7], 0);
}

TEST(Proximity, ReadingFallsWithDistance) {
  int previous = 1024;
  for (double gap = 0.0; gap < 0.06; gap += 0.005) {
    World world(empty_field(1, 1));
    world.add_robot(quiet_robot(1, 1.0 - kR - gap, 0.5, 0.0));
    const int front = sense_proximity(world, 1)[2];
    if (gap + kR * (1 - std::cos(deg_to_rad(10))) >= 0.05) {
      EXPECT_EQ(front, 0);
    } else {
      EXPECT_LT(front, previous);
    }
    previous = front;
  }
  EXPECT_EQ(previous, 0);
}

TEST(Proximity, LeftAndRightAreMirrorImages) {
  // Robot heading up (+y) at the field's centre; an obstacle block on its left, then the
  // mirrored block on its right.
  auto readings = [](bool left) {
    StaticMapConfig map = empty_field(1, 1);
    map.obstacles.push_back(left ? rectangle(0.44, 0.47, 0.46, 0.56) : rectangle(0.54, 0.47, 0.56, 0.56));
    World world(map);
    world.add_robot(quiet_robot(1, 0.5, 0.5, kPi / 2));
    return sense_proximity(world, 1);
  };
  const ProximityValues l = readings(true), r = readings(false);
  EXPECT_GT(l[0], 100);  // the left sensor is 12.5 mm from the block
  EXPECT_EQ(r[0], 0);
  for (int i = 0; i < 6; ++i)
    EXPECT_EQ(l[static_cast<std::size_t>(i)], r[static_cast<std::size_t>(5 - i)]) << "sensor " << i;
  EXPECT_EQ(l[6], r[7]);
  EXPECT_EQ(l[7], r[6]);
}

TEST(Proximity, NothingInRangeReadsAboutZero) {
  World world(empty_field(1, 1));
  world.add_robot(quiet_robot(1, 0.5, 0.5, 0.3));
  for (const int v : sense_proximity(world, 1)) EXPECT_EQ(v, 0);

  World noisy(empty_field(1, 1));
  RobotConfig c = quiet_robot(2, 0.5, 0.5, 0.3);
  c.sensors.proximity->noise_sd = 3.0;
  noisy.add_robot(c);
  NoiseRng rng(9);
  double sum = 0;
  int max = 0;
  for (int k = 0; k < 500; ++k) {
    const SensorReadings readings = noisy.sense(2, 0, rng);  // kept alive for the loop
    for (const int v : *readings.proximity) {
      sum += v;
      max = std::max(max, v);
    }
  }
  // Noise around 0, clamped at 0: mean sd / sqrt(2 pi) ~ 1.2, peaks a few sd.
  EXPECT_NEAR(sum / 4000.0, 3.0 / std::sqrt(2 * kPi), 0.2);
  EXPECT_LE(max, 20);
}

TEST(Proximity, NoiseHasTheConfiguredSpread) {
  World world(empty_field(1, 1));
  RobotConfig c = quiet_robot(1, 1.0 - 0.010 - kR * std::cos(deg_to_rad(10)), 0.5, 0.0);
  c.sensors.proximity->noise_sd = 3.0;
  world.add_robot(c);
  NoiseRng rng(4);
  double sum = 0, sum_sq = 0;
  const int n = 4000;
  for (int k = 0; k < n; ++k) {
    const double v = (*world.sense(1, 0, rng).proximity)[2];
    sum += v;
    sum_sq += v * v;
  }
  const double mean = sum / n, sd = std::sqrt(sum_sq / n - mean * mean);
  EXPECT_NEAR(mean, 449.16, 0.3);
  EXPECT_NEAR(sd, std::sqrt(9.0 + 1.0 / 12.0), 0.2);  // noise plus rounding
}

TEST(Proximity, SeesOtherRobotsRealOrVirtual) {
  for (const RobotKind kind : {RobotKind::kVirtual, RobotKind::kReal}) {
    World world(empty_field(1, 1));
    world.add_robot(quiet_robot(1, 0.5, 0.5, 0.0));
    RobotConfig other = quiet_robot(2, 0.5 + 2 * kR, 0.5, kPi);  // touching, in front
    other.kind = kind;
    world.add_robot(other);
    // Sensor 2's apex is at r (cos 10, sin 10) from robot 1's centre; the other robot's
    // centre is 2r ahead: its surface is r (sqrt(5 - 4 cos 10 deg) - 1) away, within
    // the cone (the direction is 19.7 degrees off the sensor's axis).
    const double d = kR * (std::sqrt(5.0 - 4.0 * std::cos(deg_to_rad(10))) - 1.0);
    const ProximityValues v = sense_proximity(world, 1);
    EXPECT_EQ(v[2], std::lround(expected_response(d)));
    EXPECT_EQ(v[3], v[2]);
    EXPECT_GT(v[2], 950);
    // And the other robot sees robot 1 the same way, whatever its kind.
    const ProximityValues w = sense_proximity(world, 2);
    EXPECT_EQ(w[2], v[2]);
  }
}

TEST(Proximity, SeesMovingObstacles) {
  World world(empty_field(1, 1));
  world.add_robot(quiet_robot(1, 0.5, 0.5, 0.0));
  MovingObstacleConfig disc;
  disc.radius_m = 0.05;
  disc.position_m = {0.5 + kR + 0.02 + 0.05, 0.5};  // its surface 20 mm ahead of the rim
  world.add_moving_obstacle(disc);
  const ProximityValues v = sense_proximity(world, 1);
  EXPECT_GT(v[2], 150);
  EXPECT_LT(v[2], 200);
}

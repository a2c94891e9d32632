#include <gtest/gtest.h>

#include <cmath>

#include "environment/kinematics.hpp"
#include "environment/world.hpp"
#include "world_fixtures.hpp"

using namespace rilbed;
using namespace rilbed::environment;
using namespace rilbed::environment::testing;

TEST(Kinematics, KheperaUnits) {
  EXPECT_DOUBLE_EQ(speed_units_to_mps(10), 0.08);
  EXPECT_EQ(clamp_speed_units(200), 127);
  EXPECT_EQ(clamp_speed_units(-200), -127);
  EXPECT_EQ(clamp_speed_units(-5), -5);
}

TEST(Kinematics, StraightLineAndOdometryPulses) {
  World world(empty_field(2, 2));
  world.add_robot(quiet_robot(1, 0.5, 1.0, 0.0));
  world.set_wheel_speeds(1, 10, 10);  // 80 mm/s
  run(world, 10, 100'000);            // 1 s
  const RobotState& r = world.robot(1);
  EXPECT_NEAR(r.pose.position_m.x, 0.58, 1e-12);
  EXPECT_NEAR(r.pose.position_m.y, 1.0, 1e-12);
  EXPECT_NEAR(r.pose.heading_rad, 0.0, 1e-12);
  // 80 mm of travel at 0.08 mm per pulse.
  EXPECT_EQ(r.odometer().left_pulses, 1000);
  EXPECT_EQ(r.odometer().right_pulses, 1000);
  EXPECT_EQ(world.time_us(), 1'000'000);
}

TEST(Kinematics, SpinInPlace) {
  World world(empty_field(2, 2));
  world.add_robot(quiet_robot(1, 1.0, 1.0, 0.0));
  world.set_wheel_speeds(1, -10, 10);
  run(world, 5, 100'000);  // 0.5 s: wheels 40 mm each, turn 2 * 0.04 / 0.053 rad
  const RobotState& r = world.robot(1);
  EXPECT_NEAR(r.pose.position_m.x, 1.0, 1e-12);
  EXPECT_NEAR(r.pose.position_m.y, 1.0, 1e-12);
  EXPECT_NEAR(r.pose.heading_rad, 0.08 / 0.053, 1e-12);
  EXPECT_EQ(r.odometer().left_pulses, -500);
  EXPECT_EQ(r.odometer().right_pulses, 500);
}

TEST(Kinematics, ArcRadiusFromWheelSpeeds) {
  // l = 80 mm/s, r = 160 mm/s: v = 120 mm/s, w = 80 / 53 rad/s, R = v / w = 79.5 mm.
  EXPECT_NEAR(arc_radius_m(0.08, 0.16, 0.053), 0.0795, 1e-12);
  EXPECT_TRUE(std::isinf(arc_radius_m(0.1, 0.1, 0.053)));
  EXPECT_DOUBLE_EQ(arc_radius_m(-0.1, 0.1, 0.053), 0.0);

  World world(empty_field(2, 2));
  world.add_robot(quiet_robot(1, 1.0, 1.0, 0.0));
  world.set_wheel_speeds(1, 10, 20);
  const Vec2 centre{1.0, 1.0 + 0.0795};  // heading +x, turning left
  for (int i = 0; i < 7; ++i) {
    world.step(100'000);
    const RobotState& r = world.robot(1);
    EXPECT_NEAR((r.pose.position_m - centre).norm(), 0.0795, 1e-12);
    EXPECT_NEAR(r.pose.heading_rad, wrap_rad_pi((i + 1) * 0.1 * 0.08 / 0.053), 1e-12);
  }
}

TEST(Kinematics, ExactArcsDoNotDependOnTheStepLength) {
  const Pose2 one = integrate_diff_drive({{0, 0}, 0.3}, 0.05, 0.11, 0.053, 2.0);
  Pose2 many{{0, 0}, 0.3};
  for (int i = 0; i < 2000; ++i) many = integrate_diff_drive(many, 0.05, 0.11, 0.053, 0.001);
  EXPECT_NEAR(one.position_m.x, many.position_m.x, 1e-12);
  EXPECT_NEAR(one.position_m.y, many.position_m.y, 1e-12);
  EXPECT_NEAR(one.heading_rad, many.heading_rad, 1e-12);
  // Tiny turn rates use the series and agree with a straight line.
  const Pose2 almost = integrate_diff_drive({{0, 0}, 0.0}, 0.1, 0.1 + 1e-12, 0.053, 1.0);
  EXPECT_NEAR(almost.position_m.x, 0.1, 1e-12);
}

TEST(Kinematics, SpeedsAreClampedLikeTheFirmware) {
  World world(empty_field(2, 2));
  world.add_robot(quiet_robot(1, 1.0, 1.0, 0.0));
  world.set_wheel_speeds(1, 500, -500);
  EXPECT_EQ(world.wheel_speeds(1), (WheelUnits{127, -127}));
  world.set_wheel_speeds(1, -128, 126);
  EXPECT_EQ(world.wheel_speeds(1), (WheelUnits{-127, 126}));
}

TEST(Kinematics, SystematicBiasCurvesAStraightCommand) {
  World world(empty_field(2, 2));
  RobotConfig c = quiet_robot(1, 0.5, 1.0, 0.0);
  c.noise.left_bias = 0.1;  // left wheel 10 % fast: the robot veers right
  world.add_robot(c);
  world.set_wheel_speeds(1, 10, 10);
  run(world, 10, 100'000);
  const RobotState& r = world.robot(1);
  // Left 88 mm/s, right 80 mm/s for 1 s: turn -(0.008 / 0.053) rad.
  EXPECT_NEAR(r.pose.heading_rad, -0.008 / 0.053, 1e-12);
  EXPECT_LT(r.pose.position_m.y, 1.0);
  EXPECT_EQ(r.odometer().left_pulses, 1100);  // the counters see the faster wheel
  EXPECT_EQ(r.odometer().right_pulses, 1000);
}

TEST(Kinematics, SlipNoiseIsSeededAndCanHideFromTheCounters) {
  auto drive = [](std::uint64_t seed, bool counts_slip) {
    WorldConfig config;
    config.noise_seed = seed;
    World world(empty_field(3, 3), config);
    RobotConfig c = quiet_robot(1, 0.5, 1.5, 0.0);
    c.noise.slip_sd = 0.05;
    c.noise.odometer_counts_slip = counts_slip;
    world.add_robot(c);
    world.set_wheel_speeds(1, 20, 20);
    run(world, 50, 100'000);
    return world.robot(1);
  };
  const RobotState a = drive(5, true), b = drive(5, true), other = drive(6, true);
  EXPECT_EQ(a.pose.position_m, b.pose.position_m);
  EXPECT_EQ(a.pose.heading_rad, b.pose.heading_rad);
  EXPECT_NE(a.pose.position_m, other.pose.position_m);
  EXPECT_NE(a.pose.heading_rad, 0.0);          // it wandered
  EXPECT_NE(a.odometer().left_pulses, 10000);  // 0.8 m commanded; the counters saw the slip
  const RobotState hidden = drive(5, false);
  EXPECT_EQ(hidden.odometer().left_pulses, 10000);  // counters see only the command...
  EXPECT_EQ(hidden.odometer().right_pulses, 10000);
  EXPECT_EQ(hidden.pose.position_m, a.pose.position_m);  // ...while the body slips the same way
}

TEST(Kinematics, OdometerCanBeSet) {
  World world(empty_field(2, 2));
  world.add_robot(quiet_robot(1, 0.5, 1.0, 0.0));
  world.set_odometer(1, {100, -7});
  world.set_wheel_speeds(1, 1, 1);
  world.step(10'000);  // one pulse per 10 ms
  EXPECT_EQ(world.robot(1).odometer().left_pulses, 101);
  EXPECT_EQ(world.robot(1).odometer().right_pulses, -6);
}

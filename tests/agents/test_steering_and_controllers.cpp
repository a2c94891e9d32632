#include <gtest/gtest.h>

#include <cmath>

#include "agents/basic_controllers.hpp"
#include "agents/c_controller.hpp"
#include "agents/steering.hpp"

namespace rilbed::agents {
namespace {

using environment::ProximityValues;

TEST(WheelsFromTwist, StraightSpinAndClamp) {
  EXPECT_EQ(wheels_from_twist(0.08, 0.0), (WheelCommand{10, 10}));  // 80 mm/s = 10 units
  // Spin in place at 1 rad/s: each wheel moves 26.5 mm/s = 3.3 units.
  EXPECT_EQ(wheels_from_twist(0.0, 1.0), (WheelCommand{-3, 3}));
  // Far beyond the limit: scaled together, the turn's sense and ratio kept.
  const WheelCommand w = wheels_from_twist(2.0, 10.0);
  EXPECT_EQ(w.right, 127);
  EXPECT_NEAR(static_cast<double>(w.left) / w.right, (2.0 - 0.265) / (2.0 + 0.265), 0.01);
}

TEST(SteerTo, AheadLeftStandoffInsideAndBehind) {
  SteeringConfig c;
  const Pose2 self{{0.0, 0.0}, 0.0};
  const WheelCommand ahead = steer_to(self, {1.0, 0.0}, 0.1, c);
  EXPECT_EQ(ahead.left, ahead.right);
  EXPECT_NEAR(ahead.left, c.max_speed_mps / kMetresPerSecondPerUnit, 1.0);
  const WheelCommand left = steer_to(self, {1.0, 0.5}, 0.1, c);
  EXPECT_GT(left.right, left.left);
  EXPECT_EQ(steer_to(self, {0.1, 0.0}, 0.1, c), (WheelCommand{0, 0}));
  const WheelCommand inside = steer_to(self, {0.05, 0.0}, 0.12, c);
  EXPECT_LT(inside.left, 0);
  EXPECT_EQ(inside.left, inside.right);
  const WheelCommand behind = steer_to(self, {-1.0, 0.01}, 0.1, c);
  EXPECT_EQ(behind.left, -behind.right);  // turns on the spot
  EXPECT_NE(behind.left, 0);
}

TEST(SteerTo, RepulsionBendsTheCourse) {
  SteeringConfig c;
  const Pose2 self{{0.0, 0.0}, 0.0};
  const WheelCommand pushed_left = steer_to(self, {1.0, 0.0}, 0.1, c, Vec2{0.0, 0.8});
  EXPECT_GT(pushed_left.right, pushed_left.left);
}

TEST(SteerAway, TurnsFromTheSideThatSeesMore) {
  SteeringConfig c;
  ProximityValues left_obstacle{800, 600, 200, 0, 0, 0, 0, 0};
  const WheelCommand w = steer_away(left_obstacle, c);
  EXPECT_GT(w.left, w.right);  // clockwise, away from the left
  ProximityValues right_obstacle{0, 0, 0, 200, 600, 800, 0, 0};
  const WheelCommand r = steer_away(right_obstacle, c);
  EXPECT_GT(r.right, r.left);
  ProximityValues dead_ahead{0, 0, 900, 900, 0, 0, 0, 0};
  const WheelCommand d = steer_away(dead_ahead, c);
  EXPECT_GT(d.right, d.left);      // breaks the tie to the left
  EXPECT_LE(d.left + d.right, 0);  // does not push on
}

TEST(ObstacleLevel, RampsAndIgnoresTheBack) {
  EXPECT_EQ(obstacle_level({0, 0, 0, 0, 0, 0, 1023, 1023}), 0.0);
  EXPECT_NEAR(obstacle_level({0, 0, 512, 0, 0, 0, 0, 0}, 0.3, 0.7), (512.0 / 1023 - 0.3) / 0.4, 1e-9);
  EXPECT_EQ(obstacle_level({0, 1023, 0, 0, 0, 0, 0, 0}), 1.0);
}

ControlInput with_proximity(const ProximityValues& p) {
  ControlInput in;
  in.robot_id = 3;
  in.sensors.proximity = p;
  return in;
}

TEST(WanderController, CruisesAndAvoids) {
  WanderController w;
  const ControlOutput open = w.step(with_proximity({}));
  EXPECT_EQ(open.behaviour, "cruise");
  EXPECT_GT(open.wheels.left, 0);
  EXPECT_EQ(open.wheels.left, open.wheels.right);
  const ControlOutput wall = w.step(with_proximity({0, 0, 0, 300, 700, 900, 0, 0}));
  EXPECT_EQ(wall.behaviour, "avoid");
  EXPECT_GT(wall.wheels.right, wall.wheels.left);
}

TEST(TrackFollowController, SteersToTheTrackAndSearchesWhenLost) {
  TrackFollowController t;
  ControlInput in;
  in.sensors.track = {0, 255, 0};
  ControlOutput centred = t.step(in);
  EXPECT_EQ(centred.behaviour, "follow");
  EXPECT_EQ(centred.wheels.left, centred.wheels.right);
  in.sensors.track = {255, 0, 0};
  ControlOutput left = t.step(in);
  EXPECT_GT(left.wheels.right, left.wheels.left);
  in.sensors.track = {0, 0, 0};
  ControlOutput lost = t.step(in);
  EXPECT_EQ(lost.behaviour, "search");
  EXPECT_GT(lost.wheels.right, lost.wheels.left);  // turns back towards the left, where it was
}

TEST(BeaconHomingController, TurnsToTheBeaconAndSearchesWithoutOne) {
  BeaconHomingConfig config;
  config.beacon_id = 4;
  BeaconHomingController b(config);
  ControlInput in;
  in.sensors.beacons = {{7, 0.0}, {4, 0.5}};
  ControlOutput home = b.step(in);
  EXPECT_EQ(home.behaviour, "home");
  EXPECT_GT(home.wheels.right, home.wheels.left);
  in.sensors.beacons = {{7, 0.0}};
  EXPECT_EQ(b.step(in).behaviour, "search");
  in.sensors.beacons = {{4, 0.0}};
  in.sensors.proximity = ProximityValues{0, 0, 900, 900, 0, 0, 0, 0};
  const ControlOutput arrived = b.step(in);
  EXPECT_EQ(arrived.behaviour, "arrived");
  EXPECT_EQ(arrived.wheels, (WheelCommand{0, 0}));
}

}  // namespace
}  // namespace rilbed::agents

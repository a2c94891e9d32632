#include <gtest/gtest.h>

#include "agents/convoy.hpp"

namespace rilbed::agents {
namespace {

ConvoyPerception perceive(Pose2 self, std::optional<Pose2> leader, environment::ProximityValues prox = {}) {
  ConvoyPerception p;
  p.self = self;
  p.leader = leader;
  p.proximity = prox;
  return p;
}

ControlOutput run(ConvoyAgent& a, const ConvoyPerception& p, int steps) {
  ControlOutput out;
  for (int i = 0; i < steps; ++i) out = a.step(p, 0.1);
  return out;
}

TEST(ConvoyAgent, HeadWaits) {
  ConvoyAgent head(1);
  const ControlOutput out = run(head, perceive({{0.5, 0.5}, 0.0}, std::nullopt), 10);
  EXPECT_EQ(out.behaviour, "wait");
  EXPECT_EQ(out.wheels, (WheelCommand{0, 0}));
}

TEST(ConvoyAgent, SearchesForAFarLeaderAndDrivesToIt) {
  ConvoyAgent a(3);
  const ControlOutput out = run(a, perceive({{0.2, 0.2}, 0.0}, Pose2{{1.0, 0.2}, 0.0}), 10);
  EXPECT_EQ(out.behaviour, "search");
  EXPECT_GT(out.wheels.left, 10);
  EXPECT_EQ(out.wheels.left, out.wheels.right);
}

TEST(ConvoyAgent, FollowsANearLeaderAndStopsAtTheStandoff) {
  ConvoyConfig config;
  ConvoyAgent a(2, config);
  const ControlOutput near = run(a, perceive({{0.2, 0.2}, 0.0}, Pose2{{0.2 + config.standoff_m, 0.2}, 0.0}), 10);
  EXPECT_EQ(near.behaviour, "follow");
  EXPECT_EQ(near.wheels, (WheelCommand{0, 0}));
  const ControlOutput farther = run(a, perceive({{0.2, 0.2}, 0.0}, Pose2{{0.38, 0.2}, 0.0}), 3);
  EXPECT_EQ(farther.behaviour, "follow");
  EXPECT_GT(farther.wheels.left, 0);
}

TEST(ConvoyAgent, AvoidsWhatTheSensorsSee) {
  ConvoyAgent a(2);
  const ControlOutput out =
      run(a, perceive({{0.2, 0.2}, 0.0}, Pose2{{1.0, 0.2}, 0.0}, {0, 0, 950, 950, 0, 0, 0, 0}), 10);
  EXPECT_EQ(out.behaviour, "avoid");
}

TEST(ConvoyAgent, WithoutItsLeaderItWaits) {
  ConvoyAgent a(4);
  EXPECT_EQ(run(a, perceive({{0.2, 0.2}, 0.0}, std::nullopt), 10).behaviour, "wait");
  EXPECT_THROW(ConvoyAgent(0), std::invalid_argument);
}

TEST(ConvoyController, TakesItsLeaderFromTheTeamMessages) {
  ConvoyController c(3);
  ControlInput in;
  in.robot_id = 3;
  in.pose = Pose2{{0.2, 0.2}, 0.0};
  in.sensors.proximity = environment::ProximityValues{};
  const std::vector<TeamMessage> team = {{1, {{0.2, 1.0}, 0.0}, "wait", 0}, {2, {{1.0, 0.2}, 0.0}, "search", 0}};
  in.team = team;
  EXPECT_TRUE(c.wants_team());
  ControlOutput out;
  for (int i = 0; i < 10; ++i) {
    in.t_us += 100000;
    out = c.step(in);
  }
  EXPECT_EQ(out.behaviour, "search");
  EXPECT_EQ(out.wheels.left, out.wheels.right);  // towards agent 2 straight ahead, not agent 1 to the left
}

TEST(CentralConvoy, CommandsEveryAgent) {
  CentralConvoy central;
  std::vector<CentralConvoy::AgentView> views = {
      {1, Pose2{{0.5, 0.5}, 0.0}, environment::ProximityValues{}},
      {2, Pose2{{1.0, 0.5}, kPi}, environment::ProximityValues{}},
      {3, Pose2{{1.0, 0.6}, 0.0}, environment::ProximityValues{}},
  };
  std::map<int, ControlOutput> out;
  for (int i = 1; i <= 10; ++i) out = central.step(i * 100000, views);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[1].behaviour, "wait");
  EXPECT_EQ(out[2].behaviour, "search");
  EXPECT_EQ(out[2].wheels.left, out[2].wheels.right);  // agent 1 is dead ahead of agent 2
  EXPECT_EQ(out[3].behaviour, "follow");               // agent 2 is 0.1 m away
}

std::vector<FormationMonitor::Sample> chain(double gap, std::string_view behaviour = "follow") {
  std::vector<FormationMonitor::Sample> team;
  for (int k = 1; k <= 4; ++k) team.push_back({k, {{0.2 + gap * k, 0.5}, kPi}, k == 1 ? "wait" : behaviour});
  return team;
}

TEST(FormationMonitor, FormsAfterTheHoldAndReportsWhenItBegan) {
  FormationMonitor m(4, 5.0);
  EXPECT_TRUE(m.condition(chain(0.12)));
  EXPECT_FALSE(m.condition(chain(0.35)));
  EXPECT_FALSE(m.condition(chain(0.05)));
  EXPECT_FALSE(m.condition(chain(0.12, "search")));
  auto partial = chain(0.12);
  partial.pop_back();
  EXPECT_FALSE(m.condition(partial));

  EXPECT_FALSE(m.update(seconds_to_us(1.0), chain(0.12)));
  EXPECT_FALSE(m.update(seconds_to_us(3.0), chain(0.35)));  // broken: the hold starts again
  EXPECT_FALSE(m.update(seconds_to_us(4.0), chain(0.12)));
  EXPECT_FALSE(m.update(seconds_to_us(8.9), chain(0.12)));
  EXPECT_TRUE(m.update(seconds_to_us(9.0), chain(0.12)));
  EXPECT_TRUE(m.formed());
  EXPECT_EQ(*m.formation_time_us(), seconds_to_us(4.0));
  EXPECT_EQ(*m.formed_at_us(), seconds_to_us(9.0));
  EXPECT_FALSE(m.update(seconds_to_us(10.0), chain(0.12)));  // reported once
}

}  // namespace
}  // namespace rilbed::agents

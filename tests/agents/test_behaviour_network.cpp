#include <gtest/gtest.h>

#include <cmath>

#include "agents/behaviour_network.hpp"

namespace rilbed::agents {
namespace {

BehaviourInputs only(Behaviour b, double level = 1.0) {
  BehaviourInputs in{};
  in[static_cast<std::size_t>(b)] = level;
  return in;
}

BehaviourNetworkState run(const BehaviourNetwork& net, BehaviourNetworkState s, const BehaviourInputs& in,
                          double seconds, double dt = 0.1) {
  for (double t = 0; t < seconds - 1e-9; t += dt) s = net.update(s, in, dt);
  return s;
}

TEST(BehaviourNetwork, SettlesOnTheOnlyCalledBehaviour) {
  BehaviourNetwork net;
  for (Behaviour b : {Behaviour::kSearch, Behaviour::kFollow, Behaviour::kWait, Behaviour::kAvoid}) {
    const auto s = run(net, {}, only(b), 2.0);
    EXPECT_EQ(s.active, b) << behaviour_name(b);
    EXPECT_NEAR(s.activation[static_cast<std::size_t>(b)], 1.0, 1e-3);
  }
}

TEST(BehaviourNetwork, ActivationFollowsTheFirstOrderLaw) {
  // One input, no inhibitors active: a(t) = 1 - exp(-t / tau) (explicit Euler on
  // quarter-tau steps, so within a few percent).
  BehaviourNetwork net;
  const auto s = run(net, {}, only(Behaviour::kFollow), 0.2, 0.2);
  EXPECT_NEAR(s.activation[1], 1.0 - std::pow(0.75, 4), 1e-12);  // four exact Euler steps
  EXPECT_NEAR(s.activation[1], 1.0 - std::exp(-1.0), 0.06);
}

TEST(BehaviourNetwork, StrongerInputWinsAgainstAWeakerOne) {
  BehaviourNetwork net;
  BehaviourInputs in{};
  in[static_cast<std::size_t>(Behaviour::kSearch)] = 1.0;
  in[static_cast<std::size_t>(Behaviour::kWait)] = 0.8;
  const auto s = run(net, {}, in, 3.0);
  EXPECT_EQ(s.active, Behaviour::kSearch);
  // Steady state of the two coupled equations: a_s = 1 - 0.3 a_w, a_w = 0.8 - 0.4 a_s.
  EXPECT_NEAR(s.activation[0], 0.76 / 0.88, 1e-3);
  EXPECT_NEAR(s.activation[2], 0.8 - 0.4 * 0.76 / 0.88, 1e-3);
}

TEST(BehaviourNetwork, AvoidPreemptsAndHandsBack) {
  BehaviourNetwork net;
  BehaviourInputs follow = only(Behaviour::kFollow);
  auto s = run(net, {}, follow, 2.0);
  ASSERT_EQ(s.active, Behaviour::kFollow);
  BehaviourInputs both = follow;
  both[static_cast<std::size_t>(Behaviour::kAvoid)] = 1.0;
  s = run(net, s, both, 0.5);
  EXPECT_EQ(s.active, Behaviour::kAvoid);
  s = run(net, s, follow, 2.0);
  EXPECT_EQ(s.active, Behaviour::kFollow);
}

TEST(BehaviourNetwork, SwitchingTakesTimeSoABriefBlipIsIgnored) {
  // Hysteresis: one 100 ms step of a competing input does not flip the winner.
  BehaviourNetwork net;
  auto s = run(net, {}, only(Behaviour::kFollow), 2.0);
  s = net.update(s, only(Behaviour::kSearch), 0.1);
  EXPECT_EQ(s.active, Behaviour::kFollow);
  s = run(net, s, only(Behaviour::kSearch), 1.0);
  EXPECT_EQ(s.active, Behaviour::kSearch);
}

TEST(BehaviourNetwork, ResultDoesNotDependOnTheStepLength) {
  BehaviourNetwork net;
  const auto coarse = run(net, {}, only(Behaviour::kSearch), 1.0, 0.1);
  const auto fine = run(net, {}, only(Behaviour::kSearch), 1.0, 0.05);
  EXPECT_NEAR(coarse.activation[0], fine.activation[0], 1e-9);
}

TEST(BehaviourNetwork, NoInputIsIdleAndBadArgumentsThrow) {
  BehaviourNetwork net;
  EXPECT_EQ(net.update({}, {}, 0.1).active, Behaviour::kWait);
  EXPECT_THROW(net.update({}, {}, 0.0), std::invalid_argument);
  BehaviourNetworkConfig bad;
  bad.time_constant_s = 0.0;
  EXPECT_THROW(BehaviourNetwork{bad}, std::invalid_argument);
  BehaviourInputs nan{};
  nan[0] = std::nan("");
  EXPECT_EQ(net.update({}, nan, 0.1).activation[0], 0.0);
}

TEST(BehaviourNetwork, Names) {
  EXPECT_EQ(behaviour_name(Behaviour::kSearch), "search");
  EXPECT_EQ(behaviour_name(Behaviour::kFollow), "follow");
  EXPECT_EQ(behaviour_name(Behaviour::kWait), "wait");
  EXPECT_EQ(behaviour_name(Behaviour::kAvoid), "avoid");
}

}  // namespace
}  // namespace rilbed::agents

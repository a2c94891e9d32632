// The console's actions on a real run (no bus: RunControl directly, as the LCM console
// server calls it), each at a chosen simulated time from the run's own thread: a robot
// driven by hand and handed back to its controller, the convoy's mode switched both ways,
// a reset, and the refusals.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <future>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "run/run_control.hpp"
#include "run/simulation.hpp"

namespace rilbed::run {
namespace {

Scenario shipped(const std::string& name) {
  return load_scenario(std::filesystem::path(RILBED_SOURCE_DIR) / "scenarios" / (name + ".yaml"));
}

// Acts on the run at given times and keeps what the run reports.
struct Script final : RunObserver {
  RunControl* control = nullptr;
  std::vector<std::pair<TimeUs, ControlAction>> actions;  // in time order
  std::vector<std::optional<std::string>> answers;        // act()'s, in order
  std::size_t next = 0;
  std::map<TimeUs, agents::WheelCommand> wheels_of_3;
  std::map<TimeUs, std::string> behaviour_of_3;
  std::vector<StatusReport> statuses;
  std::vector<RunEvent> events;

  void on_poses(TimeUs t, std::span<const PoseReport> poses) override {
    for (const PoseReport& p : poses) {
      if (p.id == 3) behaviour_of_3[t] = std::string(p.behaviour);
    }
    while (next < actions.size() && t >= actions[next].first) answers.push_back(control->act(actions[next++].second));
  }
  void on_wheels(TimeUs t, std::span<const WheelReport> wheels) override {
    for (const WheelReport& w : wheels) {
      if (w.id == 3) wheels_of_3[t] = w.wheels;
    }
  }
  void on_status(const StatusReport& s) override { statuses.push_back(s); }
  void on_event(const RunEvent& e) override { events.push_back(e); }
  bool has_event(const std::string& text) const {
    for (const RunEvent& e : events) {
      if (e.detail.find(text) != std::string::npos) return true;
    }
    return false;
  }
};

ControlAction action(ControlAction::Kind kind) {
  ControlAction a;
  a.kind = kind;
  a.who = "test";
  return a;
}

RunResult run_with(Scenario s, Script& script, RunControl& control, double duration_s, bool stop_when_formed = false) {
  script.control = &control;
  RunOptions o;
  o.seed = 2;
  o.duration_s = duration_s;
  o.stop_when_formed = stop_when_formed;
  o.observer = &script;
  o.control = &control;
  return run_scenario(s, o);
}

TEST(RunControl, DriveTakesARobotByHandThenGivesItBack) {
  RunControl control;
  Script script;
  ControlAction drive = action(ControlAction::Kind::kDrive);
  drive.robot_id = 3;
  drive.left = 40;
  drive.right = -40;
  drive.duration_s = 1.5;
  ControlAction no_such = drive;
  no_such.robot_id = 99;
  ControlAction too_fast = drive;
  too_fast.left = 300;
  script.actions = {{1'000'000, drive}, {1'000'000, no_such}, {1'000'000, too_fast}};
  run_with(shipped("convoy_sim"), script, control, 5.0);
  ASSERT_EQ(script.answers.size(), 3u);
  EXPECT_EQ(script.answers[0], std::nullopt);
  EXPECT_EQ(script.answers[1], "this run has no robot 99");
  EXPECT_EQ(script.answers[2], "wheel speeds are -127..127 (Khepera units)");
  EXPECT_TRUE(script.has_event("robot 3 driven 40 -40 for 1.5 s by test"));
  // Driven by hand from the step after the order to the end of the 1.5 s, then its own
  // controller again.
  int by_hand = 0;
  for (const auto& [t, w] : script.wheels_of_3) {
    const std::string& behaviour = script.behaviour_of_3.at(t);
    if (t > 1'100'000 && t < 2'500'000) {
      EXPECT_EQ(w, (agents::WheelCommand{40, -40})) << "t " << t;
      EXPECT_EQ(behaviour, "console") << "t " << t;
      ++by_hand;
    }
    if (t <= 900'000 || t >= 2'700'000) {
      EXPECT_NE(behaviour, "console") << "t " << t;
    }
  }
  EXPECT_GE(by_hand, 13);
}

TEST(RunControl, ARunWithoutACameraHasNoVisionSettings) {
  RunControl control;
  Script script;
  ControlAction tune = action(ControlAction::Kind::kVision);
  tune.vision = {{"contrast", 1.5}};
  script.actions = {{500'000, tune}};
  run_with(shipped("convoy_sim"), script, control, 2.0);
  ASSERT_EQ(script.answers.size(), 1u);
  EXPECT_EQ(script.answers[0], "this run has no camera, so no vision settings");
  ASSERT_FALSE(script.statuses.empty());
  for (const StatusReport& s : script.statuses) EXPECT_FALSE(s.vision.has_value());
}

TEST(RunControl, ModeSwitchesBothWaysAndTheConvoyStillForms) {
  RunControl control;
  Script script;
  ControlAction central = action(ControlAction::Kind::kMode);
  central.central = true;
  ControlAction distributed = action(ControlAction::Kind::kMode);
  script.actions = {{2'000'000, central}, {2'000'000, central}, {5'000'000, distributed}};
  const RunResult r = run_with(shipped("convoy_sim"), script, control, 60.0, true);
  ASSERT_EQ(script.answers.size(), 3u);
  EXPECT_EQ(script.answers[0], std::nullopt);
  EXPECT_EQ(script.answers[1], "the convoy is in central mode already");
  EXPECT_EQ(script.answers[2], std::nullopt);
  EXPECT_TRUE(script.has_event("mode central set by test"));
  EXPECT_TRUE(script.has_event("mode distributed set by test"));
  // The status says which mode drives.
  std::map<TimeUs, std::string> mode;
  for (const StatusReport& s : script.statuses) mode[s.t_us] = s.mode;
  EXPECT_EQ(mode.at(1'000'000), "distributed");
  EXPECT_EQ(mode.at(3'000'000), "central");
  EXPECT_EQ(mode.at(6'000'000), "distributed");
  EXPECT_TRUE(r.formed);
  // A run that starts central and is switched to distributed forms too.
  Scenario s = shipped("convoy_sim");
  s.mode = ConvoyMode::kCentral;
  RunControl control2;
  Script script2;
  script2.actions = {{1'000'000, distributed}};
  EXPECT_TRUE(run_with(s, script2, control2, 60.0, true).formed);
  ASSERT_EQ(script2.answers.size(), 1u);
  EXPECT_EQ(script2.answers[0], std::nullopt);
  EXPECT_EQ(script2.statuses.front().mode, "central");
  // A run without a convoy has no mode to switch.
  RunControl control3;
  Script script3;
  script3.actions = {{500'000, central}};
  run_with(shipped("beacon"), script3, control3, 1.0);
  ASSERT_EQ(script3.answers.size(), 1u);
  EXPECT_EQ(script3.answers[0], "this run has no convoy, so no mode to switch");
}

TEST(RunControl, ResetEndsTheRunToStartItOver) {
  RunControl control;
  Script script;
  script.actions = {{1'500'000, action(ControlAction::Kind::kReset)}};
  const RunResult r = run_with(shipped("convoy_sim"), script, control, 20.0);
  EXPECT_EQ(r.ended_by, "reset");
  EXPECT_LT(r.simulated_s, 2.0);
  EXPECT_TRUE(script.has_event("reset by test: the run starts over"));
  EXPECT_EQ(script.statuses.back().ended_by, "reset");
}

// A recording or a viewer learns what the run is from its world: a run the console ends
// before its first step (an exit that came while the run was being built, as after a
// reset) still reports it first. Without that a replay took the previous run's folder.
TEST(RunControl, ARunEndedBeforeItsFirstStepStillReportsItsWorldFirst) {
  struct Order final : RunObserver {
    std::vector<std::string> calls;
    void on_world(TimeUs t, const WorldReport&) override { calls.push_back("world " + std::to_string(t)); }
    void on_poses(TimeUs, std::span<const PoseReport>) override { calls.push_back("poses"); }
    void on_event(const RunEvent& e) override { calls.push_back("event " + e.detail); }
    void on_summary(TimeUs, const nlohmann::json&) override { calls.push_back("summary"); }
  };
  RunControl control;
  Order order;
  RunOptions o;
  o.seed = 2;
  o.duration_s = 5.0;
  o.observer = &order;
  o.control = &control;
  const Scenario scenario = shipped("convoy_sim");
  run::Run run(scenario, o);
  EXPECT_EQ(control.act(action(ControlAction::Kind::kExit)), std::nullopt);
  run.loop();
  const RunResult r = run.end();
  EXPECT_LT(r.simulated_s, 0.05);
  ASSERT_FALSE(order.calls.empty());
  EXPECT_EQ(order.calls.front(), "world 0");
  EXPECT_EQ(order.calls.back(), "summary");
  EXPECT_EQ(std::count(order.calls.begin(), order.calls.end(), "world 0"), 1);
  EXPECT_NE(std::find(order.calls.begin(), order.calls.end(), "event ended by test"), order.calls.end());
}

}  // namespace
}  // namespace rilbed::run

namespace rilbed::run {
namespace {

// Ctrl-C ends a paused run: a paused real-time run sleeps in its clock, where the monitor
// never looks at the interrupt; the run must end (its robots stopped) without a resume.
TEST(RunControl, AnInterruptEndsAPausedRun) {
  RunControl control;
  Script script;
  script.actions = {{300'000, action(ControlAction::Kind::kPause)}};
  std::atomic<bool> interrupt{false};
  script.control = &control;
  RunOptions o;
  o.seed = 2;
  o.duration_s = 60.0;
  o.realtime = true;
  o.observer = &script;
  o.control = &control;
  o.interrupt = &interrupt;
  auto run = std::async(std::launch::async, [&] { return run_scenario(shipped("convoy_sim"), o); });
  // Wait for what is expected: the run paused, then ended by the interrupt.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!control.paused() && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_TRUE(control.paused());
  interrupt.store(true);
  const bool ended = run.wait_until(give_up) == std::future_status::ready;
  if (!ended) control.act(action(ControlAction::Kind::kResume));  // let it end, to fail cleanly
  EXPECT_TRUE(ended) << "a paused run ignored the interrupt";
  const RunResult r = run.get();
  EXPECT_EQ(r.ended_by, "interrupt");
  EXPECT_LT(r.simulated_s, 1.0);
  EXPECT_TRUE(script.has_event("interrupted while paused"));
}

}  // namespace
}  // namespace rilbed::run

// Scenario tests: whole runs of the shipped scenarios, checked on their outcome.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <sstream>

#include "run/simulation.hpp"
#include "run/status_line.hpp"

namespace rilbed::run {
namespace {

Scenario shipped(const std::string& name) {
  return load_scenario(std::filesystem::path(RILBED_SOURCE_DIR) / "scenarios" / (name + ".yaml"));
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// What a convoy must do: convoy_sim forms in at least 95 of 100 seeds in each mode, and
// no two robots ever overlap.
void expect_convoy_forms(ConvoyMode mode) {
  Scenario s = shipped("convoy_sim");
  s.mode = mode;
  int formed = 0;
  double worst_overlap = 0.0;
  for (std::uint64_t seed = 1; seed <= 100; ++seed) {
    RunOptions o;
    o.seed = seed;
    o.stop_when_formed = true;
    const RunResult r = run_scenario(s, o);
    formed += r.formed;
    worst_overlap = std::max(worst_overlap, r.max_overlap_m);
    if (r.formed) {
      EXPECT_EQ(r.ended_by, "formed");
      ASSERT_TRUE(r.formation_time_s.has_value());
      EXPECT_NEAR(r.simulated_s, *r.formation_time_s + 5.0 + 5.0, 0.11);  // the hold, then 5 s more
    }
  }
  EXPECT_GE(formed, 95);
  EXPECT_LT(worst_overlap, 1e-6);
}

TEST(ConvoyScenario, FormsDistributed) { expect_convoy_forms(ConvoyMode::kDistributed); }
TEST(ConvoyScenario, FormsCentral) { expect_convoy_forms(ConvoyMode::kCentral); }

TEST(ConvoyScenario, FinalPosesAreAChain) {
  RunOptions o;
  o.seed = 3;
  o.stop_when_formed = true;
  o.keep_in_memory = true;
  const RunResult r = run_scenario(shipped("convoy_sim"), o);
  ASSERT_TRUE(r.formed);
  // The last control step's poses: every agent k > 1 following, 0.06..0.30 m behind k-1.
  std::map<int, TrajectorySample> last;
  for (const auto& s : r.trajectory) last[s.id] = s;
  ASSERT_EQ(last.size(), 8u);
  for (int k = 2; k <= 8; ++k) {
    EXPECT_EQ(last[k].behaviour, "follow") << k;
    const double gap = (last[k].pose.position_m - last[k - 1].pose.position_m).norm();
    EXPECT_GE(gap, 0.06) << k;
    EXPECT_LE(gap, 0.30) << k;
  }
}

TEST(Simulation, SameSeedSameRunByteForByte) {
  const auto dir = std::filesystem::temp_directory_path() / ("rilbed_determinism_" + std::to_string(::getpid()));
  const Scenario s = shipped("convoy_sim");
  for (const char* run : {"a", "b"}) {
    RunOptions o;
    o.seed = 11;
    o.duration_s = 20.0;
    o.out_dir = dir / run;
    run_scenario(s, o);
  }
  for (const char* file : {"trajectories.csv", "events.csv", "trajectories.svg"}) {
    const std::string a = slurp(dir / "a" / file), b = slurp(dir / "b" / file);
    EXPECT_GT(a.size(), 100u) << file;
    EXPECT_EQ(a, b) << file;
  }
  RunOptions other;
  other.seed = 12;
  other.duration_s = 20.0;
  other.out_dir = dir / "c";
  run_scenario(s, other);
  EXPECT_NE(slurp(dir / "a" / "trajectories.csv"), slurp(dir / "c" / "trajectories.csv"));
  std::filesystem::remove_all(dir);
}

TEST(Simulation, RunFolderHasItsFilesAndHeaders) {
  const auto dir = std::filesystem::temp_directory_path() / ("rilbed_folder_" + std::to_string(::getpid()));
  RunOptions o;
  o.seed = 2;
  o.stop_when_formed = true;
  o.out_dir = dir;
  const RunResult r = run_scenario(shipped("convoy_sim"), o);
  const std::string traj = slurp(dir / "trajectories.csv");
  EXPECT_EQ(traj.substr(0, traj.find('\n')), "t_s,id,x_m,y_m,theta_deg,behaviour");
  // Every robot at every control step: 8 rows per 0.1 s.
  const auto rows = std::count(traj.begin(), traj.end(), '\n') - 1;
  EXPECT_EQ(rows, 8 * (static_cast<long>(std::lround(r.simulated_s / 0.1)) + 1));
  const std::string events = slurp(dir / "events.csv");
  EXPECT_EQ(events.substr(0, events.find('\n')), "t_s,kind,id,other,detail");
  EXPECT_NE(events.find(",behaviour,2,0,wait -> "), std::string::npos);
  EXPECT_NE(events.find(",formed,"), std::string::npos);
  EXPECT_NE(events.find(",subteams,0,0,1-8\n"), std::string::npos);  // the whole convoy is one sub-team at the end
  const auto summary = nlohmann::json::parse(slurp(dir / "summary.json"));
  EXPECT_EQ(summary["formed"], r.formed);
  EXPECT_EQ(summary["collisions"], r.collisions);
  EXPECT_TRUE(summary.contains("formation_time_s"));
  EXPECT_NE(slurp(dir / "trajectories.svg").find("<svg"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Simulation, WanderersNeverOverlapAndTheCControllerMoves) {
  RunOptions o;
  o.seed = 4;
  o.keep_in_memory = true;
  const RunResult r = run_scenario(shipped("wander"), o);
  EXPECT_LT(r.max_overlap_m, 1e-6);
  EXPECT_DOUBLE_EQ(r.simulated_s, 60.0);
  // Robot 6 runs the C Braitenberg controller: it travels and reports its codes.
  double travelled = 0.0;
  std::optional<Vec2> previous;
  bool saw_code = false;
  for (const auto& s : r.trajectory) {
    if (s.id != 6) continue;
    if (previous) travelled += (s.pose.position_m - *previous).norm();
    previous = s.pose.position_m;
    saw_code |= s.behaviour == "c0";
  }
  EXPECT_GT(travelled, 2.0);  // 60 s at 80 mm/s, less the turns
  EXPECT_TRUE(saw_code);
}

TEST(Simulation, TrackFollowersStayOnTheTape) {
  RunOptions o;
  o.seed = 1;
  o.keep_in_memory = true;
  const RunResult r = run_scenario(shipped("track_following"), o);
  // After the first 20 s, each robot is in follow most of the time.
  for (int id : {1, 2}) {
    int follow = 0, total = 0;
    for (const auto& s : r.trajectory) {
      if (s.id != id || s.t_us < seconds_to_us(20.0)) continue;
      ++total;
      follow += s.behaviour == "follow";
    }
    EXPECT_GT(follow, total * 0.6) << "robot " << id << ": " << follow << " of " << total;
  }
}

TEST(Simulation, BeaconHomersReachTheBeacon) {
  RunOptions o;
  o.seed = 1;
  o.keep_in_memory = true;
  const RunResult r = run_scenario(shipped("beacon"), o);
  std::map<int, TrajectorySample> last;
  for (const auto& s : r.trajectory) last[s.id] = s;
  int arrived = 0;
  for (const auto& [id, s] : last) arrived += (s.pose.position_m - Vec2{1.45, 0.60}).norm() < 0.35;
  EXPECT_GE(arrived, 3) << "robots within 0.35 m of beacon 2 at the end";
}

// An observer gets every robot's readings at every step (the run keeps them for it; a
// run without one does not), each stamped with the step's instant.
TEST(Simulation, AnObserverGetsEachStepsSensorReadings) {
  struct Readings final : RunObserver {
    int steps = 0, reports = 0, with_proximity = 0;
    void on_sensors(TimeUs t_us, std::span<const SensorReport> sensors) override {
      ++steps;
      for (const SensorReport& r : sensors) {
        ++reports;
        if (r.readings->proximity && r.readings->t_us == t_us) ++with_proximity;
      }
    }
  } readings;
  const Scenario s = shipped("wander");
  RunOptions o;
  o.duration_s = 2.0;
  o.observer = &readings;
  run_scenario(s, o);
  EXPECT_GE(readings.steps, 19);
  EXPECT_EQ(readings.reports, readings.steps * static_cast<int>(s.robots.size()));
  EXPECT_EQ(readings.with_proximity, readings.reports);  // each the step's own reading
}

TEST(Simulation, TheDigestIsTheSameWhetherTheSamplesAreKeptOrNot) {
  // With nobody taking samples or events the monitor sums the digest from the world's
  // tables; keeping the samples in memory makes it read every agent's body. The same
  // terms must give the same sum, on one thread and on two.
  const int robots = 300;
  const Scenario s = wandering_scenario(robots, 3.0);
  for (const int threads : {1, 2}) {
    RunOptions plain;
    plain.duration_s = 3.0;
    plain.seed = 11;
    plain.threads = threads;
    RunOptions kept = plain;
    kept.keep_in_memory = true;
    const RunResult from_world = run_scenario(s, plain);
    const RunResult from_agents = run_scenario(s, kept);
    EXPECT_TRUE(from_world.trajectory.empty());
    ASSERT_EQ(from_agents.trajectory.size(), static_cast<std::size_t>(robots) * 30) << threads << " threads";
    EXPECT_NE(from_world.trajectory_digest, 0u);
    EXPECT_EQ(from_world.trajectory_digest, from_agents.trajectory_digest) << threads << " threads";
  }
}

TEST(Simulation, StatusLineOncePerSimulatedSecond) {
  // Control periods that divide a second and ones that do not: one status line per
  // simulated second, never the same time twice, each within a control period of its
  // whole second.
  for (const TimeUs period_us : {TimeUs{100'000}, TimeUs{150'000}, TimeUs{70'000}, TimeUs{250'000}}) {
    Scenario s = shipped("convoy_sim");
    s.control_period_us = period_us;
    s.broadcast_period_us = period_us;
    std::vector<std::string> lines;
    RunOptions o;
    o.duration_s = 12.0;
    StatusLine status_line([&](const std::string& line) { lines.push_back(line); });
    o.observer = &status_line;
    run_scenario(s, o);
    ASSERT_EQ(lines.size(), 12u) << "period " << period_us << " us";
    for (std::size_t k = 0; k < lines.size(); ++k) {
      ASSERT_EQ(lines[k].rfind("t=", 0), 0u) << lines[k];
      const double t_s = std::stod(lines[k].substr(2));
      EXPECT_GE(t_s, static_cast<double>(k) - 0.05) << lines[k];
      EXPECT_LT(t_s, static_cast<double>(k) + us_to_seconds(period_us) + 0.05) << lines[k];
      if (k > 0) {
        EXPECT_NE(lines[k].substr(0, lines[k].find(' ')), lines[k - 1].substr(0, lines[k - 1].find(' ')));
      }
    }
  }
}

TEST(Simulation, RealTimeRunsAtTheRequestedPace) {
  RunOptions o;
  o.realtime = true;
  o.rt_factor = 10.0;
  o.duration_s = 2.0;
  const auto start = std::chrono::steady_clock::now();
  const RunResult r = run_scenario(shipped("convoy_sim"), o);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GE(wall, 0.19);  // 2 s at 10x: at least 0.2 s of wall time (a lower bound only)
  EXPECT_LT(wall, 10.0);
  EXPECT_DOUBLE_EQ(r.simulated_s, 2.0);
}

TEST(Simulation, InterruptEndsTheRunCleanly) {
  std::atomic<bool> stop{true};
  RunOptions o;
  o.interrupt = &stop;
  const RunResult r = run_scenario(shipped("convoy_sim"), o);
  EXPECT_EQ(r.ended_by, "interrupt");
  EXPECT_LT(r.simulated_s, 0.2);
}

TEST(Simulation, ConvoyIdsMustBeOneToN) {
  Scenario s = shipped("convoy_sim");
  s.robots.erase(s.robots.begin() + 2);  // no robot 3
  EXPECT_THROW(run_scenario(s, RunOptions{}), ScenarioError);
  Scenario real = shipped("convoy_sim");
  real.robots[3].kind = environment::RobotKind::kReal;
  EXPECT_THROW(run_scenario(real, RunOptions{}), ScenarioError);  // real robots need real time
  RunOptions realtime;
  realtime.realtime = true;
  EXPECT_THROW(run_scenario(real, realtime), ScenarioError);  // and a way to reach them
}

TEST(Simulation, UnknownControllerOrParameterIsNamed) {
  Scenario s = shipped("wander");
  s.robots[0].controller.params["sped_mps"] = 0.1;
  try {
    run_scenario(s, RunOptions{});
    FAIL() << "expected an error";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("no parameter 'sped_mps'"), std::string::npos) << e.what();
  }
  s = shipped("wander");
  s.robots[0].controller.name = "c:nonesuch";
  EXPECT_THROW(run_scenario(s, RunOptions{}), ScenarioError);
}

}  // namespace
}  // namespace rilbed::run

namespace rilbed::run {
namespace {

TEST(StatusLine, ShowsEachRobotItsHealthAndTheFormation) {
  const std::vector<PoseReport> poses = {{1, false, true, Pose2{}, "lead", "ok"},
                                         {4, true, false, Pose2{}, "follow", "unseen"}};
  StatusReport s;
  s.t_us = 12'040'000;
  s.state = "running";
  EXPECT_EQ(StatusLine::format(s, poses), "t=12.0s  1:lead  4:follow(unseen)");
  s.formed = true;
  EXPECT_EQ(StatusLine::format(s, poses), "t=12.0s  1:lead  4:follow(unseen)  [formed]");
  s.state = "paused";
  EXPECT_EQ(StatusLine::format(s, poses), "t=12.0s  paused");
  s.state = "ended";
  EXPECT_EQ(StatusLine::format(s, poses), "");
  // As a subscriber it keeps the last poses' strings after the call that handed them.
  std::vector<std::string> lines;
  StatusLine line([&](const std::string& l) { lines.push_back(l); });
  {
    std::string behaviour = "search";
    const std::vector<PoseReport> step = {{2, false, true, Pose2{}, behaviour, "ok"}};
    line.on_poses(0, step);
    behaviour = "XXXXXX";
  }
  s.state = "running";
  s.formed = false;
  line.on_status(s);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0], "t=12.0s  2:search");
}

}  // namespace
}  // namespace rilbed::run

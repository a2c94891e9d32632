// End-to-end tests of runs with real robots: `rilbed run` starts emulated Kheperas on
// pseudo-terminals, drives them through the real serial link, and sees them through the
// emulated overhead camera and the real detector. Real time, so each takes seconds.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

// Without --realtime: a run with real robots is real time by itself.
void expect_forms_and_stops(const std::string& name, int real_robots) {
  const fs::path dir = scratch_dir(name);
  const CommandResult r = run_rilbed("run " + shipped_scenario_arg(name) + " --stop-when-formed --duration 90 --out '" +
                                     (dir / "run").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("formed at"), std::string::npos) << r.out;
  // Every real robot's last command was a stop.
  int stopped = 0;
  for (std::size_t at = r.out.find("(emulated): last speed 0 0"); at != std::string::npos;
       at = r.out.find("(emulated): last speed 0 0", at + 1)) {
    ++stopped;
  }
  EXPECT_EQ(stopped, real_robots) << r.out;
  const auto summary = nlohmann::json::parse(read_file(dir / "run" / "summary.json"));
  EXPECT_EQ(summary["formed"], true);
  EXPECT_EQ(summary["realtime"], true);
  EXPECT_EQ(summary["real_robots"].size(), static_cast<std::size_t>(real_robots));
  EXPECT_LT(summary["max_overlap_m"].get<double>(), 1e-6);
  // One status line a second: never the same second twice.
  std::set<std::string> seconds;
  for (std::size_t at = r.out.find("t="); at != std::string::npos; at = r.out.find("\nt=", at + 1)) {
    const std::size_t from = r.out[at] == '\n' ? at + 1 : at;
    EXPECT_TRUE(seconds.insert(r.out.substr(from, r.out.find(' ', from) - from)).second) << r.out;
  }
  EXPECT_GE(seconds.size(), 5u) << r.out;
  // The picture marks the real robots apart, with a legend.
  const std::string svg = read_file(dir / "run" / "trajectories.svg");
  std::size_t squares = 0;
  for (std::size_t at = svg.find("class=\"real\""); at != std::string::npos; at = svg.find("class=\"real\"", at + 1))
    ++squares;
  EXPECT_EQ(squares, static_cast<std::size_t>(real_robots)) << svg;
  EXPECT_NE(svg.find("real robot (as the camera saw it)"), std::string::npos);
  fs::remove_all(dir);
}

TEST(MixedRun, ConvoyMixedFormsAndStopsItsRealRobots) { expect_forms_and_stops("convoy_mixed", 2); }
TEST(MixedRun, ConvoyRealFormsAndStopsItsRealRobots) { expect_forms_and_stops("convoy_real", 4); }

// Interrupted by `signal` while a real-time run goes (once it printed the status of its
// first simulated second, not after a fixed time: a loaded machine may still be starting
// it then): every real robot ends stopped.
void expect_signal_stops_every_robot(const std::string& signal) {
  const fs::path dir = scratch_dir("mixed_" + signal);
  const std::string out = (dir / "out.txt").string();
  const fs::path script = dir / "interrupt.sh";
  std::ofstream(script) << "'" << RILBED_BINARY << "' run " << shipped_scenario_arg("convoy_mixed")
                        << " --realtime --duration 60 >'" << out << "' 2>&1 &\npid=$!\n"
                        << "i=0\nuntil grep -q '^t=[1-9]' '" << out
                        << "' || [ $i -ge 1200 ]; do sleep 0.1; i=$((i+1)); done\n"
                        << "kill -" << signal << " $pid\nwait $pid\n";
  const int status = std::system(("/bin/sh '" + script.string() + "'").c_str());
  EXPECT_TRUE(WIFEXITED(status));
  const std::string printed = read_file(out);
  EXPECT_NE(printed.find("\nt=1"), std::string::npos) << "the run should have been going when interrupted: " << printed;
  EXPECT_NE(printed.find("ended by interrupt"), std::string::npos) << printed;
  EXPECT_NE(printed.find("robot 4 (emulated): last speed 0 0"), std::string::npos) << printed;
  EXPECT_NE(printed.find("robot 5 (emulated): last speed 0 0"), std::string::npos) << printed;
  fs::remove_all(dir);
}

TEST(MixedRun, SigintStopsEveryRealRobot) { expect_signal_stops_every_robot("INT"); }
TEST(MixedRun, SigtermStopsEveryRealRobot) { expect_signal_stops_every_robot("TERM"); }

TEST(MixedRun, FaultsNeverStopTheRun) {
  // Robot 4's line is noisy and slow; robot 5 is unplugged after 3 s and plugged back in
  // 2 s later. The run goes on, records both, and ends with both robots stopped.
  const fs::path dir = scratch_dir("mixed_faults");
  std::string text = read_file(fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_mixed.yaml");
  const std::string real_block = "  - ids: 4-5\n    kind: real\n    link: {emulate: true}\n";
  ASSERT_NE(text.find(real_block), std::string::npos);
  text.replace(text.find(real_block), real_block.size(),
               "  - id: 4\n    kind: real\n    pose: random\n    controller: convoy\n"
               "    link: {emulate: true, faults: {garbage: 0.2, corrupt: 0.05, drop: 0.05, reply_delay_ms: 15}}\n"
               "  - id: 5\n    kind: real\n"
               "    link: {emulate: true, faults: {disconnect_after_s: 3, replug_after_s: 2}}\n");
  const fs::path scenario = dir / "faults.yaml";
  std::ofstream(scenario) << text;
  const CommandResult r =
      run_rilbed("run '" + scenario.string() + "' --realtime --duration 12 --out '" + (dir / "run").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("robot 4 (emulated): last speed 0 0"), std::string::npos) << r.out << r.err;
  EXPECT_NE(r.out.find("robot 5 (emulated): last speed 0 0"), std::string::npos) << r.out << r.err;
  const std::string events = read_file(dir / "run" / "events.csv");
  // Robot 5's link is lost (it may pass through "unresponsive" on the way), then back.
  const std::size_t lost = events.find("-> link lost");
  ASSERT_NE(lost, std::string::npos) << events;
  EXPECT_EQ(events.rfind(",health,5,0,", lost), events.rfind(",health,", lost)) << events;
  const std::size_t back = events.find(" -> ok\n", lost);
  ASSERT_NE(back, std::string::npos) << events;
  EXPECT_EQ(events.rfind(",health,5,0,", back), events.rfind(",health,", back)) << events;
  // The virtual robots went on: someone reached a leader.
  EXPECT_NE(events.find("-> follow"), std::string::npos) << events;
  const auto summary = nlohmann::json::parse(read_file(dir / "run" / "summary.json"));
  EXPECT_EQ(summary["ended_by"], "duration");
  fs::remove_all(dir);
}

TEST(MixedRun, SimToRealComparison) {
  // The same scenario and seed all virtual (fast) and with the emulated real robots (real
  // time); `rilbed compare` reports per-robot RMS distances and the formation times.
  const fs::path dir = scratch_dir("sim2real");
  const std::string common = " --stop-when-formed --duration 60 --seed 4 --out '";
  const CommandResult sim = run_rilbed("run " + shipped_scenario_arg("convoy_real") + " --all-virtual --fast" + common +
                                       (dir / "sim").string() + "'");
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const CommandResult real =
      run_rilbed("run " + shipped_scenario_arg("convoy_real") + " --realtime" + common + (dir / "real").string() + "'");
  ASSERT_EQ(real.exit_code, 0) << real.err;
  const CommandResult cmp = run_rilbed("compare '" + (dir / "sim").string() + "' '" + (dir / "real").string() + "'");
  ASSERT_EQ(cmp.exit_code, 0) << cmp.err;
  EXPECT_NE(cmp.out.find("| robot | samples | RMS distance m | max distance m |"), std::string::npos) << cmp.out;
  for (int id = 1; id <= 4; ++id)
    EXPECT_NE(cmp.out.find("| " + std::to_string(id) + " | "), std::string::npos) << cmp.out;
  EXPECT_NE(cmp.out.find("formation time: "), std::string::npos) << cmp.out;
  EXPECT_EQ(cmp.out.find("not formed"), std::string::npos) << cmp.out;
  // Emulated robots follow the virtual ones closely: same controller, same start.
  const auto all = cmp.out.find("| all | ");
  ASSERT_NE(all, std::string::npos);
  const double rms = std::stod(cmp.out.substr(cmp.out.find(" | ", all + 7) + 3));
  EXPECT_LT(rms, 0.15) << cmp.out;
  const CommandResult bad = run_rilbed("compare '" + dir.string() + "' '" + (dir / "real").string() + "'");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("trajectories.csv: cannot open"), std::string::npos) << bad.err;
  fs::remove_all(dir);
}

TEST(MixedRun, SimToRealOverABatchOfSeeds) {
  // --seeds with real robots: one run after another on the same (emulated) robots, each
  // placed at its seed's start poses first; then `rilbed compare` of the two batch
  // folders prints per seed and in summary each real robot's RMS and the formation times.
  const fs::path dir = scratch_dir("sim2real_batch");
  const std::string common = " --seeds 3 --seed 11 --duration 8 --out '";
  const CommandResult sim = run_rilbed("run " + shipped_scenario_arg("convoy_mixed") + " --all-virtual --quiet" +
                                       common + (dir / "sim").string() + "'");
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const CommandResult mixed =
      run_rilbed("run " + shipped_scenario_arg("convoy_mixed") + common + (dir / "mixed").string() + "'");
  ASSERT_EQ(mixed.exit_code, 0) << mixed.out << mixed.err;
  for (int seed = 11; seed <= 13; ++seed) {
    EXPECT_NE(mixed.out.find("seed " + std::to_string(seed) + ": "), std::string::npos) << mixed.out;
    const auto summary =
        nlohmann::json::parse(read_file(dir / "mixed" / ("seed_" + std::to_string(seed)) / "summary.json"));
    EXPECT_EQ(summary["real_robots"], nlohmann::json::array({4, 5}));
    EXPECT_EQ(summary["realtime"], true);
  }
  EXPECT_NE(mixed.out.find("| convoy_mixed | distributed | 3 |"), std::string::npos) << mixed.out;
  EXPECT_NE(mixed.out.find("robot 4 (emulated): last speed 0 0"), std::string::npos) << mixed.out;
  EXPECT_NE(mixed.out.find("robot 5 (emulated): last speed 0 0"), std::string::npos) << mixed.out;

  const CommandResult cmp = run_rilbed("compare '" + (dir / "sim").string() + "' '" + (dir / "mixed").string() + "'");
  ASSERT_EQ(cmp.exit_code, 0) << cmp.err;
  EXPECT_NE(cmp.out.find("| seed | robot 4 RMS m | robot 5 RMS m | formation A s | formation B s | difference B-A s |"),
            std::string::npos)
      << cmp.out;
  for (const char* row : {"| 11 | ", "| 12 | ", "| 13 | ", "| median | ", "| p95 | "}) {
    EXPECT_NE(cmp.out.find(row), std::string::npos) << row << "\n" << cmp.out;
  }
  // Placed at the same start poses and driven by the same controller, the real robots
  // stay near their virtual twins over 8 s.
  const std::size_t median = cmp.out.find("| median | ");
  ASSERT_NE(median, std::string::npos);
  EXPECT_LT(std::stod(cmp.out.substr(median + 11)), 0.05) << cmp.out;
  // A batch against a single run is refused, naming both.
  const CommandResult mismatch =
      run_rilbed("compare '" + (dir / "sim").string() + "' '" + (dir / "mixed" / "seed_11").string() + "'");
  EXPECT_EQ(mismatch.exit_code, 2);
  EXPECT_NE(mismatch.err.find("is a batch folder and"), std::string::npos) << mismatch.err;
  fs::remove_all(dir);
}

// A batch whose real robots must be driven to their start poses (emulated robots with
// `placement: drive`, so they go the physical way), given far too little time: rilbed
// names them to the operator and waits; Enter goes on, no operator ends the batch.
TEST(MixedRun, TheOperatorIsAskedWhenRobotsCannotBePlaced) {
  const fs::path dir = scratch_dir("mixed_operator");
  std::string text = read_file(fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_mixed.yaml");
  const std::string link = "link: {emulate: true}";
  ASSERT_NE(text.find(link), std::string::npos);
  text.replace(text.find(link), link.size(), "link: {emulate: true, placement: drive}");
  const fs::path scenario = dir / "drive.yaml";
  std::ofstream(scenario) << text;
  const std::string run = "'" + std::string(RILBED_BINARY) + "' run '" + scenario.string() +
                          "' --seeds 2 --seed 5 --duration 3 --place-timeout 0.3 --quiet --out '";
  // With an operator who presses Enter: both seeds run.
  const fs::path answered = dir / "answered.txt";
  int status =
      std::system(("printf '\\n' | " + run + (dir / "a").string() + "' >'" + answered.string() + "' 2>&1").c_str());
  const std::string a = read_file(answered);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << a;
  EXPECT_NE(a.find("robots 4, 5 did not reach their start poses within"), std::string::npos) << a;
  EXPECT_NE(a.find("robot 4 to ("), std::string::npos) << a;
  EXPECT_NE(a.find("press Enter"), std::string::npos) << a;
  EXPECT_TRUE(fs::exists(dir / "a" / "seed_6" / "summary.json")) << a;
  EXPECT_NE(a.find("robot 4 (emulated): last speed 0 0"), std::string::npos) << a;
  // Nobody there (standard input closed): the batch ends after the first seed, saying why.
  const fs::path unanswered = dir / "unanswered.txt";
  status = std::system((run + (dir / "b").string() + "' >'" + unanswered.string() + "' 2>&1 </dev/null").c_str());
  const std::string b = read_file(unanswered);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << b;
  EXPECT_NE(b.find("are not at their start poses and nobody placed them"), std::string::npos) << b;
  EXPECT_TRUE(fs::exists(dir / "b" / "seed_5" / "summary.json")) << b;
  EXPECT_FALSE(fs::exists(dir / "b" / "seed_6" / "summary.json")) << b;
  EXPECT_NE(b.find("robot 5 (emulated): last speed 0 0"), std::string::npos) << b;
  fs::remove_all(dir);
}

TEST(LoopBenchCli, PrintsItsTableAndStopsTheRobots) {
  const CommandResult r = run_rilbed("loop-bench --real 3 --virtual 20 --frames 20");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| frame arrival to `D` written on the port (per robot) |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("`D` written for 60 of 60 robot-frames; 3 of 3 robots stopped"), std::string::npos) << r.out;
}

TEST(MixedRun, FastWithRealRobotsIsAnErrorThatSaysWhy) {
  const CommandResult r = run_rilbed("run " + shipped_scenario_arg("convoy_mixed") + " --fast");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("robots 4, 5 are real and move in wall-clock time, so --fast cannot run them"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("--all-virtual"), std::string::npos) << r.err;
  // All virtual, the same scenario keeps --fast.
  const CommandResult virtual_run =
      run_rilbed("run " + shipped_scenario_arg("convoy_mixed") + " --fast --all-virtual --duration 5");
  EXPECT_EQ(virtual_run.exit_code, 0) << virtual_run.err;
}

}  // namespace
}  // namespace rilbed::e2e

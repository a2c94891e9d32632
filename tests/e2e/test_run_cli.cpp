// End-to-end tests of `rilbed run` and `rilbed sim-bench`: the real binary, real files.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <thread>

#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

TEST(RunCli, OneRunWritesItsFolder) {
  const fs::path dir = scratch_dir("run_one");
  const CommandResult r = run_rilbed("run " + shipped_scenario_arg("convoy_sim") +
                                     " --fast --stop-when-formed --seed 5 --out '" + (dir / "run").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("seed 5: formed at"), std::string::npos) << r.out;
  for (const char* f : {"trajectories.csv", "events.csv", "summary.json", "trajectories.svg"}) {
    EXPECT_TRUE(fs::exists(dir / "run" / f)) << f;
  }
  const auto summary = nlohmann::json::parse(read_file(dir / "run" / "summary.json"));
  EXPECT_EQ(summary["formed"], true);
  EXPECT_TRUE(summary["formation_time_s"].is_number());
  EXPECT_TRUE(summary["collisions"].is_number_integer());
  fs::remove_all(dir);
}

// The shipped exploring scenario to its end (--stop-when-done), its map in the run folder,
// and the same map again from a replay of its recording.
TEST(RunCli, AnExplorerEndsWhenDoneAndItsMapReplays) {
  const fs::path dir = scratch_dir("run_explore");
  const std::string log = (dir / "run.lcm").string();
  CommandResult r = run_rilbed("run " + shipped_scenario_arg("track_explore") + " --fast --stop-when-done --record '" +
                               log + "' --out '" + (dir / "run").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("(ended by done)"), std::string::npos) << r.out;
  const auto summary = nlohmann::json::parse(read_file(dir / "run" / "summary.json"));
  EXPECT_EQ(summary["ended_by"], "done");
  const std::string map_text = read_file(dir / "run" / "track_map.json");
  const auto map = nlohmann::json::parse(map_text);
  EXPECT_GE(map["nodes"].size(), 6u);
  EXPECT_GE(map["edges"].size(), map["nodes"].size() - 1);  // a connected network
  for (const auto& n : map["nodes"]) {
    const std::string kind = n["kind"];
    EXPECT_TRUE(kind == "end" || kind == "corner" || kind == "tee" || kind == "cross") << kind;
  }
  const std::string events = read_file(dir / "run" / "events.csv");
  EXPECT_NE(events.find(",track_node,1,"), std::string::npos);
  EXPECT_NE(events.find(",track_edge,1,"), std::string::npos);
  r = run_rilbed("replay '" + log + "' --out '" + (dir / "replayed").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_file(dir / "replayed" / "track_map.json"), map_text);
  fs::remove_all(dir);
}

TEST(RunCli, ABatchWritesOneFolderPerSeedAndATable) {
  const fs::path dir = scratch_dir("run_batch");
  const CommandResult r = run_rilbed("run " + shipped_scenario_arg("convoy_sim") +
                                     " --fast --stop-when-formed --seed 10 --seeds 4 --out '" + dir.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (int seed = 10; seed < 14; ++seed)
    EXPECT_TRUE(fs::exists(dir / ("seed_" + std::to_string(seed)) / "summary.json"));
  const auto batch = nlohmann::json::parse(read_file(dir / "batch.json"));
  EXPECT_EQ(batch["runs"], 4);
  EXPECT_EQ(batch["per_run"].size(), 4u);
  EXPECT_NE(r.out.find("| scenario | mode | runs | formed | formation time median s |"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

TEST(RunCli, SameSeedTwiceGivesIdenticalFiles) {
  const fs::path dir = scratch_dir("run_twice");
  for (const char* run : {"a", "b"}) {
    const CommandResult r = run_rilbed("run " + shipped_scenario_arg("wander") + " --duration 10 --seed 3 --out '" +
                                       (dir / run).string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  EXPECT_EQ(read_file(dir / "a" / "trajectories.csv"), read_file(dir / "b" / "trajectories.csv"));
  EXPECT_EQ(read_file(dir / "a" / "events.csv"), read_file(dir / "b" / "events.csv"));
  fs::remove_all(dir);
}

TEST(RunCli, ABadScenarioNamesFileLineAndKey) {
  const fs::path dir = scratch_dir("run_bad");
  const fs::path bad = dir / "bad.yaml";
  std::ofstream(bad) << "field:\n  width_m: 1.5\n  heigth_m: 1.2\nrobots:\n  - ids: 1-3\n";
  const CommandResult r = run_rilbed("run '" + bad.string() + "' --fast");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("bad.yaml:3: field.heigth_m: unknown key"), std::string::npos) << r.err;
  // A file that does not exist is a bad option value: exit 2, as every malformed option
  // (CLI11's own code for it was 105), and the reason said.
  const CommandResult missing = run_rilbed("run /nonexistent.yaml");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("/nonexistent.yaml"), std::string::npos) << missing.err;
  const CommandResult not_a_number = run_rilbed("run '" + bad.string() + "' --seed abc");
  EXPECT_EQ(not_a_number.exit_code, 2);
  fs::remove_all(dir);
}

TEST(RunCli, RealTimeRunPrintsBehavioursAndStopsOnSigint) {
  const fs::path dir = scratch_dir("run_sigint");
  // The binary in the background; SIGINT once it has printed its second status line
  // (polled: a fixed sleep was too short when a loaded machine, or a sanitizer, slowed the
  // start). --duration bounds the run should the signal be missed.
  const std::string out = (dir / "out.txt").string();
  const fs::path script = dir / "interrupt.sh";
  std::ofstream(script) << "'" << RILBED_BINARY << "' run " << shipped_scenario_arg("convoy_sim")
                        << " --realtime --duration 20 --out '" << (dir / "run").string() << "' >'" << out
                        << "' 2>&1 &\n"
                        << "pid=$!\n"
                        << "i=0; while [ $i -lt 1200 ] && ! grep -q 't=1.0s' '" << out
                        << "' 2>/dev/null; do sleep 0.05; i=$((i+1)); done\n"
                        << "kill -INT $pid\nwait $pid\n";
  const int status = std::system(("/bin/sh '" + script.string() + "'").c_str());
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  const std::string printed = read_file(out);
  EXPECT_NE(printed.find("t=0.0s  1:wait  2:"), std::string::npos) << printed;
  EXPECT_NE(printed.find("t=1.0s"), std::string::npos) << printed;
  const auto summary = nlohmann::json::parse(read_file(dir / "run" / "summary.json"));
  EXPECT_EQ(summary["ended_by"], "interrupt");
  EXPECT_GT(read_file(dir / "run" / "trajectories.csv").size(), 500u);
  fs::remove_all(dir);
}

// --threads: the same scenario and seed give the same run folder on any number of threads.
std::string run_folder_summary_without_times(const fs::path& folder) {
  auto summary = nlohmann::json::parse(read_file(folder / "summary.json"));
  for (auto it = summary.begin(); it != summary.end();) {
    const std::string& key = it.key();
    if (key.find("wall") != std::string::npos || key.find("cpu") != std::string::npos || key == "threads")
      it = summary.erase(it);
    else
      ++it;
  }
  return summary.dump();
}

void expect_same_folders(const fs::path& a, const fs::path& b) {
  for (const char* f : {"trajectories.csv", "events.csv"}) {
    const std::string fa = read_file(a / f), fb = read_file(b / f);
    EXPECT_FALSE(fa.empty()) << (a / f);
    EXPECT_TRUE(fa == fb) << f << " differs between " << a << " and " << b;
  }
  EXPECT_EQ(run_folder_summary_without_times(a), run_folder_summary_without_times(b));
}

TEST(RunCli, AnyNumberOfThreadsGivesTheSameRunFolderForTheConvoy) {
  const fs::path dir = scratch_dir("run_threads_convoy");
  for (const char* threads : {"1", "2", "3"}) {
    const CommandResult r =
        run_rilbed("run " + shipped_scenario_arg("convoy_sim") + " --duration 30 --seed 7 --threads " + threads +
                   " --out '" + (dir / threads).string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  expect_same_folders(dir / "1", dir / "2");
  expect_same_folders(dir / "1", dir / "3");
  // The convoy bumps into things: the events compared are not empty.
  EXPECT_NE(read_file(dir / "1" / "events.csv").find("collision"), std::string::npos);
  fs::remove_all(dir);
}

TEST(RunCli, AnyNumberOfThreadsGivesTheSameRunFolderForTenThousandRobots) {
  const fs::path dir = scratch_dir("run_threads_10k");
  // sim-bench's world: 10,000 wandering Kheperas at the lab's density, with wheel slip.
  const fs::path scenario = dir / "swarm.yaml";
  std::ofstream(scenario) << "name: swarm\nfield: {width_m: 53.0, height_m: 42.4}\nduration_s: 3\n"
                             "robots:\n  - ids: 1-10000\n    pose: random\n    controller: wander\n"
                             "    noise: {slip_sd: 0.02}\n";
  for (const char* threads : {"1", "2"}) {
    const CommandResult r = run_rilbed("run '" + scenario.string() + "' --seed 11 --threads " + threads + " --out '" +
                                       (dir / threads).string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  expect_same_folders(dir / "1", dir / "2");
  fs::remove_all(dir);
}

TEST(RunCli, ThreadsMustBeAPositiveCount) {
  const CommandResult r = run_rilbed("run " + shipped_scenario_arg("convoy_sim") + " --threads 0");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--threads"), std::string::npos) << r.err;
}

TEST(SimBenchCli, PrintsItsTable) {
  const CommandResult r = run_rilbed("sim-bench --robots 50,100 --seconds 2 --threads 1,2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(
      r.out.find("| robots | threads | field m | simulated s | start-up s | wall s (median of 3) | CPU s (median) | "
                 "wall ms per simulated s |"),
      std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("| 100 | 1 |"), std::string::npos) << r.out;
  // Two threads give the same trajectories as one (the "same" column).
  EXPECT_TRUE(std::regex_search(r.out, std::regex(R"(\| 100 \| 2 \|[^\n]*\| yes \|)"))) << r.out;
  EXPECT_EQ(r.out.find("| NO |"), std::string::npos) << r.out;
  // Where the time went, one row per count and thread count, the parts' shares adding up to the run.
  EXPECT_NE(r.out.find("| robots | threads | sensing | behaviours | integration | collisions | recording | DEVS kernel "
                       "and the rest |"),
            std::string::npos)
      << r.out;
  std::smatch m;
  const std::string out = r.out;
  ASSERT_TRUE(std::regex_search(
      out, m,
      std::regex(R"(\| 100 \| 1 \| [0-9.]+ \((\d+) %\) \| [0-9.]+ \((\d+) %\) \| [0-9.]+ \((\d+) %\) \| )"
                 R"([0-9.]+ \((\d+) %\) \| [0-9.]+ \((\d+) %\) \| [0-9.]+ \((\d+) %\) \|)")))
      << out;
  int total = 0;
  for (int i = 1; i <= 6; ++i) total += std::stoi(m[i]);
  EXPECT_NEAR(total, 100, 4) << out;  // each share rounded
  EXPECT_GT(std::stoi(m[1]), 0) << "sensing took no time: " << out;
  // And how much slower the timed run was than the untimed ones.
  EXPECT_TRUE(std::regex_search(out, std::regex(R"(\| 100 \| 2 \|[^\n]* %\) \| [+-]\d+ % \|\n)"))) << out;
  // --no-split leaves the timers and their table out.
  const CommandResult plain = run_rilbed("sim-bench --robots 50 --seconds 1 --repeat 1 --no-split");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_EQ(plain.out.find("Where the time goes"), std::string::npos) << plain.out;
}

}  // namespace
}  // namespace rilbed::e2e

// The run as a library: a RunSession made in code (as Python and sweeps will make one)
// runs a scenario and a batch, writes their folders, and says what was wrong with options
// that do not go together, without a command line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "run/batch_summary.hpp"
#include "session/run_session.hpp"

namespace rilbed::session {
namespace {

namespace fs = std::filesystem;

fs::path shipped(const std::string& name) { return fs::path(RILBED_SOURCE_DIR) / "scenarios" / (name + ".yaml"); }

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rilbed_session_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

// A session whose lines are kept, not printed.
struct Quiet {
  std::vector<std::string> lines;
  SessionOutput output() {
    SessionOutput o;
    o.print = [this](const std::string& line) { lines.push_back(line); };
    o.notice = [this](const std::string& line) { lines.push_back(line); };
    return o;
  }
};

TEST(RunSession, RunsAScenarioAndWritesItsFolder) {
  SessionOptions o;
  o.scenario = shipped("wander");
  o.duration_s = 5.0;
  o.seed = 3;
  o.out = scratch("one").string();
  Quiet quiet;
  const SessionResult r = RunSession(o, quiet.output()).run();
  ASSERT_EQ(r.status, SessionResult::Status::kOk) << r.error;
  ASSERT_EQ(r.runs.size(), 1u);
  EXPECT_EQ(r.runs[0].seed, 3u);
  EXPECT_DOUBLE_EQ(r.runs[0].simulated_s, 5.0);
  EXPECT_EQ(r.runs[0].ended_by, "duration");
  for (const char* file : {"trajectories.csv", "events.csv", "summary.json", "trajectories.svg"}) {
    EXPECT_TRUE(fs::exists(fs::path(o.out) / file)) << file;
  }
  ASSERT_FALSE(quiet.lines.empty());
  EXPECT_EQ(quiet.lines.front().rfind("seed 3: no convoy;", 0), 0u) << quiet.lines.front();
  fs::remove_all(o.out);
}

TEST(RunSession, ABatchsSummaryIsWhatItsBatchJsonHolds) {
  SessionOptions o;
  o.scenario = shipped("convoy_sim");
  o.duration_s = 20.0;
  o.seed = 11;
  o.seeds = 3;
  o.jobs = 2;
  o.out = scratch("batch").string();
  Quiet quiet;
  const SessionResult r = RunSession(o, quiet.output()).run();
  ASSERT_EQ(r.status, SessionResult::Status::kOk) << r.error;
  ASSERT_TRUE(r.batch);
  EXPECT_EQ(r.batch->runs, 3);
  EXPECT_EQ(r.batch->seeds(), (std::vector<std::uint64_t>{11, 12, 13}));
  for (const std::uint64_t seed : r.batch->seeds()) {
    EXPECT_TRUE(fs::exists(fs::path(o.out) / ("seed_" + std::to_string(seed)) / "summary.json")) << seed;
  }
  std::string error;
  const auto read = run::read_batch_summary(fs::path(o.out) / "batch.json", error);
  ASSERT_TRUE(read) << error;
  EXPECT_EQ(run::to_json(*read), run::to_json(*r.batch));
  // The table is the last thing printed: its header, separator and row.
  ASSERT_FALSE(quiet.lines.empty());
  EXPECT_NE(quiet.lines.back().find("| convoy_sim | distributed | 3 |"), std::string::npos) << quiet.lines.back();
  fs::remove_all(o.out);
}

TEST(RunSession, OptionsThatDoNotGoTogetherAreAUsageProblem) {
  Quiet quiet;
  SessionOptions record_a_batch;
  record_a_batch.scenario = shipped("wander");
  record_a_batch.seeds = 2;
  record_a_batch.record = (scratch("rec") / "run.lcm").string();
  SessionResult r = RunSession(record_a_batch, quiet.output()).run();
  EXPECT_EQ(r.status, SessionResult::Status::kUsage);
  EXPECT_NE(r.error.find("--record records one run"), std::string::npos) << r.error;
  SessionOptions fast_real;
  fast_real.scenario = shipped("convoy_mixed");
  fast_real.fast = true;
  r = RunSession(fast_real, quiet.output()).run();
  EXPECT_EQ(r.status, SessionResult::Status::kUsage);
  EXPECT_NE(r.error.find("are real and move in wall-clock time"), std::string::npos) << r.error;
  SessionOptions missing;
  missing.scenario = "/nonexistent/scenario.yaml";
  r = RunSession(missing, quiet.output()).run();
  EXPECT_EQ(r.status, SessionResult::Status::kFailed);
  EXPECT_NE(r.error.find("/nonexistent/scenario.yaml"), std::string::npos) << r.error;
}

TEST(RunSession, AnInterruptEndsTheRunCleanly) {
  std::atomic<bool> interrupt{true};  // raised before the run begins: it ends at its first step
  SessionOptions o;
  o.scenario = shipped("wander");
  o.interrupt = &interrupt;
  Quiet quiet;
  const SessionResult r = RunSession(o, quiet.output()).run();
  ASSERT_EQ(r.status, SessionResult::Status::kOk) << r.error;
  ASSERT_EQ(r.runs.size(), 1u);
  EXPECT_EQ(r.runs[0].ended_by, "interrupt");
  EXPECT_LT(r.runs[0].simulated_s, 1.0);
}

}  // namespace
}  // namespace rilbed::session

// Robots from parts end to end: the wedge bot example of docs/describe-a-robot.md copied out
// of the repository and run by the real binary beside rilbed's shipped e-puck and square
// robots; a broken model file refused with its file, line and key; emulated real square
// robots seen by the emulated camera on their bodies and stopped at the end.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "lcm_namespace.hpp"
#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

std::string quoted(const fs::path& p) {
  std::string q = "'";  // piece by piece: GCC 12's false -Wrestrict (PR 105329)
  q += p.string();
  q += "'";
  return q;
}

// The robot ids in a run folder's trajectories.csv.
std::set<int> robots_in(const fs::path& run) {
  std::istringstream in(read_file(run / "trajectories.csv"));
  std::string line;
  std::getline(in, line);  // the header
  std::set<int> ids;
  while (std::getline(in, line)) {
    const auto comma = line.find(',');
    ids.insert(std::stoi(line.substr(comma + 1)));
  }
  return ids;
}

TEST(RobotModelsCli, TheWedgeBotExampleRunsBesideTheShippedModels) {
  const fs::path scratch = scratch_dir("robot_models");
  fs::copy(fs::path(RILBED_SOURCE_DIR) / "examples" / "robots" / "wedge_bot", scratch / "wedge_bot",
           fs::copy_options::recursive);
  const fs::path scenario = scratch / "wedge_bot" / "mixed_team.yaml";
  const CommandResult run = run_rilbed("run " + quoted(scenario) + " --fast --seed 2 --out " + quoted(scratch / "run"));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto summary = nlohmann::json::parse(read_file(scratch / "run" / "summary.json"));
  EXPECT_LT(summary["max_overlap_m"].get<double>(), 1e-6);
  EXPECT_EQ(robots_in(scratch / "run"), (std::set<int>{1, 2, 3, 4, 5, 6, 7}));
  // The same seed, the same run.
  ASSERT_EQ(run_rilbed("run " + quoted(scenario) + " --fast --seed 2 --out " + quoted(scratch / "again")).exit_code, 0);
  EXPECT_EQ(read_file(scratch / "run" / "trajectories.csv"), read_file(scratch / "again" / "trajectories.csv"));

  // In agent processes (on a bus inside a network namespace of the test's own), which read
  // the scenario's model files as the run does: the same run.
  std::ofstream(scenario, std::ios::app) << "agents: {processes: 2}\n";
  const fs::path agents_out = scratch / "agents";
  const int status = in_namespace(scratch / "wedge_bot", "\"$R\" run mixed_team.yaml --fast --seed 2 --out '" +
                                                             agents_out.string() + "' --lcm \"$URL\" > run.txt 2>&1\n");
  ASSERT_EQ(status, 0) << read_file(scratch / "wedge_bot" / "run.txt");
  EXPECT_EQ(read_file(scratch / "run" / "trajectories.csv"), read_file(agents_out / "trajectories.csv"));

  // A lab's edit that breaks its model: refused, naming the scenario's line, the model
  // file, its line and its key.
  std::ofstream(scratch / "wedge_bot" / "wedge_bot.yaml")
      << "name: wedge bot\nbody:\n  outline_m: [[0.065, 0.0], [-0.025, 0.035], [0.0, 0.0], [-0.025, -0.035]]\n";
  const CommandResult broken = run_rilbed("run " + quoted(scenario) + " --fast --out " + quoted(scratch / "broken"));
  EXPECT_NE(broken.exit_code, 0);
  EXPECT_NE(
      broken.err.find("mixed_team.yaml:15: robots[0].model: " + (scratch / "wedge_bot" / "wedge_bot.yaml").string() +
                      ":3: body.outline_m: the body: outline is not convex"),
      std::string::npos)
      << broken.err;
  fs::remove_all(scratch);
}

TEST(RobotModelsCli, EmulatedRealSquaresAreSeenOnTheirBodiesAndStopped) {
  const fs::path scratch = scratch_dir("robot_models_real");
  std::ofstream(scratch / "real_squares.yaml") << R"(name: real_squares
field: {width_m: 1.5, height_m: 1.2}
duration_s: 3
camera: {emulate: true}
robots:
  - {id: 1, kind: real, model: square, controller: wander, link: {emulate: true}, pose: [0.4, 0.6, 0]}
  - {id: 2, kind: real, model: epuck, controller: wander, link: {emulate: true}, pose: [1.0, 0.6, 180]}
  - {id: 3, model: square, controller: wander, pose: [0.75, 0.3, 90]}
)";
  const CommandResult run =
      run_rilbed("run " + quoted(scratch / "real_squares.yaml") + " --seed 1 --out " + quoted(scratch / "run"));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string events = read_file(scratch / "run" / "events.csv");
  // Seen from the first frames on, and never lost.
  EXPECT_NE(events.find("health,1,0,unseen -> ok"), std::string::npos) << events;
  EXPECT_NE(events.find("health,2,0,unseen -> ok"), std::string::npos) << events;
  EXPECT_EQ(events.find("ok -> unseen", events.find("unseen -> ok")), std::string::npos) << events;
  // Both stopped at the end, each acknowledging its stop.
  for (const char* id : {"robot 1: ", "robot 2: "}) {
    const auto at = run.err.find(id);
    ASSERT_NE(at, std::string::npos) << run.err;
    EXPECT_NE(run.err.find("stopped (the robot acknowledged D,0,0)", at), std::string::npos) << run.err;
  }
  fs::remove_all(scratch);
}

}  // namespace
}  // namespace rilbed::e2e

// Python controllers through the real binary: the shipped Python convoy runs and forms;
// an exception stops the real robot, keeps the run folder and exits 1 with the traceback;
// --on-controller-error stop-robot lets the run go on; the same classes, per robot and
// vectorised, run in `rilbed agent` processes and give the in-process run's trajectories.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "lcm_namespace.hpp"
#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

const fs::path kPython = fs::path(RILBED_SOURCE_DIR) / "examples" / "python";
const fs::path kFaulty = fs::path(RILBED_SOURCE_DIR) / "tests" / "python" / "controllers" / "faulty.py";

// What a shell command must set for /usr/bin/python3 to load rilbed's module when this
// test runs under the sanitizers (`./run asan`): the interpreter is not instrumented, so
// the sanitizers' runtimes (this process's own, read from /proc/self/maps) must be loaded
// first, and CPython's lifetime allocations are not the module's leaks. Empty otherwise.
std::string sanitizer_preload() {
  std::ifstream maps("/proc/self/maps");
  std::string line, asan, ubsan;
  while (std::getline(maps, line)) {
    const auto slash = line.find('/');
    if (slash == std::string::npos) continue;
    const std::string path = line.substr(slash);
    const std::string name = fs::path(path).filename().string();
    if (name.rfind("libasan.so", 0) == 0) asan = path;
    if (name.rfind("libubsan.so", 0) == 0) ubsan = path;
  }
  if (asan.empty()) return "";
  return "LD_PRELOAD='" + asan + (ubsan.empty() ? "" : ":" + ubsan) + "' ASAN_OPTIONS=detect_leaks=0 ";
}

std::string quoted(const fs::path& p) {
  std::string q = "'";  // piece by piece: GCC 12's false -Wrestrict (PR 105329)
  q += p.string();
  q += "'";
  return q;
}

TEST(PythonCli, TheShippedPythonConvoyRunsAndForms) {
  const fs::path out = scratch_dir("python_convoy");
  const CommandResult r = run_rilbed("run " + shipped_scenario_arg("convoy_py") +
                                     " --fast --stop-when-formed --seed 2 --out " + quoted(out / "run"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string summary = read_file(out / "run" / "summary.json");
  EXPECT_NE(summary.find("\"convoy_size\": 8"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"formed\": true"), std::string::npos) << summary;
  EXPECT_NE(read_file(out / "run" / "trajectories.csv").find(",follow"), std::string::npos);
  // The port does what the C++ convoy does, operation for operation: the same run.
  const CommandResult cpp = run_rilbed("run " + shipped_scenario_arg("convoy_sim") +
                                       " --fast --stop-when-formed --seed 2 --out " + quoted(out / "cpp"));
  ASSERT_EQ(cpp.exit_code, 0) << cpp.err;
  EXPECT_EQ(read_file(out / "run" / "trajectories.csv"), read_file(out / "cpp" / "trajectories.csv"));
  fs::remove_all(out);
}

TEST(PythonCli, ControllersListsAPythonFilesClassesOrSaysWhyItCannot) {
  const CommandResult r = run_rilbed("controllers --python " + quoted(kPython / "wander.py"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| `wander.Wander` | A Braitenberg wanderer"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| `wander.SwarmWander` | Wander for a whole swarm"), std::string::npos) << r.out;
  const CommandResult broken =
      run_rilbed("controllers --python " + quoted(kFaulty.parent_path() / "does_not_import.py"));
  EXPECT_EQ(broken.exit_code, 1);
  EXPECT_NE(broken.err.find("does_not_import.py: it does not import:"), std::string::npos) << broken.err;
  EXPECT_NE(broken.err.find("SyntaxError: expected ':'"), std::string::npos) << broken.err;
}

// A real (emulated) Khepera under a Python controller that raises at t = 2 s.
void write_failing_scenario(const fs::path& file, const std::string& extra = "") {
  std::ofstream(file) << "field: {width_m: 1.0, height_m: 1.0}\n"
                         "camera: {emulate: true}\n"
                         "robots:\n"
                         "  - id: 1\n"
                         "    kind: real\n"
                         "    pose: [0.5, 0.5, 0]\n"
                         "    link: {emulate: true}\n"
                         "    controller: {python: "
                      << kFaulty.string()
                      << ", class: RaisesAtTwoSeconds}\n"
                         "    params: {robot: 1}\n"
                      << extra;
}

TEST(PythonCli, AnExceptionStopsTheRealRobotAndEndsTheRunWithItsTraceback) {
  const fs::path scratch = scratch_dir("python_failure");
  write_failing_scenario(scratch / "failing.yaml");
  const CommandResult r = run_rilbed("run " + quoted(scratch / "failing.yaml") + " --duration 5 --no-place --out " +
                                     quoted(scratch / "run"));
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.err.find("robot 1's controller faulty.py: RaisesAtTwoSeconds raised an error:"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("faulty.py\", line 19, in broken_sensor_model"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ZeroDivisionError: division by zero"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("robot 1 (emulated): last speed 0 0"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::exists(scratch / "run" / "trajectories.csv"));
  EXPECT_NE(
      read_file(scratch / "run" / "summary.json").find("robot 1's controller faulty.py: RaisesAtTwoSeconds raised"),
      std::string::npos)
      << read_file(scratch / "run" / "summary.json");

  // Stop-robot: the robot stands with behaviour `error`, the run goes to its end.
  const CommandResult s =
      run_rilbed("run " + quoted(scratch / "failing.yaml") +
                 " --duration 4 --no-place --on-controller-error stop-robot --out " + quoted(scratch / "run2"));
  EXPECT_EQ(s.exit_code, 0) << s.out << s.err;
  const std::string events = read_file(scratch / "run2" / "events.csv");
  EXPECT_NE(events.find(",controller,1,0,\"error, robot stopped: robot 1's controller faulty.py"), std::string::npos)
      << events;
  EXPECT_NE(read_file(scratch / "run2" / "trajectories.csv").find(",error"), std::string::npos);
  EXPECT_NE(read_file(scratch / "run2" / "summary.json").find("\"controller_failed\": [\n    1\n  ]"),
            std::string::npos)
      << read_file(scratch / "run2" / "summary.json");
  fs::remove_all(scratch);
}

TEST(PythonCli, PythonClassesRunInAgentProcessesAsInTheRunsOwn) {
  const fs::path scratch = scratch_dir("python_agents");
  for (const std::string cls : {"Wander", "SwarmWander"}) {
    const fs::path dir = scratch / cls;  // a namespace script's folder each
    fs::create_directories(dir);
    const std::string body =
        "name: wander_agents\nduration_s: 6\nfield: {width_m: 1.5, height_m: 1.2, walls: true}\n"
        "robots:\n  - ids: 1-6\n    pose: random\n    controller: {python: " +
        (kPython / "wander.py").string() + ", class: " + cls +
        "}\n    sensors:\n      proximity: {range_m: 0.05, noise_sd: 3}\n";
    std::ofstream(dir / "local.yaml") << body;
    std::ofstream(dir / "agents.yaml") << body << "agents: {processes: 2}\n";
    const CommandResult local =
        run_rilbed("run " + quoted(dir / "local.yaml") + " --fast --seed 3 --out " + quoted(dir / "local"));
    ASSERT_EQ(local.exit_code, 0) << local.err;
    const int status =
        in_namespace(dir, "\"$R\" run agents.yaml --fast --seed 3 --out agents --lcm \"$URL\" > run.txt 2>&1\n");
    ASSERT_EQ(status, 0) << read_file(dir / "run.txt");
    const std::string trajectories = read_file(dir / "local" / "trajectories.csv");
    EXPECT_NE(trajectories.find(",avoid"), std::string::npos) << cls;
    EXPECT_EQ(trajectories, read_file(dir / "agents" / "trajectories.csv")) << cls;
  }
  fs::remove_all(scratch);
}

// rilbed.run's overrides reach the agent processes: they get the scenario the run read,
// not the file's, and the run gives the in-process run's trajectories.
TEST(PythonCli, ARunFromPythonGivesItsAgentProcessesTheScenarioItRead) {
  const fs::path dir = scratch_dir("python_run_agents");
  std::ofstream(dir / "wander.yaml")
      << "name: wander_agents\nduration_s: 5\nfield: {width_m: 1.5, height_m: 1.2, walls: "
         "true}\nrobots:\n  - ids: 1-4\n    pose: random\n    controller: {python: "
      << (kPython / "wander.py").string()
      << ", class: Wander}\n    params: {speed_mps: 0.05}\n    sensors:\n      "
         "proximity: {range_m: 0.05}\n";
  std::ofstream(dir / "runs.py") << "import sys, rilbed\n"
                                    "url = sys.argv[1]\n"
                                    "fast = {'robots.0.params.speed_mps': 0.2}\n"
                                    "rilbed.run('wander.yaml', seed=4, out='local', overrides=fast)\n"
                                    "rilbed.run('wander.yaml', seed=4, out='agents', lcm_url=url,\n"
                                    "           overrides=dict(fast, **{'agents': {'processes': 2}}))\n"
                                    "rilbed.run('wander.yaml', seed=4, out='slow')\n";
  const fs::path python_dir = fs::path(RILBED_BINARY).parent_path() / "python";
  const int status = in_namespace(dir, sanitizer_preload() + "PYTHONPATH='" + python_dir.string() +
                                           "' /usr/bin/python3 runs.py \"$URL\" > runs.txt 2>&1\n");
  ASSERT_EQ(status, 0) << read_file(dir / "runs.txt");
  const std::string local = read_file(dir / "local" / "trajectories.csv");
  EXPECT_EQ(local, read_file(dir / "agents" / "trajectories.csv"));
  EXPECT_NE(local, read_file(dir / "slow" / "trajectories.csv"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rilbed::e2e

// Plug-in libraries end to end: the examples of docs/write-a-controller.md, copied out of
// the repository and built there against the build's SDK exactly as the page says (CMake
// with find_package(rilbed), and the C one with pkg-config too), then run by the real binary
// in its process, on two threads and in an agent process; and what the loader and the run
// say when a library or its controller is wrong, with a real (emulated) robot stopped.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "lcm_namespace.hpp"
#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

const fs::path kSdk = fs::path(RILBED_BINARY).parent_path() / "sdk";
const fs::path kExamples = fs::path(RILBED_SOURCE_DIR) / "examples" / "controllers";
const fs::path kSensorExamples = fs::path(RILBED_SOURCE_DIR) / "examples" / "sensors";
const fs::path kActuatorExamples = fs::path(RILBED_SOURCE_DIR) / "examples" / "actuators";

std::string quoted(const fs::path& p) {
  std::string q = "'";  // piece by piece: GCC 12's false -Wrestrict (PR 105329)
  q += p.string();
  q += "'";
  return q;
}

// Runs `command` through /bin/sh in `dir`; its exit status, with stdout and stderr in `log`.
int shell_in(const fs::path& dir, const std::string& command, std::string& log) {
  const fs::path out = dir / "shell.log";
  const std::string line = "cd " + quoted(dir) + " && { " + command + " ; } >" + quoted(out) + " 2>&1 </dev/null";
  const int status = std::system(line.c_str());
  log = read_file(out);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The example folder `name` copied into `scratch`, as a lab copies it to start its own.
fs::path copy_example(const fs::path& scratch, const std::string& name, const fs::path& from = kExamples) {
  const fs::path to = scratch / name;
  fs::copy(from / name, to, fs::copy_options::recursive);
  fs::remove_all(to / "build");
  return to;
}

// CMake, as docs/write-a-controller.md says: configure with the SDK on CMAKE_PREFIX_PATH, build.
void cmake_build(const fs::path& dir, const std::string& build = "build") {
  std::string log;
  ASSERT_EQ(
      shell_in(dir, "cmake -B " + build + " -DCMAKE_PREFIX_PATH=" + quoted(kSdk) + " && cmake --build " + build, log),
      0)
      << log;
}

// The trajectories of a run folder without the behaviour column (the C controller names
// its behaviours c0 and c1, its C++ twin cruise and avoid).
std::string poses_of(const fs::path& run) {
  std::istringstream in(read_file(run / "trajectories.csv"));
  std::string line, out;
  int behaviour_column = -1;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream cells_in(line);
    for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
    if (behaviour_column < 0) {
      for (std::size_t i = 0; i < cells.size(); ++i) {
        if (cells[i] == "behaviour") behaviour_column = static_cast<int>(i);
      }
    }
    for (std::size_t i = 0; i < cells.size(); ++i) {
      if (static_cast<int>(i) != behaviour_column) out += cells[i] + ",";
    }
    out += "\n";
  }
  return out;
}

CommandResult run_in(const fs::path& dir, const std::string& args) {
  return run_rilbed("run " + quoted(dir / "arena.yaml") + " --fast --seed 4 --duration 8 " + args);
}

TEST(PluginsCli, TheExamplesBuildOutOfTreeAgainstTheSdkAndRun) {
  const fs::path scratch = scratch_dir("plugins");
  const fs::path c = copy_example(scratch, "braitenberg_c");
  const fs::path cpp = copy_example(scratch, "braitenberg_cpp");
  // The C example with pkg-config alone, the C++ one with CMake; the C one with CMake as well.
  std::string log;
  ASSERT_EQ(shell_in(c,
                     "mkdir -p build && cc -shared -fPIC -O2 $(PKG_CONFIG_PATH=" + quoted(kSdk / "lib" / "pkgconfig") +
                         " pkg-config --cflags rilbed) braitenberg.c -o build/braitenberg.so",
                     log),
            0)
      << log;
  cmake_build(cpp);
  cmake_build(c, "cmake_build");
  ASSERT_TRUE(fs::exists(c / "cmake_build" / "braitenberg.so"));

  const CommandResult listed = run_rilbed("controllers --library " + quoted(cpp / "build" / "braitenberg_cpp.so"));
  ASSERT_EQ(listed.exit_code, 0) << listed.err;
  EXPECT_NE(listed.out.find("| `braitenberg_cpp` | `cruise_mps` | m/s | 0.08 | 0 to 0.5 |"), std::string::npos)
      << listed.out;

  // In rilbed's process: the C library gives the built-in c:braitenberg's run exactly, the
  // C++ twin the same poses; on two threads and in an agent process the same again.
  const CommandResult c_run = run_in(c, "--out " + quoted(scratch / "c"));
  ASSERT_EQ(c_run.exit_code, 0) << c_run.err;
  std::string builtin = read_file(c / "arena.yaml");
  builtin.replace(builtin.find("{library: build/braitenberg.so, name: braitenberg}"),
                  std::string("{library: build/braitenberg.so, name: braitenberg}").size(), "c:braitenberg");
  fs::create_directories(scratch / "builtin");
  std::ofstream(scratch / "builtin" / "arena.yaml") << builtin;
  ASSERT_EQ(run_in(scratch / "builtin", "--out " + quoted(scratch / "builtin_run")).exit_code, 0);
  EXPECT_EQ(read_file(scratch / "c" / "trajectories.csv"), read_file(scratch / "builtin_run" / "trajectories.csv"));

  const CommandResult cpp_run = run_in(cpp, "--out " + quoted(scratch / "cpp"));
  ASSERT_EQ(cpp_run.exit_code, 0) << cpp_run.err;
  EXPECT_EQ(poses_of(scratch / "c"), poses_of(scratch / "cpp"));
  EXPECT_NE(read_file(scratch / "cpp" / "trajectories.csv").find(",cruise"), std::string::npos);

  const CommandResult threads = run_in(cpp, "--threads 2 --out " + quoted(scratch / "cpp_threads"));
  ASSERT_EQ(threads.exit_code, 0) << threads.err;
  EXPECT_EQ(read_file(scratch / "cpp" / "trajectories.csv"), read_file(scratch / "cpp_threads" / "trajectories.csv"));

  // In agent processes (on a bus inside a network namespace of the test's own).
  for (const fs::path& example : {c, cpp}) {
    std::ofstream(example / "arena.yaml", std::ios::app) << "agents: {processes: 2}\n";
    const fs::path out = scratch / (example.filename().string() + "_agents");
    const int status = in_namespace(example, "\"$R\" run arena.yaml --fast --seed 4 --duration 8 --out '" +
                                                 out.string() + "' --lcm \"$URL\" > run.txt 2>&1\n");
    ASSERT_EQ(status, 0) << read_file(example / "run.txt");
    const fs::path in_process = scratch / (example == c ? "c" : "cpp");
    EXPECT_EQ(read_file(in_process / "trajectories.csv"), read_file(out / "trajectories.csv")) << example;
  }
  fs::remove_all(scratch);
}

// The track sensor rebuilt as a plug-in outside rilbed: scenarios/track_following.yaml with
// its elements from the library gives the built-in's trajectories byte for byte, seed for
// seed, also when its parameter file is YAML; a wrong parameter file is refused with its
// file, line and key.
TEST(PluginsCli, ThePluginTrackSensorGivesTheBuiltInsRunByteForByte) {
  const fs::path scratch = scratch_dir("sensor_plugin");
  const fs::path example = copy_example(scratch, "track_sensor", kSensorExamples);
  cmake_build(example);
  const std::string builtin = shipped_scenario_arg("track_following");
  for (const int seed : {1, 2}) {
    const std::string tail = " --fast --seed " + std::to_string(seed) + " --duration 30 --out ";
    const CommandResult b = run_rilbed("run " + builtin + tail + quoted(scratch / ("builtin" + std::to_string(seed))));
    ASSERT_EQ(b.exit_code, 0) << b.err;
    const CommandResult p = run_rilbed("run " + quoted(example / "track_following.yaml") + tail +
                                       quoted(scratch / ("plugin" + std::to_string(seed))));
    ASSERT_EQ(p.exit_code, 0) << p.err;
    const std::string trajectories = read_file(scratch / ("builtin" + std::to_string(seed)) / "trajectories.csv");
    EXPECT_NE(trajectories.find(",follow"), std::string::npos);  // the robots found the tape
    EXPECT_EQ(trajectories, read_file(scratch / ("plugin" + std::to_string(seed)) / "trajectories.csv")) << seed;
  }
  // The same parameters as YAML.
  std::ofstream(example / "element.yaml") << "Sensor:\n  Height: 8\n  Inclination: 0\n  Cone Angle: 30\n"
                                             "  Precision: 16\n  Coverage: 15\n  Max Value: 255\n  Error Level: 5\n";
  std::string yaml = read_file(example / "track_following.yaml");
  for (std::size_t at; (at = yaml.find("element.txt")) != std::string::npos;) yaml.replace(at, 11, "element.yaml");
  std::ofstream(example / "yaml.yaml") << yaml;
  const CommandResult y = run_rilbed("run " + quoted(example / "yaml.yaml") + " --fast --seed 1 --duration 30 --out " +
                                     quoted(scratch / "yaml"));
  ASSERT_EQ(y.exit_code, 0) << y.err;
  EXPECT_EQ(read_file(scratch / "builtin1" / "trajectories.csv"), read_file(scratch / "yaml" / "trajectories.csv"));

  std::ofstream(example / "bad.txt") << "Sensor = {\n    Height = 8\n    Cone Angel = 30\n}\n";
  std::string bad = read_file(example / "track_following.yaml");
  for (std::size_t at; (at = bad.find("element.txt")) != std::string::npos;) bad.replace(at, 11, "bad.txt");
  std::ofstream(example / "bad.yaml") << bad;
  const CommandResult refused = run_rilbed("run " + quoted(example / "bad.yaml") + " --fast");
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find("robots[0].sensors.models[0].parameters: " + (example / "bad.txt").string() +
                             ":3: Cone Angel: the sensor model track_element has no such parameter"),
            std::string::npos)
      << refused.err;
  fs::remove_all(scratch);
}

// The built-in differential drive with slip rebuilt as an actuator plug-in: wander.yaml with
// robots 1-5's wheels from it gives the built-in's trajectories byte for byte; an actuator
// on a real robot, or beside `noise`, is refused where the scenario gives it.
TEST(PluginsCli, ThePluginDifferentialDriveGivesTheBuiltInsRunByteForByte) {
  const fs::path scratch = scratch_dir("actuator_plugin");
  const fs::path example = copy_example(scratch, "differential_drive", kActuatorExamples);
  cmake_build(example);
  for (const int seed : {1, 3}) {
    const std::string tail = " --fast --seed " + std::to_string(seed) + " --duration 30 --out ";
    const std::string b = "builtin" + std::to_string(seed), p = "plugin" + std::to_string(seed);
    ASSERT_EQ(run_rilbed("run " + shipped_scenario_arg("wander") + tail + quoted(scratch / b)).exit_code, 0);
    const CommandResult run = run_rilbed("run " + quoted(example / "wander.yaml") + tail + quoted(scratch / p));
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(read_file(scratch / b / "trajectories.csv"), read_file(scratch / p / "trajectories.csv")) << seed;
  }
  const std::string actuator = "    actuator: {library: " + (example / "build" / "differential_drive.so").string() +
                               ", name: differential_drive}\n";
  std::ofstream(scratch / "real.yaml") << "camera: {emulate: true}\nrobots:\n  - id: 1\n    kind: real\n"
                                          "    link: {emulate: true}\n"
                                       << actuator;
  const CommandResult real = run_rilbed("run " + quoted(scratch / "real.yaml") + " --duration 1 --no-place");
  EXPECT_EQ(real.exit_code, 1);
  EXPECT_NE(real.err.find("real.yaml:6: robots[0].actuator: a real robot's wheels are its own"), std::string::npos)
      << real.err;
  std::ofstream(scratch / "both.yaml") << "robots:\n  - id: 1\n    noise: {slip_sd: 0.1}\n" << actuator;
  const CommandResult both = run_rilbed("run " + quoted(scratch / "both.yaml") + " --fast --duration 1");
  EXPECT_EQ(both.exit_code, 1);
  EXPECT_NE(both.err.find("give either `noise` (the built-in drive's) or `actuator`, not both"), std::string::npos)
      << both.err;
  fs::remove_all(scratch);
}

// A scenario that names a library wrongly is refused where it names it; the cause is the loader's.
TEST(PluginsCli, ALibraryThatWillNotServeIsRefusedWithItsCause) {
  const fs::path scratch = scratch_dir("plugin_errors");
  const fs::path test_plugins = fs::path(RILBED_BINARY).parent_path() / "test_plugins";
  struct Case {
    std::string controller;
    std::string error;
  };
  const std::vector<Case> cases = {
      {"{library: missing.so, name: x}", "missing.so: no such file"},
      {"{library: " + (test_plugins / "test_classes.so").string() + ", name: nonesuch}",
       "holds no controller 'nonesuch' (it holds cruise, failing, needs_track)"},
      {"{library: " + (test_plugins / "broken_1.so").string() + ", name: fine}",
       "ABI version 999, this rilbed loads version 1"},
      {"{library: " + (test_plugins / "test_classes.so").string() + ", name: needs_track}", "needs `sensors: track:`"},
      {"{library: " + (test_plugins / "test_classes.so").string() + ", name: failing}", "needs parameter 'fail_at_ms'"},
      {"{library: " + (test_plugins / "test_classes.so").string() + ", namee: cruise}",
       "controller.namee: unknown key"},
  };
  for (const Case& c : cases) {
    std::ofstream(scratch / "bad.yaml") << "robots:\n  - id: 1\n    controller: " << c.controller << "\n";
    const CommandResult r = run_rilbed("run " + quoted(scratch / "bad.yaml") + " --fast --duration 1");
    EXPECT_EQ(r.exit_code, 1) << c.controller;
    EXPECT_NE(r.err.find("bad.yaml:3: robots[0]"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.error), std::string::npos) << r.err;
  }
  const CommandResult listed = run_rilbed("controllers --library " + quoted(scratch / "missing.so"));
  EXPECT_EQ(listed.exit_code, 1);
  EXPECT_NE(listed.err.find("missing.so: no such file"), std::string::npos) << listed.err;
  fs::remove_all(scratch);
}

// A controller that fails in the middle of a run ends it with an error that names the robot
// and the library, and the real robot it drove is stopped.
TEST(PluginsCli, AControllerThatFailsEndsTheRunAndStopsTheRealRobot) {
  const fs::path scratch = scratch_dir("plugin_failure");
  const fs::path library = fs::path(RILBED_BINARY).parent_path() / "test_plugins" / "test_classes.so";
  std::ofstream(scratch / "failing.yaml") << "field: {width_m: 1.0, height_m: 1.0}\n"
                                             "camera: {emulate: true}\n"
                                             "robots:\n"
                                             "  - id: 1\n"
                                             "    kind: real\n"
                                             "    pose: [0.5, 0.5, 0]\n"
                                             "    link: {emulate: true}\n"
                                             "    controller: {library: "
                                          << library.string()
                                          << ", name: failing}\n"
                                             "    params: {fail_at_ms: 1500}\n";
  const CommandResult r = run_rilbed("run " + quoted(scratch / "failing.yaml") + " --duration 5 --no-place");
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.err.find("controller failing of robot 1 (" + library.string() +
                       "): its step at t = 1500 ms failed: "
                       "the gyro is gone"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find("robot 1 (emulated): last speed 0 0"), std::string::npos) << r.out;

  // The same controller in an agent process: the process ends with the error, the run
  // finds it lost, stops the robot and goes on to its end.
  std::ofstream(scratch / "failing.yaml", std::ios::app) << "agents: {processes: 1, dead_after_ms: 300}\n";
  const int status = in_namespace(
      scratch, "\"$R\" run failing.yaml --duration 4 --no-place --out run --lcm \"$URL\" > run.txt 2>&1\n");
  const std::string run_text = read_file(scratch / "run.txt");
  EXPECT_EQ(status, 0) << run_text;
  EXPECT_NE(run_text.find("the gyro is gone"), std::string::npos) << run_text;
  EXPECT_NE(run_text.find("robot 1 (emulated): last speed 0 0"), std::string::npos) << run_text;
  EXPECT_NE(read_file(scratch / "run" / "events.csv").find("stopped answering"), std::string::npos)
      << read_file(scratch / "run" / "events.csv");
  fs::remove_all(scratch);
}

}  // namespace
}  // namespace rilbed::e2e

// Python controllers in rilbed's own process (the embedded interpreter): a scenario names
// a class, the parser imports it, the run steps it per robot or per swarm, and each way a
// lab's Python can go wrong ends in an error that names the file, the class and the robot.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "agents/basic_controllers.hpp"
#include "python/python_controllers.hpp"
#include "run/scenario.hpp"
#include "run/simulation.hpp"

namespace rilbed::run {
namespace {

const std::string kExamples = RILBED_SOURCE_DIR "/examples/python";
const std::string kFaulty = RILBED_SOURCE_DIR "/tests/python/controllers";

// A scenario of `robots` virtual Kheperas with IR sensors in the lab's field, each with
// `controller` (YAML) and `params`, read as if it were a file in tests/python.
Scenario scenario_with(const std::string& controller, const std::string& params = "{}", int robots = 4,
                       double duration_s = 6.0) {
  const std::string yaml =
      "name: py\nduration_s: " + std::to_string(duration_s) +
      "\nfield: {width_m: 1.5, height_m: 1.2, walls: true}\nrobots:\n  - ids: 1-" + std::to_string(robots) +
      "\n    pose: random\n    controller: " + controller + "\n    params: " + params +
      "\n    noise: {slip_sd: 0.02}\n    sensors:\n      proximity: {range_m: 0.05, noise_sd: 3}\n";
  return parse_scenario(yaml, RILBED_SOURCE_DIR "/tests/python/py.yaml");
}

std::string error_of(const std::string& controller, const std::string& params = "{}") {
  try {
    const Scenario s = scenario_with(controller, params);
    RunOptions o;
    run_scenario(s, o);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

std::string faulty(const std::string& class_name) {
  return "{python: controllers/faulty.py, class: " + class_name + "}";
}

RunResult run_of(const Scenario& s, std::uint64_t seed = 5,
                 ControllerErrorAction on_error = ControllerErrorAction::kEndRun) {
  RunOptions o;
  o.seed = seed;
  o.keep_in_memory = true;
  o.on_controller_error = on_error;
  return run_scenario(s, o);
}

TEST(PythonControllers, APerRobotClassDrivesAsItsCppTwin) {
  const Scenario py = scenario_with("{python: ../../examples/python/wander.py, class: Wander}");
  EXPECT_EQ(py.robots[0].controller.name, "wander.Wander");
  EXPECT_EQ(py.robots[0].controller.library, kExamples + "/wander.py");
  const Scenario cpp = scenario_with("wander");
  const RunResult a = run_of(py), b = run_of(cpp);
  ASSERT_FALSE(a.trajectory.empty());
  // Operation for operation the same wanderer: the same trajectories, bit for bit.
  EXPECT_EQ(a.trajectory_digest, b.trajectory_digest);
  bool avoided = false;
  for (const TrajectorySample& t : a.trajectory) avoided = avoided || t.behaviour == "avoid";
  EXPECT_TRUE(avoided);
}

TEST(PythonControllers, AVectorisedClassStepsTheSwarmInOneCallAndDrivesAsItsCppTwin) {
  const Scenario py = scenario_with("{python: ../../examples/python/wander.py, class: SwarmWander}", "{}", 12);
  const Scenario cpp = scenario_with("wander", "{}", 12);
  const RunResult a = run_of(py, 9), b = run_of(cpp, 9);
  EXPECT_EQ(a.trajectory_digest, b.trajectory_digest);
}

TEST(PythonControllers, ParamsReachTheClassAndItsRefusalNamesTheRobot) {
  const Scenario fast = scenario_with("{python: ../../examples/python/wander.py, class: Wander}", "{speed_mps: 0.2}");
  const Scenario slow = scenario_with("{python: ../../examples/python/wander.py, class: Wander}", "{speed_mps: 0.05}");
  EXPECT_NE(run_of(fast).trajectory_digest, run_of(slow).trajectory_digest);
  const std::string e = error_of(faulty("RefusesParams"), "{gain: -1}");
  EXPECT_NE(e.find("robot 1: controller faulty.RefusesParams: faulty.py: RefusesParams refused its params for robot 1"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("ValueError: gain must be positive, not -1.0"), std::string::npos) << e;
}

TEST(PythonControllers, FilesAndClassesThatCannotBeUsedAreScenarioErrors) {
  std::string e = error_of("{python: controllers/missing.py, class: X}");
  EXPECT_NE(e.find("py.yaml:7: robots[0].controller: Python controller " + kFaulty + "/missing.py: no such file"),
            std::string::npos)
      << e;
  e = error_of("{python: controllers/does_not_import.py, class: Broken}");
  EXPECT_NE(e.find("does_not_import.py: it does not import:"), std::string::npos) << e;
  EXPECT_NE(e.find("line 5"), std::string::npos) << e;
  EXPECT_NE(e.find("SyntaxError"), std::string::npos) << e;
  e = error_of(faulty("Missing"));
  EXPECT_NE(e.find("it has no class 'Missing' (its rilbed.Controller classes: RaisesAtTwoSeconds, ReturnsText"),
            std::string::npos)
      << e;
  e = error_of(faulty("NotAController"));
  EXPECT_NE(e.find("'NotAController' is not a class that subclasses rilbed.Controller"), std::string::npos) << e;
  e = error_of(faulty("NoStep"));
  EXPECT_NE(e.find("NoStep defines neither step(self, inp) nor step_all(self, inp)"), std::string::npos) << e;
  e = error_of(faulty("BothSteps"));
  EXPECT_NE(e.find("BothSteps defines both step and step_all"), std::string::npos) << e;
  e = error_of("{python: controllers/faulty.py}");
  EXPECT_NE(e.find("robots[0].controller.class: give the name of a class"), std::string::npos) << e;
}

TEST(PythonControllers, AnExceptionEndsTheRunWithItsTracebackAndTheRobot) {
  const Scenario s = scenario_with(faulty("RaisesAtTwoSeconds"));
  const std::filesystem::path out = std::filesystem::temp_directory_path() / "rilbed_py_error_run";
  std::filesystem::remove_all(out);
  RunOptions o;
  o.out_dir = out;
  std::string e;
  try {
    run_scenario(s, o);
  } catch (const std::exception& error) {  // the DEVS kernel names the model around the controller's error
    e = error.what();
  }
  EXPECT_NE(e.find("robot 2's controller faulty.py: RaisesAtTwoSeconds raised an error:"), std::string::npos) << e;
  EXPECT_NE(e.find(kFaulty + "/faulty.py\", line 19, in broken_sensor_model"), std::string::npos) << e;
  EXPECT_NE(e.find("ZeroDivisionError: division by zero"), std::string::npos) << e;
  // What was recorded up to the error is kept, and says how the run ended.
  EXPECT_TRUE(std::filesystem::exists(out / "trajectories.csv"));
  EXPECT_TRUE(std::filesystem::exists(out / "summary.json"));
  std::filesystem::remove_all(out);
}

TEST(PythonControllers, StopRobotStopsOnlyTheFailingRobotAndRecordsWhy) {
  const Scenario s = scenario_with(faulty("RaisesAtTwoSeconds"));
  RunOptions o;
  o.keep_in_memory = true;
  o.on_controller_error = ControllerErrorAction::kStopRobot;
  const RunResult r = run_scenario(s, o);
  EXPECT_EQ(r.ended_by, "duration");
  EXPECT_EQ(r.controller_failed, std::vector<int>{2});
  // Robot 2 stands with behaviour "error" from t = 2 s; the others drive on.
  const TrajectorySample* last2 = nullptr;
  const TrajectorySample* last1 = nullptr;
  for (const TrajectorySample& t : r.trajectory) {
    if (t.id == 2) last2 = &t;
    if (t.id == 1) last1 = &t;
  }
  ASSERT_TRUE(last1 && last2);
  EXPECT_EQ(last2->behaviour, "error");
  EXPECT_EQ(last1->behaviour, "python");
}

TEST(PythonControllers, AnswersOfTheWrongShapeOrTypeAreNamed) {
  std::string e = error_of(faulty("ReturnsText"));
  EXPECT_NE(e.find("robot 1's controller faulty.py: ReturnsText returned 'forward'; return (left, right) wheel speeds"),
            std::string::npos)
      << e;
  e = error_of(faulty("ReturnsThree"));
  EXPECT_NE(e.find("ReturnsThree returned (1, 2, 3); return (left, right)"), std::string::npos) << e;
  e = error_of(faulty("ReturnsNaN"));
  EXPECT_NE(e.find("robot 1's controller faulty.py: ReturnsNaN's left wheel is not a finite number"), std::string::npos)
      << e;
  e = error_of(faulty("SwarmWrongShape"));
  EXPECT_NE(e.find("the controller faulty.py: SwarmWrongShape of robots 1, 2, 3, 4: step_all returned [[1, 2, 3]"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("return an array of shape (4, 2)"), std::string::npos) << e;
}

TEST(PythonControllers, AFailingSwarmStopsEveryRobotOfItUnderStopRobot) {
  const Scenario s = scenario_with(faulty("SwarmRaises"));
  const RunResult r = run_of(s, 3, ControllerErrorAction::kStopRobot);
  EXPECT_EQ(r.controller_failed, (std::vector<int>{1, 2, 3, 4}));
  EXPECT_EQ(r.ended_by, "duration");
  EXPECT_EQ(r.trajectory.back().behaviour, "error");
  EXPECT_NE(error_of(faulty("SwarmRaises")).find("RuntimeError: the swarm's model diverged"), std::string::npos);
}

TEST(PythonControllers, ARealTimeRunCountsStepsLongerThanThePeriod) {
  const Scenario s = scenario_with(faulty("Slow"), "{}", 1, 0.5);
  RunOptions o;
  o.realtime = true;
  o.rt_factor = 1.0;
  o.keep_in_memory = true;
  const RunResult r = run_scenario(s, o);
  EXPECT_GE(r.controller_overruns, 3);
  EXPECT_EQ(r.summary()["controller_overruns"], r.controller_overruns);
}

}  // namespace
}  // namespace rilbed::run

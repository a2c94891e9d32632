// Robots from parts: the robot model files shipped in robots/, `model:` in a scenario with
// overrides, every error a model file can give, and whole runs of robots with outlines.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <fstream>
#include <string>

#include "run/robot_description.hpp"
#include "run/scenario.hpp"
#include "run/simulation.hpp"

namespace rilbed::run {
namespace {

// A scratch folder for scenarios and model files, removed at the end.
class RobotFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("rilbed_robots_" + std::to_string(::getpid()) + "_" +
                                                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_ / "robots");
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  void write(const std::string& name, const std::string& text) { std::ofstream(dir_ / name) << text; }
  Scenario scenario(const std::string& robots) {
    const bool real = robots.find("kind: real") != std::string::npos;
    write("s.yaml", "field: {width_m: 1.0, height_m: 1.0}\n" + std::string(real ? "camera: {emulate: true}\n" : "") +
                        "robots:\n" + robots);
    return load_scenario(dir_ / "s.yaml");
  }
  // The error loading a scenario with these robots gives, or "" when it loads.
  std::string error_of(const std::string& robots) {
    try {
      scenario(robots);
    } catch (const ScenarioError& e) {
      return e.what();
    }
    return "";
  }
  std::filesystem::path dir_;
};

TEST_F(RobotFiles, TheShippedModelsAreFoundByNameOrPath) {
  const Scenario s = scenario(
      "  - {id: 1, model: epuck, controller: wander}\n"
      "  - {id: 2, model: robots/square.yaml, controller: wander}\n"
      "  - {id: 3, model: khepera2, controller: wander}\n");
  const RobotBody& epuck = s.robots[0].body;
  EXPECT_EQ(epuck.name, "e-puck");
  EXPECT_DOUBLE_EQ(epuck.radius_m, 0.035);
  EXPECT_DOUBLE_EQ(epuck.wheel_radius_m, 0.0205);
  EXPECT_TRUE(epuck.outline_m.empty());
  const RobotBody& square = s.robots[1].body;
  ASSERT_EQ(square.outline_m.size(), 4u);
  EXPECT_DOUBLE_EQ(square.radius_m, 0.035 * std::sqrt(2.0));  // its bounding disc
  EXPECT_DOUBLE_EQ(square.wheel_base_m, 0.06);
  EXPECT_EQ(std::filesystem::path(square.file).filename(), "square.yaml");
  // Khepera II's file is what a robot without a model is.
  RobotBody khepera = s.robots[2].body;
  EXPECT_EQ(khepera.name, "Khepera II");
  khepera.name = RobotBody{}.name;
  khepera.file.clear();
  EXPECT_EQ(khepera, RobotBody{});
  EXPECT_EQ(s.robots[2].sensors, environment::SensorSuiteConfig{});
}

TEST_F(RobotFiles, AScenarioEntryOverridesPartsOfItsModel) {
  const Scenario s = scenario(
      "  - id: 1\n    model: epuck\n    controller: wander\n"
      "    body: {radius_m: 0.03}\n    wheels: {base_m: 0.05}\n    sensors: {proximity: false}\n"
      "  - id: 2\n    model: epuck\n    controller: none\n"
      "    body: {outline_m: [[0.04, 0], [-0.02, 0.03], [-0.02, -0.03]]}\n");
  EXPECT_DOUBLE_EQ(s.robots[0].body.radius_m, 0.03);
  EXPECT_DOUBLE_EQ(s.robots[0].body.wheel_base_m, 0.05);
  EXPECT_DOUBLE_EQ(s.robots[0].body.wheel_radius_m, 0.0205);  // the model's
  EXPECT_FALSE(s.robots[0].sensors.proximity.has_value());    // the entry's sensors replace the model's
  EXPECT_EQ(s.robots[1].body.outline_m.size(), 3u);
}

TEST_F(RobotFiles, AModelFilesLinkIsTheDefaultOfARealRobotsLink) {
  const Scenario s = scenario(
      "  - {id: 1, kind: real, model: epuck, controller: none, link: {emulate: true}}\n"
      "  - {id: 2, kind: real, model: epuck, controller: none, link: {emulate: true, model: khepera2}}\n");
  EXPECT_EQ(s.robots[0].link->model, "epuck");
  EXPECT_NEAR(*s.robots[0].link->speed_unit_mps, 0.000128805, 1e-12);
  EXPECT_EQ(s.robots[1].link->model, "khepera2");
  EXPECT_FALSE(s.robots[1].link->speed_unit_mps);  // the e-puck's units are not a Khepera's
  EXPECT_NE(error_of("  - {id: 1, kind: real, controller: none, link: {emulate: true, model: nxt}}\n")
                .find("robots[0].link.model: is khepera2 or epuck, not 'nxt'"),
            std::string::npos);
}

TEST_F(RobotFiles, EveryErrorNamesTheFileTheLineAndTheKey) {
  EXPECT_NE(error_of("  - {id: 1, model: nosuch}\n")
                .find("s.yaml:3: robots[0].model: no robot model file 'nosuch' (looked for "),
            std::string::npos);
  const std::string m = (dir_ / "robots" / "m.yaml").string();
  auto model_error = [&](const std::string& text) {
    write("robots/m.yaml", text);
    return error_of("  - {id: 1, model: robots/m.yaml}\n");
  };
  struct Case {
    const char* file;
    std::string expected;
  };
  const Case cases[] = {
      {"colour: red\n", m + ":1: colour: unknown key"},
      {"body: {outline_m: [[0.1, 0.1], [-0.1, 0.1], [0, 0], [-0.1, -0.1], [0.1, -0.1]]}\n",
       m + ":1: body.outline_m: the body: outline is not convex"},
      {"body:\n  outline_m: [[0.1, 0.1], [0.2, 0.1], [0.2, 0.2]]\n",
       m + ":2: body.outline_m: the body: outline must hold"},
      {"body: {outline_m: [[0.1, 0.1], [0.2]]}\n", m + ":1: body.outline_m: must be a point [x_m, y_m]"},
      {"body: {radius_m: 0.03, outline_m: [[0.1, 0], [0, 0.1], [-0.1, -0.1]]}\n",
       "give either radius_m (a disc) or outline_m"},
      {"body: {radius_m: -0.03}\n", m + ":1: body.radius_m: must be greater than 0"},
      {"body: {radius_m: 3}\n", "body.radius_m: is at most 1 m"},
      {"wheels: {base_m: 0}\n", m + ":1: wheels.base_m: must be greater than 0"},
      {"wheels: {radius_m: abc}\n", "wheels.radius_m: must be a number, not 'abc'"},
      {"link: {model: nxt}\n", m + ":1: link.model: is khepera2 or epuck, not 'nxt'"},
      {"link: {speed_unit_mps: 0}\n", "link.speed_unit_mps: must be greater than 0"},
      {"sensors: {sonar: {}}\n", m + ":1: sensors.sonar: unknown key"},
      {"body: [1, 2\n", m + ":2: not YAML"},
      {"", m + ":1: the robot model file is empty"},
  };
  for (const Case& c : cases) {
    const std::string e = model_error(c.file);
    EXPECT_NE(e.find(c.expected), std::string::npos) << "file: " << c.file << "\nerror: " << e;
    EXPECT_EQ(e.rfind((dir_ / "s.yaml").string() + ":3: robots[0].model: ", 0), 0u)
        << e;  // where the scenario named it
  }
  // Overrides in the scenario are checked alike, against the scenario's lines.
  EXPECT_NE(error_of("  - id: 1\n    body: {outline_m: [[0.1, 0.1], [-0.1, -0.1], [-0.1, 0.1], [0.1, -0.1]]}\n")
                .find("s.yaml:4: robots[0].body.outline_m: the body: outline crosses itself"),
            std::string::npos);
}

TEST_F(RobotFiles, SquareRobotsRunWithTheirOutlinesAndNeverOverlap) {
  write("s.yaml",
        "field: {width_m: 0.8, height_m: 0.8}\nduration_s: 30\n"
        "obstacles: [{polygon: [[0.35, 0.35], [0.45, 0.35], [0.45, 0.45], [0.35, 0.45]]}]\n"
        // Blind wanderers (no IR ring): they drive into the walls and each other.
        "robots:\n  - {ids: 1-6, model: square, controller: wander, sensors: {proximity: false}}\n"
        "  - {ids: 7-8, model: epuck, controller: wander, sensors: {proximity: false}}\n");
  const Scenario s = load_scenario(dir_ / "s.yaml");
  RunOptions o;
  o.seed = 5;
  o.keep_in_memory = true;
  o.out_dir = dir_ / "run";
  const RunResult r = run_scenario(s, o);
  // The picture draws each square's outline and each e-puck's disc at its last pose.
  std::ifstream svg_in(dir_ / "run" / "trajectories.svg");
  const std::string svg((std::istreambuf_iterator<char>(svg_in)), std::istreambuf_iterator<char>());
  std::size_t outlines = 0;
  for (auto at = svg.find("<polygon class=\"virtual\""); at != std::string::npos;
       at = svg.find("<polygon class=\"virtual\"", at + 1))
    ++outlines;
  EXPECT_EQ(outlines, 6u);
  EXPECT_LT(r.max_overlap_m, 1e-6);
  EXPECT_DOUBLE_EQ(r.simulated_s, 30.0) << r.ended_by;
  EXPECT_GT(r.collisions, 0);  // wanderers in a small field meet walls and each other
  // A square's centre gets nearer the walls than its bounding disc (49.5 mm) would let it.
  double nearest_wall_m = 1.0;
  for (const auto& sample : r.trajectory) {
    if (sample.id > 6) continue;
    const Vec2 p = sample.pose.position_m;
    nearest_wall_m = std::min({nearest_wall_m, p.x, p.y, 0.8 - p.x, 0.8 - p.y});
  }
  EXPECT_LT(nearest_wall_m, 0.049);
  EXPECT_GE(nearest_wall_m, 0.035 - 1e-6);
}

TEST_F(RobotFiles, KheperaFromItsFileRunsAsTheBuiltInKhepera) {
  auto run_with = [&](const std::string& model) {
    write("s.yaml", "field: {width_m: 1.0, height_m: 1.0}\nduration_s: 20\nrobots:\n  - {ids: 1-5, controller: wander" +
                        model + "}\n");
    RunOptions o;
    o.seed = 9;
    o.keep_in_memory = true;
    return run_scenario(load_scenario(dir_ / "s.yaml"), o).trajectory;
  };
  const auto builtin = run_with(""), from_file = run_with(", model: khepera2");
  ASSERT_EQ(builtin.size(), from_file.size());
  for (std::size_t k = 0; k < builtin.size(); ++k) {
    ASSERT_EQ(builtin[k].pose.position_m.x, from_file[k].pose.position_m.x) << k;
    ASSERT_EQ(builtin[k].pose.heading_rad, from_file[k].pose.heading_rad) << k;
  }
}

}  // namespace
}  // namespace rilbed::run

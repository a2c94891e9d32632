// A controller registered by a lab (here, the test) goes through the whole run: the
// parser checks its parameters where they stand in the file, the run makes it from the
// scenario's registry, and the registry's table and JSON (what `rilbed controllers` and
// the web editor show) list it.
#include <gtest/gtest.h>

#include <string>

#include "agents/builtin_controllers.hpp"
#include "agents/controller_registry.hpp"
#include "run/scenario.hpp"
#include "run/simulation.hpp"
#include "support/spinner_controller.hpp"

namespace rilbed::run {
namespace {

using agents::ControllerRegistry;
using rilbed::testing::spinner_entry;

std::shared_ptr<const ControllerRegistry> with_spinner() {
  ControllerRegistry r = agents::builtin_controllers();
  r.add(spinner_entry());
  return std::make_shared<const ControllerRegistry>(std::move(r));
}

std::string spinner_scenario(const std::string& params) {
  return "name: spin\nduration_s: 2\nrobots:\n  - id: 1\n    pose: [0.5, 0.5, 0]\n    controller: spinner\n" +
         (params.empty() ? std::string() : "    params: " + params + "\n");
}

std::string error_of(const std::string& yaml, std::shared_ptr<const ControllerRegistry> registry = {}) {
  try {
    parse_scenario(yaml, "spin.yaml", std::move(registry));
  } catch (const ScenarioError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(RegisteredController, IsParsedBuiltListedAndServed) {
  const auto registry = with_spinner();
  // The parser knows it and checks its parameters against its entry.
  const Scenario s = parse_scenario(spinner_scenario("{turn_radps: 2}"), "spin.yaml", registry);
  EXPECT_EQ(s.robots[0].controller.name, "spinner");
  EXPECT_EQ(error_of(spinner_scenario("{turn_radps: 9}"), registry),
            "spin.yaml:7: robots[0].params.turn_radps: must be 0 to 5 (rad/s), not 9");
  EXPECT_EQ(error_of(spinner_scenario("{turn_rate: 2}"), registry),
            "spin.yaml:7: robots[0].params.turn_rate: controller spinner has no parameter 'turn_rate' (it takes "
            "turn_radps)");
  // Without it in the registry the same file names the controllers there are.
  EXPECT_NE(error_of(spinner_scenario("")).find("spin.yaml:6: robots[0].controller: unknown controller 'spinner'"),
            std::string::npos);
  // The run makes it from the scenario's registry: the robot turns on the spot.
  RunOptions options;
  options.keep_in_memory = true;
  const RunResult r = run_scenario(s, options);
  ASSERT_FALSE(r.trajectory.empty());
  EXPECT_EQ(r.trajectory.back().behaviour, "spin");
  EXPECT_NEAR(r.trajectory.back().pose.position_m.x, 0.5, 1e-3);
  EXPECT_GT(std::abs(wrap_rad_pi(r.trajectory.back().pose.heading_rad)), 0.5);
  // `rilbed controllers` and the web editor's JSON list it with its parameter.
  EXPECT_NE(agents::controllers_table(*registry).find(
                "| `spinner` | `turn_radps` | rad/s | 1 | 0 to 5 | how fast it turns |"),
            std::string::npos);
  const nlohmann::ordered_json json = agents::controllers_json(*registry);
  const auto entry = std::find_if(json.begin(), json.end(), [](const auto& e) { return e["name"] == "spinner"; });
  ASSERT_NE(entry, json.end());
  EXPECT_EQ((*entry)["summary"], "turns on the spot");
  EXPECT_EQ((*entry)["origin"], "the test");
  ASSERT_EQ((*entry)["params"].size(), 1u);
  EXPECT_EQ((*entry)["params"][0]["name"], "turn_radps");
  EXPECT_EQ((*entry)["params"][0]["unit"], "rad/s");
  EXPECT_EQ((*entry)["params"][0]["default"], 1.0);
  EXPECT_EQ((*entry)["params"][0]["min"], 0.0);
  EXPECT_EQ((*entry)["params"][0]["max"], 5.0);
}

TEST(RegisteredController, MissingParametersAndSensorsAreNamedWhereTheRobotStands) {
  // A missing required parameter names the robot's params line.
  const std::string yaml = "robots:\n  - id: 1\n    controller: goto\n    params: {x_m: 0.3}\n";
  EXPECT_NE(error_of(yaml).find("spin.yaml:4: robots[0].params: controller goto needs parameter 'y_m'"),
            std::string::npos);
  // A controller that needs a sensor the robot lacks is named where the robot is.
  const std::string no_track = "robots:\n  - id: 1\n    controller: track_follow\n";
  EXPECT_NE(error_of(no_track).find("spin.yaml:3: robots[0].controller: track_follow needs `sensors: track:`"),
            std::string::npos);
}

}  // namespace
}  // namespace rilbed::run

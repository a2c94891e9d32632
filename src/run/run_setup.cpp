#include "run/run_setup.hpp"

#include <random>

#include "agents/builtin_controllers.hpp"

namespace rilbed::run {

std::unique_ptr<agents::Controller> make_controller(const Scenario& scenario, const RobotSpec& spec,
                                                    agents::ControllerGroups* groups) {
  const std::string where =
      scenario.source.string() + ":" + std::to_string(spec.line) + ": robot " + std::to_string(spec.id);
  const std::shared_ptr<const agents::ControllerRegistry> registry =
      scenario.controllers ? scenario.controllers : agents::default_controllers();
  const agents::ControllerEntry* entry = registry->find(spec.controller.name);
  if (!entry) {
    throw ScenarioError(where + ": unknown controller '" + spec.controller.name +
                        "' (known: " + registry->names_text() + ")");
  }
  // A scenario read from a file was checked already; one built in code is checked here.
  if (const auto problem = agents::check_params(*entry, spec.controller.params)) {
    throw ScenarioError(where + ": " + (problem->key.empty() ? "" : "params." + problem->key + ": ") +
                        problem->problem);
  }
  if (const auto sensor = agents::missing_sensor(*entry, spec.sensors)) {
    throw ScenarioError(where + ": " + entry->name + " needs `sensors: " + *sensor + ":`");
  }
  const agents::ControllerParams params(entry->params, spec.controller.params);
  try {
    return entry->make(agents::ControllerContext{spec.id, params, spec.sensors, scenario.convoy, groups});
  } catch (const std::invalid_argument& e) {
    throw ScenarioError(where + ": controller " + entry->name + ": " + e.what());
  }
}

std::vector<Pose2> start_poses(const Scenario& scenario, std::uint64_t seed) {
  std::seed_seq pose_seed{seed, std::uint64_t{0x706f736573}};
  std::mt19937_64 pose_rng(pose_seed);
  return draw_initial_poses(scenario, pose_rng);
}

}  // namespace rilbed::run

// What a run makes from its scenario before it starts: each robot's controller (from the
// scenario's controller registry) and the robots' start poses for a seed.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "agents/controller.hpp"
#include "agents/controller_group.hpp"
#include "core/geometry.hpp"
#include "run/scenario.hpp"

namespace rilbed::run {

/// Makes the controller named in `spec` from the scenario's registry (nullptr for "none";
/// a convoy agent gets its own controller in central mode too, idle until the console
/// switches the run to distributed). Throws ScenarioError naming the robot for an unknown
/// name, a parameter its entry does not allow, or a sensor the controller needs.
/// `groups` (may be null; must outlive the controller): the run's groups of controllers
/// that step together, which a vectorised controller joins (agents::ControllerGroups).
std::unique_ptr<agents::Controller> make_controller(const Scenario& scenario, const RobotSpec& spec,
                                                    agents::ControllerGroups* groups = nullptr);

/// The robots' start poses of a run with `seed` (in scenario.robots' order): fixed poses
/// as given, the others drawn from the seed (draw_initial_poses), exactly as
/// run_scenario() places them. Real robots are placed there before a run (RealRobots).
std::vector<Pose2> start_poses(const Scenario& scenario, std::uint64_t seed);

}  // namespace rilbed::run

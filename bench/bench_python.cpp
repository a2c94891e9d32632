// Python controllers against their C++ twins, in one run of this program: the real-time
// factor of a swarm of wandering Kheperas (8 IR sensors, collisions) driven by rilbed's
// C++ `wander`, by the per-robot Python class examples/python/wander.py:Wander, and by the
// vectorised SwarmWander; then what one call costs (a Python step per robot-step, one
// step_all per control step). Prints Markdown tables; `./run bench` runs it.
#include <cstdio>
#include <string>
#include <vector>

#include <patchlevel.h>
#include <CLI/CLI.hpp>

#include "agents/basic_controllers.hpp"
#include "agents/builtin_controllers.hpp"
#include "agents/controller_group.hpp"
#include "machine.hpp"
#include "python/python_controllers.hpp"
#include "run/scenario.hpp"
#include "run/simulation.hpp"
#include "timing.hpp"

namespace rilbed::bench {
namespace {

const std::string kWanderFile = RILBED_SOURCE_DIR "/examples/python/wander.py";

// The registry with both Python wanderers in it.
std::shared_ptr<const agents::ControllerRegistry> registry_with_python() {
  agents::ControllerRegistry r = agents::builtin_controllers();
  for (const char* cls : {"Wander", "SwarmWander"}) {
    core::Result<agents::ControllerEntry> e = python::load_python_controller(kWanderFile, cls);
    if (!e) throw std::runtime_error(e.error());
    r.add(std::move(*e));
  }
  return std::make_shared<const agents::ControllerRegistry>(std::move(r));
}

struct Row {
  std::string controller;
  int robots = 0;
  run::RunResult result;
};

Row timed_run(const std::string& controller, int robots, double seconds,
              const std::shared_ptr<const agents::ControllerRegistry>& registry) {
  run::Scenario s = run::wandering_scenario(robots, seconds);
  s.source = "(bench_python)";
  s.controllers = registry;
  for (run::RobotSpec& r : s.robots) r.controller.name = controller;
  run::RunOptions o;
  o.seed = 7;
  o.duration_s = seconds;
  o.overlap_check_us = 1'000'000;
  return {controller, robots, run::run_scenario(s, o)};
}

void print_rows(const std::vector<Row>& rows) {
  std::printf(
      "| controller | robots | simulated s | wall s | CPU s | real-time factor (CPU) | us per robot-step (CPU) | cost "
      "against C++ wander | same trajectories as C++ |\n| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- "
      "|\n");
  for (const Row& row : rows) {
    const run::RunResult& r = row.result;
    const Row* twin = nullptr;
    for (const Row& other : rows) {
      if (other.robots == row.robots && other.controller == "wander") twin = &other;
    }
    const double steps = row.robots * r.simulated_s / 0.1;
    std::printf("| %s | %d | %.1f | %.2f | %.2f | %.1f | %.2f | %.2fx | %s |\n", row.controller.c_str(), row.robots,
                r.simulated_s, r.run_wall_s, r.run_cpu_s, r.simulated_s / r.run_cpu_s, 1e6 * r.run_cpu_s / steps,
                twin ? r.run_cpu_s / twin->result.run_cpu_s : 0.0,
                twin ? (twin->result.trajectory_digest == r.trajectory_digest ? "yes" : "NO") : "-");
  }
}

// A robot's input as a wandering Khepera sees it near a wall.
agents::ControlInput sample_input(int id) {
  agents::ControlInput in;
  in.t_us = 1'000'000;
  in.robot_id = id;
  in.sensors.proximity = environment::ProximityValues{0, 40, 300, 500, 20, 0, 0, 0};
  in.pose = Pose2{{0.3, 0.4}, 0.5};
  return in;
}

// CPU microseconds per call of `call`, the median of 5 rounds of `calls` calls.
template <typename Call>
double us_per_call(int calls, Call call) {
  std::vector<double> rounds;
  for (int round = 0; round < 5; ++round) {
    const double t0 = thread_cpu_ms();
    for (int i = 0; i < calls; ++i) call(i);
    rounds.push_back(1000.0 * (thread_cpu_ms() - t0) / calls);
  }
  std::sort(rounds.begin(), rounds.end());
  return rounds[2];
}

void print_call_costs(const agents::ControllerRegistry& registry) {
  std::printf(
      "\nOne call, CPU us (median of 5 rounds): a controller's step for one robot (the input copied into a "
      "rilbed.Input, the answer checked), and the vectorised class's step for n robots (n inputs gathered, the "
      "NumPy arrays built, step_all, the (n, 2) answer checked).\n\n| call | robots per call | us per call | us per "
      "robot |\n| --- | ---: | ---: | ---: |\n");
  const agents::ControllerParams no_params({}, {});
  const environment::SensorSuiteConfig sensors;
  const agents::ConvoyConfig convoy;
  const agents::ControlInput in = sample_input(1);
  agents::WanderController cpp;
  const double cpp_us = us_per_call(200000, [&](int) { (void)cpp.step(in); });
  std::printf("| C++ wander step | 1 | %.3f | %.3f |\n", cpp_us, cpp_us);
  const auto per_robot = registry.find("wander.Wander")->make({1, no_params, sensors, convoy, nullptr});
  const double py_us = us_per_call(20000, [&](int) { (void)per_robot->step(in); });
  std::printf("| Python Wander.step | 1 | %.2f | %.2f |\n", py_us, py_us);
  for (const int n : {1, 1000, 100000}) {
    agents::ControllerGroups groups;
    std::vector<std::unique_ptr<agents::Controller>> members;
    for (int id = 1; id <= n; ++id) {
      members.push_back(registry.find("wander.SwarmWander")->make({id, no_params, sensors, convoy, &groups}));
    }
    agents::ControllerGroup& group = *members.front()->group();
    std::vector<agents::ControlInput> inputs;
    for (int id = 1; id <= n; ++id) inputs.push_back(sample_input(id));
    const int calls = n >= 100000 ? 5 : n >= 1000 ? 200 : 20000;
    const double us = us_per_call(calls, [&](int) {
      for (const agents::ControlInput& i : inputs) group.gather(i);
      (void)group.step_gathered();
    });
    std::printf("| Python SwarmWander.step_all | %d | %.1f | %.3f |\n", n, us, us / n);
  }
}

}  // namespace
}  // namespace rilbed::bench

int main(int argc, char** argv) {
  using namespace rilbed;
  CLI::App app{"Python controllers against their C++ twins"};
  double seconds_small = 10.0, seconds_large = 2.0;
  int small = 1000, large = 100000;
  app.add_option("--robots", small, "Robots of the per-robot comparison")->default_val(small);
  app.add_option("--swarm", large, "Robots of the vectorised comparison")->default_val(large);
  app.add_option("--seconds", seconds_small, "Simulated seconds of the per-robot runs")->default_val(seconds_small);
  app.add_option("--swarm-seconds", seconds_large, "Simulated seconds of the swarm runs")->default_val(seconds_large);
  CLI11_PARSE(app, argc, argv);
  const auto registry = bench::registry_with_python();
  std::printf("## Python controllers (bench_python)\n\n");
  std::printf(
      "Wandering Kheperas with all 8 IR sensors (noise), wheel slip 2 %%, collisions, control period 100 ms, physics "
      "step 100 ms, the lab's density (8 robots on 1.5 x 1.2 m), seed 7, one thread, no files: the whole DEVS run "
      "timed (start-up excluded), CPU time of the run's thread. The same world with rilbed's C++ `wander`, with "
      "examples/python/wander.py's Wander (a Python call per robot and control step), and with its SwarmWander "
      "(one NumPy call per control step). Python %s, in rilbed's embedded interpreter. CPU: %s.\n\n",
      PY_VERSION, bench::cpu_model().c_str());
  std::vector<bench::Row> rows;
  rows.push_back(bench::timed_run("wander", small, seconds_small, registry));
  rows.push_back(bench::timed_run("wander.Wander", small, seconds_small, registry));
  rows.push_back(bench::timed_run("wander.SwarmWander", small, seconds_small, registry));
  rows.push_back(bench::timed_run("wander", large, seconds_large, registry));
  rows.push_back(bench::timed_run("wander.SwarmWander", large, seconds_large, registry));
  bench::print_rows(rows);
  bench::print_call_costs(*registry);
  return 0;
}

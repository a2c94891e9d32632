// `rilbed quantum-bench --robots N --processes P --quanta Q --lcm URL`: paper 000's
// experiment (section 10, Table 10-1, Fig. 10-1) on rilbed's agent exchange: the time per
// time quantum of a lock-step run whose controllers run in P `rilbed agent` processes, for
// each robot count and process count given, beside the same run in one process and SPREAD's
// published figures. `--table` runs the paper's grid (1, 5, 10, ..., 40 robots over 1, 2, 4,
// 8 and 12 processes) and 1,000 robots over 8 processes.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <unistd.h>

#include "app/commands.hpp"
#include "bus/lcm_bus.hpp"
#include "bus/remote_agents.hpp"
#include "core/id_list.hpp"
#include "core/statistics.hpp"
#include "run/scenario.hpp"
#include "run/simulation.hpp"
#include "session/agent_processes.hpp"

namespace rilbed::app {

namespace {

struct QuantumBenchArgs {
  std::string robots = "40";
  std::string processes = "12";
  int quanta = 1000;
  std::string url;
  std::string prefix = "QBENCH_";
  bool table = false;
  std::uint64_t seed = 1;
  std::string condition;  // printed with the table (e.g. "10 % of LCM's packets dropped")
};

// SPREAD's Table 10-1: the processes it spawned for each robot count (13 + 7 per robot on
// average: each robot's sensors, actuators, controller and memory were processes of their own).
const std::map<int, int> kSpreadProcesses = {{1, 13},   {5, 41},   {10, 76},  {15, 111}, {20, 146},
                                             {25, 181}, {30, 216}, {35, 251}, {40, 286}};

// N wandering Kheperas (eight IR sensors, Braitenberg avoidance) at the lab's density, as
// sim-bench runs them, written as a scenario file for the agent processes to read too.
std::filesystem::path write_scenario(const std::filesystem::path& dir, int robots, int quanta) {
  const double density = 8.0 / (1.5 * 1.2);
  const double area = robots / density;
  const double width = std::sqrt(area * 1.25), height = area / width;
  const std::filesystem::path file = dir / ("qbench_" + std::to_string(robots) + ".yaml");
  std::ofstream out(file);
  out << "name: qbench-" << robots << "\n"
      << "field: {width_m: " << width << ", height_m: " << height << ", walls: true}\n"
      << "timing: {physics_step_ms: 100, control_period_ms: 100, broadcast_period_ms: 100}\n"
      << "duration_s: " << (quanta - 1) * 0.1 << "\n"
      << "robots:\n  - ids: 1-" << robots << "\n    kind: virtual\n    pose: random\n    controller: wander\n"
      << "    noise: {slip_sd: 0.02}\n    sensors:\n      proximity: {range_m: 0.05, noise_sd: 3}\n";
  return file;
}

struct Row {
  int robots = 0, processes = 0, quanta = 0;
  double ms_per_quantum = 0.0, local_ms_per_quantum = 0.0;
  double exchange_p50 = 0.0, exchange_p99 = 0.0;
  long long repeats = 0, lost = 0;
  bool same_result = false;
};

// Runs `scenario` with its controllers in the processes of `remote` (or in this process),
// timing the DEVS run alone.
run::RunResult run_once(const run::Scenario& scenario, std::uint64_t seed, run::AgentExchange* remote) {
  run::RunOptions o;
  o.seed = seed;
  o.keep_in_memory = true;
  o.remote_agents = remote;
  return run::run_scenario(scenario, o);
}

std::optional<Row> bench_one(const QuantumBenchArgs& args, lcm::LCM& lcm, lcm::LCM& answers,
                             const std::filesystem::path& dir, int robots, int processes, int quanta) {
  const std::filesystem::path file = write_scenario(dir, robots, quanta);
  run::Scenario scenario = run::load_scenario(file);
  const run::RunResult local = run_once(scenario, args.seed, nullptr);
  std::vector<int> ids;
  for (int id = 1; id <= robots; ++id) ids.push_back(id);
  session::AgentProcesses agents_here;
  std::string error;
  session::AgentLaunchConfig launch;
  launch.scenario_file = file.string();
  launch.url = args.url;
  launch.prefix = args.prefix;
  if (!agents_here.start(launch, session::place_agents(ids, processes, {}), error)) {
    spdlog::error("quantum-bench: {}", error);
    return std::nullopt;
  }
  bus::RemoteAgentsConfig config;
  config.channels = bus::Channels::with_prefix(args.prefix);
  config.scenario_name = scenario.name;
  config.robot_ids = ids;
  config.record_exchange_times = true;
  bus::RemoteAgents remote(lcm, answers, config);
  if (const auto missing =
          remote.wait_for_agents(std::chrono::seconds(20), [&] { return agents_here.ended_early(); })) {
    spdlog::error("quantum-bench: {}", *missing);
    return std::nullopt;
  }
  const run::RunResult r = run_once(scenario, args.seed, &remote);
  Row row;
  row.robots = robots;
  row.processes = processes;
  row.quanta = quanta;
  row.ms_per_quantum = r.run_wall_s * 1000.0 / quanta;
  row.local_ms_per_quantum = local.run_wall_s * 1000.0 / quanta;
  const std::vector<double>& t = remote.exchange_times_ms();
  row.exchange_p50 = percentile(t, 0.5);
  row.exchange_p99 = percentile(t, 0.99);
  row.repeats = remote.counters().repeats;
  row.lost = remote.counters().lost_processes;
  row.same_result = local.trajectory.size() == r.trajectory.size() &&
                    std::equal(local.trajectory.begin(), local.trajectory.end(), r.trajectory.begin(),
                               [](const auto& a, const auto& b) {
                                 return a.t_us == b.t_us && a.id == b.id &&
                                        a.pose.position_m.x == b.pose.position_m.x &&
                                        a.pose.position_m.y == b.pose.position_m.y && a.behaviour == b.behaviour;
                               });
  return row;
}

void print_row(const Row& r) {
  const auto spread = kSpreadProcesses.find(r.robots);
  const double bus = std::max(0.0, r.ms_per_quantum - r.local_ms_per_quantum);
  std::printf("| %d | %d | %s | %d | %.3f | %.0f | %.3f | %.3f | %.3f | %.3f (%.0f %%) | %lld | %lld | %s |\n",
              r.robots, r.processes, spread == kSpreadProcesses.end() ? "—" : std::to_string(spread->second).c_str(),
              r.quanta, r.ms_per_quantum, 1000.0 / r.ms_per_quantum, r.exchange_p50, r.exchange_p99,
              r.local_ms_per_quantum, bus, r.ms_per_quantum > 0.0 ? 100.0 * bus / r.ms_per_quantum : 0.0, r.repeats,
              r.lost, r.same_result ? "yes" : "NO");
  std::fflush(stdout);
}

int quantum_bench_command(const QuantumBenchArgs& args) {
  std::vector<std::pair<int, int>> grid;  // (robots, processes)
  std::map<int, int> quanta_of;           // robots -> quanta
  if (args.table) {
    for (int n : {1, 5, 10, 15, 20, 25, 30, 35, 40}) {
      for (int p : {1, 2, 4, 8, 12}) {
        if (p <= n) grid.emplace_back(n, p);
      }
      quanta_of[n] = args.quanta;
    }
    grid.emplace_back(1000, 8);
    quanta_of[1000] = std::max(50, args.quanta / 5);
  } else {
    const IdListResult robots = parse_id_list(args.robots, 1, 100'000, "list");
    const IdListResult processes = parse_id_list(args.processes, 1, 64, "list");
    if (!robots.ok() || !processes.ok()) {
      spdlog::error("quantum-bench: {}",
                    !robots.ok() ? "--robots: " + robots.error : "--processes: " + processes.error);
      return kExitUsage;
    }
    for (int n : robots.ids) {
      for (int p : processes.ids) {
        if (p <= n) grid.emplace_back(n, p);
      }
      quanta_of[n] = args.quanta;
    }
  }
  std::string error;
  std::unique_ptr<lcm::LCM> lcm = bus::open_lcm(args.url, error);
  std::unique_ptr<lcm::LCM> answers = lcm ? bus::open_lcm(bus::agent_reply_url(args.url), error) : nullptr;
  if (!lcm || !answers || args.url.rfind("memq://", 0) == 0) {
    spdlog::error("quantum-bench: {}",
                  lcm ? "the agents run in other processes: give a bus they reach, not memq://" : error);
    return kExitUsage;
  }
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("rilbed-qbench-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  struct Remove {
    std::filesystem::path dir;
    ~Remove() {
      std::error_code ec;
      std::filesystem::remove_all(dir, ec);
    }
  } remove{dir};
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  std::printf("## Time per quantum (rilbed quantum-bench), after paper 000 section 10\n\n");
  std::printf(
      "A lock-step run (fast mode) of N wandering Kheperas (8 IR sensors each, Braitenberg avoidance, the lab's "
      "density), their controllers in P `rilbed agent` processes on this machine (%s, %ld cores), on the bus %s%s%s. "
      "One quantum is one control step of 100 ms simulated: the processes get their robots' sensor readings and "
      "poses in one quantum_t (one per process when all would not fit in a datagram) and each answers its robots' "
      "wheel commands in one quantum_reply_t, on the next port. Timed: the whole DEVS run "
      "(world, sensors, exchange) divided by its quanta; the exchange alone (p50, p99: sending, the agents' "
      "work, the answers); the same run in one process; their difference, the bus's cost. Same result: the "
      "remote run's trajectories equal the in-process run's.\n\n",
      host, sysconf(_SC_NPROCESSORS_ONLN), args.url.c_str(), args.condition.empty() ? "" : "; ",
      args.condition.c_str());
  std::printf(
      "| robots | processes | SPREAD's processes (Table 10-1) | quanta | ms per quantum | quanta per s | exchange p50 "
      "ms | "
      "exchange p99 ms | one process: ms per quantum | bus ms per quantum (share) | repeats | lost | same result |\n");
  std::printf("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n");
  for (const auto& [n, p] : grid) {
    const auto row = bench_one(args, *lcm, *answers, dir, n, p, quanta_of[n]);
    if (!row) return kExitFailure;
    print_row(*row);
  }
  std::printf(
      "\nSPREAD (12 486 DX2 66 MHz PCs on 10 Mbit/s Ethernet, one process per sensor, actuator, controller and "
      "memory) reports its times per quantum only as a figure (Fig. 10-1), not in numbers; its best speed-up was "
      "35 robots on 12 machines about 5 times faster than on one, and the network, not the CPUs, bound it.\n");
  return 0;
}

}  // namespace

void add_quantum_bench_command(CLI::App& app) {
  auto args = std::make_shared<QuantumBenchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "quantum-bench", "Time per lock-step quantum with the controllers in agent processes (paper 000, section 10)");
  cmd->add_option("--robots", args->robots, "Robot counts, e.g. 1,5,10-40 (default 40)");
  cmd->add_option("--processes", args->processes, "Agent process counts, e.g. 1,2,4,8,12 (default 12)");
  cmd->add_option("--quanta", args->quanta, "Quanta per run (1,000 robots: a fifth of them with --table)")
      ->check(CLI::Range(10, 1'000'000));
  cmd->add_option("--lcm", args->url, "The bus the agents reach (e.g. udpm://239.255.76.67:7667?ttl=0)")->required();
  cmd->add_option("--channel-prefix", args->prefix, "Channel prefix of the bench's messages")->default_val("QBENCH_");
  cmd->add_flag("--table", args->table,
                "The paper's grid: 1, 5, ..., 40 robots over 1, 2, 4, 8, 12 processes, and 1,000 robots over 8");
  cmd->add_option("--seed", args->seed, "Seed of the start poses and sensor noise");
  cmd->add_option("--condition", args->condition,
                  "A note on the bus's condition, printed with the table (e.g. 10 % loss)");
  cmd->callback([args] { exit_code() = quantum_bench_command(*args); });
}

}  // namespace rilbed::app

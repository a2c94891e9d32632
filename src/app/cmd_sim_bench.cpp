// `rilbed sim-bench`: how fast the simulation runs with many virtual Kheperas.
#include <spdlog/spdlog.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

#include "app/commands.hpp"
#include "app/sim_bench_sensors.hpp"
#include "bus/lcm_bus.hpp"
#include "bus/run_publisher.hpp"
#include "core/id_list.hpp"
#include "run/scenario.hpp"
#include "run/simulation.hpp"

namespace rilbed::app {

namespace {

struct BenchArgs {
  std::string robots = "100,1000,10000";
  double seconds = 10.0;
  double physics_step_ms = 100.0;
  double density_per_m2 = 8.0 / (1.5 * 1.2);  // the lab's convoy: 8 robots on 1.5 x 1.2 m
  std::uint64_t seed = 1;
  int repeat = 3;
  std::vector<std::string> lcm_urls;  // also time each count with the run published on each of these buses
  bool no_split = false;              // leave the run's parts untimed (RunOptions::profile)
  std::string threads = "1";          // thread counts to time each robot count with
  std::string sensor_plugin;          // also time a plug-in sensor model against the built-in one
  std::string robot_model;            // every robot with this robot model file's body and wheels
};

// The process's peak resident set so far, MB (getrusage; Linux reports kilobytes).
double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

// N wandering Kheperas with their eight IR sensors in a field of constant density.
run::Scenario bench_scenario(int robots, const BenchArgs& args) {
  run::Scenario s = run::wandering_scenario(robots, args.seconds, args.physics_step_ms, args.density_per_m2);
  s.name = "sim-bench-" + std::to_string(robots);
  s.source = "(sim-bench)";
  if (!args.robot_model.empty()) {
    const core::Result<std::filesystem::path> file = run::find_robot_model(args.robot_model, ".");
    if (!file) throw run::ScenarioError("--robot-model: " + file.error());
    // Its body and wheels; the sensors stay the bench's IR ring, for the same work per robot.
    const run::RobotDescription d = run::read_robot_description(
        *file, [](const run::yaml_detail::Reader&) { return environment::SensorSuiteConfig{}; });
    for (run::RobotSpec& r : s.robots) r.body = d.body;
  }
  return s;
}

// Where the time of each timed run went: each part's wall ms per simulated second and its
// share of the run; the kernel's share is the rest (the DEVS coordinator's scheduling and
// routing, the world model's own bookkeeping, and the clock reads themselves).
template <class Split>
void print_splits(const std::vector<Split>& splits) {
  std::printf(
      "\nWhere the time goes (one more run of each row above, timed in parts with steady_clock, three reads "
      "per robot and step, which make that run slower: by how much, against the median of the untimed runs, is "
      "the last column; `--no-split` leaves it out): wall ms per simulated "
      "second, and the share of that run. With "
      "more than one thread, sensing and behaviours run on all threads at once: their columns are the time "
      "summed over the threads, divided by the thread count.\n\n"
      "| robots | threads | sensing | behaviours | integration | collisions | recording | DEVS kernel and the rest | "
      "timed run slower by |\n"
      "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  for (const Split& s : splits) {
    run::RunProfile p = s.profile;
    p.sensing_s /= s.threads;
    p.behaviours_s /= s.threads;
    const double parts[] = {
        p.sensing_s,
        p.behaviours_s,
        p.integration_s,
        p.collisions_s,
        p.monitor_s,
        std::max(0.0, s.run_s - p.sensing_s - p.behaviours_s - p.integration_s - p.collisions_s - p.monitor_s)};
    std::printf("| %d | %d |", s.robots, s.threads);
    for (const double part_s : parts) {
      std::printf(" %.1f (%.0f %%) |", 1000.0 * part_s / s.simulated_s, 100.0 * part_s / std::max(1e-9, s.run_s));
    }
    std::printf(" %+.0f %% |\n",
                100.0 * (s.run_s / s.simulated_s / std::max(1e-12, s.plain_wall_per_simulated_s) - 1.0));
  }
}

// One run of sim-bench: its options, the buses it also publishes on, and what it measured.
class SimBench {
 public:
  SimBench(const BenchArgs& args, std::vector<int> counts, std::vector<int> threads)
      : args_(args), counts_(std::move(counts)), thread_counts_(std::move(threads)) {}

  int run() {
    print_intro();
    if (!open_buses()) return kExitFailure;
    for (const int n : counts_) {
      if (!time_count(n)) return kExitFailure;
    }
    if (!splits_.empty()) print_splits(splits_);
    if (any_differs_) spdlog::error("runs of the same robot count gave different trajectories (the \"same\" column)");
    if (!buses_.empty()) print_bus_tables();
    return any_differs_ ? kExitFailure : 0;
  }

 private:
  struct Split {
    int robots = 0;
    int threads = 1;
    double run_s = 0.0, simulated_s = 0.0;
    double plain_wall_per_simulated_s = 0.0;  // the untimed runs' median
    run::RunProfile profile;
  };
  // With --lcm: each count also with every message of the run published on each bus
  // (nobody need listen), runs with and without it taking turns so that other load on
  // the machine falls on all alike.
  struct Bus {
    std::string url;
    std::unique_ptr<lcm::LCM> lcm;
    std::unique_ptr<bus::LcmRunPublisher> publisher;
    std::vector<std::pair<int, double>> costs;  // robots, CPU cost in per cent
    std::vector<double> core_shares;            // extra CPU per simulated second: the share of a core at real time
  };
  struct Timing {
    std::vector<double> walls, cpus, startups;
    run::RunResult r;
  };
  // One robot count's runs: per thread count, the plain runs and each bus's.
  struct CountRuns {
    explicit CountRuns(std::size_t thread_rows, std::size_t buses)
        : plain(thread_rows),
          bused(thread_rows, std::vector<Timing>(buses)),
          splits(thread_rows),
          same(thread_rows, 1) {}
    std::vector<Timing> plain;
    std::vector<std::vector<Timing>> bused;
    std::vector<Split> splits;
    std::vector<char> same;
    std::optional<std::uint64_t> first_digest;
  };

  void print_intro() const {
    const BenchArgs& args = args_;
    std::printf("## Simulation speed (rilbed sim-bench)\n\n");
    std::printf(
        "Virtual Kheperas (55 mm discs) with all 8 IR proximity sensors (cones of +-30 deg, 50 mm range, noise), "
        "the wander controller (Braitenberg avoidance), wheel slip 2 %%, collisions on (robot-robot, robot-wall), "
        "control period 100 ms, physics step %.0f ms (exact arcs, collision substeps as needed), a field of %.2f "
        "robots per m^2 (the lab's 8 robots on 1.5 x 1.2 m), random starts (seed %llu). The whole DEVS "
        "run (world model, one atomic model per agent, monitor; no files written) on the given threads (`--threads`: "
        "agents and robot motion spread over them, collisions and recording on the run's thread), timed from the "
        "first event to the last (building the world, the start-up column, excluded); wall and the CPU time of the "
        "run's threads, medians of --repeat runs; speed-up is against the same count on the fewest threads; peak "
        "memory is the process's resident peak so far (getrusage). Every run of a count, on any threads, must give the "
        "same trajectories (the \"same\" column).\n\n",
        args.physics_step_ms, args.density_per_m2, static_cast<unsigned long long>(args.seed));
    std::printf(
        "| robots | threads | field m | simulated s | start-up s | wall s (median of %d) | CPU s (median) | wall ms "
        "per "
        "simulated s | real-time factor (wall) | real-time factor (CPU) | us per robot-step (CPU) | speed-up | peak "
        "memory MB | collisions | max overlap m (each simulated s) | same |\n",
        args.repeat);
    std::printf(
        "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | "
        "--- "
        "|\n");
  }

  bool open_buses() {
    for (const std::string& url : args_.lcm_urls) {
      Bus b;
      b.url = url;
      std::string error;
      b.lcm = bus::open_lcm(url, error);
      if (!b.lcm) {
        spdlog::error("sim-bench: {}", error);
        return false;
      }
      b.publisher = std::make_unique<bus::LcmRunPublisher>(*b.lcm, bus::Channels{}, url.rfind("memq://", 0) == 0);
      buses_.push_back(std::move(b));
    }
    return true;
  }

  // Every round of one robot count, then its rows.
  bool time_count(int n) {
    const run::Scenario s = bench_scenario(n, args_);
    CountRuns runs(thread_counts_.size(), buses_.size());
    // The timed runs carry no timers (they cost 3-8 %); one more round, after them, is
    // timed in parts for the split table. Each round runs every thread count (and bus) in
    // turn, so that other load on the machine falls on all of them alike.
    const int rounds = args_.repeat + (args_.no_split ? 0 : 1);
    for (int rep = 0; rep < rounds; ++rep) {
      for (std::size_t ti = 0; ti < thread_counts_.size(); ++ti) {
        if (!time_round(s, n, ti, rep == args_.repeat, runs)) return false;
      }
    }
    print_rows(s, n, runs);
    std::fflush(stdout);
    return true;
  }

  // One round of one thread count: plain, then on each bus (the split round: plain only).
  bool time_round(const run::Scenario& s, int n, std::size_t ti, bool split_run, CountRuns& runs) {
    for (std::size_t k = 0; k <= buses_.size(); ++k) {
      if (split_run && k > 0) break;
      Timing scratch;
      Timing& t = split_run ? scratch : k == 0 ? runs.plain[ti] : runs.bused[ti][k - 1];
      run::RunOptions o;
      o.seed = args_.seed;
      o.duration_s = args_.seconds;
      o.threads = thread_counts_[ti];
      o.overlap_check_us = 1'000'000;
      if (k > 0) o.observer = buses_[k - 1].publisher.get();
      o.profile = split_run;
      try {
        t.r = run::run_scenario(s, o);
      } catch (const std::exception& e) {
        spdlog::error("{} robots: {}", n, e.what());
        return false;
      }
      if (!runs.first_digest) runs.first_digest = t.r.trajectory_digest;
      if (t.r.trajectory_digest != *runs.first_digest) runs.same[ti] = 0;
      t.walls.push_back(t.r.run_wall_s);
      t.cpus.push_back(t.r.run_cpu_s);
      t.startups.push_back(t.r.wall_s - t.r.run_wall_s);
      if (t.r.profile) add_split(runs.splits[ti], n, thread_counts_[ti], t.r);
    }
    return true;
  }

  static void add_split(Split& split, int robots, int threads, const run::RunResult& r) {
    split.robots = robots;
    split.threads = threads;
    split.run_s += r.run_wall_s;
    split.simulated_s += r.simulated_s;
    const run::RunProfile& p = *r.profile;
    split.profile.sensing_s += p.sensing_s;
    split.profile.behaviours_s += p.behaviours_s;
    split.profile.integration_s += p.integration_s;
    split.profile.collisions_s += p.collisions_s;
    split.profile.monitor_s += p.monitor_s;
  }

  void print_rows(const run::Scenario& s, int n, CountRuns& runs) {
    auto& plain = runs.plain;
    auto& bused = runs.bused;
    auto& row_splits = runs.splits;
    auto& same = runs.same;
    const std::vector<int>& thread_counts_ids = thread_counts_;
    double first_threads_wall_s = 0.0;
    for (std::size_t ti = 0; ti < thread_counts_.size(); ++ti) {
      const int threads = thread_counts_ids[ti];
      auto row = [&](Timing& t, const std::string& label) {
        std::sort(t.walls.begin(), t.walls.end());
        std::sort(t.cpus.begin(), t.cpus.end());
        std::sort(t.startups.begin(), t.startups.end());
        const double startup_s = t.startups[t.startups.size() / 2];
        const double wall_s = std::max(1e-9, t.walls[t.walls.size() / 2]);
        const double cpu_s = std::max(1e-9, t.cpus[t.cpus.size() / 2]);
        if (ti == 0 && label.empty()) first_threads_wall_s = wall_s;
        const run::RunResult& r = t.r;
        const double steps = n * r.simulated_s / 0.1;
        std::printf(
            "| %d%s | %d | %.1f x %.1f | %.1f | %.3f | %.3f | %.3f | %.1f | %.1f | %.1f | %.2f | %.2f | %.0f | %d | "
            "%.2g | %s |\n",
            n, label.c_str(), threads, s.map.field.width_m, s.map.field.height_m, r.simulated_s, startup_s, wall_s,
            cpu_s, 1000.0 * wall_s / r.simulated_s, r.simulated_s / wall_s, r.simulated_s / cpu_s, 1e6 * cpu_s / steps,
            first_threads_wall_s / wall_s, peak_rss_mb(), r.collisions, r.max_overlap_m, same[ti] ? "yes" : "NO");
        return cpu_s;
      };
      const double plain_cpu = row(plain[ti], "");
      row_splits[ti].plain_wall_per_simulated_s = plain[ti].walls[plain[ti].walls.size() / 2] / plain[ti].r.simulated_s;
      for (std::size_t k = 0; k < buses_.size(); ++k) {
        const double bused_cpu = row(bused[ti][k], " (bus " + buses_[k].url + ")");
        buses_[k].costs.push_back({n, 100.0 * (bused_cpu / plain_cpu - 1.0)});
        buses_[k].core_shares.push_back(100.0 * (bused_cpu - plain_cpu) / std::max(1e-9, bused[ti][k].r.simulated_s));
      }
      if (!same[ti]) any_differs_ = true;
      if (row_splits[ti].robots > 0) splits_.push_back(row_splits[ti]);
    }
  }

  void print_bus_tables() const {
    const auto& buses = buses_;
    const auto& counts_ids = counts_;
    std::printf(
        "\nThe bus: every message of the run published on it (rows \"(bus ...)\"): the world and status every "
        "simulated second; every robot's pose, wheel command and sensor readings every control step; each event. "
        "Nobody in this process listens; on memq:// (the default bus of `rilbed run`) that means nothing is even "
        "encoded. CPU cost of the bus against the same run without it (medians), and that extra CPU per "
        "simulated second, which is the share of one core the bus takes when the run goes in real time:\n\n"
        "| robots |");
    for (const Bus& b : buses)
      std::printf(" %s: slower by | %s: share of a core at real time |", b.url.c_str(), b.url.c_str());
    std::printf("\n| ---: |");
    for (std::size_t k = 0; k < buses.size(); ++k) std::printf(" ---: | ---: |");
    std::printf("\n");
    for (std::size_t i = 0; i < counts_ids.size(); ++i) {
      std::printf("| %d |", counts_ids[i]);
      for (const Bus& b : buses) std::printf(" %+.1f %% | %.2f %% |", b.costs[i].second, b.core_shares[i]);
      std::printf("\n");
    }
    for (const Bus& b : buses) {
      std::printf(
          "\nMessages and bytes per channel on %s, all its runs together:\n\n| channel | messages | bytes | "
          "failed publishes |\n| --- | ---: | ---: | ---: |\n",
          b.url.c_str());
      const auto counts_now = b.publisher->counts();
      if (counts_now.empty()) std::printf("| (none: nothing was encoded) | 0 | 0 | 0 |\n");
      for (const auto& [channel, c] : counts_now) {
        std::printf("| %s | %llu | %llu | %llu |\n", channel.c_str(), static_cast<unsigned long long>(c.messages),
                    static_cast<unsigned long long>(c.bytes), static_cast<unsigned long long>(c.failures));
      }
    }
  }

  const BenchArgs& args_;
  std::vector<int> counts_;
  std::vector<int> thread_counts_;
  std::vector<Bus> buses_;
  std::vector<Split> splits_;
  bool any_differs_ = false;
};

int bench_command(const BenchArgs& args) {
  const auto counts = parse_id_list(args.robots, 1, 1'000'000, "list");
  if (!counts.ok()) {
    spdlog::error("--robots: {}", counts.error);
    return kExitUsage;
  }
  const auto thread_counts = parse_id_list(args.threads, 1, 256, "list");
  if (!thread_counts.ok()) {
    spdlog::error("--threads: {}", thread_counts.error);
    return kExitUsage;
  }
  if (!args.lcm_urls.empty() && thread_counts.ids != std::vector<int>{1}) {
    spdlog::error("--lcm times the bus on one thread: give it without --threads");
    return kExitUsage;
  }
  const int status = SimBench(args, counts.ids, thread_counts.ids).run();
  if (status != 0 || args.sensor_plugin.empty()) return status;
  SensorBenchOptions sensors;
  sensors.library = args.sensor_plugin;
  sensors.robots = counts.ids;
  sensors.seconds = args.seconds;
  sensors.physics_step_ms = args.physics_step_ms;
  sensors.density_per_m2 = args.density_per_m2;
  sensors.seed = args.seed;
  sensors.repeat = args.repeat;
  return run_sensor_bench(sensors);
}

}  // namespace

void add_sim_bench_command(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* cmd = app.add_subcommand("sim-bench", "Time the simulation with many virtual robots (prints a table)");
  cmd->add_option("--robots", args->robots, "Robot counts, a list or ranges (e.g. 100,1000,10000)")
      ->default_val(args->robots);
  cmd->add_option("--seconds", args->seconds, "Simulated seconds per count")
      ->check(CLI::PositiveNumber)
      ->default_val(args->seconds);
  cmd->add_option("--physics-step-ms", args->physics_step_ms, "World integration step")
      ->check(CLI::PositiveNumber)
      ->default_val(args->physics_step_ms);
  cmd->add_option("--density", args->density_per_m2, "Robots per square metre")
      ->check(CLI::PositiveNumber)
      ->default_val(args->density_per_m2);
  cmd->add_option("--seed", args->seed, "Seed")->default_val(args->seed);
  cmd->add_option("--repeat", args->repeat, "Runs per count; the table shows medians")
      ->check(CLI::PositiveNumber)
      ->default_val(args->repeat);
  cmd->add_option("--lcm", args->lcm_urls,
                  "Also time each count with the run published on this LCM bus, nobody listening (repeatable; e.g. "
                  "memq:// as `rilbed run` publishes by default, or udpm://239.255.76.67:7667?ttl=0)");
  cmd->add_option("--threads", args->threads,
                  "Thread counts to time each robot count with, a list (e.g. 1,2): the world and the agents stepped on "
                  "that many threads; every count must give the same trajectories")
      ->default_val(args->threads);
  cmd->add_option("--sensor-plugin", args->sensor_plugin,
                  "Also time each count with three track elements per robot, built in and from this plug-in library's "
                  "track_element (examples/sensors/track_sensor), and print them side by side");
  cmd->add_option("--robot-model", args->robot_model,
                  "Every robot with this robot model's body and wheels (a file, or a shipped model's name: square, "
                  "epuck); its sensors stay the bench's IR ring. Default: Kheperas");
  cmd->add_flag("--no-split", args->no_split,
                "Do not time the runs' parts (sensing, behaviours, integration, collisions, recording): the table of "
                "where the time goes is left out, and the clock reads with it");
  cmd->callback([args] { exit_code() = bench_command(*args); });
}

}  // namespace rilbed::app

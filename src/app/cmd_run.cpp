// `rilbed run SCENARIO.yaml`: one run, or a batch of runs over seeds, of a scenario.
#include <signal.h>
#include <spawn.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <nlohmann/json.hpp>

#include "app/commands.hpp"
#include "app/panel_options.hpp"
#include "bus/lcm_bus.hpp"
#include "bus/lcm_console.hpp"
#include "bus/remote_agents.hpp"
#include "core/id_list.hpp"
#include "core/statistics.hpp"
#include "gui_web/gui_service.hpp"
#include "run/placement.hpp"
#include "run/real_robots.hpp"
#include "run/run_folder_writer.hpp"
#include "run/scenario.hpp"
#include "run/simulation.hpp"
#include "run/status_line.hpp"
#include "session/agent_processes.hpp"

namespace rilbed::app {

namespace {

// Set by SIGINT/SIGTERM; the run polls it after every control step and ends cleanly
// (every robot stopped, the run folder written).
std::atomic<bool> interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void on_signal(int) { interrupted.store(true); }

// Set when a batch cannot go on (its real robots could not be placed): the seeds left are
// not run.
std::atomic<bool> batch_aborted{false};

void log_to_spdlog(serial::LogLevel level, const std::string& message) {
  if (level == serial::LogLevel::kError)
    spdlog::error("{}", message);
  else if (level == serial::LogLevel::kWarning)
    spdlog::warn("{}", message);
  else if (level == serial::LogLevel::kInfo)
    spdlog::info("{}", message);
}

void print_emulated_last_speeds(const run::RealRobots& real) {
  for (const auto& [id, emulator] : real.emulators()) {
    const auto speeds = emulator->last_speeds();
    std::printf("robot %d (emulated): last speed %d %d\n", id, speeds.left_units, speeds.right_units);
  }
}

// The operator, on the terminal: reads a line from standard input once the robots are in
// place; "q" (or the end of input: nobody there) gives up.
bool ask_operator_on_stdin(const std::string& message) {
  std::fprintf(stderr, "%s\nPlace them, then press Enter (q and Enter to give up): ", message.c_str());
  std::fflush(stderr);
  std::string answer;
  if (!std::getline(std::cin, answer)) {
    std::fprintf(stderr, "\n");
    spdlog::error("no operator answered (standard input is closed)");
    return false;
  }
  return answer != "q" && answer != "Q";
}

struct RunArgs {
  std::string scenario;
  bool fast = false;
  bool realtime = false;
  double rt_factor = 1.0;
  std::optional<double> duration_s;
  bool stop_when_formed = false;
  std::uint64_t seed = 1;
  int seeds = 0;
  std::string out;
  int jobs = 0;
  int threads = 1;
  bool quiet = false;
  std::string mode;  // overrides the scenario's
  bool all_virtual = false;
  std::string lcm_url;         // publish the run on this LCM bus (empty: no bus)
  std::string record;          // write every message of the run to this LCM log
  bool record_frames = false;  // and the camera's frames (JPEG)
  std::string channel_prefix;
  bool no_place = false;  // real robots start where they stand
  double place_timeout_s = 90.0;
  bool gui = false;    // serve the web control panel from this process
  PanelOptions panel;  // with --gui
};

// The console sink of `rilbed run --gui`: a browser's command acts on this run's own
// RunControl, checked as a console's command over LCM is (the web server has checked the
// token already).
gui_web::ConsoleSink run_control_sink(run::RunControl& control) {
  return [&control](const gui_web::ConsoleRequest& request) -> gui_web::ConsoleAnswer {
    rilbed::console_command_t c;
    c.client = "gui " + request.client;
    c.command = request.command;
    c.args = request.args;
    c.num_args = static_cast<std::int32_t>(c.args.size());
    auto parsed = bus::parse_console_command(c);
    if (auto* why = std::get_if<std::string>(&parsed)) return {false, *why};
    if (auto refusal = control.act(std::get<run::ControlAction>(parsed))) return {false, *refusal};
    std::string done = request.command;
    for (const std::string& arg : request.args) done += " " + arg;
    return {true, done};
  };
}

// Puts the real robots at the start poses of `seed` (links::place_real_robots), reports
// what it did, and throws when they could not be placed (the batch then ends).
void place_or_throw(run::RealRobots& real, const run::Scenario& scenario, std::uint64_t seed, const RunArgs& args) {
  const std::vector<Pose2> poses = run::start_poses(scenario, seed);
  std::map<int, Pose2> targets;
  for (std::size_t i = 0; i < scenario.robots.size(); ++i) {
    if (scenario.robots[i].kind == environment::RobotKind::kReal) targets[scenario.robots[i].id] = poses[i];
  }
  run::PlacementOptions o;
  o.timeout_s = args.place_timeout_s;
  o.ask_operator = ask_operator_on_stdin;
  o.interrupt = &interrupted;
  o.log = log_to_spdlog;
  const run::PlacementResult r = run::place_real_robots(real, targets, o);
  if (!r.ok) {
    batch_aborted.store(true);
    throw std::runtime_error("seed " + std::to_string(seed) + ": " + r.error);
  }
  if (!r.offset_m.empty()) {
    std::string offsets;
    for (const auto& [id, d] : r.offset_m)
      offsets += fmt::format("{}robot {}: {:.1f} mm", offsets.empty() ? "" : ", ", id, d * 1000.0);
    spdlog::info("seed {}: real robots driven to their start poses in {:.1f} s (left from the pose: {})", seed,
                 r.wall_s, offsets);
  }
  if (!r.placed_by_operator.empty()) {
    spdlog::info("seed {}: robots {} placed by the operator", seed, id_list_text(r.placed_by_operator));
  }
}

void print_result(const run::RunResult& r) {
  char formed[64] = "no convoy";
  if (r.convoy_size > 0) std::snprintf(formed, sizeof formed, "convoy not formed");
  if (r.formation_time_s) std::snprintf(formed, sizeof formed, "formed at %.1f s", *r.formation_time_s);
  std::printf(
      "seed %llu: %s; %d collisions (%d robot-robot), max overlap %.2g m; %.1f s simulated in %.2f s (ended by %s)\n",
      static_cast<unsigned long long>(r.seed), formed, r.collisions, r.robot_collisions, r.max_overlap_m, r.simulated_s,
      r.wall_s, r.ended_by.c_str());
}

// Runs one seed of a batch (its options already hold the seed and out_dir).
using SeedRunner = std::function<run::RunResult(const run::RunOptions&)>;

int run_batch(const run::Scenario& scenario, const RunArgs& args, run::RunOptions base, const SeedRunner& run_seed,
              int max_jobs) {
  const int n = args.seeds;
  std::vector<run::RunResult> results(n);
  std::vector<std::string> errors(n);
  std::atomic<int> next{0};
  std::mutex print_mutex;
  const auto wall_start = std::chrono::steady_clock::now();
  auto worker = [&] {
    for (int i = next++; i < n && !interrupted.load() && !batch_aborted.load(); i = next++) {
      run::RunOptions o = base;
      o.seed = args.seed + static_cast<std::uint64_t>(i);
      if (!args.out.empty()) o.out_dir = std::filesystem::path(args.out) / ("seed_" + std::to_string(o.seed));
      try {
        results[i] = run_seed(o);
      } catch (const std::exception& e) {
        errors[i] = e.what();
        results[i].seed = o.seed;
        results[i].ended_by = "error";
      }
      std::lock_guard lock(print_mutex);
      if (!args.quiet) {
        print_result(results[i]);
        std::fflush(stdout);  // a batch of real-time runs takes minutes: show each as it ends
      }
    }
  };
  // By default as many runs at once as the cores hold with each run's threads.
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int jobs = std::clamp(args.jobs > 0 ? args.jobs : cores / std::max(1, args.threads), 1, max_jobs);
  if (jobs * args.threads > cores)
    spdlog::warn(
        "{} runs at once on {} threads each is more threads than this machine's {} cores: they will wait on "
        "each other",
        jobs, args.threads, cores);
  std::vector<std::thread> threads;
  for (int j = 0; j < std::min(jobs, n); ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  int formed = 0, collisions = 0, robot_collisions = 0, failed = 0, done = 0;
  double max_overlap = 0.0;
  std::vector<double> times;
  nlohmann::json runs = nlohmann::json::array();
  for (int i = 0; i < n; ++i) {
    const auto& r = results[i];
    if (r.ended_by.empty()) continue;  // not run (interrupted)
    ++done;
    if (!errors[i].empty()) {
      ++failed;
      spdlog::error("seed {}: {}", r.seed, errors[i]);
    }
    formed += r.formed;
    if (r.formation_time_s) times.push_back(*r.formation_time_s);
    collisions += r.collisions;
    robot_collisions += r.robot_collisions;
    max_overlap = std::max(max_overlap, r.max_overlap_m);
    nlohmann::json j = r.summary();
    if (!errors[i].empty()) j["error"] = errors[i];
    runs.push_back(j);
  }
  nlohmann::json batch;
  batch["scenario"] = scenario.name;
  batch["mode"] = scenario.mode == run::ConvoyMode::kCentral ? "central" : "distributed";
  batch["runs"] = done;
  batch["formed"] = formed;
  batch["failed"] = failed;
  batch["formation_time_median_s"] = times.empty() ? nlohmann::json(nullptr) : nlohmann::json(percentile(times, 0.5));
  batch["formation_time_p95_s"] = times.empty() ? nlohmann::json(nullptr) : nlohmann::json(percentile(times, 0.95));
  batch["collisions"] = collisions;
  batch["robot_collisions"] = robot_collisions;
  batch["max_overlap_m"] = max_overlap;
  batch["wall_s"] = wall_s;
  batch["jobs"] = jobs;
  batch["per_run"] = runs;
  if (!args.out.empty()) {
    std::filesystem::create_directories(args.out);
    std::ofstream(std::filesystem::path(args.out) / "batch.json")
        << batch.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
  }
  std::printf(
      "\n| scenario | mode | runs | formed | formation time median s | formation time p95 s | collisions (robot-robot) "
      "| max overlap m | wall s (%d jobs) |\n",
      jobs);
  std::printf("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  char median[32] = "-", p95[32] = "-";
  if (!times.empty()) {
    std::snprintf(median, sizeof median, "%.1f", percentile(times, 0.5));
    std::snprintf(p95, sizeof p95, "%.1f", percentile(times, 0.95));
  }
  std::printf("| %s | %s | %d | %d | %s | %s | %d (%d) | %.2g | %.1f |\n", scenario.name.c_str(),
              batch["mode"].get<std::string>().c_str(), done, formed, median, p95, collisions, robot_collisions,
              max_overlap, wall_s);
  return failed > 0 || done == 0 ? kExitFailure : 0;
}

int run_command(const RunArgs& args) {
  run::Scenario scenario;
  try {
    scenario = run::load_scenario(args.scenario);
  } catch (const run::ScenarioError& e) {
    spdlog::error("{}", e.what());
    return kExitFailure;
  }
  std::vector<int> stand_ins;  // real robots this run simulates (--all-virtual)
  if (args.all_virtual) {
    // The same robots, poses and controllers, every one virtual: the simulation half of a
    // sim-to-real comparison (`rilbed compare`).
    for (run::RobotSpec& r : scenario.robots) {
      if (r.kind == environment::RobotKind::kReal) stand_ins.push_back(r.id);
      r.kind = environment::RobotKind::kVirtual;
      r.link.reset();
    }
    scenario.camera.reset();
  }
  const std::vector<int> real_ids = run::real_robot_ids(scenario);
  if (!real_ids.empty() && args.fast) {
    // Safe default: real robots move in wall-clock time, whatever the simulation's clock.
    spdlog::error(
        "{}: robots {} are real and move in wall-clock time, so --fast cannot run them: leave --fast out "
        "(runs with real robots are real time), or add --all-virtual to run them as virtual robots",
        args.scenario, id_list_text(real_ids));
    return kExitUsage;
  }
  if (args.mode == "central") scenario.mode = run::ConvoyMode::kCentral;
  if (args.mode == "distributed") scenario.mode = run::ConvoyMode::kDistributed;
  run::RunOptions options;
  options.realtime = args.realtime || !real_ids.empty();
  options.virtual_stand_ins = stand_ins;
  options.rt_factor = args.rt_factor;
  options.duration_s = args.duration_s;
  options.stop_when_formed = args.stop_when_formed;
  options.seed = args.seed;
  options.threads = args.threads;
  options.interrupt = &interrupted;
  // The LCM bus: everything the run reports goes out on it while it runs, and the run's
  // own outputs (its folder, its status line) are subscribers of the same messages.
  if (const auto problem = bus::check_channel_prefix(args.channel_prefix)) {
    spdlog::error("{}", *problem);
    return kExitUsage;
  }
  const bus::Channels channels = bus::Channels::with_prefix(args.channel_prefix);
  std::unique_ptr<lcm::LogFile> recording;
  if (!args.record.empty()) {
    if (args.seeds > 0) {
      spdlog::error("--record records one run: leave out --seeds (or record each seed's run on its own)");
      return kExitUsage;
    }
    recording = std::make_unique<lcm::LogFile>(args.record, "w");
    if (!recording->good()) {
      spdlog::error("cannot write the recording {}", args.record);
      return kExitFailure;
    }
  }
  if (args.record_frames && (!recording || !scenario.camera)) {
    if (!recording) {
      spdlog::error("--record-frames adds the camera's frames to a recording: give --record FILE.lcm too");
    } else {
      spdlog::error("--record-frames: {} has no camera (no real robots)", args.scenario);
    }
    return kExitUsage;
  }
  // A bus other processes reach is one for the whole batch; the in-process bus is one per
  // run (memq:// is not safe with runs of a batch publishing on it from several threads).
  const bool network_bus = !args.lcm_url.empty() && args.lcm_url.rfind("memq://", 0) != 0;
  std::unique_ptr<lcm::LCM> network_lcm;
  if (network_bus) {
    std::string error;
    network_lcm = bus::open_lcm(args.lcm_url, error);
    if (!network_lcm) {
      spdlog::error("{}", error);
      return kExitFailure;
    }
  }
  if (!args.out.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(args.out, ec);
    if (ec) {
      spdlog::error("cannot make the run folder {}: {}", args.out, ec.message());
      return kExitFailure;
    }
  }
  // Steering the run (the console on the bus, the web panel).
  run::RunControl control;
  // The web panel (--gui), made below; declared here for the runs' buses to feed it. It
  // outlives every run (a reset starts a new one; its viewers stay) and goes before the
  // control its commands act on.
  std::unique_ptr<gui_web::GuiService> gui;
  // The publisher of the run now going (a paused run re-publishes its world and status).
  std::mutex current_mutex;
  bus::LcmRunPublisher* current_publisher = nullptr;
  const bool status_line = options.realtime && !args.quiet && args.seeds == 0;
  // Runs one seed with `run` on its bus: its folder (options.out_dir) written by a
  // subscriber, not by the run.
  auto on_bus = [&](const SeedRunner& run) -> SeedRunner {
    return [&, run](const run::RunOptions& given) {
      run::RunOptions o = given;
      std::unique_ptr<lcm::LCM> own_lcm;
      lcm::LCM* bus = network_lcm.get();
      if (!bus) {
        std::string error;
        own_lcm = bus::open_lcm("memq://", error);
        if (!own_lcm) throw std::runtime_error(error);
        bus = own_lcm.get();
      }
      bus::LcmRunPublisher::Options po;
      po.in_process = !network_bus;
      po.log = recording.get();
      po.frames = args.record_frames;
      // The panel shows the camera at most 10 frames a second; they go to it alone.
      if (gui) po.local_frame_period_ms = static_cast<int>(1000.0 / gui_web::kMaxCameraFps);
      bus::LcmRunPublisher publisher(*bus, channels, po);
      std::unique_ptr<run::RunFolderWriter> folder;
      if (o.out_dir) {
        folder = std::make_unique<run::RunFolderWriter>(*o.out_dir);
        publisher.add_local_subscriber(*folder);
        o.out_dir.reset();
      }
      run::StatusLine line([](const std::string& text) {
        std::printf("%s\n", text.c_str());
        std::fflush(stdout);
      });
      if (status_line) publisher.add_local_subscriber(line);
      if (gui) publisher.add_local_subscriber(*gui);
      o.observer = &publisher;
      {
        std::lock_guard lock(current_mutex);
        current_publisher = &publisher;
      }
      struct Forget {
        std::mutex& m;
        bus::LcmRunPublisher*& p;
        ~Forget() {
          std::lock_guard lock(m);
          p = nullptr;
        }
      } forget{current_mutex, current_publisher};
      run::RunResult r = run(o);
      if (network_bus) {
        // The end goes out twice more: a watcher that lost it would wait for it forever.
        for (int k = 0; k < 2; ++k) {
          std::this_thread::sleep_for(std::chrono::milliseconds(50));
          publisher.repeat_end();
        }
        // A publish the network refused (a firewall's EPERM) is lost: say how many.
        std::uint64_t refused = 0;
        for (const auto& [channel, count] : publisher.counts()) refused += count.failures;
        if (refused > 0) {
          spdlog::warn("seed {}: the bus refused {} of the run's messages (they were lost; a firewall?)", o.seed,
                       refused);
        }
      }
      return r;
    };
  };
  // The console: commands on the bus, each with this run's token.
  std::unique_ptr<bus::LcmConsoleServer> console;
  std::filesystem::path token_file;
  std::string token;
  // A finished run's token opens nothing: its file goes with the run (unless a newer run
  // with the same prefix has written its own since).
  struct TokenFileRemover {
    const std::filesystem::path& file;
    const std::string& token;
    ~TokenFileRemover() {
      if (!file.empty() && bus::read_token(file) == token) std::filesystem::remove(file);
    }
  } remove_token_at_exit{token_file, token};
  // Only on a bus other processes reach: memq:// is this process alone (and liblcm's
  // memq provider is not safe with a second thread handling it).
  if (network_bus) {
    token = bus::make_run_token();
    token_file = bus::token_path(args.channel_prefix);
    const auto problem = bus::write_token(token_file, token);
    std::fprintf(stderr, "rilbed: run token %s%s%s\n", token.c_str(), problem ? "" : " (in ",
                 problem ? "" : (token_file.string() + ", readable by you only)").c_str());
    if (problem) spdlog::warn("the token is not in a file ({}): give it to rilbed console with --token", *problem);
    console = std::make_unique<bus::LcmConsoleServer>(
        *network_lcm, channels, token, control, [](const std::string& m) { spdlog::info("{}", m); }, true,
        [&] {
          // While paused the run reports nothing: its last world and status go out again
          // every second, for viewers that join meanwhile.
          std::lock_guard lock(current_mutex);
          if (current_publisher) current_publisher->republish_world_and_status();
        });
    options.control = &control;
  }
  // The web control panel, in this process: a local subscriber of the run's messages
  // (as the folder is) whose commands act on the run's control.
  if (args.gui) {
    if (args.seeds > 0) {
      spdlog::error("--gui shows one run: leave out --seeds");
      return kExitUsage;
    }
    if (const auto problem = check_panel_options(args.panel)) {
      spdlog::error("{}", *problem);
      return kExitUsage;
    }
    gui = start_panel(args.panel, token, run_control_sink(control));
    if (!gui) return kExitFailure;
    std::printf("rilbed gui: %s\n", gui->url().c_str());
    std::fflush(stdout);
    options.control = &control;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  if (!args.out.empty()) options.out_dir = args.out;  // a batch puts each seed in a folder of its own
  // Real robots: their links (and emulators) stay open from run to run of a batch, and
  // live until every run has stopped them.
  std::unique_ptr<run::RealRobots> real;
  run::RealBodyFactory real_bodies;
  SeedRunner run_seed = on_bus([&](const run::RunOptions& o) { return run::run_scenario(scenario, o, real_bodies); });
  if (!real_ids.empty()) {
    real = std::make_unique<run::RealRobots>(scenario, log_to_spdlog);
    real_bodies = real->body_factory();
    options.emulated_markers = [&real] { return real->emulated_markers(); };
    // Before each run, every real robot goes to the run's start pose (as its all-virtual
    // twin starts): emulated ones are put there, physical ones driven there.
    run_seed = on_bus([&](const run::RunOptions& o) {
      if (!args.no_place) place_or_throw(*real, scenario, o.seed, args);
      return run::run_scenario(scenario, o, real_bodies);
    });
  }
  // Controllers in other processes (issue 18): each run waits for every remote robot's
  // process to announce itself, then steps them one quantum per control instant.
  std::unique_ptr<lcm::LCM> agents_lcm, agents_answers_lcm;
  session::AgentProcesses agent_processes;
  if (scenario.agents) {
    const run::AgentsSpec& spec = *scenario.agents;
    if (!network_bus) {
      spdlog::error(
          "{}: its agents run in other processes, which need a bus they reach: give --lcm URL "
          "(e.g. udpm://239.255.76.67:7667?ttl=0)",
          args.scenario);
      return kExitUsage;
    }
    std::string error;
    agents_lcm = bus::open_lcm(args.lcm_url, error);
    if (agents_lcm) agents_answers_lcm = bus::open_lcm(bus::agent_reply_url(args.lcm_url), error);
    if (!agents_lcm || !agents_answers_lcm) {
      spdlog::error("{}", error);
      return kExitFailure;
    }
    const session::AgentLaunchConfig launch{args.scenario, args.lcm_url, args.channel_prefix, spec.launch,
                                            spec.remote_rilbed};
    if (spec.processes > 0 &&
        !agent_processes.start(launch, session::place_agents(spec.ids, spec.processes, spec.hosts), error)) {
      spdlog::error("{}", error);
      return kExitFailure;
    }
    bus::RemoteAgentsConfig config;
    config.channels = channels;
    config.scenario_name = scenario.name;
    config.robot_ids = spec.ids;
    for (const int id : spec.ids) {
      const auto robot =
          std::find_if(scenario.robots.begin(), scenario.robots.end(), [&](const auto& r) { return r.id == id; });
      if (const auto c = run::make_controller(scenario, *robot); c && c->wants_team()) config.team_readers.insert(id);
    }
    config.realtime = options.realtime;
    config.resend_ms = spec.resend_ms;
    config.dead_after_ms = spec.dead_after_ms;
    config.deadline_ms = spec.deadline_ms;
    const auto timeout = std::chrono::milliseconds(static_cast<std::int64_t>(spec.announce_timeout_s * 1000.0));
    run_seed = [&, config, timeout, inner = run_seed](const run::RunOptions& given) {
      run::RunOptions o = given;
      bus::RemoteAgents remote(*agents_lcm, *agents_answers_lcm, config);
      if (const auto missing = remote.wait_for_agents(timeout, [&] { return agent_processes.ended_early(); })) {
        throw run::ScenarioError(args.scenario + ": " + *missing);
      }
      o.remote_agents = &remote;
      run::RunResult r = inner(o);
      const bus::RemoteAgentsCounters& c = remote.counters();
      if (!args.quiet) {
        std::printf(
            "agents: %lld quanta sent, %lld sent again, %lld duplicate answers, %lld late, %lld processes lost, "
            "%lld robots rejoined\n",
            static_cast<long long>(c.quanta_sent), static_cast<long long>(c.repeats),
            static_cast<long long>(c.duplicates), static_cast<long long>(c.late),
            static_cast<long long>(c.lost_processes), static_cast<long long>(c.rejoins));
        std::fflush(stdout);
      }
      return r;
    };
  }
  // The console's reset ends a run to start it over (its folder too), as it began: real
  // robots are placed again.
  run_seed = [run_seed](const run::RunOptions& o) {
    for (;;) {
      run::RunResult r = run_seed(o);
      if (r.ended_by != "reset" || interrupted.load()) return r;
      spdlog::info("seed {}: reset from the console: the run starts over", o.seed);
    }
  };
  if (args.seeds > 0) {
    // With real robots one run after another: the robots are the same ones.
    // With real robots one run after another (the robots are the same ones), and on a bus
    // others watch too (a watcher follows one run at a time).
    const int status =
        run_batch(scenario, args, options, run_seed, real || network_bus ? 1 : std::numeric_limits<int>::max());
    if (real) print_emulated_last_speeds(*real);
    return status;
  }
  try {
    const run::RunResult r = run_seed(options);
    print_result(r);
    if (real) print_emulated_last_speeds(*real);
    if (!args.out.empty()) std::printf("run folder: %s\n", args.out.c_str());
    // The page's viewers get the run's end (its last status and summary) before the
    // server goes; their page then says the run ended, not that the server vanished.
    if (gui) gui->flush(std::chrono::seconds(2));
  } catch (const run::ScenarioError& e) {
    spdlog::error("{}", e.what());
    return kExitFailure;
  } catch (const std::exception& e) {
    spdlog::error("run failed: {}", e.what());
    return kExitFailure;
  }
  return 0;
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("run", "Run a scenario (simulation; robot-in-the-loop when it has real robots)");
  cmd->add_option("scenario", args->scenario, "Scenario file (YAML, see scenarios/README.md)")
      ->required()
      ->check(CLI::ExistingFile);
  auto* fast = cmd->add_flag("--fast", args->fast,
                             "As fast as the CPU allows (the default without real robots; an error with them)");
  auto* realtime =
      cmd->add_flag("--realtime", args->realtime, "Paced to the wall clock (the default with real robots)");
  fast->excludes(realtime);
  cmd->add_option("--rt-factor", args->rt_factor, "With --realtime: simulated seconds per wall second")
      ->check(CLI::PositiveNumber)
      ->needs(realtime);
  cmd->add_option("--duration", args->duration_s, "Simulated seconds to run (default: the scenario's duration_s)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--stop-when-formed", args->stop_when_formed, "End 5 s after the convoy formed");
  cmd->add_option("--seed", args->seed, "Seed of the initial poses and the noise (first seed of a batch)")
      ->default_val(1);
  cmd->add_option("--seeds", args->seeds, "Run a batch of N seeds (seed, seed+1, ...) and print its table")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out", args->out, "Write the run folder here (a batch: one folder per seed and batch.json)");
  cmd->add_option("--jobs", args->jobs, "Runs of a batch at once (default: one per core, or per --threads cores)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--threads", args->threads,
                  "Threads that step each run's world and agents (the run folder is the same for any count; only the "
                  "speed differs)")
      ->check(CLI::Range(1, 256))
      ->default_val(1);
  cmd->add_option("--mode", args->mode, "Override the scenario's convoy mode")
      ->check(CLI::IsMember({"central", "distributed"}));
  cmd->add_flag(
      "--all-virtual", args->all_virtual,
      "Make every real robot virtual (same poses and controllers): the simulation half of a sim-to-real comparison");
  cmd->add_option("--lcm", args->lcm_url,
                  "Publish the run on this LCM bus, visible to other processes (e.g. udpm://239.255.76.67:7667?ttl=0; "
                  "default: memq://, the run's own in-process bus, which sends nothing on the network)");
  cmd->add_option("--channel-prefix", args->channel_prefix,
                  "Put this before every channel name (two runs on one network)");
  cmd->add_option("--record", args->record,
                  "Write every message of the run to this LCM log (lcm-logplayer plays it; rilbed replay reads it)");
  cmd->add_flag("--record-frames", args->record_frames,
                "With --record: add the overhead camera's frames (JPEG, channel RILBED_FRAMES), so that `rilbed detect "
                "FILE.lcm` can run the vision pipeline on them again with other settings");
  cmd->add_flag("--no-place", args->no_place,
                "Real robots start where they stand (default: before each run they are driven, or put if emulated, "
                "to the run's start poses)");
  cmd->add_option("--place-timeout", args->place_timeout_s,
                  "Seconds the real robots get to drive to their start poses before the operator is asked")
      ->check(CLI::PositiveNumber)
      ->default_val(90);
  cmd->add_flag("--gui", args->gui, "Serve the web control panel from this run (prints its URL with a fresh token)");
  add_panel_options(*cmd, args->panel, "With --gui: ");
  cmd->add_flag("--quiet", args->quiet, "No per-second status (realtime) or per-run lines (batch)");
  cmd->callback([args] { exit_code() = run_command(*args); });
}

}  // namespace rilbed::app

#include "session/run_session.hpp"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <stdexcept>

#include "agents/builtin_controllers.hpp"
#include "bus/lcm_bus.hpp"
#include "bus/lcm_console.hpp"
#include "core/id_list.hpp"
#include "gui_web/gui_service.hpp"
#include "run/placement.hpp"
#include "run/real_robots.hpp"
#include "run/run_control.hpp"
#include "run/run_setup.hpp"
#include "run/simulation.hpp"
#include "session/batch_runner.hpp"
#include "session/remote_controllers.hpp"
#include "session/run_outputs.hpp"
#include "session/run_token.hpp"

namespace rilbed::session {

namespace {

using Status = SessionResult::Status;

SessionResult problem(Status status, std::string error) {
  spdlog::error("{}", error);
  SessionResult r;
  r.status = status;
  r.error = std::move(error);
  return r;
}

void log_to_spdlog(serial::LogLevel level, const std::string& message) {
  if (level == serial::LogLevel::kError) {
    spdlog::error("{}", message);
  } else if (level == serial::LogLevel::kWarning) {
    spdlog::warn("{}", message);
  } else if (level == serial::LogLevel::kInfo) {
    spdlog::info("{}", message);
  }
}

// One run's line: "seed 3: formed at 41.2 s; 2 collisions (0 robot-robot), ...".
std::string result_line(const run::RunResult& r) {
  char formed[64] = "no convoy";
  if (r.convoy_size > 0) std::snprintf(formed, sizeof formed, "convoy not formed");
  if (r.formation_time_s) std::snprintf(formed, sizeof formed, "formed at %.1f s", *r.formation_time_s);
  char line[512];
  std::snprintf(line, sizeof line,
                "seed %llu: %s; %d collisions (%d robot-robot), max overlap %.2g m; %.1f s simulated in %.2f s (ended "
                "by %s)",
                static_cast<unsigned long long>(r.seed), formed, r.collisions, r.robot_collisions, r.max_overlap_m,
                r.simulated_s, r.wall_s, r.ended_by.c_str());
  return line;
}

// The console sink of the web panel: a browser's command acts on this run's own
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

}  // namespace

// Everything a session sets up, in the order it is made (and the reverse of the order it
// goes in: the agent processes and the real robots first, the bus last).
struct SessionParts {
  run::Scenario scenario;
  std::string scenario_text;  // the scenario as read, when not the file's (SessionOptions::scenario_text, overrides)
  std::vector<int> real_ids;
  run::RunOptions base;  // every run's options but its seed and folder
  bus::Channels channels;
  std::unique_ptr<lcm::LogFile> recording;
  std::unique_ptr<lcm::LCM> network_bus;  // null: each run on an in-process bus of its own
  run::RunControl control;
  std::unique_ptr<gui_web::GuiService> gui;
  CurrentPublisher current;
  OutputsConfig outputs;
  std::optional<RunToken> token;
  std::unique_ptr<bus::LcmConsoleServer> console;
  std::unique_ptr<run::RealRobots> real;
  run::RealBodyFactory real_bodies;
  std::unique_ptr<RemoteControllers> remote;
  std::atomic<bool> batch_aborted{false};  // its real robots could not be placed: no further seed
};

RunSession::RunSession(SessionOptions options, SessionOutput output)
    : options_(std::move(options)), output_(std::move(output)), parts_(std::make_unique<SessionParts>()) {
  // Each line at once: a batch of real-time runs takes minutes, and other programs wait
  // for lines such as the panel's URL.
  if (!output_.print) {
    output_.print = [](const std::string& line) {
      std::printf("%s\n", line.c_str());
      std::fflush(stdout);
    };
  }
  if (!output_.notice) output_.notice = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
}

RunSession::~RunSession() = default;

namespace {

// The steps of setting a session up, each of which may end it with a problem.
class SessionSetup {
 public:
  SessionSetup(const SessionOptions& o, const SessionOutput& out, SessionParts& p) : o_(o), out_(out), p_(p) {}

  std::optional<SessionResult> all() {
    for (auto step : {&SessionSetup::read_scenario, &SessionSetup::check_options, &SessionSetup::open_outputs,
                      &SessionSetup::open_console, &SessionSetup::open_panel, &SessionSetup::open_real_robots,
                      &SessionSetup::open_remote_controllers}) {
      if (auto problem = (this->*step)()) return problem;
    }
    return std::nullopt;
  }

 private:
  // The scenario file, or the text given, with the overrides applied. Throws ScenarioError.
  run::Scenario scenario_from_options() {
    if (o_.scenario_text.empty() && o_.overrides.empty()) return run::load_scenario(o_.scenario, o_.controllers);
    std::string text = o_.scenario_text;
    if (text.empty()) {
      std::ifstream in(o_.scenario);
      if (!in) throw run::ScenarioError(o_.scenario.string() + ": cannot read the file");
      text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    if (!o_.overrides.empty()) text = run::apply_overrides(text, o_.overrides, o_.scenario.string());
    p_.scenario_text = text;  // what agent processes must read too
    run::Scenario scenario = run::parse_scenario(text, o_.scenario.string(), o_.controllers);
    scenario.source = o_.scenario;
    return scenario;
  }

  std::optional<SessionResult> read_scenario() {
    try {
      p_.scenario = scenario_from_options();
    } catch (const run::ScenarioError& e) {
      return problem(Status::kFailed, e.what());
    }
    std::vector<int> stand_ins;  // real robots this run simulates (all_virtual)
    if (o_.all_virtual) {
      // The same robots, poses and controllers, every one virtual: the simulation half of
      // a sim-to-real comparison (`rilbed compare`).
      for (run::RobotSpec& r : p_.scenario.robots) {
        if (r.kind == environment::RobotKind::kReal) stand_ins.push_back(r.id);
        r.kind = environment::RobotKind::kVirtual;
        r.link.reset();
      }
      p_.scenario.camera.reset();
    }
    p_.real_ids = run::real_robot_ids(p_.scenario);
    if (o_.mode) p_.scenario.mode = *o_.mode;
    run::RunOptions& b = p_.base;
    b.realtime = o_.realtime || !p_.real_ids.empty();
    b.virtual_stand_ins = stand_ins;
    b.rt_factor = o_.rt_factor;
    b.duration_s = o_.duration_s;
    b.on_controller_error = o_.on_controller_error;
    b.stop_when_formed = o_.stop_when_formed;
    b.stop_when_done = o_.stop_when_done;
    b.seed = o_.seed;
    b.threads = o_.threads;
    b.interrupt = o_.interrupt;
    return std::nullopt;
  }

  std::optional<SessionResult> check_options() {
    const std::string file = o_.scenario.string();
    if (!p_.real_ids.empty() && o_.fast) {
      // Safe default: real robots move in wall-clock time, whatever the simulation's clock.
      return problem(Status::kUsage, file + ": robots " + id_list_text(p_.real_ids) +
                                         " are real and move in wall-clock time, so --fast cannot run them: leave "
                                         "--fast out (runs with real robots are real time), or add --all-virtual to "
                                         "run them as virtual robots");
    }
    if (const auto why = bus::check_channel_prefix(o_.channel_prefix)) return problem(Status::kUsage, *why);
    if (!o_.record.empty() && o_.seeds > 0) {
      return problem(Status::kUsage,
                     "--record records one run: leave out --seeds (or record each seed's run on its own)");
    }
    return std::nullopt;
  }

  bool network_bus() const { return !o_.lcm_url.empty() && o_.lcm_url.rfind("memq://", 0) != 0; }

  // The LCM bus: everything the run reports goes out on it while it runs, and the run's own
  // outputs (its folder, its status line) are subscribers of the same messages.
  std::optional<SessionResult> open_outputs() {
    p_.channels = bus::Channels::with_prefix(o_.channel_prefix);
    if (!o_.record.empty()) {
      p_.recording = std::make_unique<lcm::LogFile>(o_.record, "w");
      if (!p_.recording->good()) return problem(Status::kFailed, "cannot write the recording " + o_.record);
    }
    if (o_.record_frames && !p_.recording) {
      return problem(Status::kUsage,
                     "--record-frames adds the camera's frames to a recording: give --record FILE.lcm too");
    }
    if (o_.record_frames && !p_.scenario.camera) {
      return problem(Status::kUsage, "--record-frames: " + o_.scenario.string() + " has no camera (no real robots)");
    }
    // A bus other processes reach is one for the whole batch; the in-process bus is one per
    // run (memq:// is not safe with runs of a batch publishing on it from several threads).
    if (network_bus()) {
      std::string error;
      p_.network_bus = bus::open_lcm(o_.lcm_url, error);
      if (!p_.network_bus) return problem(Status::kFailed, error);
    }
    if (!o_.out.empty()) {
      std::error_code ec;
      std::filesystem::create_directories(o_.out, ec);
      if (ec) return problem(Status::kFailed, "cannot make the run folder " + o_.out + ": " + ec.message());
      p_.base.out_dir = o_.out;  // a batch puts each seed in a folder of its own
    }
    OutputsConfig& c = p_.outputs;
    c.network_bus = p_.network_bus.get();
    c.channels = p_.channels;
    c.recording = p_.recording.get();
    c.record_frames = o_.record_frames;
    c.status_line = p_.base.realtime && !o_.quiet && o_.seeds == 0;
    c.print = out_.print;
    c.current = &p_.current;
    return std::nullopt;
  }

  // The console: commands on the bus, each with this run's token. Only on a bus other
  // processes reach: memq:// is this process alone (and liblcm's memq provider is not safe
  // with a second thread handling it).
  std::optional<SessionResult> open_console() {
    if (!network_bus()) return std::nullopt;
    p_.token.emplace(o_.channel_prefix);
    const auto& file_problem = p_.token->file_problem();
    out_.notice("rilbed: run token " + p_.token->token() +
                (file_problem ? "" : " (in " + p_.token->file().string() + ", readable by you only)"));
    if (file_problem) {
      spdlog::warn("the token is not in a file ({}): give it to rilbed console with --token", *file_problem);
    }
    p_.console = std::make_unique<bus::LcmConsoleServer>(
        *p_.network_bus, p_.channels, p_.token->token(), p_.control,
        [](const std::string& m) { spdlog::info("{}", m); }, true,
        // While paused the run reports nothing: its last world and status go out again every
        // second, for viewers that join meanwhile.
        [current = &p_.current] { current->republish_world_and_status(); });
    p_.base.control = &p_.control;
    return std::nullopt;
  }

  // The web control panel, in this process: a local subscriber of the run's messages (as
  // the folder is) whose commands act on the run's control.
  std::optional<SessionResult> open_panel() {
    if (!o_.gui) return std::nullopt;
    if (o_.seeds > 0) return problem(Status::kUsage, "--gui shows one run: leave out --seeds");
    if (const auto why = check_panel_options(o_.panel)) return problem(Status::kUsage, *why);
    const auto& controllers = p_.scenario.controllers ? *p_.scenario.controllers : *agents::default_controllers();
    p_.gui = start_panel(o_.panel, p_.token ? p_.token->token() : "", run_control_sink(p_.control), controllers);
    if (!p_.gui) return problem(Status::kFailed, "the web panel could not start");
    out_.print("rilbed gui: " + p_.gui->url());
    p_.outputs.gui = p_.gui.get();
    p_.base.control = &p_.control;
    return std::nullopt;
  }

  // Real robots: their links (and emulators) stay open from run to run of a batch, and live
  // until every run has stopped them.
  std::optional<SessionResult> open_real_robots() {
    if (p_.real_ids.empty()) return std::nullopt;
    p_.real = std::make_unique<run::RealRobots>(p_.scenario, log_to_spdlog);
    p_.real_bodies = p_.real->body_factory();
    p_.base.emulated_markers = [real = p_.real.get()] { return real->emulated_markers(); };
    return std::nullopt;
  }

  // Controllers in other processes: each run waits for every remote robot's process to
  // announce itself, then steps them one quantum per control instant.
  std::optional<SessionResult> open_remote_controllers() {
    if (!p_.scenario.agents) return std::nullopt;
    if (!network_bus()) {
      return problem(Status::kUsage, o_.scenario.string() +
                                         ": its agents run in other processes, which need a bus they reach: give "
                                         "--lcm URL (e.g. udpm://239.255.76.67:7667?ttl=0)");
    }
    try {
      p_.remote = std::make_unique<RemoteControllers>(p_.scenario, o_.scenario.string(), o_.lcm_url, p_.channels,
                                                      o_.channel_prefix, p_.base.realtime, p_.scenario_text);
    } catch (const std::runtime_error& e) {
      return problem(Status::kFailed, e.what());
    }
    return std::nullopt;
  }

  const SessionOptions& o_;
  const SessionOutput& out_;
  SessionParts& p_;
};

// Puts the real robots at the start poses of `seed` (run::place_real_robots), reports
// what it did, and throws when they could not be placed (the batch then ends).
void place_or_throw(SessionParts& p, const SessionOptions& o, const SessionOutput& out, std::uint64_t seed) {
  const std::vector<Pose2> poses = run::start_poses(p.scenario, seed);
  std::map<int, Pose2> targets;
  for (std::size_t i = 0; i < p.scenario.robots.size(); ++i) {
    if (p.scenario.robots[i].kind == environment::RobotKind::kReal) targets[p.scenario.robots[i].id] = poses[i];
  }
  run::PlacementOptions po;
  po.timeout_s = o.place_timeout_s;
  po.ask_operator = out.ask_operator ? out.ask_operator : [](const std::string&) { return false; };
  po.interrupt = o.interrupt;
  po.log = log_to_spdlog;
  const run::PlacementResult r = run::place_real_robots(*p.real, targets, po);
  if (!r.ok) {
    p.batch_aborted.store(true);
    throw std::runtime_error(r.error);  // the batch names the seed
  }
  if (!r.offset_m.empty()) {
    std::string offsets;
    for (const auto& [id, d] : r.offset_m) {
      offsets += fmt::format("{}robot {}: {:.1f} mm", offsets.empty() ? "" : ", ", id, d * 1000.0);
    }
    spdlog::info("seed {}: real robots driven to their start poses in {:.1f} s (left from the pose: {})", seed,
                 r.wall_s, offsets);
  }
  if (!r.placed_by_operator.empty()) {
    spdlog::info("seed {}: robots {} placed by the operator", seed, id_list_text(r.placed_by_operator));
  }
}

bool interrupted(const SessionOptions& o) { return o.interrupt && o.interrupt->load(); }

// One run of a seed, with its remote controllers, its outputs and its real robots placed.
run::RunResult run_once(SessionParts& p, const SessionOptions& o, const SessionOutput& out,
                        const run::RunOptions& given) {
  run::RunOptions options = given;
  std::unique_ptr<bus::RemoteAgents> remote;
  if (p.remote) {
    remote = p.remote->connect();
    options.remote_agents = remote.get();
  }
  run::RunResult result;
  {
    RunOutputs outputs(p.outputs, options);
    if (p.real && !o.no_place) place_or_throw(p, o, out, options.seed);
    result = run::run_scenario(p.scenario, options, p.real_bodies);
    outputs.after_run(options.seed);
  }
  if (remote && !o.quiet) out.print(RemoteControllers::counters_text(remote->counters()));
  return result;
}

// A seed's run, started over after each console reset (its folder too), as it began: real
// robots are placed again.
run::RunResult run_seed(SessionParts& p, const SessionOptions& o, const SessionOutput& out,
                        const run::RunOptions& options) {
  for (;;) {
    run::RunResult r = run_once(p, o, out, options);
    if (r.ended_by != "reset" || interrupted(o)) return r;
    spdlog::info("seed {}: reset from the console: the run starts over", options.seed);
  }
}

void print_emulated_last_speeds(const SessionParts& p, const SessionOutput& out) {
  if (!p.real) return;
  for (const auto& [id, emulator] : p.real->emulators()) {
    const auto speeds = emulator->last_speeds();
    out.print("robot " + std::to_string(id) + " (emulated): last speed " + std::to_string(speeds.left_units) + " " +
              std::to_string(speeds.right_units));
  }
}

SessionResult run_batch_of_seeds(SessionParts& p, const SessionOptions& o, const SessionOutput& out) {
  BatchPlan plan;
  plan.first_seed = o.seed;
  plan.seeds = o.seeds;
  plan.out = o.out;
  // With real robots one run after another (the robots are the same ones), and on a bus
  // others watch too (a watcher follows one run at a time).
  const bool one_at_a_time = p.real || p.network_bus;
  plan.jobs = batch_jobs(o.jobs, o.threads, one_at_a_time ? 1 : std::numeric_limits<int>::max());
  plan.stop_flags = {o.interrupt, &p.batch_aborted};
  plan.on_run = [&](const run::BatchRun& r) {
    if (o.quiet) return;
    out.print(result_line(r.result));
    std::fflush(stdout);  // a batch of real-time runs takes minutes: show each as it ends
  };
  double wall_s = 0.0;
  const auto runs = run_batch(
      plan, p.base, [&](const run::RunOptions& options) { return run_seed(p, o, out, options); }, wall_s);
  SessionResult result;
  result.batch =
      run::summarise_batch(p.scenario.name, p.scenario.mode == run::ConvoyMode::kCentral ? "central" : "distributed",
                           runs, wall_s, plan.jobs);
  for (const run::BatchRun& r : runs) result.runs.push_back(r.result);
  if (!o.out.empty()) {
    std::filesystem::create_directories(o.out);
    run::write_batch_summary(std::filesystem::path(o.out) / "batch.json", *result.batch);
  }
  out.print(run::batch_table(*result.batch));
  print_emulated_last_speeds(p, out);
  if (result.batch->failed > 0 || result.batch->runs == 0) {
    result.status = Status::kFailed;
    result.error = result.batch->runs == 0 ? "no run took place" : "a run of the batch failed";
  }
  return result;
}

SessionResult run_single(SessionParts& p, const SessionOptions& o, const SessionOutput& out) {
  SessionResult result;
  try {
    result.runs.push_back(run_seed(p, o, out, p.base));
  } catch (const run::ScenarioError& e) {
    print_emulated_last_speeds(p, out);  // the run's end stopped them: say so
    return problem(Status::kFailed, e.what());
  } catch (const std::exception& e) {
    print_emulated_last_speeds(p, out);
    return problem(Status::kFailed, std::string("run failed: ") + e.what());
  }
  out.print(result_line(result.runs.back()));
  print_emulated_last_speeds(p, out);
  if (!o.out.empty()) out.print("run folder: " + o.out);
  // The page's viewers get the run's end (its last status and summary) before the server
  // goes; their page then says the run ended, not that the server vanished.
  if (p.gui) p.gui->flush(std::chrono::seconds(2));
  return result;
}

}  // namespace

SessionResult RunSession::run() {
  if (auto problem = SessionSetup(options_, output_, *parts_).all()) return std::move(*problem);
  if (options_.seeds > 0) return run_batch_of_seeds(*parts_, options_, output_);
  return run_single(*parts_, options_, output_);
}

}  // namespace rilbed::session

// `rilbed run SCENARIO.yaml`: one run, or a batch of runs over seeds, of a scenario. The
// options become a session::SessionOptions; session::RunSession does the rest.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "app/commands.hpp"
#include "app/interrupt.hpp"
#include "app/panel_options.hpp"
#include "session/run_session.hpp"

namespace rilbed::app {

namespace {

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

// What the flags say, before they become the session's options.
struct RunArgs {
  session::SessionOptions session;
  std::string scenario;
  std::string mode;  // overrides the scenario's
  std::string on_controller_error = "end-run";
};

int run_command(RunArgs& args) {
  const InterruptFlag interrupt;
  session::SessionOptions& o = args.session;
  o.scenario = args.scenario;
  if (args.mode == "central") o.mode = run::ConvoyMode::kCentral;
  if (args.mode == "distributed") o.mode = run::ConvoyMode::kDistributed;
  if (args.on_controller_error == "stop-robot") o.on_controller_error = run::ControllerErrorAction::kStopRobot;
  o.interrupt = &interrupt.flag();
  session::SessionOutput output;
  output.ask_operator = ask_operator_on_stdin;
  const session::SessionResult result = session::RunSession(o, output).run();
  switch (result.status) {
    case session::SessionResult::Status::kOk: return 0;
    case session::SessionResult::Status::kUsage: return kExitUsage;
    case session::SessionResult::Status::kFailed: return kExitFailure;
  }
  return kExitFailure;
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("run", "Run a scenario (simulation; robot-in-the-loop when it has real robots)");
  cmd->add_option("scenario", args->scenario, "Scenario file (YAML, see scenarios/README.md)")
      ->required()
      ->check(CLI::ExistingFile);
  auto* fast = cmd->add_flag("--fast", args->session.fast,
                             "As fast as the CPU allows (the default without real robots; an error with them)");
  auto* realtime =
      cmd->add_flag("--realtime", args->session.realtime, "Paced to the wall clock (the default with real robots)");
  fast->excludes(realtime);
  cmd->add_option("--rt-factor", args->session.rt_factor, "With --realtime: simulated seconds per wall second")
      ->check(CLI::PositiveNumber)
      ->needs(realtime);
  cmd->add_option("--duration", args->session.duration_s,
                  "Simulated seconds to run (default: the scenario's duration_s)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--stop-when-formed", args->session.stop_when_formed, "End 5 s after the convoy formed");
  cmd->add_flag("--stop-when-done", args->session.stop_when_done,
                "End once every robot's controller is done (track_explore: every edge seen; go_to: at its pose)");
  cmd->add_option("--seed", args->session.seed, "Seed of the initial poses and the noise (first seed of a batch)")
      ->default_val(1);
  cmd->add_option("--seeds", args->session.seeds, "Run a batch of N seeds (seed, seed+1, ...) and print its table")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out", args->session.out,
                  "Write the run folder here (a batch: one folder per seed and batch.json)");
  cmd->add_option("--jobs", args->session.jobs,
                  "Runs of a batch at once (default: one per core, or per --threads cores)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--threads", args->session.threads,
                  "Threads that step each run's world and agents (the run folder is the same for any count; only the "
                  "speed differs)")
      ->check(CLI::Range(1, 256))
      ->default_val(1);
  cmd->add_option("--mode", args->mode, "Override the scenario's convoy mode")
      ->check(CLI::IsMember({"central", "distributed"}));
  cmd->add_option("--on-controller-error", args->on_controller_error,
                  "What a controller's error (a Python exception, an answer rilbed cannot use) does: end-run stops "
                  "every robot and ends the run with exit 1; stop-robot stops that robot only (behaviour `error`, "
                  "an event) and the run goes on")
      ->check(CLI::IsMember({"end-run", "stop-robot"}))
      ->default_val("end-run");
  cmd->add_flag(
      "--all-virtual", args->session.all_virtual,
      "Make every real robot virtual (same poses and controllers): the simulation half of a sim-to-real comparison");
  cmd->add_option("--lcm", args->session.lcm_url,
                  "Publish the run on this LCM bus, visible to other processes (e.g. udpm://239.255.76.67:7667?ttl=0; "
                  "default: memq://, the run's own in-process bus, which sends nothing on the network)");
  cmd->add_option("--channel-prefix", args->session.channel_prefix,
                  "Put this before every channel name (two runs on one network)");
  cmd->add_option("--record", args->session.record,
                  "Write every message of the run to this LCM log (lcm-logplayer plays it; rilbed replay reads it)");
  cmd->add_flag("--record-frames", args->session.record_frames,
                "With --record: add the overhead camera's frames (JPEG, channel RILBED_FRAMES), so that `rilbed detect "
                "FILE.lcm` can run the vision pipeline on them again with other settings");
  cmd->add_flag("--no-place", args->session.no_place,
                "Real robots start where they stand (default: before each run they are driven, or put if emulated, "
                "to the run's start poses)");
  cmd->add_option("--place-timeout", args->session.place_timeout_s,
                  "Seconds the real robots get to drive to their start poses before the operator is asked")
      ->check(CLI::PositiveNumber)
      ->default_val(90);
  cmd->add_flag("--gui", args->session.gui,
                "Serve the web control panel from this run (prints its URL with a fresh token)");
  add_panel_options(*cmd, args->session.panel, "With --gui: ");
  cmd->add_flag("--quiet", args->session.quiet, "No per-second status (realtime) or per-run lines (batch)");
  cmd->callback([args] { exit_code() = run_command(*args); });
}

}  // namespace rilbed::app

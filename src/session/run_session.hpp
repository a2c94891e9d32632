// A run with everything around it, as `rilbed run` makes it and as Python and sweeps will:
// the scenario read against a registry of controllers, the LCM bus the run is published
// on (its own in-process one, or one other processes reach), a recording, the run's token
// and console, the web panel, real robots (their links and emulators, placed before each
// run), controllers in other processes, the console's reset, and batches over seeds.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "agents/controller_registry.hpp"
#include "run/batch_summary.hpp"
#include "run/run_options.hpp"
#include "run/scenario.hpp"
#include "run/scenario_overrides.hpp"
#include "session/panel.hpp"

namespace rilbed::session {

/// What a session is asked to do (the options of `rilbed run`, without the command line).
struct SessionOptions {
  std::filesystem::path scenario;  ///< the scenario file (YAML)
  /// The scenario's text instead of reading `scenario` (a scenario Python built as a dict);
  /// `scenario` then only names it, and its folder is where relative paths start.
  std::string scenario_text;
  /// Changes to the scenario before it is read (run::apply_overrides), in order.
  std::vector<run::ScenarioOverride> overrides;
  /// What a controller's failure does (`--on-controller-error`).
  run::ControllerErrorAction on_controller_error = run::ControllerErrorAction::kEndRun;
  bool fast = false;                    ///< as fast as possible (refused with real robots)
  bool realtime = false;                ///< paced to the wall clock (the default with real robots)
  double rt_factor = 1.0;               ///< simulated seconds per wall second, when realtime
  std::optional<double> duration_s;     ///< simulated seconds; default: the scenario's
  bool stop_when_formed = false;        ///< end 5 s after the convoy formed
  bool stop_when_done = false;          ///< end once every controller is done
  std::uint64_t seed = 1;               ///< the seed (the first of a batch)
  int seeds = 0;                        ///< > 0: a batch of this many seeds
  std::string out;                      ///< the run folder (a batch: one folder per seed and batch.json); empty: none
  int jobs = 0;                         ///< runs of a batch at once; 0: one per core (per `threads` cores)
  int threads = 1;                      ///< threads that step each run
  bool quiet = false;                   ///< no per-second status (real time) or per-run lines (batch)
  std::optional<run::ConvoyMode> mode;  ///< overrides the scenario's convoy mode
  bool all_virtual = false;             ///< every real robot virtual: the simulation half of a sim-to-real comparison
  std::string lcm_url;                  ///< a bus other processes reach; empty or memq://: the run's own
  std::string record;                   ///< write every message of the run to this LCM log
  bool record_frames = false;           ///< and the camera's frames
  std::string channel_prefix;           ///< before every channel name
  bool no_place = false;                ///< real robots start where they stand
  double place_timeout_s = 90.0;        ///< seconds the real robots get to drive to their start poses
  bool gui = false;                     ///< serve the web control panel
  PanelOptions panel;                   ///< with gui
  /// The controllers the scenario may name (null: rilbed's own).
  std::shared_ptr<const agents::ControllerRegistry> controllers;
  /// Set (from a signal handler, another thread) to end the run or batch cleanly; may be null.
  const std::atomic<bool>* interrupt = nullptr;
};

/// What the session says on the way, for a terminal or a caller that keeps it.
struct SessionOutput {
  /// A line for the user (stdout: results, the batch table, the panel's URL, the status line).
  std::function<void(const std::string&)> print;
  /// A notice for the user apart from the results (stderr: the run's token).
  std::function<void(const std::string&)> notice;
  /// Asks the operator to place real robots by hand (`message` says which, and where);
  /// true once they are, false to give up. Null: nobody to ask (placing then fails).
  std::function<bool(const std::string&)> ask_operator;
};

/// How a session ended.
struct SessionResult {
  enum class Status {
    kOk,      ///< every run ran (a batch: none failed)
    kFailed,  ///< an input could not be used, an output not written, or a run failed
    kUsage,   ///< the options do not go together (a malformed request)
  };
  Status status = Status::kOk;
  std::string error;                       ///< why, when not kOk (already logged)
  std::vector<run::RunResult> runs;        ///< each run's result (a batch: in seed order; not run: ended_by empty)
  std::optional<run::BatchSummary> batch;  ///< a batch's summary (what batch.json holds)
};

struct SessionParts;  // what a session sets up (run_session.cpp)

/// A session: make it, then run() it once. Logs through spdlog; prints through `output`.
class RunSession {
 public:
  RunSession(SessionOptions options, SessionOutput output);
  ~RunSession();
  RunSession(const RunSession&) = delete;
  RunSession& operator=(const RunSession&) = delete;

  /// Reads the scenario, sets everything up, runs the run or the batch and ends it: every
  /// real robot stopped, every file written.
  SessionResult run();

 private:
  SessionOptions options_;
  SessionOutput output_;
  std::unique_ptr<SessionParts> parts_;
};

}  // namespace rilbed::session

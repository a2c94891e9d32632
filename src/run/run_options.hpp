// How to run a scenario (RunOptions), what a run came to (RunResult), and how a run gets
// the bodies of its real robots (RealBodyFactory).
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "agents/body.hpp"
#include "core/time.hpp"
#include "environment/world.hpp"
#include "run/agent_exchange.hpp"
#include "run/run_control.hpp"
#include "run/run_observer.hpp"
#include "run/run_profile.hpp"
#include "run/run_recorder.hpp"
#include "run/scenario.hpp"
#include "vision/synthetic_camera.hpp"

namespace rilbed::run {

/// What a run does when a controller fails (raises an error, answers what rilbed cannot use).
enum class ControllerErrorAction {
  kEndRun,     ///< stop every robot, keep what was recorded, end the run with the error
  kStopRobot,  ///< stop that robot only (behaviour "error", an event); the run goes on
};

/// How to run.
struct RunOptions {
  std::uint64_t seed = 1;            ///< initial poses, wheel slip and sensor noise derive from it
  std::optional<double> duration_s;  ///< simulated seconds; default: the scenario's duration_s
  bool realtime = false;             ///< pace to the wall clock (else as fast as possible)
  double rt_factor = 1.0;            ///< simulated seconds per wall second when realtime
  bool stop_when_formed = false;     ///< end after_formed_s after the convoy formed
  bool stop_when_done = false;       ///< end once every agent is done (Controller::done)
  double after_formed_s = 5.0;
  std::optional<std::filesystem::path> out_dir;  ///< write the run folder here
  /// Set from another thread or a signal handler (it is only read) to end the run early.
  const std::atomic<bool>* interrupt = nullptr;
  /// Record trajectories and events even without an out_dir (kept in memory, for tests).
  bool keep_in_memory = false;
  /// With `camera: {emulate: true}`: the markers of the emulated real robots at their true
  /// poses now (the links layer reads them from its emulators). Called on the run's thread.
  std::function<std::vector<vision::SceneMarker>()> emulated_markers;
  /// The scenario's real robots that this run simulates instead (`--all-virtual`): written
  /// to summary.json, so that `rilbed compare` knows which robots the comparison is about.
  std::vector<int> virtual_stand_ins;
  /// Told the world, every robot's pose at every control step, every event and the
  /// status as the run goes (the LCM bus, tests); may be null. Must outlive the call.
  RunObserver* observer = nullptr;
  /// Attached while the run runs, so that another thread (a console) can pause, resume,
  /// change the real-time factor or end it; may be null. Must outlive the call.
  RunControl* control = nullptr;
  /// The controllers that run in other processes or on other machines: each
  /// robot it serves is stepped through it, one quantum per control instant. May be null
  /// (every controller in this process). Must outlive the call.
  AgentExchange* remote_agents = nullptr;
  /// What a controller's failure does (`--on-controller-error`).
  ControllerErrorAction on_controller_error = ControllerErrorAction::kEndRun;
  /// Time the run's parts (RunResult::profile): a few clock reads per robot and step.
  bool profile = false;
  /// Threads that step the world and the agents (>= 1). The run folder and every result
  /// are the same for any count (each robot's noise has its own stream, and what runs at
  /// once depends on nothing that runs beside it); only the speed differs. Agents whose
  /// controllers run in another process, and real robots, stay on the run's thread.
  int threads = 1;
  /// How often the monitor checks every robot for overlaps (RunResult::max_overlap_m):
  /// 0 at every control step; otherwise at the first control step of each such period.
  /// The check visits every robot's neighbours: at every step it costs about 5 % of a
  /// swarm's run (sim-bench checks once per simulated second).
  TimeUs overlap_check_us = 0;
};

/// What a run came to.
struct RunResult {
  std::uint64_t seed = 0;
  int convoy_size = 0;                     ///< robots with the convoy controller (0: no convoy)
  bool formed = false;                     ///< the convoy formed (see FormationMonitor)
  std::optional<double> formation_time_s;  ///< when the hold that formed it began
  int collisions = 0;                      ///< contact episodes (robot–anything)
  int robot_collisions = 0;                ///< of those, robot–robot
  double max_overlap_m = 0.0;  ///< largest overlap seen at the control steps checked (RunOptions::overlap_check_us)
  double simulated_s = 0.0;
  double wall_s = 0.0;      ///< the whole call, building the world included
  double run_wall_s = 0.0;  ///< the DEVS run alone (what sim-bench reports)
  double run_cpu_s =
      0.0;  ///< CPU time of the run's threads (the caller's and RunOptions::threads' workers) in the DEVS run
  /// A 64-bit digest of every trajectory sample (the sum of a hash of each sample's time,
  /// id, position and heading, bit for bit): equal digests mean, but for a tiny chance,
  /// the same trajectories (runs on different thread counts are compared by it).
  std::uint64_t trajectory_digest = 0;
  /// With RunOptions::profile: where run_wall_s went (the rest is the DEVS kernel's).
  std::optional<RunProfile> profile;
  /// Real-time runs: control steps of this process's controllers that took longer than
  /// the control period in wall time (each robot's first one is also an event).
  int controller_overruns = 0;
  /// Robots whose controller failed and was stopped (ControllerErrorAction::kStopRobot).
  std::vector<int> controller_failed;
  std::string ended_by;                      ///< "duration", "formed", "done" or "interrupt"
  std::vector<int> not_done;                 ///< with stop_when_done: the robots whose agent was not done at the end
  std::vector<TrajectorySample> trajectory;  ///< with keep_in_memory only
  std::vector<RunEvent> events;  ///< the monitor's events (not the console's notes), with keep_in_memory only
  /// A real-time run with an observer: how far behind the wall clock each control step
  /// finished, its reports handed to the observer, ms (what a viewer's cost adds to).
  std::vector<float> loop_latency_ms;
  /// summary.json's content.
  nlohmann::json summary() const;
};

/// Makes the body of a real robot (the links module supplies it); nullptr if it cannot.
/// Its virtual sensors read the world (World::sense), with the world's noise streams.
using RealBodyFactory = std::function<std::unique_ptr<agents::Body>(const RobotSpec&, environment::World&)>;

}  // namespace rilbed::run

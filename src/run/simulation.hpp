// One run of a scenario: builds the world and the robots' bodies, couples the DEVS
// models (world, sensing, agents, team broadcast or central coordinator, monitor, camera,
// control), runs them as fast as possible or paced to the wall clock, and ends it:
// every body stopped, the summary written and reported.
//
// Model order (the coordinator's tie-break at equal times): the world first, so it has
// moved to time t before any agent senses at t; then the sensing sweep and the agents;
// then the remote agents' quantum; then the team broadcaster or the central coordinator;
// the monitor samples 1 µs after each control step, when every decision of that step has
// been applied; the camera comes last.
#pragma once

#include <atomic>
#include <chrono>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "agents/body.hpp"
#include "agents/controller_group.hpp"
#include "core/worker_pool.hpp"
#include "environment/world.hpp"
#include "run/run_options.hpp"
#include "run/run_setup.hpp"
#include "run/scenario.hpp"
#include "sim/clock.hpp"
#include "sim/coordinator.hpp"
#include "sim/coupled.hpp"

namespace rilbed::run {

class VisionModel;
class WorldModel;
class SensingModel;
class AgentModel;
class QuantumModel;
class CentralConvoyModel;
class MonitorModel;
class GroupExchange;
struct ControllerWatch;

/// A run, in three steps: the constructor builds it, loop() runs it, end() stops every body
/// and reports what it came to. Borrows the scenario, the options and what they point to
/// (observer, control, remote agents), which must outlive it. Not copyable or movable:
/// its models hold references to its world and bodies. Every body is stopped by end(), or
/// by the destructor if end() was never called.
class Run {
 public:
  /// Builds the world, the bodies (real ones from `real_bodies`; the camera is checked
  /// before any real body is made) and the models. Throws ScenarioError for a scenario the
  /// run cannot use (convoy IDs not 1..N, real robots without a factory or not in real time
  /// at factor 1, a bad camera) and std::runtime_error for a run folder it cannot write.
  Run(const Scenario& scenario, const RunOptions& options, const RealBodyFactory& real_bodies = {});
  ~Run();
  Run(const Run&) = delete;
  Run& operator=(const Run&) = delete;

  /// Runs the DEVS models to the run's end time, or until the monitor, the console or an
  /// interrupt stops them. An exception from a model ends the loop; end() rethrows it.
  void loop();

  /// Stops every body (a real robot must not drive on), fills the result, writes the
  /// summary and reports the end to the observer. Rethrows an exception loop() caught,
  /// after all that. Call once.
  RunResult end();

 private:
  // A thread that stops the run when an interrupt comes while it is paused (none for a
  // fast run, or without an interrupt flag); `fired` tells loop() it did.
  std::jthread interrupt_watcher(std::atomic<bool>& fired);
  void check_convoy();
  void make_bodies(const RealBodyFactory& real_bodies);
  void add_agents();
  // The exchange of `group` (made the first time), for its members' agents.
  GroupExchange& group_exchange(agents::ControllerGroup& group);
  void make_watch();
  void add_team_models();
  void add_monitor();
  void add_control();
  void attach_control();
  void finish_profile();
  nlohmann::json summary() const;
  void report_end(const nlohmann::json& summary);

  const Scenario& scenario_;
  const RunOptions& options_;
  std::chrono::steady_clock::time_point wall_start_;
  RunResult result_;
  std::vector<int> convoy_ids_;  // the convoy's robots, 1..N (empty: no convoy)
  std::vector<int> real_ids_;
  environment::World world_;
  std::optional<core::WorkerPool> workers_;
  std::shared_ptr<VisionModel> camera_;
  std::vector<std::unique_ptr<agents::Body>> bodies_;  // in scenario.robots' order
  // Before the models: the agents' controllers point into the groups, the groups' quanta
  // to their exchanges, and every agent to the watch.
  agents::ControllerGroups groups_;
  std::vector<std::unique_ptr<GroupExchange>> group_exchanges_;
  std::unique_ptr<ControllerWatch> watch_;
  std::mutex watch_mutex_;  // the watch's reports may come from several threads
  std::shared_ptr<sim::Coupled> root_;
  WorldModel* world_model_ = nullptr;
  SensingModel* sensing_ = nullptr;
  std::vector<AgentModel*> agents_;  // in scenario.robots' (ID) order
  QuantumModel* quantum_ = nullptr;
  std::vector<QuantumModel*> group_quanta_;  // one per group of controllers
  CentralConvoyModel* central_model_ = nullptr;
  MonitorModel* monitor_ = nullptr;
  RunProfile profile_;
  std::unique_ptr<RunRecorder> recorder_;
  TimeUs end_us_ = 0;
  sim::Coordinator* coordinator_ptr_ = nullptr;  // the monitor's way to stop the run
  sim::FastClock fast_clock_;
  std::optional<sim::RealTimeClock> real_clock_;
  sim::Port<ControlAction>* control_in_ = nullptr;
  std::optional<sim::Coordinator> coordinator_;
  // The run as the console's accepted actions leave it, for checking the next one at once.
  std::atomic<bool> paused_{false};
  std::atomic<bool> central_now_{false};
  bool control_attached_ = false;
  bool ended_ = false;
  std::exception_ptr failure_;
};

/// Runs `scenario` once with `options`: Run's three steps. Throws as Run's constructor
/// does, and rethrows what a model threw once every body is stopped.
RunResult run_scenario(const Scenario& scenario, const RunOptions& options, const RealBodyFactory& real_bodies = {});

}  // namespace rilbed::run

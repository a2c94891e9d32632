// The DEVS models of a run (src/sim): an agent per robot that runs its controller every
// control period against its body; a team broadcaster that tells every agent where the
// others are (distributed mode); and the central convoy coordinator that commands every
// agent (central mode). The world model and the run's monitor live in simulation.hpp.
//
// Same-instant order: the coordinator runs imminent models in the order they were added
// (its flat order), so a run adds the world first: it has moved to time t before any
// agent senses at t.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "agents/body.hpp"
#include "agents/controller.hpp"
#include "agents/convoy.hpp"
#include "run/agent_exchange.hpp"
#include "run/run_profile.hpp"
#include "sim/atomic.hpp"
#include "sim/time.hpp"

namespace rilbed::run {

/// One team broadcast: every member's message, shared by all receivers (a broadcast to N
/// agents must not cost N copies of N messages).
using TeamBroadcast = std::shared_ptr<const std::vector<agents::TeamMessage>>;

/// A wheel command for one agent, from a central coordinator.
struct AgentCommand {
  int id = 0;
  agents::ControlOutput output;
};

/// An order from the console (RunControl) to the agents and the central coordinator,
/// applied between two steps.
struct ConsoleOrder {
  enum class Kind { kDrive, kMode };
  Kind kind = Kind::kDrive;
  int robot_id = 0;             ///< kDrive: the robot driven by hand
  agents::WheelCommand wheels;  ///< kDrive
  TimeUs until_us = 0;   ///< kDrive: its controller (or the coordinator) takes over again at the first step from then
  bool central = false;  ///< kMode: the convoy's agents obey the central coordinator (else their own controllers)
};

/// A robot driven by hand (the console's drive command) until a time.
struct ManualDrive {
  agents::WheelCommand wheels;
  TimeUs until_us = 0;
};

/// State of an agent model.
struct AgentState {
  TimeUs t_us = 0;      ///< simulated time of the last transition
  TimeUs sigma_us = 0;  ///< time left to the next control step
  std::shared_ptr<const std::vector<agents::TeamMessage>>
      team;                           ///< the latest broadcast, as received (shared, not copied)
  agents::ControlOutput last;         ///< the last command applied to the body
  bool commanded = false;             ///< it obeys the "command" input (central mode), its controller idle
  std::optional<ManualDrive> manual;  ///< driven by hand (its controller and commands set aside) until then
};

/// What the agents of a run do when a controller fails or is slow (one per run, shared).
struct ControllerWatch {
  /// A step that throws agents::ControllerError stops that robot only (behaviour
  /// "error", an event, never stepped again) instead of ending the run.
  bool stop_robot_on_error = false;
  /// > 0 (real-time runs): a step that takes longer than this, wall seconds, is an overrun.
  double step_budget_s = 0.0;
  /// Records an event (kind "controller") for robot `robot_id` at `t_us`; thread-safe.
  std::function<void(TimeUs t_us, int robot_id, const std::string& detail)> report;
};

/// One robot's agent: every control period it senses through its body, runs its
/// controller and drives its body. Without a controller, or while commanded (central
/// mode), it applies the commands that arrive on its `command` port instead. A console
/// order may switch it between the two, or drive its robot by hand for a while.
/// Inputs: "team" (TeamBroadcast), "command" (AgentCommand), "console" (ConsoleOrder).
class AgentModel final : public sim::AtomicModel<AgentState> {
 public:
  /// `body` must outlive the model. `controller` may be null (commanded agent).
  /// The first control step is at `first_step_us`, then every `period_us` (> 0).
  /// `commanded`: it starts obeying its "command" input (central mode) rather than its
  /// controller.
  /// `remote` (may be null; must outlive the model): when it serves this robot, the
  /// controller runs there. At each step the model then submits the input to it and
  /// drives nothing itself; the QuantumModel of the same instant applies the answer
  /// (complete()). `controller` is still given: it says whether the robot reads the team
  /// broadcast, and is never stepped here.
  AgentModel(agents::Body& body, std::unique_ptr<agents::Controller> controller, TimeUs period_us,
             TimeUs first_step_us = 0, bool commanded = false, AgentExchange* remote = nullptr);

  TimeUs time_advance() const override;
  void internal_transition() override;
  void external_transition(TimeUs elapsed_us) override;
  void output() override {}

  agents::Body& body() const { return *body_; }
  /// Whether its controller reads the team broadcast.
  bool wants_team() const { return controller_ && controller_->wants_team(); }
  /// Whether it has no goal left: no controller (it stands still or is commanded), or
  /// its controller is done.
  bool done() const {
    return !controller_ || state_.commanded || failed_ || (remote_ ? remote_done_ : controller_->done());
  }
  /// Whether its controller reports events (agents::Controller::reports_events; asked
  /// once, at construction).
  bool reports_events() const { return reports_events_; }
  /// Moves its controller's events since the last call to the end of `out`.
  void take_events(std::vector<agents::ControllerEvent>& out) {
    if (reports_events_) controller_->take_events(out);
  }
  /// Whether its controller runs elsewhere (see the constructor).
  bool is_remote() const { return remote_ != nullptr; }
  /// A remote controller's answer: drives the body with it, as step() would have (ignored
  /// while the robot is commanded or driven by hand).
  void complete(const RemoteOutput& answer);
  /// The active behaviour (a static string), "idle" before the first step.
  std::string_view behaviour() const { return state_.last.behaviour; }
  const agents::WheelCommand& wheels() const { return state_.last.wheels; }
  /// What its controller read at its last step (empty before the first, for a
  /// commanded agent, which reads nothing, and when not kept: set_keep_sensors).
  const environment::SensorReadings& sensors() const { return sensors_; }
  /// Whether sensors() keeps each step's readings (the default): a run whose observer
  /// may ask for them keeps them; a swarm's benchmark, with none, spares the copy.
  void set_keep_sensors(bool on) { keep_sensors_ = on; }
  /// Tells the controller the run ended (Controller::finish) and stops the body.
  void finish();
  /// How it treats its controller's errors and slowness; null (the default): an error
  /// ends the run, slowness is not timed. Must outlive the model.
  void set_watch(const ControllerWatch* watch) { watch_ = watch; }
  /// Steps that took longer than the watch's budget so far.
  int overruns() const { return overruns_; }
  /// Whether its controller failed and the robot was stopped (ControllerWatch).
  bool failed() const { return failed_; }
  /// Times its sensing and its controller's steps (times()), or not.
  void set_profile(bool on) { profiled_ = on; }
  /// Its sensing and behaviours times so far (set_profile); the rest of `RunProfile` is 0.
  const RunProfile& times() const { return times_; }
  /// Concurrent (Coordinator::set_workers) when its controller runs here and says so, and
  /// its body is concurrent: an agent touches its own state, its controller and its body.
  bool transitions_concurrent() const override {
    return !remote_ && body_->concurrent() && (!controller_ || controller_->concurrent());
  }
  void prefetch(int round) const override;
  /// A hint for a reader of many agents in turn (the run's monitor), in two rounds like
  /// prefetch(): 0 asks for the agent's lines that behaviour(), wheels() and body() read,
  /// 1 (later) for its body, whose pose(), id() and health() the reader calls next.
  void prefetch_view(int round) const {
    if (round == 0) {
      __builtin_prefetch(&state_.last);  // hints; GCC and Clang on any CPU
      __builtin_prefetch(&body_);
    } else {
      __builtin_prefetch(body_);
    }
  }
  /// The lines a step touches: those up to keep_sensors_ (see the members' order).
  std::size_t prefetch_bytes() const override {
    return static_cast<std::size_t>(reinterpret_cast<const char*>(&keep_sensors_ + 1) -
                                    reinterpret_cast<const char*>(this));
  }

 private:
  void apply(const ConsoleOrder& order);
  // Its own step: sense, decide (controller or hand), drive.
  void step();
  // Its controller's step, watched (ControllerWatch): the output, or a stop once it failed.
  agents::ControlOutput decide(const agents::ControlInput& input);

  // What every step touches first, together after the state (a swarm's agents are cold
  // at each step: the fewer lines, the fewer waits on memory); what it rarely touches
  // after, from the ports on (prefetch_bytes).
  agents::Body* body_;  // never null (a pointer, so that prefetch_view can name its line)
  std::unique_ptr<agents::Controller> controller_;
  TimeUs period_us_;
  AgentExchange* remote_ = nullptr;  // serves this robot, or null
  bool profiled_ = false;
  bool remote_done_ = false;  // the remote controller's done() at its last answer
  bool keep_sensors_ = true;
  bool failed_ = false;          // its controller failed; the robot stands (ControllerWatch)
  bool reports_events_ = false;  // its controller's reports_events(), asked once
  int overruns_ = 0;
  const ControllerWatch* watch_ = nullptr;
  sim::Port<TeamBroadcast>& team_in_;
  sim::Port<AgentCommand>& command_in_;
  sim::Port<ConsoleOrder>& console_in_;
  RunProfile times_;                     // its own (agents may step on several threads at once)
  environment::SensorReadings sensors_;  // what its controller read at its last step, when kept
};

/// Broadcasts every agent's pose and behaviour to the team every period.
/// Output: "team" (TeamBroadcast), one message per broadcast, shared by every receiver.
class TeamBroadcaster final : public sim::AtomicModel<TimeUs> {  // state: time to the next broadcast
 public:
  /// `agents` must outlive the model. First broadcast at `first_us`.
  TeamBroadcaster(std::vector<const AgentModel*> agents, TimeUs period_us, TimeUs first_us = 0);
  TimeUs time_advance() const override { return state_; }
  void internal_transition() override { state_ = period_us_; }
  void external_transition(TimeUs elapsed_us) override { state_ -= elapsed_us; }
  void output() override;

 private:
  std::vector<const AgentModel*> agents_;
  TimeUs period_us_;
  TimeUs t_us_ = 0;  // simulated time, advanced with each broadcast
  sim::Port<TeamBroadcast>& team_out_;
};

/// Sends each control instant's quantum to the remote controllers and applies their
/// answers (processes of their own, here or on other machines). Added after every AgentModel, with the same period and
/// first step, so that at each control instant every agent has submitted its input before the exchange, and the answers
/// drive the bodies before anything later in the instant (the central coordinator, the monitor) reads them. State: time
/// to the next quantum.
class QuantumModel final : public sim::AtomicModel<TimeUs> {
 public:
  /// `exchange` and the agents must outlive the model; `agents` are every AgentModel of
  /// the run (those the exchange serves are answered).
  QuantumModel(AgentExchange& exchange, std::vector<AgentModel*> agents, TimeUs period_us, TimeUs first_us = 0);
  TimeUs time_advance() const override { return state_; }
  void internal_transition() override;
  void external_transition(TimeUs elapsed_us) override { state_ -= elapsed_us; }
  void output() override {}
  /// Where the exchange's notices go (the run's events), from then on.
  void on_notice(std::function<void(TimeUs, const ExchangeNotice&)> record) { record_ = std::move(record); }

 private:
  AgentExchange& exchange_;
  std::vector<AgentModel*> agents_;
  TimeUs period_us_;
  TimeUs t_us_ = 0;  // the instant of the next quantum
  std::function<void(TimeUs, const ExchangeNotice&)> record_;
};

/// State of the central coordinator: when it next decides, and the commands it is about
/// to send (decided at time t, sent at the same t).
struct CentralState {
  TimeUs t_us = 0;
  TimeUs sigma_us = 0;
  std::vector<AgentCommand> pending;
};

/// Central mode (paper 001 §5): one coordinator that knows every agent's pose and sensors
/// and sends each its command. Output: "commands" (AgentCommand, one per agent). Input:
/// "console" (ConsoleOrder kMode): it decides only while central mode is on, and starts
/// afresh each time it is switched on.
class CentralConvoyModel final : public sim::AtomicModel<CentralState> {
 public:
  /// `bodies` must outlive the model. Decides every `period_us` from `first_us`.
  CentralConvoyModel(std::vector<agents::Body*> bodies, agents::ConvoyConfig config, TimeUs period_us,
                     TimeUs first_us = 0, bool active = true);
  TimeUs time_advance() const override { return state_.sigma_us; }
  void internal_transition() override;
  void external_transition(TimeUs elapsed_us) override;
  void output() override;

 private:
  std::vector<agents::Body*> bodies_;
  agents::ConvoyConfig config_;
  agents::CentralConvoy convoy_;
  TimeUs period_us_;
  bool active_;
  sim::Port<AgentCommand>& commands_out_;
  sim::Port<ConsoleOrder>& console_in_;
};

}  // namespace rilbed::run

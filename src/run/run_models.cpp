#include "run/run_models.hpp"

#include <chrono>

#include <algorithm>
#include <stdexcept>

namespace rilbed::run {

AgentModel::AgentModel(agents::Body& body, std::unique_ptr<agents::Controller> controller, TimeUs period_us,
                       TimeUs first_step_us, bool commanded, AgentExchange* remote)
    : sim::AtomicModel<AgentState>("agent" + std::to_string(body.id()), AgentState{}),
      body_(&body),
      controller_(std::move(controller)),
      period_us_(period_us),
      remote_(remote && remote->serves(body.id()) ? remote : nullptr),
      team_in_(add_input<TeamBroadcast>("team")),
      command_in_(add_input<AgentCommand>("command")),
      console_in_(add_input<ConsoleOrder>("console")) {
  if (period_us <= 0)
    throw std::invalid_argument("agent " + std::to_string(body.id()) + ": control period must be > 0");
  state_.commanded = commanded;
  state_.sigma_us = controller_ && !commanded ? first_step_us : sim::kInfinity;
  reports_events_ = controller_ && !remote_ && controller_->reports_events();
}

TimeUs AgentModel::time_advance() const { return state_.sigma_us; }

void AgentModel::prefetch(int round) const {
  // Round 0: its body's and controller's first lines (its own lines were asked for
  // earlier, prefetch_bytes); round 1: what the body will touch in the world. Hints;
  // GCC and Clang on any CPU.
  if (round == 0) {
    __builtin_prefetch(body_);
    if (controller_) {
      // Two lines: a controller is its vtable pointer and a configuration of a few
      // numbers at least (a wander controller is 72 bytes), rarely aligned to a line.
      const char* controller = reinterpret_cast<const char*>(controller_.get());
      __builtin_prefetch(controller);
      __builtin_prefetch(controller + 64);
    }
  } else {
    body_->prefetch();
  }
}

void AgentModel::internal_transition() {
  state_.t_us += state_.sigma_us;
  if (state_.manual && state_.t_us >= state_.manual->until_us) {
    // The hand drive is over: the controller (or the coordinator's next command) takes over.
    state_.manual.reset();
    state_.last = {};
    body_->stop();
  }
  if (state_.manual) {
    body_->drive(state_.manual->wheels);
    state_.last.wheels = state_.manual->wheels;
    state_.last.behaviour = "console";
  } else if (controller_ && !state_.commanded && !failed_) {
    step();
  }
  const bool stepping = controller_ && !state_.commanded && !failed_;
  if (stepping) {
    state_.sigma_us = period_us_;
  } else if (state_.manual) {
    state_.sigma_us = std::min(period_us_, state_.manual->until_us - state_.t_us);
  } else {
    state_.sigma_us = sim::kInfinity;
  }
}

void AgentModel::step() {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = profiled_ ? Clock::now() : Clock::time_point{};
  agents::ControlInput input;
  input.t_us = state_.t_us;
  input.robot_id = body_->id();
  input.sensors = body_->sense(state_.t_us);
  input.pose = body_->pose();
  if (state_.team) input.team = *state_.team;
  const Clock::time_point sensed = profiled_ ? Clock::now() : Clock::time_point{};
  if (remote_) {
    // Its answer comes back through complete(), later in this instant.
    remote_->submit(input);
  } else {
    state_.last = decide(input);
    body_->drive(state_.last.wheels);
  }
  if (keep_sensors_) sensors_ = std::move(input.sensors);  // for the run's observer
  if (profiled_) {
    times_.sensing_s += std::chrono::duration<double>(sensed - start).count();
    times_.behaviours_s += std::chrono::duration<double>(Clock::now() - sensed).count();
  }
}

agents::ControlOutput AgentModel::decide(const agents::ControlInput& input) {
  using Clock = std::chrono::steady_clock;
  if (!watch_) return controller_->step(input);
  const Clock::time_point start = watch_->step_budget_s > 0 ? Clock::now() : Clock::time_point{};
  try {
    agents::ControlOutput out = controller_->step(input);
    if (watch_->step_budget_s > 0) {
      const double took_s = std::chrono::duration<double>(Clock::now() - start).count();
      if (took_s > watch_->step_budget_s && overruns_++ == 0 && watch_->report) {
        watch_->report(input.t_us, body_->id(),
                       "overran: a step took " + std::to_string(int(took_s * 1000 + 0.5)) + " ms of its " +
                           std::to_string(int(watch_->step_budget_s * 1000 + 0.5)) +
                           " ms period (the summary counts every overrun)");
      }
    }
    return out;
  } catch (const agents::ControllerError& e) {
    if (!watch_->stop_robot_on_error) throw;
    failed_ = true;
    if (watch_->report) watch_->report(input.t_us, body_->id(), std::string("error, robot stopped: ") + e.what());
    return {{}, "error"};
  }
}

void AgentModel::complete(const RemoteOutput& answer) {
  if (!remote_ || state_.commanded || state_.manual) return;
  state_.last = answer.output;
  remote_done_ = answer.done;
  body_->drive(state_.last.wheels);
}

void AgentModel::external_transition(TimeUs elapsed_us) {
  state_.t_us += elapsed_us;
  if (state_.sigma_us != sim::kInfinity) state_.sigma_us -= elapsed_us;
  if (!team_in_.messages().empty()) state_.team = team_in_.messages().back();
  for (const ConsoleOrder& order : console_in_.messages()) apply(order);
  if (state_.manual) return;  // driven by hand: commands wait
  for (const AgentCommand& c : command_in_.messages()) {
    if (c.id != body_->id()) continue;
    state_.last = c.output;
    body_->drive(c.output.wheels);
  }
}

void AgentModel::apply(const ConsoleOrder& order) {
  switch (order.kind) {
    case ConsoleOrder::Kind::kDrive:
      if (order.robot_id != body_->id()) return;
      state_.manual = ManualDrive{order.wheels, order.until_us};
      body_->drive(order.wheels);  // now, not at the next step
      state_.last.wheels = order.wheels;
      state_.last.behaviour = "console";
      // A stepping agent keeps its step times (the drive ends at a step); one that waits
      // for commands wakes when the drive ends.
      if (!controller_ || state_.commanded) state_.sigma_us = std::max<TimeUs>(0, order.until_us - state_.t_us);
      return;
    case ConsoleOrder::Kind::kMode:
      if (!controller_ || state_.commanded == order.central) return;
      state_.commanded = order.central;
      // Distributed: its controller decides from now on (this instant); central: it waits
      // for the coordinator's commands (or the end of a hand drive).
      if (!state_.commanded) {
        state_.sigma_us = 0;
      } else if (!state_.manual) {
        state_.sigma_us = sim::kInfinity;
      }
      return;
  }
}

void AgentModel::finish() {
  // A remote controller finishes in its own process (AgentExchange::end).
  if (controller_ && !remote_) controller_->finish();
  body_->stop();
  state_.last.wheels = {};
}

QuantumModel::QuantumModel(AgentExchange& exchange, std::vector<AgentModel*> agents, TimeUs period_us, TimeUs first_us)
    : sim::AtomicModel<TimeUs>("quantum", first_us),
      exchange_(exchange),
      agents_(std::move(agents)),
      period_us_(period_us),
      t_us_(first_us) {
  if (period_us <= 0) throw std::invalid_argument("quantum: period must be > 0");
  std::sort(agents_.begin(), agents_.end(),
            [](const AgentModel* a, const AgentModel* b) { return a->body().id() < b->body().id(); });
}

void QuantumModel::internal_transition() {
  const TimeUs t = t_us_;
  auto next = agents_.begin();
  for (const RemoteOutput& answer : exchange_.exchange(t)) {
    // The agents are in ID order (a search: a world of 1,000 robots made this loop a
    // million comparisons per step). Answers mostly come in ID order too (a group's
    // always): the agent after the last one answered is tried first, which spares a
    // swarm's 100,000 agents 17 cold reads each.
    auto it = next;
    if (it == agents_.end() || (*it)->body().id() != answer.robot_id) {
      it = std::lower_bound(agents_.begin(), agents_.end(), answer.robot_id,
                            [](const AgentModel* a, int id) { return a->body().id() < id; });
    }
    if (it != agents_.end() && (*it)->body().id() == answer.robot_id) {
      // The agents a group's answers reach next are cold: asked for ahead, as the
      // monitor does (prefetch_view's two rounds).
      if (agents_.end() - it > 8) (*(it + 8))->prefetch_view(0);
      if (agents_.end() - it > 4) (*(it + 4))->prefetch_view(1);
      (*it)->complete(answer);
      next = it + 1;
    }
  }
  if (record_) {
    for (const ExchangeNotice& n : exchange_.take_notices()) record_(t, n);
  }
  t_us_ += period_us_;
  state_ = period_us_;
}

TeamBroadcaster::TeamBroadcaster(std::vector<const AgentModel*> agents, TimeUs period_us, TimeUs first_us)
    : sim::AtomicModel<TimeUs>("team_broadcast", first_us),
      agents_(std::move(agents)),
      period_us_(period_us),
      t_us_(first_us),
      team_out_(add_output<TeamBroadcast>("team")) {
  if (period_us <= 0) throw std::invalid_argument("team broadcast: period must be > 0");
}

void TeamBroadcaster::output() {
  // output() runs at the instant of the internal transition that follows; t_us_ is
  // that instant (first_us, then every period).
  auto team = std::make_shared<std::vector<agents::TeamMessage>>();
  team->reserve(agents_.size());
  for (const AgentModel* a : agents_) {
    if (const auto pose = a->body().pose()) team->push_back({a->body().id(), *pose, a->behaviour(), t_us_});
  }
  team_out_.add(std::move(team));
  t_us_ += period_us_;
}

CentralConvoyModel::CentralConvoyModel(std::vector<agents::Body*> bodies, agents::ConvoyConfig config, TimeUs period_us,
                                       TimeUs first_us, bool active)
    : sim::AtomicModel<CentralState>("central_convoy", CentralState{0, active ? first_us : sim::kInfinity, {}}),
      bodies_(std::move(bodies)),
      config_(config),
      convoy_(config),
      period_us_(period_us),
      active_(active),
      commands_out_(add_output<AgentCommand>("commands")),
      console_in_(add_input<ConsoleOrder>("console")) {
  if (period_us <= 0) throw std::invalid_argument("central convoy: period must be > 0");
}

void CentralConvoyModel::internal_transition() {
  state_.t_us += state_.sigma_us;
  if (!state_.pending.empty()) {  // the commands just went out; next decision in a period
    state_.pending.clear();
    state_.sigma_us = period_us_;
    return;
  }
  std::vector<agents::CentralConvoy::AgentView> views;
  views.reserve(bodies_.size());
  for (agents::Body* b : bodies_) views.push_back({b->id(), b->pose(), b->sense(state_.t_us).proximity});
  for (auto& [id, out] : convoy_.step(state_.t_us, views)) state_.pending.push_back({id, out});
  // Send at this same instant (a zero time advance): decision and command share time t.
  state_.sigma_us = state_.pending.empty() ? period_us_ : 0;
}

void CentralConvoyModel::external_transition(TimeUs elapsed_us) {
  state_.t_us += elapsed_us;
  if (state_.sigma_us != sim::kInfinity) state_.sigma_us -= elapsed_us;
  for (const ConsoleOrder& order : console_in_.messages()) {
    if (order.kind != ConsoleOrder::Kind::kMode || order.central == active_) continue;
    active_ = order.central;
    state_.pending.clear();
    if (active_) {
      convoy_ = agents::CentralConvoy(config_);  // afresh: the agents moved on meanwhile
      state_.sigma_us = 0;                       // decide now
    } else {
      state_.sigma_us = sim::kInfinity;
    }
  }
}
void CentralConvoyModel::output() {
  for (const AgentCommand& c : state_.pending) commands_out_.add(c);
}

}  // namespace rilbed::run

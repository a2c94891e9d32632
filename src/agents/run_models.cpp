#include "agents/run_models.hpp"

#include <stdexcept>

namespace rilbed::agents {

AgentModel::AgentModel(Body& body, std::unique_ptr<Controller> controller, TimeUs period_us, TimeUs first_step_us)
    : sim::AtomicModel<AgentState>("agent" + std::to_string(body.id()), AgentState{}),
      body_(body),
      controller_(std::move(controller)),
      period_us_(period_us),
      team_in_(add_input<TeamBroadcast>("team")),
      command_in_(add_input<AgentCommand>("command")) {
  if (period_us <= 0) throw std::invalid_argument("agent " + std::to_string(body.id()) + ": control period must be > 0");
  state_.sigma_us = controller_ ? first_step_us : sim::kInfinity;
}

TimeUs AgentModel::time_advance() const { return state_.sigma_us; }

void AgentModel::internal_transition() {
  state_.t_us += state_.sigma_us;
  ControlInput input;
  input.t_us = state_.t_us;
  input.robot_id = body_.id();
  input.sensors = body_.sense(state_.t_us);
  input.pose = body_.pose();
  if (state_.team) input.team = *state_.team;
  state_.last = controller_->step(input);
  body_.drive(state_.last.wheels);
  state_.sensors = std::move(input.sensors);  // kept for the run's observer
  state_.sigma_us = period_us_;
}

void AgentModel::external_transition(TimeUs elapsed_us) {
  state_.t_us += elapsed_us;
  if (state_.sigma_us != sim::kInfinity) state_.sigma_us -= elapsed_us;
  if (!team_in_.messages().empty()) state_.team = team_in_.messages().back();
  for (const AgentCommand& c : command_in_.messages()) {
    if (c.id != body_.id()) continue;
    state_.last = c.output;
    body_.drive(c.output.wheels);
  }
}

void AgentModel::finish() {
  if (controller_) controller_->finish();
  body_.stop();
  state_.last.wheels = {};
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
  auto team = std::make_shared<std::vector<TeamMessage>>();
  team->reserve(agents_.size());
  for (const AgentModel* a : agents_) {
    if (const auto pose = a->body().pose()) team->push_back({a->body().id(), *pose, a->behaviour(), t_us_});
  }
  team_out_.add(std::move(team));
  t_us_ += period_us_;
}

CentralConvoyModel::CentralConvoyModel(std::vector<Body*> bodies, ConvoyConfig config, TimeUs period_us, TimeUs first_us)
    : sim::AtomicModel<CentralState>("central_convoy", CentralState{0, first_us, {}}),
      bodies_(std::move(bodies)),
      convoy_(config),
      period_us_(period_us),
      commands_out_(add_output<AgentCommand>("commands")) {
  if (period_us <= 0) throw std::invalid_argument("central convoy: period must be > 0");
}

void CentralConvoyModel::internal_transition() {
  state_.t_us += state_.sigma_us;
  if (!state_.pending.empty()) {  // the commands just went out; next decision in a period
    state_.pending.clear();
    state_.sigma_us = period_us_;
    return;
  }
  std::vector<CentralConvoy::AgentView> views;
  views.reserve(bodies_.size());
  for (Body* b : bodies_) views.push_back({b->id(), b->pose(), b->sense(state_.t_us).proximity});
  for (auto& [id, out] : convoy_.step(state_.t_us, views)) state_.pending.push_back({id, out});
  // Send at this same instant (a zero time advance): decision and command share time t.
  state_.sigma_us = state_.pending.empty() ? period_us_ : 0;
}

void CentralConvoyModel::external_transition(TimeUs elapsed_us) {
  state_.t_us += elapsed_us;
  state_.sigma_us -= elapsed_us;
}

void CentralConvoyModel::output() {
  for (const AgentCommand& c : state_.pending) commands_out_.add(c);
}

}  // namespace rilbed::agents

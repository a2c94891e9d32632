#include "bus/agent_server.hpp"

#include <unistd.h>

#include <algorithm>
#include <random>
#include <sstream>

#include "bus/agent_messages.hpp"
#include "bus/lcm_checked.hpp"
#include "bus/lcm_conversion.hpp"
#include "rilbed/agent_hello_t.hpp"
#include "rilbed/quantum_t.hpp"

namespace rilbed::bus {

namespace {

using Clock = std::chrono::steady_clock;

std::string host_name() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "unknown";
  return name;
}

}  // namespace

AgentServer::AgentServer(lcm::LCM& quanta, lcm::LCM& answers, AgentServerConfig config, GroupedControllerFactory make)
    : quanta_(quanta), answers_(answers), config_(std::move(config)), make_(std::move(make)) {
  std::random_device rd;
  std::ostringstream s;
  s << host_name() << ":" << getpid() << ":" << std::hex << rd();
  session_ = s.str();
  quantum_sub_ =
      std::make_unique<LcmSubscription>(quanta_, config_.channels.quantum,
                                        [this](const std::string&, const void* d, std::size_t n) { on_quantum(d, n); });
}

AgentServer::~AgentServer() { finish_run(); }

void AgentServer::hello() {
  rilbed::agent_hello_t h;
  h.session = session_;
  h.scenario = config_.scenario_name;
  h.ids = config_.robot_ids;
  h.num_ids = static_cast<std::int32_t>(h.ids.size());
  h.host = host_name();
  h.pid = static_cast<std::int32_t>(getpid());
  publish_encoded(answers_, config_.channels.agent_hello, h);
}

void AgentServer::start_run(const std::string& run) {
  finish_run();
  run_ = run;
  run_ended_ = false;
  last_quantum_ = -1;
  last_reply_ = {};
  groups_ = std::make_unique<agents::ControllerGroups>();
  for (const int id : config_.robot_ids) controllers_[id] = make_(id, *groups_);
  ++counters_.runs;
}

void AgentServer::finish_run() {
  for (auto& [id, controller] : controllers_) {
    if (controller) controller->finish();
  }
  controllers_.clear();
  groups_.reset();
}

void AgentServer::on_quantum(const void* data, std::size_t size) {
  rilbed::quantum_t q;
  // (A run always has a nonce: an empty one is nobody's.)
  if (!decode_checked(data, size, q) || !plausible(q) || q.run.empty()) {
    ++counters_.refused;
    return;
  }
  if (std::find(q.sessions.begin(), q.sessions.end(), session_) == q.sessions.end()) return;  // for other processes
  last_quantum_at_ = Clock::now();
  if (q.run != run_) {
    if (q.end) return;  // the end of a run we never served
    start_run(q.run);
  }
  if (run_ended_) return;
  if (q.end) {
    finish_run();
    run_ended_ = true;
    return;
  }
  if (q.quantum == last_quantum_) {  // the run did not hear our answer: the same again
    for (int copy = 0; copy < std::max(1, config_.answer_copies); ++copy) {
      publish_encoded(answers_, config_.channels.quantum_reply, last_reply_);
    }
    ++counters_.repeats;
    return;
  }
  if (q.quantum < last_quantum_) return;  // stale
  if (last_quantum_ >= 0 && q.quantum > last_quantum_ + 1) counters_.skipped += q.quantum - last_quantum_ - 1;
  rilbed::quantum_reply_t reply;
  reply.run = q.run;
  reply.session = session_;
  reply.quantum = q.quantum;
  step_quantum(q, reply);
  reply.num_outputs = static_cast<std::int32_t>(reply.outputs.size());
  last_quantum_ = q.quantum;
  last_reply_ = reply;
  for (int copy = 0; copy < std::max(1, config_.answer_copies); ++copy) {
    publish_encoded(answers_, config_.channels.quantum_reply, reply);
  }
  ++counters_.steps;
}

void AgentServer::step_quantum(const rilbed::quantum_t& q, rilbed::quantum_reply_t& reply) {
  std::vector<agents::TeamMessage> team;
  if (q.has_team) {
    team.reserve(q.team.size());
    for (const rilbed::team_member_t& m : q.team) team.push_back(from_lcm(m));
  }
  std::vector<agents::ControllerGroup*> groups;  // those with members in this quantum, in order met
  for (const rilbed::agent_input_t& in : q.inputs) {
    const auto it = controllers_.find(in.id);
    if (it == controllers_.end() || !it->second) continue;  // not one of ours
    agents::ControlInput input = from_lcm(in, q.utime, model_names_);
    if (q.has_team && it->second->wants_team()) input.team = team;
    if (agents::ControllerGroup* group = it->second->group()) {
      group->gather(input);
      if (std::find(groups.begin(), groups.end(), group) == groups.end()) groups.push_back(group);
      continue;
    }
    run::RemoteOutput out;
    out.robot_id = in.id;
    out.output = it->second->step(input);
    out.done = it->second->done();
    reply.outputs.push_back(to_lcm(out));
  }
  for (agents::ControllerGroup* group : groups) {
    for (const agents::GroupAnswer& a : group->step_gathered()) {
      reply.outputs.push_back(to_lcm(run::RemoteOutput{a.robot_id, a.output, a.done}));
    }
  }
}

void AgentServer::serve(const std::atomic<bool>& stop) {
  auto last_hello = Clock::now() - std::chrono::hours(1);
  while (!stop.load()) {
    const auto now = Clock::now();
    const bool idle =
        run_.empty() || run_ended_ || now - last_quantum_at_ > std::chrono::milliseconds(config_.silence_ms);
    if (idle && now - last_hello >= std::chrono::milliseconds(config_.hello_ms)) {
      hello();
      last_hello = now;
    }
    quanta_.handleTimeout(std::min(100, config_.hello_ms));
    if (config_.once && run_ended_) break;
  }
  finish_run();
}

}  // namespace rilbed::bus

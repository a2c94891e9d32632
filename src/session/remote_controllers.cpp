#include "session/remote_controllers.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "run/run_setup.hpp"

namespace rilbed::session {

RemoteControllers::RemoteControllers(const run::Scenario& scenario, const std::string& scenario_file,
                                     const std::string& lcm_url, const bus::Channels& channels,
                                     const std::string& channel_prefix, bool realtime, const std::string& scenario_text)
    : scenario_file_(scenario_file) {
  const run::AgentsSpec& spec = *scenario.agents;
  std::string error;
  quanta_bus_ = bus::open_lcm(lcm_url, error);
  if (quanta_bus_) answers_bus_ = bus::open_lcm(bus::agent_reply_url(lcm_url), error);
  if (!quanta_bus_ || !answers_bus_) throw std::runtime_error(error);
  const AgentLaunchConfig launch{scenario_file,  scenario_text, lcm_url,
                                 channel_prefix, spec.launch,   spec.remote_rilbed};
  if (spec.processes > 0 && !processes_.start(launch, place_agents(spec.ids, spec.processes, spec.hosts), error)) {
    throw std::runtime_error(error);
  }
  config_.channels = channels;
  config_.scenario_name = scenario.name;
  config_.robot_ids = spec.ids;
  for (const int id : spec.ids) {
    const auto robot =
        std::find_if(scenario.robots.begin(), scenario.robots.end(), [&](const auto& r) { return r.id == id; });
    if (const auto c = run::make_controller(scenario, *robot); c && c->wants_team()) config_.team_readers.insert(id);
  }
  config_.realtime = realtime;
  config_.resend_ms = spec.resend_ms;
  config_.dead_after_ms = spec.dead_after_ms;
  config_.deadline_ms = spec.deadline_ms;
  announce_timeout_ = std::chrono::milliseconds(static_cast<std::int64_t>(spec.announce_timeout_s * 1000.0));
}

std::unique_ptr<bus::RemoteAgents> RemoteControllers::connect() {
  auto remote = std::make_unique<bus::RemoteAgents>(*quanta_bus_, *answers_bus_, config_);
  if (const auto missing = remote->wait_for_agents(announce_timeout_, [this] { return processes_.ended_early(); })) {
    throw run::ScenarioError(scenario_file_ + ": " + *missing);
  }
  return remote;
}

std::string RemoteControllers::counters_text(const bus::RemoteAgentsCounters& c) {
  char line[320];
  std::snprintf(line, sizeof line,
                "agents: %lld quanta sent, %lld sent again, %lld duplicate answers, %lld late, %lld processes lost, "
                "%lld robots rejoined",
                static_cast<long long>(c.quanta_sent), static_cast<long long>(c.repeats),
                static_cast<long long>(c.duplicates), static_cast<long long>(c.late),
                static_cast<long long>(c.lost_processes), static_cast<long long>(c.rejoins));
  return line;
}

}  // namespace rilbed::session

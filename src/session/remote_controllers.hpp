// The controllers a scenario's `agents:` block runs in other processes: the two LCM
// buses of the exchange, the `rilbed agent` processes the session starts (here or over
// ssh), and, for each run, the exchange that waits for every process to announce itself.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "bus/remote_agents.hpp"
#include "run/scenario.hpp"
#include "session/agent_processes.hpp"

namespace rilbed::session {

/// A session's remote controllers. Not copyable; its processes stop when it goes.
class RemoteControllers {
 public:
  /// Opens the exchange's buses on `lcm_url` (and its next port, for the answers) and
  /// starts the scenario's agent processes. Throws std::runtime_error when a bus cannot be
  /// opened or a process cannot start.
  RemoteControllers(const run::Scenario& scenario, const std::string& scenario_file, const std::string& lcm_url,
                    const bus::Channels& channels, const std::string& channel_prefix, bool realtime,
                    const std::string& scenario_text = {});
  RemoteControllers(const RemoteControllers&) = delete;
  RemoteControllers& operator=(const RemoteControllers&) = delete;

  /// The exchange for one run, once every remote robot's process has announced itself.
  /// Throws run::ScenarioError naming the scenario file for robots whose process did not
  /// come in time (or ended early).
  std::unique_ptr<bus::RemoteAgents> connect();

  /// What a run's exchange counted, as one line ("agents: 120 quanta sent, ...").
  static std::string counters_text(const bus::RemoteAgentsCounters& counters);

 private:
  std::string scenario_file_;
  std::unique_ptr<lcm::LCM> quanta_bus_, answers_bus_;
  AgentProcesses processes_;
  bus::RemoteAgentsConfig config_;
  std::chrono::milliseconds announce_timeout_{0};
};

}  // namespace rilbed::session

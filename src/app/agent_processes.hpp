// The `rilbed agent` processes that `rilbed run` (a scenario's `agents: {processes: N}`) and
// `rilbed quantum-bench` start on this machine.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace rilbed::app {

/// Agent processes started on this machine with a run's bus, stopped (SIGTERM, then
/// waited for) when this goes.
class AgentProcesses {
 public:
  AgentProcesses() = default;
  AgentProcesses(const AgentProcesses&) = delete;
  AgentProcesses& operator=(const AgentProcesses&) = delete;
  ~AgentProcesses();
  /// Starts one `rilbed agent --scenario FILE --ids ... --lcm URL --quiet` per group of
  /// robots (this very binary); false (and the reason) when one cannot start.
  bool start(const std::string& scenario_file, const std::vector<std::vector<int>>& groups, const std::string& url,
             const std::string& prefix, std::string& error);
  /// Stops them now (as the destructor would).
  void stop();

 private:
  std::vector<pid_t> pids_;
};

/// `ids` in `processes` groups of consecutive IDs, as even as can be.
std::vector<std::vector<int>> split_ids(const std::vector<int>& ids, int processes);

}  // namespace rilbed::app

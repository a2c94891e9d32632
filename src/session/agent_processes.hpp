// The `rilbed agent` processes that `rilbed run` (a scenario's `agents:` block) and
// `rilbed quantum-bench` start: on this machine, or on other machines through a launch
// command (ssh by default).
#pragma once

#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

namespace rilbed::session {

/// How the agent processes of a run are started (shared by all of them).
struct AgentLaunchConfig {
  std::string scenario_file;  ///< the run's scenario file (agents on this machine read it)
  /// The scenario as the run read it, when that is not the file's text (a scenario from
  /// Python, overrides): every agent then gets it on its input, as agents on other hosts
  /// get the file's, with `scenario_file` naming it. Empty: the file as it is.
  std::string scenario_text;
  std::string url;     ///< the run's LCM URL
  std::string prefix;  ///< the run's channel prefix; empty: none
  /// For agents on other hosts: the launch command, `{host}` and `{command}` in its items
  /// (agents::AgentsSpec::launch), and the rilbed binary there (empty: this binary's path).
  std::vector<std::string> launch;
  std::string remote_rilbed;
};

/// One agent process to start: its robots, and where.
struct AgentPlacement {
  std::vector<int> ids;
  std::string host;  ///< empty: this machine, started directly
};

/// Agent processes started with a run's bus, stopped when this goes: a local one gets
/// SIGTERM; a remote one's launch command (ssh) gets its standard input closed and SIGTERM,
/// which closes the connection, and the agent at the far end ends when its input closes.
class AgentProcesses {
 public:
  AgentProcesses() = default;
  AgentProcesses(const AgentProcesses&) = delete;
  AgentProcesses& operator=(const AgentProcesses&) = delete;
  ~AgentProcesses();
  /// Starts one process per placement: `rilbed agent --scenario FILE --ids ... --lcm URL
  /// --quiet` here, or the launch command with `rilbed agent --scenario-stdin NAME ...` for a
  /// host, the scenario's text written to its input. False (and the reason) when one
  /// cannot start; those started so far keep running until stop().
  bool start(const AgentLaunchConfig& config, const std::vector<AgentPlacement>& placements, std::string& error);
  /// A process that has already ended (an ssh that could not connect, a binary missing on
  /// the host), described with its robots, host and exit status; nullopt while all run.
  std::optional<std::string> ended_early();
  /// Stops them now (as the destructor would).
  void stop();

 private:
  struct Started {
    pid_t pid = 0;
    int input_fd = -1;  ///< the write end of the process's standard input (the scenario); -1: it reads a file
    AgentPlacement placement;
    bool ended = false;
  };
  // Starts `args` (searched on PATH with `search_path`); `with_input`: `input` goes to its
  // standard input, which stays open while the process is ours.
  bool spawn(const std::vector<std::string>& args, bool search_path, bool with_input, const std::string& input,
             Started& started, std::string& error);
  std::vector<Started> started_;
};

/// `ids` in `processes` groups of consecutive IDs, as even as can be.
std::vector<std::vector<int>> split_ids(const std::vector<int>& ids, int processes);

/// `ids` split into `processes` groups (split_ids), group i placed on hosts[i % size], or
/// on this machine when there are no hosts.
std::vector<AgentPlacement> place_agents(const std::vector<int>& ids, int processes,
                                         const std::vector<std::string>& hosts);

/// `text` quoted for a POSIX shell as one word ('...', a ' inside as '\'').
std::string shell_quote(const std::string& text);

/// The launch command for one host: each item of `launch` with `{host}` and `{command}`
/// replaced.
std::vector<std::string> launch_arguments(const std::vector<std::string>& launch, const std::string& host,
                                          const std::string& command);

}  // namespace rilbed::session

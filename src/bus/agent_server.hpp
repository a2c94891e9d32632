// The agent process's side of the agent exchange over LCM (`rilbed agent`):
// it runs some robots' controllers for whichever run sends it quanta. See remote_agents.hpp
// for the protocol. A controller here is the same code as in the run's process; only
// where it runs differs.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "agents/controller.hpp"
#include "agents/controller_group.hpp"
#include "bus/lcm_bus.hpp"
#include "rilbed/quantum_reply_t.hpp"
#include "rilbed/quantum_t.hpp"

namespace rilbed::bus {

/// Knobs of an agent process.
struct AgentServerConfig {
  Channels channels;           ///< with the run's channel prefix
  std::string scenario_name;   ///< announced; a run of another scenario does not take it
  std::vector<int> robot_ids;  ///< the robots whose controllers it runs
  int hello_ms = 200;          ///< announce this often until a run sends a quantum
  /// Announce again when no quantum came for this long (the run ended without its "end"
  /// reaching us, or a new run waits).
  int silence_ms = 1000;
  bool once = false;  ///< return after the first run ends
  /// Each answer is sent this many times. A lock-step quantum waits for the last of its P
  /// answers, so on a lossy bus one lost answer in P costs the whole step a repeat round
  /// (with 10 % loss and 12 processes, 7 steps in 10); a second copy makes that 1 in 10.
  /// Costs the run one more datagram per process and step; no other agent hears answers.
  int answer_copies = 2;
};

/// What an agent process has counted.
struct AgentServerCounters {
  std::int64_t runs = 0;     ///< runs served (a new run nonce each)
  std::int64_t steps = 0;    ///< quanta stepped
  std::int64_t repeats = 0;  ///< quanta answered again without stepping (the run's repeats)
  std::int64_t skipped = 0;  ///< quanta that never arrived before a later one (real time)
  std::int64_t refused = 0;  ///< messages that were not well formed, or held values no robot reads (plausible())
};

class AgentServer {
 public:
  /// Builds a fresh controller for a robot, for each run; a controller that decides with a
  /// group (a vectorised Python class) joins `groups`, the run's, and the server then steps
  /// each group once per quantum.
  using GroupedControllerFactory =
      std::function<std::unique_ptr<agents::Controller>(int robot_id, agents::ControllerGroups& groups)>;
  /// The same for controllers that never form groups.
  using ControllerFactory = std::function<std::unique_ptr<agents::Controller>(int robot_id)>;
  /// `quanta` (handled here) and `answers` (published on only: answers and announcements)
  /// must outlive the server and be handled by no other thread; they may be one instance.
  AgentServer(lcm::LCM& quanta, lcm::LCM& answers, AgentServerConfig config, GroupedControllerFactory make);
  AgentServer(lcm::LCM& quanta, lcm::LCM& answers, AgentServerConfig config, ControllerFactory make)
      : AgentServer(quanta, answers, std::move(config),
                    GroupedControllerFactory(
                        [make = std::move(make)](int id, agents::ControllerGroups&) { return make(id); })) {}
  ~AgentServer();

  /// Serves until `stop` becomes true (checked at least every 100 ms) or, with `once`,
  /// until a run ends. Every controller is finished (Controller::finish) when its run
  /// ends, and before returning.
  void serve(const std::atomic<bool>& stop);

  /// Announces this process once (serve() does so every hello_ms while idle); for callers
  /// that handle the bus themselves.
  void announce() { hello(); }
  /// Handles one quantum's bytes as if they came off the bus (serve() does this for
  /// every message on the quantum channel).
  void handle_quantum(const void* data, std::size_t size) { on_quantum(data, size); }

  /// This process's session name (in its announcements).
  const std::string& session() const { return session_; }
  const AgentServerCounters& counters() const { return counters_; }

 private:
  void on_quantum(const void* data, std::size_t size);
  // Steps one quantum's inputs: each lone controller in turn, then each group once.
  void step_quantum(const rilbed::quantum_t& q, rilbed::quantum_reply_t& reply);
  void hello();
  void start_run(const std::string& run);
  void finish_run();

  lcm::LCM& quanta_;
  lcm::LCM& answers_;
  AgentServerConfig config_;
  GroupedControllerFactory make_;
  std::string session_;
  std::string run_;  // the run being served, empty between runs
  bool run_ended_ = false;
  std::int64_t last_quantum_ = -1;
  rilbed::quantum_reply_t last_reply_;              // sent again for a repeat
  std::set<std::string, std::less<>> model_names_;  // what its controllers' sensor-model readings name
  // The run's groups before its controllers: members point into them.
  std::unique_ptr<agents::ControllerGroups> groups_;
  std::map<int, std::unique_ptr<agents::Controller>> controllers_;
  std::chrono::steady_clock::time_point last_quantum_at_{};
  AgentServerCounters counters_;
  std::unique_ptr<LcmSubscription> quantum_sub_;
};

}  // namespace rilbed::bus

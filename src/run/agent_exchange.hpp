// Controllers that run outside the run's process: in other processes or on
// other machines, reached in time quanta (paper 000 section 6.1). The run hands each
// remote robot's input to an AgentExchange at the robot's control step and, once every
// agent of that instant has stepped, asks it for the answers of the whole quantum. The
// exchange is an interface so that the DEVS side can be tested without a network
// (links::RemoteAgents is the LCM implementation).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "agents/controller.hpp"
#include "core/time.hpp"

namespace rilbed::run {

/// One remote controller's answer to one control step.
struct RemoteOutput {
  int robot_id = 0;
  agents::ControlOutput output;  ///< its behaviour points to a string that lives as long as the program
  bool done = false;             ///< Controller::done() after the step
};

/// What an exchange tells the run between quanta: a late answer, an agent process that
/// stopped answering or came back. Recorded as the run's events.
struct ExchangeNotice {
  std::string kind;    ///< "agent" (events.csv kind)
  int robot_id = 0;    ///< the robot concerned, 0 for a whole process
  std::string detail;  ///< e.g. "lost: process host:pid stopped answering"
};

/// Where the inputs of remote controllers go and their outputs come from.
class AgentExchange {
 public:
  virtual ~AgentExchange() = default;

  /// Whether robot `robot_id`'s controller runs elsewhere.
  virtual bool serves(int robot_id) const = 0;

  /// The input of one remote robot for the quantum at input.t_us (copied; input.team
  /// need not outlive the call).
  virtual void submit(const agents::ControlInput& input) = 0;

  /// Sends the quantum at `t_us` (everything submitted since the last call) and returns
  /// the answers to apply now. In lock-step (fast) mode that is every submitted robot's
  /// answer to this quantum, or a stop for a robot whose process is gone. In real-time
  /// mode it is whatever has arrived by the exchange's deadline: an answer that comes
  /// later is counted late and returned by the next call.
  virtual std::vector<RemoteOutput> exchange(TimeUs t_us) = 0;

  /// What happened since the last call (lost and rejoined agents, late answers), in order.
  virtual std::vector<ExchangeNotice> take_notices() { return {}; }

  /// The run is over: tells every agent process (Controller::finish on its side).
  virtual void end() {}
};

}  // namespace rilbed::run

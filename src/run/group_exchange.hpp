// A group of controllers that decide together (agents::ControllerGroup: a vectorised
// Python class) as the run's agents see it: an AgentExchange in this process. Each
// member's agent submits its input at its control step, and the group's QuantumModel,
// once every agent of the instant has submitted, steps the whole group in one call.
#pragma once

#include <string>
#include <vector>

#include "agents/controller_group.hpp"
#include "run/agent_exchange.hpp"
#include "run/run_models.hpp"

namespace rilbed::run {

/// One group's exchange. Borrows the group and the watch, which must outlive it.
class GroupExchange final : public AgentExchange {
 public:
  GroupExchange(agents::ControllerGroup& group, const ControllerWatch& watch) : group_(group), watch_(watch) {}
  /// Robot `robot_id` steps with the group (its agent is given this exchange).
  void add_member(int robot_id);

  bool serves(int robot_id) const override;
  void submit(const agents::ControlInput& input) override;
  /// Steps the group once; a ControllerError ends the run, or, with the watch's
  /// stop_robot_on_error, stops every member (behaviour "error", done) from then on.
  std::vector<RemoteOutput> exchange(TimeUs t_us) override;
  std::vector<ExchangeNotice> take_notices() override;
  void end() override { group_.finish(); }

  /// Steps that took longer than the watch's budget so far.
  int overruns() const { return overruns_; }
  /// The members stopped because the group failed (empty unless it did).
  std::vector<int> failed_members() const { return failed_ ? members_ : std::vector<int>{}; }
  agents::ControllerGroup& group() const { return group_; }

 private:
  std::vector<RemoteOutput> stop_all(const std::string& reason);

  agents::ControllerGroup& group_;
  std::vector<int> members_;  // sorted
  const ControllerWatch& watch_;
  std::vector<int> submitted_;  // this instant's
  std::vector<ExchangeNotice> notices_;
  bool failed_ = false;
  int overruns_ = 0;
};

}  // namespace rilbed::run

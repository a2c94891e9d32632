#include "run/group_exchange.hpp"

#include <algorithm>
#include <chrono>

namespace rilbed::run {

void GroupExchange::add_member(int robot_id) {
  members_.insert(std::upper_bound(members_.begin(), members_.end(), robot_id), robot_id);
}

bool GroupExchange::serves(int robot_id) const {
  return std::binary_search(members_.begin(), members_.end(), robot_id);
}

void GroupExchange::submit(const agents::ControlInput& input) {
  submitted_.push_back(input.robot_id);
  if (!failed_) group_.gather(input);
}

std::vector<RemoteOutput> GroupExchange::exchange(TimeUs t_us) {
  (void)t_us;
  if (failed_) return stop_all("");
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  std::vector<agents::GroupAnswer> answers;
  try {
    answers = group_.step_gathered();
  } catch (const agents::ControllerError& e) {
    if (!watch_.stop_robot_on_error) throw;
    failed_ = true;
    return stop_all(std::string("error, robot stopped: ") + e.what());
  }
  if (watch_.step_budget_s > 0) {
    const double took_s = std::chrono::duration<double>(Clock::now() - start).count();
    if (took_s > watch_.step_budget_s && overruns_++ == 0) {
      notices_.push_back({"controller", 0,
                          group_.describe() + " overran: a step took " + std::to_string(int(took_s * 1000 + 0.5)) +
                              " ms of its " + std::to_string(int(watch_.step_budget_s * 1000 + 0.5)) +
                              " ms period (the summary counts every overrun)"});
    }
  }
  submitted_.clear();
  std::vector<RemoteOutput> out;
  out.reserve(answers.size());
  for (const agents::GroupAnswer& a : answers) out.push_back({a.robot_id, a.output, a.done});
  return out;
}

std::vector<RemoteOutput> GroupExchange::stop_all(const std::string& reason) {
  std::vector<RemoteOutput> out;
  for (const int id : submitted_) {
    out.push_back({id, {{}, "error"}, true});
    if (reason.empty()) continue;
    // The cause once, on the first robot; the others point to it.
    notices_.push_back({"controller", id,
                        id == submitted_.front() ? reason
                                                 : "error, robot stopped with its group (see robot " +
                                                       std::to_string(submitted_.front()) + ")"});
  }
  submitted_.clear();
  return out;
}

std::vector<ExchangeNotice> GroupExchange::take_notices() {
  std::vector<ExchangeNotice> out;
  out.swap(notices_);
  return out;
}

}  // namespace rilbed::run

#include "run/run_control.hpp"

namespace rilbed::run {

std::optional<std::string> RunControl::act(const ControlAction& action) {
  std::lock_guard lock(mutex_);
  if (!apply_) return "no run is running";
  if (auto why = check_(action)) return why;
  apply_(action);
  if (action.kind == ControlAction::Kind::kPause) paused_ = true;
  if (action.kind == ControlAction::Kind::kResume) paused_ = false;
  return std::nullopt;
}

void RunControl::attach(std::function<std::optional<std::string>(const ControlAction&)> check,
                        std::function<void(const ControlAction&)> apply) {
  std::lock_guard lock(mutex_);
  check_ = std::move(check);
  apply_ = std::move(apply);
}

void RunControl::detach() {
  std::lock_guard lock(mutex_);
  check_ = nullptr;
  apply_ = nullptr;
  paused_ = false;
}

}  // namespace rilbed::run

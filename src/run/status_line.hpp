// The terminal's status line of a running run, as a subscriber of what the run reports
// (RunObserver): once per simulated second, the time, every robot's behaviour (and its
// health when not "ok") and whether the convoy has formed, e.g.
//   t=12.0s  1:lead  2:follow  3:search(unseen)  [formed]
// It reads only the messages, so a run's line and a watcher's agree.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "run/run_observer.hpp"

namespace rilbed::run {

/// Writes one status line per status the run reports.
class StatusLine final : public RunObserver {
 public:
  /// `print` gets each line (without a newline).
  explicit StatusLine(std::function<void(const std::string&)> print) : print_(std::move(print)) {}
  void on_poses(TimeUs t_us, std::span<const PoseReport> poses) override;
  void on_status(const StatusReport& status) override;
  /// The line for `status` after `poses` (what on_status prints; empty for an ended run).
  static std::string format(const StatusReport& status, std::span<const PoseReport> poses);

 private:
  struct Robot {
    int id;
    std::string behaviour, health;
  };
  std::function<void(const std::string&)> print_;
  std::vector<PoseReport> poses_;  // the last step's, their strings in names_
  std::vector<Robot> robots_;
};

}  // namespace rilbed::run

// Steering a run while it runs, from another thread (a console on the LCM bus): pause,
// resume, change the real-time factor, end it, start it over, switch the convoy's mode,
// drive one robot by hand for a while, tune the camera's vision settings. The run attaches itself for as long as it
// runs; the actions reach it as external events of its DEVS run (Coordinator::inject), so
// they are applied on the run's own thread between two steps and recorded as events.
#pragma once

#include <atomic>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rilbed::run {

/// One action on a run.
struct ControlAction {
  /// kRefused records a command the console refused (a wrong token), as an event.
  enum class Kind { kPause, kResume, kRtFactor, kExit, kReset, kMode, kDrive, kVision, kRefused };
  Kind kind = Kind::kPause;
  double rt_factor = 1.0;   ///< kRtFactor: the new factor
  bool central = false;     ///< kMode: true for central mode, false for distributed
  int robot_id = 0;         ///< kDrive: the robot
  int left = 0, right = 0;  ///< kDrive: wheel speeds, Khepera units (+-127, 8 mm/s each)
  double duration_s = 0.0;  ///< kDrive: for this long (simulated seconds), then its controller again
  /// kVision: settings by name (vision::kVisionSettingNames) and value, all or none applied
  std::vector<std::pair<std::string, double>> vision;
  std::string who;   ///< who asked (for the run's events)
  std::string what;  ///< kRefused: the command and why it was refused
};

/// A handle on the run that is running, usable from any thread. Every action returns
/// nullopt when the run took it, or the reason it cannot ("no run is running", "a run
/// with real robots runs at a factor of 1", ...).
class RunControl {
 public:
  /// Checks `action` against the run now and hands it to the run.
  std::optional<std::string> act(const ControlAction& action);

  /// For run_scenario: while attached, act() asks `check` (from any thread; quick) and
  /// hands accepted actions to `apply`.
  void attach(std::function<std::optional<std::string>(const ControlAction&)> check,
              std::function<void(const ControlAction&)> apply);
  void detach();
  /// Whether the run took a pause it has not resumed from (any thread).
  bool paused() const { return paused_.load(); }

 private:
  std::atomic<bool> paused_{false};
  std::mutex mutex_;
  std::function<std::optional<std::string>(const ControlAction&)> check_;
  std::function<void(const ControlAction&)> apply_;
};

}  // namespace rilbed::run

// The console's actions as a DEVS model, applied on the run's thread between two steps.
#pragma once

#include <atomic>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "run/camera_model.hpp"
#include "run/monitor_model.hpp"
#include "run/run_control.hpp"
#include "run/run_models.hpp"
#include "run/run_observer.hpp"
#include "sim/atomic.hpp"
#include "sim/clock.hpp"

namespace rilbed::run {

// The console's actions as a DEVS model: they arrive on its input (injected from the
// console's thread) and are applied here, on the run's thread, between two steps. Those
// for the agents (drive one by hand, switch the convoy's mode) go out on its "orders"
// output at the same instant.
class ControlModel final : public sim::AtomicModel<std::vector<ConsoleOrder>> {  // state: orders to send now
 public:
  struct Setup {
    std::vector<AgentModel*> agents;
    MonitorModel* monitor = nullptr;
    sim::RealTimeClock* clock = nullptr;  // null in a fast run
    RunObserver* observer = nullptr;
    VisionModel* camera = nullptr;  // the overhead camera, if any (its settings)
  };
  explicit ControlModel(Setup setup)
      : sim::AtomicModel<std::vector<ConsoleOrder>>("control", {}),
        s_(std::move(setup)),
        in_(add_input<ControlAction>("action")),
        out_(add_output<ConsoleOrder>("orders")) {}
  TimeUs time_advance() const override { return state_.empty() ? sim::kInfinity : 0; }
  void internal_transition() override { state_.clear(); }
  void output() override {
    for (const ConsoleOrder& o : state_) out_.add(o);
  }
  void external_transition(TimeUs elapsed_us) override {
    t_us_ += elapsed_us;
    for (const ControlAction& a : in_.messages()) apply(a);
  }
  sim::Port<ControlAction>& input() { return in_; }
  sim::Port<ConsoleOrder>& orders() { return out_; }

 private:
  void apply(const ControlAction& a);

  // The last hand drive of each robot (to tell a renewal from a new drive).
  struct LastDrive {
    agents::WheelCommand wheels;
    TimeUs until_us = 0;
    std::string who;
  };

  Setup s_;
  sim::Port<ControlAction>& in_;
  sim::Port<ConsoleOrder>& out_;
  TimeUs t_us_ = 0;
  std::map<int, LastDrive> drives_;
};

/// Checks a console's action as the run would apply it, at once, on the console's thread
/// (RunControl hands on one action at a time, so the checks see them in the order the run
/// applies them). What the accepted actions change is kept here: the pause, the convoy's
/// mode, the vision settings.
struct ActionChecker {
  bool realtime = false;                             ///< the run is paced to the clock (it can be paused)
  bool has_real = false;                             ///< it has real robots (factor 1 only)
  bool has_convoy = false;                           ///< it has a convoy (a mode to switch)
  std::set<int> robot_ids;                           ///< the robots a drive may name
  std::optional<vision::VisionSettings> vision_now;  ///< the camera's settings; nullopt: no camera
  std::atomic<bool>* paused = nullptr;               ///< the run's; must outlive the checker
  std::atomic<bool>* central_now = nullptr;          ///< the run's; must outlive the checker
  /// nullopt to accept `a`; else why it is refused.
  std::optional<std::string> operator()(const ControlAction& a);
};

}  // namespace rilbed::run

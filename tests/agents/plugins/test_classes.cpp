// A C++ plug-in library of controller classes for the loader's tests
// (test_library_controllers.cpp, test_scenario.cpp): built against the SDK's headers only,
// as a lab's library is.
#include <rilbed/controller.hpp>

#include <stdexcept>
#include <string>

namespace {

// Drives both wheels at `speed_mps`; its behaviour names how many team members it was sent.
class Cruise : public rilbed::sdk::Controller {
 public:
  Cruise(double speed_mps, double stop_after_steps) : speed_mps_(speed_mps), stop_after_steps_(stop_after_steps) {}
  rilbed::sdk::Output step(const rilbed::sdk::Input& in) override {
    ++steps_;
    last_proximity_ = in.proximity() ? (*in.proximity())[2] : -1;
    return rilbed::sdk::wheels_from_twist(speed_mps_, 0.0, "team" + std::to_string(in.team_size()));
  }
  bool done() const override { return stop_after_steps_ > 0 && steps_ >= stop_after_steps_; }

 private:
  double speed_mps_;
  double stop_after_steps_;
  int steps_ = 0;
  int last_proximity_ = 0;
};

// Fails at its step at or after `fail_at_ms`.
class Failing : public rilbed::sdk::Controller {
 public:
  explicit Failing(double fail_at_ms) : fail_at_ms_(fail_at_ms) {}
  rilbed::sdk::Output step(const rilbed::sdk::Input& in) override {
    if (static_cast<double>(in.t_us()) >= fail_at_ms_ * 1000) throw std::runtime_error("the gyro is gone");
    return rilbed::sdk::wheels_from_twist(0.05, 0.0, "cruise");
  }

 private:
  double fail_at_ms_;
};

rilbed::sdk::ControllerInfo cruise() {
  rilbed::sdk::ControllerInfo info{"cruise", "drives straight ahead at its speed"};
  info.params = {rilbed::sdk::Param::number("speed_mps", "m/s", 0.1, 0.0, 1.016, "its speed"),
                 rilbed::sdk::Param::number("stop_after_steps", "", 0, 0, 1e6, "done after so many steps; 0: never")};
  info.params.back().integer = true;
  info.sensors = {"proximity", "pose"};
  info.wants_team = true;
  info.make = [](const rilbed::sdk::Context& c) {
    return std::make_unique<Cruise>(c.params.get("speed_mps"), c.params.get("stop_after_steps"));
  };
  return info;
}

rilbed::sdk::ControllerInfo failing() {
  rilbed::sdk::ControllerInfo info{"failing", "fails at its step at fail_at_ms"};
  info.params = {rilbed::sdk::Param::required_number("fail_at_ms", "ms", 0, 1e9, "when it fails")};
  info.make = [](const rilbed::sdk::Context& c) {
    if (c.robot_id == 13) throw std::invalid_argument("robot 13 is unlucky");
    return std::make_unique<Failing>(c.params.get("fail_at_ms"));
  };
  return info;
}

rilbed::sdk::ControllerInfo tracker() {
  rilbed::sdk::ControllerInfo info{"needs_track", "reads track sensors, which a robot must carry"};
  info.sensors = {"track"};
  info.required_sensors = {"track"};
  info.concurrent = false;
  info.make = [](const rilbed::sdk::Context& c) { return std::make_unique<Failing>(1e12 + c.robot_id); };
  return info;
}

}  // namespace

RILBED_DEFINE_PLUGIN();
RILBED_CONTROLLERS(cruise(), failing(), tracker());

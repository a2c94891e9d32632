// A controller of the tests' own, as a lab would register one: it turns on the spot at
// the rate its one parameter gives.
#pragma once

#include <memory>

#include "agents/controller.hpp"
#include "agents/controller_registry.hpp"

namespace rilbed::testing {

class Spinner final : public agents::Controller {
 public:
  explicit Spinner(double turn_radps) : turn_radps_(turn_radps) {}
  agents::ControlOutput step(const agents::ControlInput&) override {
    return {agents::wheels_from_twist(0.0, turn_radps_), "spin"};
  }

 private:
  double turn_radps_;
};

/// Its registry entry: "spinner", parameter turn_radps (rad/s, default 1, 0 to 5).
inline agents::ControllerEntry spinner_entry() {
  agents::ControllerEntry e;
  e.name = "spinner";
  e.summary = "turns on the spot";
  e.params = {{"turn_radps", "rad/s", 1.0, false, 0.0, 5.0, false, "how fast it turns"}};
  e.origin = "the test";
  e.make = [](const agents::ControllerContext& c) { return std::make_unique<Spinner>(c.params.get("turn_radps")); };
  return e;
}

}  // namespace rilbed::testing

// The Braitenberg wanderer of ../braitenberg_c, written in C++ against rilbed's SDK: the
// same weights and the same wheel speeds, but its numbers are parameters that a scenario
// may set (rilbed checks them against the ranges below before the controller is made), and
// its state is a member rather than a register. docs/write-a-controller.md walks through it.
#include <rilbed/controller.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

namespace {

// Weights from each proximity sensor to each wheel, per 1023 of reading (sensor 0 is on the
// left): an obstacle on the left speeds the left wheel and slows the right one.
constexpr std::array<int, 8> kLeftWeights = {4, 6, 8, -8, -6, -4, 0, 0};
constexpr std::array<int, 8> kRightWeights = {-4, -6, -8, 8, 6, 4, 0, 0};

struct BraitenbergConfig {
  int cruise_units = 10;      // wheel speed in the open, Khepera units (8 mm/s each)
  int max_units = 20;         // fastest wheel speed
  int avoid_threshold = 200;  // a reading above it counts as avoiding
};

class Braitenberg : public rilbed::sdk::Controller {
 public:
  explicit Braitenberg(BraitenbergConfig config) : config_(config) {}

  rilbed::sdk::Output step(const rilbed::sdk::Input& in) override {
    const std::array<int, 8> proximity = in.proximity().value_or(std::array<int, 8>{});
    int left = config_.cruise_units * 1023, right = config_.cruise_units * 1023, nearest = 0;
    for (int i = 0; i < 8; ++i) {
      const int p = std::max(proximity[i], 0);
      nearest = std::max(nearest, p);
      left += kLeftWeights[i] * p;
      right += kRightWeights[i] * p;
    }
    ++steps_;
    return {std::clamp(left / 1023, -config_.max_units, config_.max_units),
            std::clamp(right / 1023, -config_.max_units, config_.max_units),
            nearest > config_.avoid_threshold ? "avoid" : "cruise"};
  }

 private:
  BraitenbergConfig config_;
  long steps_ = 0;  // this robot's own: each robot has its own Braitenberg
};

// Khepera units from m/s: 8 mm/s each.
int units(double speed_mps) { return static_cast<int>(std::lround(speed_mps / rilbed::sdk::kMetresPerSecondPerUnit)); }

rilbed::sdk::ControllerInfo braitenberg() {
  rilbed::sdk::ControllerInfo info("braitenberg_cpp",
                                   "a Braitenberg wanderer: IR readings weighted onto the wheels, so that it turns "
                                   "away from what it sees (the C++ twin of braitenberg_c)");
  info.params = {
      rilbed::sdk::Param::number("cruise_mps", "m/s", 0.08, 0.0, 0.5, "speed in the open"),
      rilbed::sdk::Param::number("max_mps", "m/s", 0.16, 0.008, 1.016, "fastest wheel speed"),
      rilbed::sdk::Param::number("avoid_threshold", "", 200, 0, 1023, "a reading above it counts as avoiding"),
  };
  info.params.back().integer = true;
  info.sensors = {"proximity"};
  info.required_sensors = {"proximity"};
  info.make = [](const rilbed::sdk::Context& c) {
    BraitenbergConfig config;
    config.cruise_units = units(c.params.get("cruise_mps"));
    config.max_units = units(c.params.get("max_mps"));
    config.avoid_threshold = static_cast<int>(c.params.get("avoid_threshold"));
    return std::make_unique<Braitenberg>(config);
  };
  return info;
}

}  // namespace

RILBED_DEFINE_PLUGIN();
RILBED_CONTROLLERS(braitenberg());

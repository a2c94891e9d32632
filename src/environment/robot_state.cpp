#include "environment/robot_state.hpp"

#include <cmath>

namespace rilbed::environment {

std::string_view to_string(RobotKind kind) { return kind == RobotKind::kReal ? "real" : "virtual"; }

OdometryReading RobotState::odometer() const {
  // A small slack keeps exact multiples (1000 pulses after 80 mm) from flooring to 999
  // through rounding error in the travel sum.
  constexpr double kSlack = 1e-6;
  return {static_cast<std::int64_t>(std::floor(left_wheel_travel_m / kKheperaPulse_m + kSlack)),
          static_cast<std::int64_t>(std::floor(right_wheel_travel_m / kKheperaPulse_m + kSlack))};
}

}  // namespace rilbed::environment

#include "agents/steering.hpp"

#include <algorithm>
#include <cmath>

namespace rilbed::agents {

WheelCommand steer_to(const Pose2& self, Vec2 target_m, double standoff_m, const SteeringConfig& config, Vec2 repulse) {
  const Vec2 to = target_m - self.position_m;
  const double distance = to.norm();
  if (distance < 1e-9) return {};
  Vec2 course = to / distance + repulse;
  if (course.norm() < 1e-9) course = to / distance;
  const double error = wrap_rad_pi(std::atan2(course.y, course.x) - self.heading_rad);
  const double turn = std::clamp(config.turn_gain * error, -config.max_turn_radps, config.max_turn_radps);
  // Speed falls to zero at the standoff and turns negative inside it; only while roughly
  // facing the course, so the robot turns first and never drives sideways into a crowd.
  const double approach = std::clamp((distance - standoff_m) / config.slow_zone_m, -1.0, 1.0);
  double speed = approach >= 0 ? approach * config.max_speed_mps : approach * config.max_reverse_mps;
  const double facing = std::cos(error);
  speed = facing > 0.0 ? speed * facing : 0.0;
  return wheels_from_twist(speed, turn);
}

WheelCommand steer_away(const environment::ProximityValues& p, const SteeringConfig& config) {
  const double scale = 1.0 / environment::kProximityMax;
  // Left-side sensors are 0..2, right-side 3..5 (0 and 5 point sideways).
  const double left = scale * (0.5 * p[0] + p[1] + p[2]);
  const double right = scale * (p[3] + p[4] + 0.5 * p[5]);
  const double front = scale * std::max({p[1], p[2], p[3], p[4]});
  double turn = config.max_turn_radps * std::clamp(right - left, -1.0, 1.0);
  // Dead ahead with nothing to choose between: turn left rather than stall.
  if (std::abs(right - left) < 0.1 && front > 0.3) turn = config.max_turn_radps;
  const double speed = config.max_speed_mps * std::clamp(0.6 - front, -0.3, 0.6);
  return wheels_from_twist(speed, turn);
}

double obstacle_level(const environment::ProximityValues& p, double low, double high) {
  const double scale = 1.0 / environment::kProximityMax;
  const double nearest = scale * std::max({p[0], p[1], p[2], p[3], p[4], p[5]});
  if (high <= low) return nearest >= high ? 1.0 : 0.0;
  return std::clamp((nearest - low) / (high - low), 0.0, 1.0);
}

}  // namespace rilbed::agents

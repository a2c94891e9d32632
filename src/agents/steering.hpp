// Low-level steering shared by the behaviours: drive to a point, keep a distance, turn
// away from what the proximity sensors see. Each returns wheel speeds in Khepera units.
#pragma once

#include <optional>

#include "agents/controller.hpp"
#include "core/geometry.hpp"
#include "environment/sensor_readings.hpp"

namespace rilbed::agents {

/// Knobs of the steering laws.
struct SteeringConfig {
  /// Cruising speed, m/s (the Khepera II manages about 1 m/s; the lab drives slowly so
  /// that the camera sees no blur and the IR sensors have time to react).
  double max_speed_mps = 0.15;
  /// Speed while reversing out of a too-close standoff, m/s.
  double max_reverse_mps = 0.04;
  /// Turn rate per radian of heading error, 1/s. Higher turns sharper, overshoots sooner.
  double turn_gain = 3.0;
  /// Largest turn rate, rad/s.
  double max_turn_radps = 4.0;
  /// Distance over which the speed ramps down to zero at a standoff, metres.
  double slow_zone_m = 0.08;
};

/// Drives towards `target_m`, stopping `standoff_m` from it (reversing slowly if closer),
/// turning on the spot while the target is more than 90 degrees off the heading.
/// `repulse` (optional, field frame, unitless) bends the course away from nearby robots.
WheelCommand steer_to(const Pose2& self, Vec2 target_m, double standoff_m, const SteeringConfig& config,
                      Vec2 repulse = {});

/// Braitenberg avoidance from the eight proximity values: slows as the front fills and
/// turns away from the side that sees more; with an obstacle dead ahead it turns left.
WheelCommand steer_away(const environment::ProximityValues& proximity, const SteeringConfig& config);

/// How much the proximity sensors call for avoiding, in [0, 1]: 0 below `low` (fraction of
/// full scale) on every front and side sensor, 1 at or above `high`; back sensors ignored.
double obstacle_level(const environment::ProximityValues& proximity, double low = 0.3, double high = 0.7);

}  // namespace rilbed::agents

// Small builders shared by the environment tests.
#pragma once

#include <cmath>
#include <vector>

#include "environment/world.hpp"

namespace rilbed::environment::testing {

/// A walled field of the given size with nothing in it.
inline StaticMapConfig empty_field(double width_m, double height_m) {
  StaticMapConfig map;
  map.field.width_m = width_m;
  map.field.height_m = height_m;
  return map;
}

/// An axis-aligned rectangle as a counter-clockwise polygon.
inline ObstacleConfig rectangle(double x0, double y0, double x1, double y1) {
  return ObstacleConfig{{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}, {}};
}

/// A virtual Khepera with no sensor noise and no wheel noise.
inline RobotConfig quiet_robot(int id, double x, double y, double heading_rad) {
  RobotConfig r;
  r.id = id;
  r.pose = {{x, y}, heading_rad};
  r.sensors.proximity->noise_sd = 0.0;
  return r;
}

/// Runs `steps` steps of dt_us.
inline void run(World& world, int steps, TimeUs dt_us) {
  for (int i = 0; i < steps; ++i) world.step(dt_us);
}

/// Distance from p to the nearest edge of a closed polygon.
inline double distance_to_polygon(Vec2 p, const std::vector<Vec2>& v) {
  double best = 1e300;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const Vec2 a = v[i], b = v[(i + 1) % v.size()];
    const Vec2 ab = b - a;
    double t = (p - a).dot(ab) / ab.dot(ab);
    t = std::fmax(0.0, std::fmin(1.0, t));
    best = std::fmin(best, (p - (a + ab * t)).norm());
  }
  return best;
}

}  // namespace rilbed::environment::testing

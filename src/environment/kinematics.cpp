#include "environment/kinematics.hpp"

#include <cmath>
#include <limits>

namespace rilbed::environment {

ArcStep diff_drive_arc(double left_mps, double right_mps, double wheel_base_m, double dt_s) {
  const double v = 0.5 * (left_mps + right_mps);
  const double turn = (right_mps - left_mps) / wheel_base_m * dt_s;
  const double dist = v * dt_s;
  const double s = std::sin(turn), c = std::cos(turn);
  // sin(t)/t and (1 - cos t)/t, by their series near 0 where the closed forms lose digits.
  double sinc, cosc;
  if (std::abs(turn) < 1e-4) {
    const double t2 = turn * turn;
    sinc = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0);
    cosc = turn / 2.0 * (1.0 - t2 / 12.0);
  } else {
    sinc = s / turn;
    cosc = (1.0 - c) / turn;
  }
  return {{dist * sinc, dist * cosc}, turn, c, s};
}

Pose2 integrate_diff_drive(Pose2 start, double left_mps, double right_mps, double wheel_base_m, double dt_s) {
  const ArcStep arc = diff_drive_arc(left_mps, right_mps, wheel_base_m, dt_s);
  const double c = std::cos(start.heading_rad), s = std::sin(start.heading_rad);
  const Vec2 d = arc.local_displacement_m;
  return {start.position_m + Vec2{c * d.x - s * d.y, s * d.x + c * d.y},
          wrap_rad_pi(start.heading_rad + arc.heading_change_rad)};
}

double arc_radius_m(double left_mps, double right_mps, double wheel_base_m) {
  if (left_mps == right_mps) return std::numeric_limits<double>::infinity();
  return 0.5 * wheel_base_m * (right_mps + left_mps) / (right_mps - left_mps);
}

}  // namespace rilbed::environment

// Plane geometry shared by every module: 2-D vectors, poses and angle helpers.
#pragma once

#include <cmath>

namespace rilbed {

/// Pi as a double, for angle arithmetic.
inline constexpr double kPi = 3.14159265358979323846;

/// A 2-D vector or point. Units are the caller's (metres in the field frame,
/// pixels in an image); the name of the variable holding it says which.
struct Vec2 {
  double x = 0.0;
  double y = 0.0;

  constexpr Vec2 operator+(Vec2 o) const { return {x + o.x, y + o.y}; }
  constexpr Vec2 operator-(Vec2 o) const { return {x - o.x, y - o.y}; }
  constexpr Vec2 operator*(double s) const { return {x * s, y * s}; }
  constexpr Vec2 operator/(double s) const { return {x / s, y / s}; }
  constexpr bool operator==(const Vec2&) const = default;
  /// Dot product.
  constexpr double dot(Vec2 o) const { return x * o.x + y * o.y; }
  /// z of the 3-D cross product (positive when `o` is counter-clockwise of this).
  constexpr double cross(Vec2 o) const { return x * o.y - y * o.x; }
  /// Euclidean length.
  double norm() const { return std::hypot(x, y); }
};

/// A pose in the field frame: position in metres, heading in radians counter-clockwise
/// from +x (x right, y up, as seen from above).
struct Pose2 {
  Vec2 position_m;
  double heading_rad = 0.0;
};

/// Degrees to radians.
constexpr double deg_to_rad(double deg) { return deg * kPi / 180.0; }
/// Radians to degrees.
constexpr double rad_to_deg(double rad) { return rad * 180.0 / kPi; }

/// Wraps an angle in degrees into [0, 360).
inline double wrap_deg_360(double deg) {
  // Within a turn of the range (most callers) without fmod; the same result as it
  // (fmod is exact, and so is adding or removing one turn here).
  if (deg >= 0.0 && deg < 360.0) return deg;
  if (deg >= -360.0 && deg < 720.0) {
    const double w = deg < 0.0 ? deg + 360.0 : deg - 360.0;
    return w >= 360.0 ? w - 360.0 : w;  // a tiny negative plus a turn can round up to 360
  }
  double w = std::fmod(deg, 360.0);
  if (w < 0.0) w += 360.0;
  if (w >= 360.0) w -= 360.0;  // fmod of a tiny negative can round up to 360
  return w;
}

/// Wraps an angle in degrees into [-180, 180).
inline double wrap_deg_180(double deg) { return wrap_deg_360(deg + 180.0) - 180.0; }

/// Wraps an angle in radians into [-pi, pi).
inline double wrap_rad_pi(double rad) { return deg_to_rad(wrap_deg_180(rad_to_deg(rad))); }

}  // namespace rilbed

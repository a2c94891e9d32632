// The Khepera's eight IR proximity sensors, modelled: each sensor sits on the robot's
// rim at its mounting angle, looks outward through a cone (a 2-D wedge), and reports
// 0..1023 from the distance to the nearest surface inside the cone (walls, obstacles,
// moving obstacles, other robots real or virtual), plus Gaussian noise.
#pragma once

#include <array>
#include <string>
#include "environment/random.hpp"

#include "environment/scene.hpp"
#include "environment/sensor_readings.hpp"

namespace rilbed::environment {

/// Knobs of the proximity model; the defaults match a Khepera II against a white wall.
///
/// Response curve (noiseless), for distance d from the sensor to the nearest surface in
/// its cone, R = range_m, L = falloff_m:
///   value(d) = 1023 * (exp(-d/L) - exp(-R/L)) / (1 - exp(-R/L))   for d < R, else 0.
/// With the defaults: 1023 at contact, about 450 at 10 mm, 190 at 20 mm, 75 at 30 mm,
/// 22 at 40 mm and 0 from 50 mm: steep near the robot with a short tail, like the
/// measured Khepera curves. The cone is exact (the nearest point of each surface inside
/// the wedge), not sampled by rays; surface orientation and colour are not modelled.
struct ProximityConfig {
  /// Distance (from the sensor, on the robot's rim) beyond which the reading is 0.
  /// Longer ranges widen every robot's neighbour query and cost time.
  double range_m = 0.05;
  /// Decay length of the response: smaller makes it steeper near contact.
  double falloff_m = 0.0125;
  /// Half the cone's opening, (0, 90) degrees in radians. Default +-30 degrees.
  double half_angle_rad = deg_to_rad(30.0);
  /// Standard deviation of the additive Gaussian noise, in reading units; 0 turns the
  /// noise off (and saves eight normal draws per robot per reading).
  double noise_sd = 3.0;
  /// Mounting angles, radians counter-clockwise from the robot's forward direction.
  std::array<double, kProximityCount> mount_angles_rad = kProximityAngles_rad;
  bool operator==(const ProximityConfig&) const = default;
};

/// A robot's proximity sensor ring, ready to sense (directions precomputed).
class ProximitySensor {
 public:
  /// Validates `config` (finite, positive range and falloff, half angle in (0, 90)
  /// degrees, noise >= 0); throws std::invalid_argument prefixed with `what`.
  ProximitySensor(ProximityConfig config, const std::string& what);

  /// The validated configuration.
  const ProximityConfig& config() const { return config_; }

  /// The noiseless response at distance_m (not rounded), 0..1023.
  double response(double distance_m) const;

  /// For each sensor of the robot in slot `body` of `scene`, facing `heading` (unit
  /// vector), the distance from the sensor to the nearest surface in its cone (kNoHit
  /// when none within range_m).
  void nearest_distances(const Scene& scene, int body, Vec2 heading,
                         std::array<double, kProximityCount>& distances_m) const;

  /// The readings: response of each distance plus noise, rounded and clamped to
  /// [0, 1023]. Draws eight normals from `rng` (fast_normal, in sensor order) when
  /// noise_sd > 0.
  void sense(const Scene& scene, int body, Vec2 heading, NoiseRng& rng, ProximityValues& out) const;

 private:
  ProximityConfig config_;
  std::array<Vec2, kProximityCount> directions_;  // unit, robot frame
  double cos_half_ = 0.0, sin_half_ = 0.0;
  double floor_ = 0.0;  // exp(-range / falloff)
};

}  // namespace rilbed::environment

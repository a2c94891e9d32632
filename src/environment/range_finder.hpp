// Ultrasonic range finders (paper 000 §6.7, §7.2): each reports the distance to the
// nearest object inside its cone, nothing about where in the cone it is.
#pragma once

#include <string>
#include <vector>
#include "environment/random.hpp"

#include "environment/scene.hpp"
#include "environment/sensor_readings.hpp"

namespace rilbed::environment {

/// One range finder, mounted on the robot's rim.
struct RangeFinderConfig {
  /// Where on the rim it sits and where it looks: radians counter-clockwise from the
  /// robot's forward direction.
  double mount_angle_rad = 0.0;
  /// Full opening of the cone, (0, 180) degrees in radians.
  double opening_angle_rad = deg_to_rad(30.0);
  /// Farthest distance it reports (from the sensor); longer ranges query more cells.
  double max_range_m = 1.0;
  /// Standard deviation of additive Gaussian noise on a hit's distance, metres (the
  /// result is clamped to [0, max_range_m]). 0: none, and no draw.
  double noise_sd_m = 0.0;
  bool operator==(const RangeFinderConfig&) const = default;
};

/// The range finders of one robot, sensed together (one neighbour query for all).
class RangeFinders {
 public:
  /// Validates each configuration; throws std::invalid_argument naming `what` and the
  /// finder's index.
  RangeFinders(std::vector<RangeFinderConfig> configs, const std::string& what);

  /// Number of range finders.
  std::size_t size() const { return configs_.size(); }
  /// Their configurations, in reading order.
  const std::vector<RangeFinderConfig>& configs() const { return configs_; }

  /// Fills out[k] for finder k of the robot in slot `body` facing `heading` (unit
  /// vector); out is resized to size(). Draws one normal per hit from `rng` for finders
  /// with noise.
  void sense(const Scene& scene, int body, Vec2 heading, NoiseRng& rng, std::vector<RangeReading>& out) const;

 private:
  struct Precomputed {
    Vec2 direction;  // unit, robot frame
    double cos_half, sin_half;
  };
  std::vector<RangeFinderConfig> configs_;
  std::vector<Precomputed> pre_;
};

}  // namespace rilbed::environment

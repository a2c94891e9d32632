// The floor-track sensor of paper 000 §8.1–8.2: a photo-reflective emitter/detector
// pair under the robot that sees reflective tape on the floor.
//
// Geometry (§8.1, Figure 8-1): the element sits height_mm above the floor, its axis
// inclined inclination_deg from the vertical towards its mount yaw, and it sees a cone of
// full opening cone_angle_deg. The cone meets the floor in an ellipse reaching from
// h tan(alpha - beta/2) to h tan(alpha + beta/2) along the lean direction.
//
// Segments (§8.1, Figure 8-2, "each rectangle receives an equal amount of light"): the
// emitter's intensity is taken as uniform over the cone's solid angle, so the light
// falling on a floor patch is proportional to the solid angle it subtends; a patch at
// distance r, seen at angle theta from the vertical, gets irradiance ~ cos(theta) / r^2,
// which falls with distance. The ellipse is therefore cut into `precision` cells of
// equal solid angle: rings of equal solid-angle steps around the axis, each ring cut
// into sectors, ring j getting cells in proportion to 2j + 1 so the cells stay compact.
// Near the sensor foot, where the light is strongest, the cells are small and dense;
// far out they are large and sparse, so tape in the far part of the ellipse covers
// fewer cells and is less likely to trigger the element, as the paper describes. Each
// cell is represented by its solid-angle centre projected onto the floor.
//
// Reading (§8.2): the element triggers when at least coverage_percent of its cells lie
// on a track (and at least one does). Output: max_value when triggered, else 0 (or,
// with graded, max_value times the fraction of cells covered); then Gaussian noise of
// standard deviation error_level_percent of max_value, rounded and clamped to
// [0, max_value].
#pragma once

#include <string>
#include <vector>
#include "environment/random.hpp"

#include "environment/scene.hpp"

namespace rilbed::environment {

/// One track sensor element: one key per parameter of the paper's configuration block
/// (defaults are the paper's example), plus where it sits on the robot.
struct TrackSensorConfig {
  double mount_x_m = 0.0;  ///< position on the robot, metres forward of the centre
  double mount_y_m = 0.0;  ///< position on the robot, metres left of the centre
  /// Direction the element leans towards, degrees counter-clockwise from the robot's
  /// forward direction (only matters when inclined).
  double mount_yaw_deg = 0.0;
  double height_mm = 8.0;         ///< "Height": h, above the floor
  double inclination_deg = 45.0;  ///< "Inclination": alpha, of the axis from the vertical
  double cone_angle_deg = 30.0;   ///< "Cone Angle": beta, full opening of the cone
  /// "Precision": number of segments the ellipse is cut into, 1..4096. More segments
  /// resolve thinner tape and cost one track lookup each per reading.
  int precision = 16;
  double coverage_percent = 15.0;    ///< "Coverage": share of segments that must be on a track, 0..100
  int max_value = 255;               ///< "Max Value": full-scale reading, >= 1
  double error_level_percent = 5.0;  ///< "Error Level": noise sd in percent of max_value, >= 0
  /// false (default): binary output, max_value or 0, like the real device's high bit.
  /// true: max_value times the covered fraction when triggered.
  bool graded = false;
  bool operator==(const TrackSensorConfig&) const = default;
};

/// Where the segments of one element fall on the floor.
struct TrackFootprint {
  /// One point per segment (its solid-angle centre on the floor), in the robot frame
  /// (x forward, y left), metres. Every segment receives the same amount of light.
  std::vector<Vec2> points_m;
  /// Near and far ends of the ellipse along the lean direction, measured from the point
  /// on the floor below the element, metres (near is negative when the cone reaches
  /// behind the foot).
  double near_m = 0.0;
  double far_m = 0.0;
};

/// Computes the footprint of a (valid) configuration.
TrackFootprint track_footprint(const TrackSensorConfig& config);

/// One element, ready to sense.
class TrackSensor {
 public:
  /// Validates `config`: finite numbers, height > 0, inclination in [0, 90), cone angle
  /// in (0, 180), inclination + cone/2 below 89 degrees (else the cone reaches the
  /// horizon and meets the floor in no ellipse), precision in 1..4096, coverage in
  /// [0, 100], max_value >= 1, error level >= 0. Throws std::invalid_argument prefixed
  /// with `what`.
  TrackSensor(TrackSensorConfig config, const std::string& what);

  /// The validated configuration.
  const TrackSensorConfig& config() const { return config_; }
  /// Where its segments fall on the floor, robot frame.
  const TrackFootprint& footprint() const { return footprint_; }
  /// Least number of covered segments that triggers the element.
  int required_segments() const { return required_; }

  /// Number of segments on a track for a robot at `pose` (heading given as a unit vector
  /// too, to save the trigonometry).
  int covered_segments(const Scene& scene, Vec2 position_m, Vec2 heading) const;
  /// The reading for `covered` segments on a track. Draws one normal when the error level
  /// is non-zero.
  int reading(int covered, NoiseRng& rng) const;

 private:
  TrackSensorConfig config_;
  TrackFootprint footprint_;
  int required_ = 1;
};

}  // namespace rilbed::environment

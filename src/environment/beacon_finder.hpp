// The IR beacon direction finder (paper 000 §6.7, §6.10): reports the ID and bearing of
// each beacon in view, never the distance.
#pragma once

#include <string>
#include <vector>
#include "environment/random.hpp"

#include "environment/scene.hpp"
#include "environment/sensor_readings.hpp"

namespace rilbed::environment {

/// Knobs of the direction finder, mounted at the robot's centre.
///
/// A beacon is in view when (1) the robot's centre is within the beacon's range_m,
/// (2) the direction from the beacon to the robot is within half the beacon's aperture
/// of its facing direction, (3) the bearing is within half of field_of_view_rad of the
/// robot's forward direction, and (4) no wall, static obstacle or moving obstacle crosses
/// the line between beacon and robot centre (robots do not hide beacons).
struct BeaconFinderConfig {
  /// Full angle of view centred on the robot's forward direction, (0, 2 pi]; 2 pi sees
  /// all round.
  double field_of_view_rad = 2.0 * kPi;
  /// Standard deviation of Gaussian noise added to each bearing, radians. 0: none.
  double bearing_noise_sd_rad = 0.0;
  bool operator==(const BeaconFinderConfig&) const = default;
};

/// Validates `config`; throws std::invalid_argument prefixed with `what`.
void validate(const BeaconFinderConfig& config, const std::string& what);

/// The beacons the robot in slot `body` with pose `pose` sees, in the map's beacon
/// order, bearings wrapped to [-pi, pi). `out` is cleared first (its capacity reused).
/// Draws one normal per sighting when bearing noise is on.
void sense_beacons(const BeaconFinderConfig& config, const Scene& scene, Pose2 pose, NoiseRng& rng,
                   std::vector<BeaconSighting>& out);

}  // namespace rilbed::environment

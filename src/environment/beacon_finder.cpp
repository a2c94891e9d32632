#include "environment/beacon_finder.hpp"

#include <cmath>
#include <stdexcept>

#include "environment/random.hpp"

namespace rilbed::environment {

void validate(const BeaconFinderConfig& config, const std::string& what) {
  if (!(config.field_of_view_rad > 0.0 && config.field_of_view_rad <= 2.0 * kPi + 1e-12))
    throw std::invalid_argument(what + ": beacon finder: field_of_view_rad must be in (0, 2 pi]");
  if (!std::isfinite(config.bearing_noise_sd_rad) || config.bearing_noise_sd_rad < 0.0)
    throw std::invalid_argument(what + ": beacon finder: bearing_noise_sd_rad must be >= 0");
}

void sense_beacons(const BeaconFinderConfig& config, const Scene& scene, Pose2 pose, NoiseRng& rng,
                   std::vector<BeaconSighting>& out) {
  out.clear();
  const double half_view = 0.5 * config.field_of_view_rad;
  for (const BeaconConfig& beacon : scene.beacons) {
    const Vec2 to_robot = pose.position_m - beacon.position_m;
    if (to_robot.dot(to_robot) > beacon.range_m * beacon.range_m) continue;
    if (beacon.aperture_rad < 2.0 * kPi) {
      const double off_axis = wrap_rad_pi(std::atan2(to_robot.y, to_robot.x) - beacon.facing_rad);
      if (std::abs(off_axis) > 0.5 * beacon.aperture_rad) continue;
    }
    const double bearing = wrap_rad_pi(std::atan2(-to_robot.y, -to_robot.x) - pose.heading_rad);
    if (config.field_of_view_rad < 2.0 * kPi && std::abs(bearing) > half_view) continue;
    if (scene.sight_blocked(beacon.position_m, pose.position_m)) continue;
    double reported = bearing;
    if (config.bearing_noise_sd_rad > 0.0)
      reported = wrap_rad_pi(bearing + config.bearing_noise_sd_rad * fast_normal(rng));
    out.push_back({beacon.id, reported});
  }
}

}  // namespace rilbed::environment

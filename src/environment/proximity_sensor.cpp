#include "environment/proximity_sensor.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "environment/random.hpp"

namespace rilbed::environment {

ProximitySensor::ProximitySensor(ProximityConfig config, const std::string& what) : config_(config) {
  auto fail = [&](const std::string& why) { throw std::invalid_argument(what + ": proximity: " + why); };
  if (!std::isfinite(config_.range_m) || config_.range_m <= 0.0) fail("range_m must be a positive number");
  if (!std::isfinite(config_.falloff_m) || config_.falloff_m <= 0.0) fail("falloff_m must be a positive number");
  if (!(config_.half_angle_rad > 0.0 && config_.half_angle_rad < 0.5 * kPi))
    fail("half_angle_rad must be in (0, pi/2)");
  if (!std::isfinite(config_.noise_sd) || config_.noise_sd < 0.0) fail("noise_sd must be >= 0");
  for (int i = 0; i < kProximityCount; ++i) {
    const double a = config_.mount_angles_rad[static_cast<std::size_t>(i)];
    if (!std::isfinite(a)) fail("mount angle " + std::to_string(i) + " is not finite");
    directions_[static_cast<std::size_t>(i)] = {std::cos(a), std::sin(a)};
  }
  cos_half_ = std::cos(config_.half_angle_rad);
  sin_half_ = std::sin(config_.half_angle_rad);
  floor_ = std::exp(-config_.range_m / config_.falloff_m);
}

double ProximitySensor::response(double distance_m) const {
  if (!(distance_m < config_.range_m)) return 0.0;
  const double d = std::max(0.0, distance_m);
  return kProximityMax * (std::exp(-d / config_.falloff_m) - floor_) / (1.0 - floor_);
}

void ProximitySensor::nearest_distances(const Scene& scene, int body, Vec2 heading,
                                        std::array<double, kProximityCount>& distances_m) const {
  const Body& self = scene.bodies[static_cast<std::size_t>(body)];
  // Left uninitialised: most robots of a swarm have nothing in reach and never build
  // their wedges, and zeroing eight of them cost more than the rest of a quiet sensing.
  union WedgeStorage {
    WedgeStorage() {}
    std::array<Wedge, kProximityCount> wedges;
  } storage;
  auto make_wedges = [&](std::span<Wedge> out) {
    for (std::size_t i = 0; i < out.size(); ++i) {
      const Vec2 d = directions_[i];
      const Vec2 axis{heading.x * d.x - heading.y * d.y, heading.y * d.x + heading.x * d.y};
      out[i] = make_wedge(self.position_m + axis * self.radius_m, axis, cos_half_, sin_half_);
    }
  };
  scene.nearest_in_lazy_wedges(self.position_m, self.radius_m + config_.range_m, body, storage.wedges, make_wedges,
                               distances_m);
}

void ProximitySensor::sense(const Scene& scene, int body, Vec2 heading, NoiseRng& rng, ProximityValues& out) const {
  std::array<double, kProximityCount> distances;
  nearest_distances(scene, body, heading, distances);
  const bool noisy = config_.noise_sd > 0.0;
  std::array<double, kProximityCount> noise;
  if (noisy) fast_normals(rng, noise);
  std::array<double, kProximityCount> values;
  for (std::size_t i = 0; i < values.size(); ++i) values[i] = response(distances[i]);
  if (noisy) {
    for (std::size_t i = 0; i < values.size(); ++i) values[i] += noise[i] * config_.noise_sd;
  }
  // Clamp, then round half up (cheaper than std::round, a library call). Written as
  // selects, not std::clamp's branches: with noise on an empty reading the sign is a coin
  // toss, and mispredicted branches were a fifth of this function's time.
  constexpr double kMax = kProximityMax;
  for (std::size_t i = 0; i < out.size(); ++i) {
    double v = values[i] < 0.0 ? 0.0 : values[i];
    v = v > kMax ? kMax : v;
    out[i] = static_cast<int>(v + 0.5);
  }
}

}  // namespace rilbed::environment

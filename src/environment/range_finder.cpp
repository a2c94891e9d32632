#include "environment/range_finder.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "environment/random.hpp"

namespace rilbed::environment {

RangeFinders::RangeFinders(std::vector<RangeFinderConfig> configs, const std::string& what)
    : configs_(std::move(configs)) {
  for (std::size_t k = 0; k < configs_.size(); ++k) {
    const RangeFinderConfig& c = configs_[k];
    auto fail = [&](const std::string& why) {
      throw std::invalid_argument(what + ": range finder " + std::to_string(k) + ": " + why);
    };
    if (!std::isfinite(c.mount_angle_rad)) fail("mount_angle_rad is not finite");
    if (!(c.opening_angle_rad > 0.0 && c.opening_angle_rad < kPi)) fail("opening_angle_rad must be in (0, pi)");
    if (!std::isfinite(c.max_range_m) || c.max_range_m <= 0.0) fail("max_range_m must be a positive number");
    if (!std::isfinite(c.noise_sd_m) || c.noise_sd_m < 0.0) fail("noise_sd_m must be >= 0");
    pre_.push_back({{std::cos(c.mount_angle_rad), std::sin(c.mount_angle_rad)},
                    std::cos(0.5 * c.opening_angle_rad),
                    std::sin(0.5 * c.opening_angle_rad)});
  }
}

void RangeFinders::sense(const Scene& scene, int body, Vec2 heading, NoiseRng& rng,
                         std::vector<RangeReading>& out) const {
  out.resize(configs_.size());
  if (configs_.empty()) return;  // most robots carry none: skip the wedge buffers
  const Body& self = scene.bodies[static_cast<std::size_t>(body)];
  // Wedges go through the scene in chunks on the stack: no allocation per reading.
  constexpr std::size_t kChunk = 16;
  std::array<Wedge, kChunk> wedges;
  std::array<double, kChunk> distances;
  for (std::size_t first = 0; first < configs_.size(); first += kChunk) {
    const std::size_t n = std::min(kChunk, configs_.size() - first);
    double reach = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const Precomputed& p = pre_[first + k];
      const Vec2 axis{heading.x * p.direction.x - heading.y * p.direction.y,
                      heading.y * p.direction.x + heading.x * p.direction.y};
      wedges[k] = make_wedge(self.position_m + axis * self.radius_m, axis, p.cos_half, p.sin_half);
      reach = std::max(reach, configs_[first + k].max_range_m);
    }
    scene.nearest_in_wedges(self.position_m, self.radius_m + reach, body, std::span(wedges.data(), n),
                            std::span(distances.data(), n));
    for (std::size_t k = 0; k < n; ++k) {
      const RangeFinderConfig& c = configs_[first + k];
      RangeReading& r = out[first + k];
      if (distances[k] <= c.max_range_m) {
        double d = distances[k];
        if (c.noise_sd_m > 0.0) d = std::clamp(d + c.noise_sd_m * fast_normal(rng), 0.0, c.max_range_m);
        r = {true, d};
      } else {
        r = {false, c.max_range_m};
      }
    }
  }
}

}  // namespace rilbed::environment

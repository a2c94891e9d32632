#include "environment/track_sensor.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "environment/random.hpp"

namespace rilbed::environment {

namespace {

// Cells per ring: n_rings about sqrt(N / pi) (so that a ring's cells are about as long
// as wide), ring j weighted 2j + 1 (its area in equal solid-angle steps grows so), the
// rounding by largest remainder so that the counts add up to exactly N.
std::vector<int> cells_per_ring(int n) {
  const int rings = std::max(1, static_cast<int>(std::lround(std::sqrt(n / kPi))));
  const int weight_sum = rings * rings;  // sum of 2j + 1 for j < rings
  std::vector<int> cells(static_cast<std::size_t>(rings));
  std::vector<std::pair<double, int>> remainders;
  int given = 0;
  for (int j = 0; j < rings; ++j) {
    const double exact = static_cast<double>(n) * (2 * j + 1) / weight_sum;
    cells[static_cast<std::size_t>(j)] = static_cast<int>(exact);
    given += cells[static_cast<std::size_t>(j)];
    remainders.push_back({exact - std::floor(exact), j});
  }
  std::stable_sort(remainders.begin(), remainders.end(), [](auto a, auto b) { return a.first > b.first; });
  for (std::size_t k = 0; given < n; ++k, ++given)
    ++cells[static_cast<std::size_t>(remainders[k % remainders.size()].second)];
  // A ring left without cells (only possible for tiny N) is dropped.
  std::erase(cells, 0);
  return cells;
}

}  // namespace

TrackFootprint track_footprint(const TrackSensorConfig& c) {
  const double h = c.height_mm * 1e-3;
  const double alpha = deg_to_rad(c.inclination_deg);
  const double half_beta = 0.5 * deg_to_rad(c.cone_angle_deg);
  const double u_max = 1.0 - std::cos(half_beta);  // solid angle / 2 pi of the cone
  const double yaw = deg_to_rad(c.mount_yaw_deg);
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  const double ca = std::cos(alpha), sa = std::sin(alpha);

  TrackFootprint fp;
  fp.near_m = h * std::tan(alpha - half_beta);
  fp.far_m = h * std::tan(alpha + half_beta);

  // A ray at polar angle psi from the axis and azimuth phi (phi = 0 towards the lean),
  // in the lean frame (x' along the lean on the floor, y' to its left, z up): axis
  // (sin a, 0, -cos a), e1 = (cos a, 0, sin a), e2 = (0, 1, 0). It meets the floor
  // z = -h at t = h / (cos psi cos a - sin psi cos phi sin a).
  auto floor_point = [&](double psi, double phi) {
    const double sp = std::sin(psi), cp = std::cos(psi);
    const double rx = cp * sa + sp * std::cos(phi) * ca;
    const double ry = sp * std::sin(phi);
    const double down = cp * ca - sp * std::cos(phi) * sa;
    const double t = h / down;
    const Vec2 lean{t * rx, t * ry};
    return Vec2{c.mount_x_m + cy * lean.x - sy * lean.y, c.mount_y_m + sy * lean.x + cy * lean.y};
  };

  const std::vector<int> rings = cells_per_ring(c.precision);
  int before = 0;
  for (std::size_t j = 0; j < rings.size(); ++j) {
    const int n_j = rings[j];
    const double u_mid = u_max * (before + 0.5 * n_j) / c.precision;
    before += n_j;
    if (j == 0 && n_j == 1) {
      fp.points_m.push_back(floor_point(0.0, 0.0));  // the central cap: its centre is the axis
      continue;
    }
    const double psi = std::acos(1.0 - u_mid);
    for (int k = 0; k < n_j; ++k) fp.points_m.push_back(floor_point(psi, 2.0 * kPi * (k + 0.5) / n_j));
  }
  return fp;
}

TrackSensor::TrackSensor(TrackSensorConfig config, const std::string& what) : config_(config) {
  auto fail = [&](const std::string& why) { throw std::invalid_argument(what + ": track sensor: " + why); };
  const TrackSensorConfig& c = config_;
  for (const double v : {c.mount_x_m, c.mount_y_m, c.mount_yaw_deg, c.height_mm, c.inclination_deg, c.cone_angle_deg,
                         c.coverage_percent, c.error_level_percent})
    if (!std::isfinite(v)) fail("a parameter is not finite");
  if (c.height_mm <= 0.0) fail("height_mm must be positive");
  if (c.inclination_deg < 0.0 || c.inclination_deg >= 90.0) fail("inclination_deg must be in [0, 90)");
  if (c.cone_angle_deg <= 0.0 || c.cone_angle_deg >= 180.0) fail("cone_angle_deg must be in (0, 180)");
  if (c.inclination_deg + 0.5 * c.cone_angle_deg >= 89.0)
    fail("inclination_deg + cone_angle_deg / 2 must stay below 89 (the cone must meet the floor in an ellipse)");
  if (c.precision < 1 || c.precision > 4096) fail("precision must be in 1..4096");
  if (c.coverage_percent < 0.0 || c.coverage_percent > 100.0) fail("coverage_percent must be in [0, 100]");
  if (c.max_value < 1) fail("max_value must be >= 1");
  if (c.error_level_percent < 0.0) fail("error_level_percent must be >= 0");
  footprint_ = track_footprint(config_);
  // A small slack so that e.g. 50 % of 16 needs 8 segments, not 9 by rounding.
  required_ = std::max(1, static_cast<int>(std::ceil(c.precision * c.coverage_percent / 100.0 - 1e-9)));
}

int TrackSensor::covered_segments(const Scene& scene, Vec2 position_m, Vec2 heading) const {
  int covered = 0;
  for (const Vec2 p : footprint_.points_m) {
    const Vec2 world{position_m.x + heading.x * p.x - heading.y * p.y,
                     position_m.y + heading.y * p.x + heading.x * p.y};
    if (scene.on_track(world)) ++covered;
  }
  return covered;
}

int TrackSensor::reading(int covered, NoiseRng& rng) const {
  const double max = config_.max_value;
  double value = 0.0;
  if (covered >= required_) value = config_.graded ? max * covered / config_.precision : max;
  if (config_.error_level_percent > 0.0) value += fast_normal(rng) * config_.error_level_percent / 100.0 * max;
  return static_cast<int>(std::clamp(std::round(value), 0.0, max));
}

}  // namespace rilbed::environment

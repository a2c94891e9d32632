#include "vision/ring_search.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "vision/marker_family.hpp"

namespace rilbed::vision {

namespace {

constexpr int kRays = 16;
// Middle of the black ring and of the white ring, in units of the dark disc's radius.
constexpr double kBlackMid = 0.5 * (MarkerFamily::code_outer_radius + MarkerFamily::black_ring_outer_radius) /
                             MarkerFamily::black_ring_outer_radius;
constexpr double kWhiteMid =
    0.5 * (1.0 + MarkerFamily::black_ring_outer_radius) / MarkerFamily::black_ring_outer_radius;
// One ray's difference counts at most this much (grey levels), so that a bright speck
// on the white ring or a dark one on the black cannot outweigh rays that show no ring.
constexpr int kMaxRayContrast = 96;

// The rays' byte offsets from the centre pixel, at one radius.
struct RayOffsets {
  std::array<std::ptrdiff_t, kRays> black, white;
  int reach_px = 0;  // the farthest read from the centre along either axis
};

// The rays' directions (cosine, sine), computed once.
struct RayDirections {
  std::array<double, kRays> cos, sin;
  RayDirections() {
    for (int i = 0; i < kRays; ++i) {
      const double angle = 2.0 * std::numbers::pi * i / kRays;
      cos[static_cast<std::size_t>(i)] = std::cos(angle);
      sin[static_cast<std::size_t>(i)] = std::sin(angle);
    }
  }
};

int nearest(double v) { return static_cast<int>(std::floor(v + 0.5)); }

RayOffsets ray_offsets(double radius_px, std::ptrdiff_t stride) {
  static const RayDirections directions;
  RayOffsets out;
  for (int i = 0; i < kRays; ++i) {
    const double c = directions.cos[static_cast<std::size_t>(i)], s = directions.sin[static_cast<std::size_t>(i)];
    const int bx = nearest(kBlackMid * radius_px * c), by = nearest(kBlackMid * radius_px * s);
    const int wx = nearest(kWhiteMid * radius_px * c), wy = nearest(kWhiteMid * radius_px * s);
    out.black[static_cast<std::size_t>(i)] = by * stride + bx;
    out.white[static_cast<std::size_t>(i)] = wy * stride + wx;
    out.reach_px = std::max({out.reach_px, std::abs(wx), std::abs(wy), std::abs(bx), std::abs(by)});
  }
  return out;
}

// Sum over the rays (every `ray_step`-th) of the white ring's grey level less the black
// ring's (each capped), for the circle centred on pixel `centre`; scaled to all rays.
int ring_score(const std::uint8_t* centre, const RayOffsets& rays, int ray_step) {
  int sum = 0;
  for (int i = 0; i < kRays; i += ray_step) {
    const int d = centre[rays.white[static_cast<std::size_t>(i)]] - centre[rays.black[static_cast<std::size_t>(i)]];
    sum += std::min(d, kMaxRayContrast);
  }
  return sum * ray_step;
}

struct Circle {
  int x = 0, y = 0;
  double radius_px = 0.0;
  int score = 0;
  bool found = false;
};

// Scores the circles of radius `radius_px` centred on the grid points (spacing `step`)
// within `max_offset_px` of (cx, cy) that lie wholly inside the image, on every
// `ray_step`-th ray; keeps the best in `best`.
void try_radius(const cv::Mat& grey, double cx, double cy, double radius_px, double max_offset_px, int step,
                int ray_step, Circle& best) {
  const std::ptrdiff_t stride = static_cast<std::ptrdiff_t>(grey.step[0]);
  const RayOffsets rays = ray_offsets(radius_px, stride);
  const int reach = static_cast<int>(std::floor(max_offset_px / step)) * step;
  const int x0 = static_cast<int>(std::lround(cx)), y0 = static_cast<int>(std::lround(cy));
  for (int dy = -reach; dy <= reach; dy += step) {
    const int y = y0 + dy;
    if (y - rays.reach_px < 0 || y + rays.reach_px >= grey.rows) continue;
    const std::uint8_t* row = grey.ptr<std::uint8_t>(y);
    for (int dx = -reach; dx <= reach; dx += step) {
      if (dx * dx + dy * dy > max_offset_px * max_offset_px) continue;
      const int x = x0 + dx;
      if (x - rays.reach_px < 0 || x + rays.reach_px >= grey.cols) continue;
      const int score = ring_score(row + x, rays, ray_step);
      if (!best.found || score > best.score) best = {x, y, radius_px, score, true};
    }
  }
}

}  // namespace

std::optional<Blob> search_ring(const cv::Mat& grey, const Blob& fragment, const RingSearchConfig& config) {
  CV_Assert(grey.type() == CV_8UC1);
  const double fragment_radius_px = 0.5 * fragment.disc_diameter_px();
  if (!(fragment_radius_px > 0.0) || !(config.scale_step > 0.0)) return std::nullopt;
  if (2.0 * fragment_radius_px > config.max_fragment_diameter_px) return std::nullopt;
  // Centres on a grid whose spacing grows with the radius tried (the ring score, and the
  // edge fit after it, tolerate a guess off by a fixed fraction of the radius).
  auto coarse_step = [&](double radius_px) {
    return std::max(1, static_cast<int>(std::lround(config.centre_step * radius_px)));
  };
  Circle best;
  for (double scale = config.min_scale; scale <= config.max_scale + 1e-9; scale += config.scale_step) {
    const double radius_px = scale * fragment_radius_px;
    try_radius(grey, fragment.u, fragment.v, radius_px, config.max_offset * radius_px, coarse_step(radius_px), 2, best);
  }
  if (!best.found) return std::nullopt;
  // The coarse pass read every other ray: score the best on all of them, refining its
  // centre to the pixel and its radius to a fraction of a step.
  const Circle coarse = best;
  best.found = false;
  for (const double f : {1.0 - 0.4 * config.scale_step, 1.0, 1.0 + 0.4 * config.scale_step})
    try_radius(grey, coarse.x, coarse.y, f * coarse.radius_px, coarse_step(coarse.radius_px), 1, 1, best);
  if (best.score < config.min_ring_contrast * kRays) return std::nullopt;
  Blob disc = fragment;
  disc.u = best.x;
  disc.v = best.y;
  disc.shape = cv::Matx22d(best.radius_px, 0.0, 0.0, best.radius_px);
  disc.filled_area_px = std::numbers::pi * best.radius_px * best.radius_px;
  disc.doubtful = true;  // a guess, for the edge fit to confirm
  return disc;
}

}  // namespace rilbed::vision

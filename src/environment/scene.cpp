#include "environment/scene.hpp"

#include <algorithm>

namespace rilbed::environment {

void Scene::nearest_in_wedges(Vec2 centre, double reach_m, int exclude_body, std::span<const Wedge> wedges,
                              std::span<double> out) const {
  std::fill(out.begin(), out.end(), kNoHit);
  struct Visitor {
    std::span<const Wedge> wedges;
    std::span<double> out;
    void disc(Vec2 c, double r) {
      for (std::size_t k = 0; k < wedges.size(); ++k)
        out[k] = std::min(out[k], wedge_distance_to_disc(wedges[k], c, r));
    }
    void segment(Vec2 a, Vec2 b) {
      for (std::size_t k = 0; k < wedges.size(); ++k)
        out[k] = std::min(out[k], wedge_distance_to_segment(wedges[k], a, b));
    }
  };
  for_each_surface_near(centre, reach_m, exclude_body, Visitor{wedges, out});
}

bool Scene::sight_blocked(Vec2 from, Vec2 to) const {
  if (statics.blocks_sight(from, to)) return true;
  for (const MovingObstacle& m : movers) {
    if (m.shape() == MovingShape::kDisc) {
      // Blocked when the line passes through the disc between its ends.
      const double r = m.bounding_radius_m();
      if (distance_sq_to_segment(m.position_m(), from, to) < r * r) return true;
    } else {
      const auto& v = m.world_vertices_m();
      for (std::size_t i = 0, n = v.size(); i < n; ++i)
        if (segment_blocks_sight(from, to, v[i], v[(i + 1) % n])) return true;
    }
  }
  return false;
}

bool Scene::on_track(Vec2 p) const {
  bool on = false;
  tracks.for_each_at(p, [&](const IndexedSegment& s) {
    if (!on && distance_sq_to_segment(p, s.a_m, s.b_m) <= s.half_width_m * s.half_width_m) on = true;
  });
  return on;
}

}  // namespace rilbed::environment

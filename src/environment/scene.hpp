// What a virtual sensor can see: a read-only view of the world's indexed contents
// (static segments, floor tracks, robots in their grid, moving obstacles, beacons), and
// the queries sensors share. The World builds one on demand; it holds references only
// and must not outlive the World's state it points to.
#pragma once

#include <algorithm>

#include <span>

#include "environment/body.hpp"
#include "environment/mobile_pose.hpp"
#include "environment/moving_obstacle.hpp"
#include "environment/segment_index.hpp"
#include "environment/spatial_grid.hpp"
#include "environment/static_map.hpp"

namespace rilbed::environment {

/// Read-only view of the world for sensing.
struct Scene {
  const SegmentIndex& statics;             ///< boundary walls (when on) and obstacle edges
  const SegmentIndex& tracks;              ///< floor track segments, with their half widths
  std::span<const Body> bodies;            ///< robots, by slot
  const SpatialGrid& grid;                 ///< bodies hashed by cell; current
  std::span<const MovingObstacle> movers;  ///< by index
  std::span<const BeaconConfig> beacons;   ///< the map's, in its order
  double max_body_radius_m = 0.0;          ///< largest robot radius, to widen grid queries
  /// Every robot and moving obstacle now, for sensor models; empty unless a robot carries one.
  std::span<const MobilePose> mobiles = {};

  /// Calls visitor.disc(centre, radius_m) and visitor.segment(a, b) for every surface
  /// that may come within reach_m of p: robots (except slot `exclude_body`), wall and
  /// obstacle segments, moving obstacles (discs, or polygon edges). Items farther than
  /// reach_m are skipped by a cheap squared-distance test first.
  template <class Visitor>
  void for_each_surface_near(Vec2 p, double reach_m, int exclude_body, Visitor&& visitor) const {
    const double reach_sq = reach_m * reach_m;
    grid.for_each_in_box(box_around(p, reach_m + max_body_radius_m), [&](int j) {
      if (j == exclude_body) return;
      const Body& b = bodies[static_cast<std::size_t>(j)];
      const double limit = reach_m + b.radius_m;
      if (distance_sq(p, b.position_m) < limit * limit) visitor.disc(b.position_m, b.radius_m);
    });
    statics.for_each_in_box(box_around(p, reach_m), [&](const IndexedSegment& s) {
      if (distance_sq_to_segment(p, s.a_m, s.b_m) < reach_sq) visitor.segment(s.a_m, s.b_m);
    });
    for (const MovingObstacle& m : movers) {
      const double limit = reach_m + m.bounding_radius_m();
      if (distance_sq(p, m.position_m()) >= limit * limit) continue;
      if (m.shape() == MovingShape::kDisc) {
        visitor.disc(m.position_m(), m.bounding_radius_m());
      } else {
        const auto& v = m.world_vertices_m();
        for (std::size_t i = 0, n = v.size(); i < n; ++i) visitor.segment(v[i], v[(i + 1) % n]);
      }
    }
  }

  /// For each wedge, the distance from its apex to the nearest surface inside it (or
  /// kNoHit), considering surfaces within reach_m of `centre` (which must cover every
  /// wedge's apex plus its range), robots except `exclude_body`. out.size() must equal
  /// wedges.size().
  void nearest_in_wedges(Vec2 centre, double reach_m, int exclude_body, std::span<const Wedge> wedges,
                         std::span<double> out) const;

  /// As nearest_in_wedges, with the wedges made by `make_wedges(wedges)` only once a
  /// surface is within reach: in a swarm most robots have none near at most steps, and
  /// skip setting up their wedges (same results).
  template <class MakeWedges>
  void nearest_in_lazy_wedges(Vec2 centre, double reach_m, int exclude_body, std::span<Wedge> wedges,
                              MakeWedges&& make_wedges, std::span<double> out) const {
    std::fill(out.begin(), out.end(), kNoHit);
    bool made = false;
    struct Visitor {
      std::span<Wedge> wedges;
      std::span<double> out;
      MakeWedges& make;
      bool& made;
      void ready() {
        if (!made) make(wedges);
        made = true;
      }
      void disc(Vec2 c, double r) {
        ready();
        for (std::size_t k = 0; k < wedges.size(); ++k)
          out[k] = std::min(out[k], wedge_distance_to_disc(wedges[k], c, r));
      }
      void segment(Vec2 a, Vec2 b) {
        ready();
        for (std::size_t k = 0; k < wedges.size(); ++k)
          out[k] = std::min(out[k], wedge_distance_to_segment(wedges[k], a, b));
      }
    };
    for_each_surface_near(centre, reach_m, exclude_body, Visitor{wedges, out, make_wedges, made});
  }

  /// Whether an obstacle (wall, static obstacle, moving obstacle) blocks the sight line
  /// [from, to]. Robots do not block (they are lower than the beacons).
  bool sight_blocked(Vec2 from, Vec2 to) const;

  /// Whether floor point p lies on a track (within half its width of its centre line).
  bool on_track(Vec2 p) const;
};

}  // namespace rilbed::environment

// Static line segments (walls, obstacle edges, floor tracks) hashed into a uniform grid,
// so that a collision or sensor query near a point only looks at the segments close to
// it, however many obstacles the map holds.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "environment/collision_event.hpp"
#include "environment/grid_geometry.hpp"

namespace rilbed::environment {

/// One segment and what it belongs to.
struct IndexedSegment {
  Vec2 a_m;                   ///< one end, field frame
  Vec2 b_m;                   ///< the other end
  BodyRef owner;              ///< wall or obstacle (for tracks: kind Obstacle, id = track index)
  double half_width_m = 0.0;  ///< tracks: half the tape's width; walls and obstacles: 0
};

/// An immutable grid index of segments, in compressed rows (one contiguous list per
/// cell). A segment is listed in every cell that comes within its half width of it.
class SegmentIndex {
 public:
  /// An empty index (no segments, no cells).
  SegmentIndex() = default;
  /// Builds the index over `grid`. The grid should cover every segment (clamped border
  /// cells would otherwise hold segments far outside them, which is correct but slow).
  SegmentIndex(GridGeometry grid, std::vector<IndexedSegment> segments);

  /// Calls f(const IndexedSegment&) for every segment listed in a cell overlapping
  /// `box`: every segment that comes within the box, some that do not, and a segment
  /// once per cell it is listed in (callers' tests are idempotent, so duplicates cost a
  /// little time and no correctness).
  template <class F>
  void for_each_in_box(const Box& box, F&& f) const {
    for_each_listed_in_box(box, [&](std::uint32_t index) { f(segments_[index]); });
  }

  /// Fills `out` with the index (in segments()) of every segment whose bounding box,
  /// widened by its half width, overlaps `box`: each once, in ascending order. The same
  /// list whatever the grid's cell size, unlike for_each_in_box's visits, for callers
  /// whose visit of one segment changes what the next one sees (a robot pushed off one
  /// wall of a corner, then off the other).
  void segments_in_box(const Box& box, std::vector<std::uint32_t>& out) const;

  /// Calls f for the segments listed in the cell holding p: every segment within its
  /// half width of p is among them (used for "is this point on a track").
  template <class F>
  void for_each_at(Vec2 p, F&& f) const {
    if (segments_.empty()) return;
    const int cell = grid_.cell_of(p);
    if (!occupied(cell)) return;
    for (std::uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) f(segments_[ids_[k]]);
  }

  /// Whether any segment blocks the sight line [from, to] (segment_blocks_sight). Walks
  /// only the cells the line passes through.
  bool blocks_sight(Vec2 from, Vec2 to) const;

  /// All segments, in the order given.
  std::span<const IndexedSegment> segments() const { return segments_; }
  /// The grid the segments are hashed on.
  const GridGeometry& grid() const { return grid_; }

 private:
  // Calls f(index in segments_) for every listing of a segment in a cell overlapping
  // `box` (a segment once per such cell).
  template <class F>
  void for_each_listed_in_box(const Box& box, F&& f) const {
    if (segments_.empty()) return;
    const int c0 = grid_.column(box.lo_m.x), c1 = grid_.column(box.hi_m.x);
    const int r0 = grid_.row(box.lo_m.y), r1 = grid_.row(box.hi_m.y);
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        const int cell = grid_.cell(c, r);
        if (!occupied(cell)) continue;
        for (std::uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) f(ids_[k]);
      }
    }
  }

  // Calls f(cell) for each cell the segment [a, b], widened by `margin`, may touch.
  template <class F>
  void for_each_cell_along(Vec2 a, Vec2 b, double margin, F&& f) const;

  // Whether a cell lists any segment: one bit per cell, small enough to stay in cache,
  // so that queries over the (mostly empty) field skip the offsets array.
  bool occupied(int cell) const { return (occupied_bits_[static_cast<std::size_t>(cell) >> 6] >> (cell & 63)) & 1u; }

  GridGeometry grid_;
  std::vector<std::uint64_t> occupied_bits_;
  std::vector<IndexedSegment> segments_;
  std::vector<std::uint32_t> cell_start_;  // cell_count + 1 offsets into ids_
  std::vector<std::uint32_t> ids_;         // segment indices, grouped by cell
};

}  // namespace rilbed::environment

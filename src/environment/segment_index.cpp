#include "environment/segment_index.hpp"

#include <algorithm>
#include <limits>

namespace rilbed::environment {

template <class F>
void SegmentIndex::for_each_cell_along(Vec2 a, Vec2 b, double margin, F&& f) const {
  // Column by column: the cells of a column the segment can touch are those whose rows
  // span the segment's y-range over the column's x-span (both widened by `margin`; a
  // square margin contains the round one). Visits O(cells crossed), not O(bounding box).
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // A hair of extra margin: a segment lying exactly on a cell border (x = 0.3 with
  // cells of 0.1) must land in the cell that column() gives its points, whichever way
  // the border's own arithmetic rounds.
  margin += 1e-9 * grid_.cell_m;
  const double min_x = std::min(a.x, b.x), max_x = std::max(a.x, b.x);
  const double dx = b.x - a.x;
  const int c0 = grid_.column(min_x - margin), c1 = grid_.column(max_x + margin);
  for (int c = c0; c <= c1; ++c) {
    const double col_lo = c == 0 ? -kInf : grid_.origin_m.x + c * grid_.cell_m;
    const double col_hi = c == grid_.nx - 1 ? kInf : grid_.origin_m.x + (c + 1) * grid_.cell_m;
    // Every column in [c0, c1] meets the widened segment; clamping (not skipping) keeps
    // rounding in col_lo / col_hi from dropping one.
    const double qx_lo = std::clamp(col_lo - margin, min_x, max_x);
    const double qx_hi = std::max(qx_lo, std::clamp(col_hi + margin, min_x, max_x));
    double y_lo, y_hi;
    if (dx == 0.0) {
      y_lo = std::min(a.y, b.y);
      y_hi = std::max(a.y, b.y);
    } else {
      const double ya = a.y + (b.y - a.y) * ((qx_lo - a.x) / dx);
      const double yb = a.y + (b.y - a.y) * ((qx_hi - a.x) / dx);
      y_lo = std::min(ya, yb);
      y_hi = std::max(ya, yb);
    }
    const int r0 = grid_.row(y_lo - margin), r1 = grid_.row(y_hi + margin);
    for (int r = r0; r <= r1; ++r) {
      if (!f(grid_.cell(c, r))) return;
    }
  }
}

SegmentIndex::SegmentIndex(GridGeometry grid, std::vector<IndexedSegment> segments)
    : grid_(grid), segments_(std::move(segments)) {
  if (segments_.empty()) return;  // queries check for this first; no per-cell arrays needed
  const std::size_t cells = grid_.cell_count();
  cell_start_.assign(cells + 1, 0);
  // Counting sort in two passes: count each cell's segments, then place them.
  for (const IndexedSegment& s : segments_) {
    for_each_cell_along(s.a_m, s.b_m, s.half_width_m, [&](int cell) {
      ++cell_start_[static_cast<std::size_t>(cell) + 1];
      return true;
    });
  }
  occupied_bits_.assign((cells + 63) / 64, 0);
  for (std::size_t i = 0; i < cells; ++i) {
    if (cell_start_[i + 1] != 0) occupied_bits_[i >> 6] |= std::uint64_t{1} << (i & 63);
    cell_start_[i + 1] += cell_start_[i];
  }
  ids_.resize(cell_start_[cells]);
  std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::uint32_t i = 0; i < segments_.size(); ++i) {
    const IndexedSegment& s = segments_[i];
    for_each_cell_along(s.a_m, s.b_m, s.half_width_m, [&](int cell) {
      ids_[fill[static_cast<std::size_t>(cell)]++] = i;
      return true;
    });
  }
}

bool SegmentIndex::blocks_sight(Vec2 from, Vec2 to) const {
  if (segments_.empty()) return false;
  bool blocked = false;
  for_each_cell_along(from, to, 0.0, [&](int cell) {
    if (!occupied(cell)) return true;
    for (std::uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
      const IndexedSegment& s = segments_[ids_[k]];
      if (segment_blocks_sight(from, to, s.a_m, s.b_m)) {
        blocked = true;
        return false;
      }
    }
    return true;
  });
  return blocked;
}

void SegmentIndex::segments_in_box(const Box& box, std::vector<std::uint32_t>& out) const {
  out.clear();
  for_each_listed_in_box(box, [&](std::uint32_t index) {
    const IndexedSegment& seg = segments_[index];
    const double w = seg.half_width_m;
    const Box bounds{{std::min(seg.a_m.x, seg.b_m.x) - w, std::min(seg.a_m.y, seg.b_m.y) - w},
                     {std::max(seg.a_m.x, seg.b_m.x) + w, std::max(seg.a_m.y, seg.b_m.y) + w}};
    if (overlap(bounds, box)) out.push_back(index);
  });
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

}  // namespace rilbed::environment

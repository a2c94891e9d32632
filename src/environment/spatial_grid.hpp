// The robot grid: every robot hashed by the cell its centre is in, so that collision and
// sensor queries look only at robots in nearby cells and a world step costs about
// linearly in the number of robots.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "environment/grid_geometry.hpp"

namespace rilbed::environment {

/// Items are dense indices 0..n-1 (the world's robot slots). Each cell holds a singly
/// linked list (head per cell, next per item), which makes insert O(1), rebuild O(n)
/// whatever the number of cells (only the cells that were occupied are cleared), and
/// needs no allocation once the item arrays have grown.
class SpatialGrid {
 public:
  /// A grid with one cell and no items (assign a real one before use).
  SpatialGrid() = default;
  /// An empty grid over `geometry`; allocates one list head per cell.
  explicit SpatialGrid(GridGeometry geometry);

  /// The cells.
  const GridGeometry& geometry() const { return geometry_; }
  /// Number of items held.
  std::size_t size() const { return cell_of_.size(); }

  /// Re-hashes items 0..positions.size()-1 at `positions` (drops all previous items).
  void rebuild(std::span<const Vec2> positions);
  /// Same, reading the position of item i as positions_of(i).
  template <class PositionOf>
  void rebuild(std::size_t count, PositionOf&& positions_of) {
    clear_occupied();
    resize_items(count);
    for (std::size_t i = 0; i < count; ++i) link(static_cast<std::int32_t>(i), geometry_.cell_of(positions_of(i)));
  }
  /// Brings items 0..count-1 to positions_of(i) after they moved: only the items whose
  /// cell changed are relinked (a step moves few robots out of their cell), the rest cost
  /// a cell computation each. Rebuilds when count differs from size(). The order of items
  /// within a cell then depends on the history of moves: callers must not depend on it.
  template <class PositionOf>
  void refresh(std::size_t count, PositionOf&& positions_of) {
    if (count != cell_of_.size()) {
      rebuild(count, positions_of);
      return;
    }
    // The cells a move touches are far apart in a large grid (a cache miss each at
    // 100,000 robots): a robot's old and new cells' heads are asked for a few robots ahead.
    constexpr std::size_t kAhead = 16;
    for (std::size_t i = 0; i < count; ++i) {
      if (i + kAhead < count) {
        const int ahead = geometry_.cell_of(positions_of(i + kAhead));
        const int was = cell_of_[i + kAhead];
        if (ahead != was) {
          __builtin_prefetch(&head_[static_cast<std::size_t>(was)], 1);
          __builtin_prefetch(&head_[static_cast<std::size_t>(ahead)], 1);
        }
      }
      const int cell = geometry_.cell_of(positions_of(i));
      if (cell == cell_of_[i]) continue;
      unlink(static_cast<std::int32_t>(i));
      link(static_cast<std::int32_t>(i), cell);
    }
  }
  /// A hint, for a pass over the items in order that queries around each: asks for the
  /// list heads of item `item`'s cell and of the cells above and below it (in its 8 x 8
  /// block, so a line each). In a large grid they are cold (the heads of 100,000 robots'
  /// cells are 1.5 MB, most of them empty cells).
  void prefetch_around(std::size_t item) const {
    const int cell = cell_of_[item];
    const int last = static_cast<int>(head_.size()) - 1;
    const int block_row = GridGeometry::kBlock;
    __builtin_prefetch(&head_[static_cast<std::size_t>(std::max(cell - block_row, 0))]);
    __builtin_prefetch(&head_[static_cast<std::size_t>(cell)]);
    __builtin_prefetch(&head_[static_cast<std::size_t>(std::min(cell + block_row, last))]);
  }
  /// Adds item size() at p.
  void push_back(Vec2 p);
  /// Moves item `item` to p (O(length of its old cell's list)).
  void move(std::size_t item, Vec2 p);

  /// Calls f(int item) for every item whose cell overlaps `box`; the caller tests the
  /// actual distance. Box corners outside the grid are clamped.
  template <class F>
  void for_each_in_box(const Box& box, F&& f) const {
    const int c0 = geometry_.column(box.lo_m.x), c1 = geometry_.column(box.hi_m.x);
    const int r0 = geometry_.row(box.lo_m.y), r1 = geometry_.row(box.hi_m.y);
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        for (std::int32_t i = head_[static_cast<std::size_t>(geometry_.cell(c, r))]; i >= 0;
             i = next_[static_cast<std::size_t>(i)])
          f(static_cast<int>(i));
      }
    }
  }

 private:
  void clear_occupied();
  void resize_items(std::size_t count);
  void link(std::int32_t item, int cell);
  void unlink(std::int32_t item);

  GridGeometry geometry_;
  std::vector<std::int32_t> head_;     // per cell: first item, -1 for none
  std::vector<std::int32_t> next_;     // per item: next item in the same cell, -1 at the end
  std::vector<std::int32_t> cell_of_;  // per item: its cell
};

}  // namespace rilbed::environment

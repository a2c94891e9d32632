// A uniform grid laid over the field: which square cell a point falls in. Shared by the
// static segment index and the robot grid so that both are queried with the same boxes.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "environment/shapes.hpp"

namespace rilbed::environment {

/// Square cells of side cell_m, nx columns by ny rows, starting at origin_m. Points
/// outside the covered area are clamped into the border cells, so every point has a
/// cell and queries stay correct (only slower) for bodies that left the field.
///
/// Cells are numbered in blocks of 8 x 8 (blocks row by row, cells row by row within a
/// block), not row by row across the field: a query's few neighbouring cells then lie in
/// one or a few blocks of 256 bytes of a per-cell int array, instead of on as many cache
/// lines as rows, kilobytes apart on a large field.
struct GridGeometry {
  Vec2 origin_m;        ///< lower-left corner of cell (0, 0)
  double cell_m = 0.1;  ///< side of a cell
  int nx = 1;           ///< columns
  int ny = 1;           ///< rows

  /// A grid covering `box` with cells of about `cell_m`; the cells are made larger when
  /// more than `max_cells` would be needed (memory and rebuild time grow with the count).
  static GridGeometry covering(Box box, double cell_m, std::size_t max_cells) {
    const double w = std::max(box.hi_m.x - box.lo_m.x, cell_m);
    const double h = std::max(box.hi_m.y - box.lo_m.y, cell_m);
    if (w / cell_m * (h / cell_m) > static_cast<double>(max_cells))
      cell_m = std::sqrt(w * h / static_cast<double>(max_cells));
    GridGeometry g;
    g.origin_m = box.lo_m;
    g.cell_m = cell_m;
    g.nx = std::max(1, static_cast<int>(std::ceil(w / cell_m)));
    g.ny = std::max(1, static_cast<int>(std::ceil(h / cell_m)));
    return g;
  }

  /// Column of x, clamped to [0, nx - 1].
  int column(double x) const { return clamp_index((x - origin_m.x) / cell_m, nx); }
  /// Row of y, clamped to [0, ny - 1].
  int row(double y) const { return clamp_index((y - origin_m.y) / cell_m, ny); }
  /// Cells per side of a block.
  static constexpr int kBlock = 8;
  /// Blocks across the field.
  int blocks_x() const { return (nx + kBlock - 1) / kBlock; }
  /// Linear index of (column, row), in [0, cell_count()).
  int cell(int col, int row_index) const {
    // Unsigned: columns and rows are never negative, and / and % by 8 become shifts and masks.
    const auto c = static_cast<unsigned>(col), r = static_cast<unsigned>(row_index);
    constexpr unsigned b = kBlock;
    const unsigned block = (r / b) * static_cast<unsigned>(blocks_x()) + c / b;
    return static_cast<int>(block * b * b + (r % b) * b + c % b);
  }
  /// Linear index of the cell holding p.
  int cell_of(Vec2 p) const { return cell(column(p.x), row(p.y)); }
  /// Number of cell indices (whole blocks: a few more than nx * ny).
  std::size_t cell_count() const {
    const std::size_t blocks_y = static_cast<std::size_t>((ny + kBlock - 1) / kBlock);
    return static_cast<std::size_t>(blocks_x()) * blocks_y * kBlock * kBlock;
  }

 private:
  static int clamp_index(double f, int n) {
    // Clamp in floating point first: casting a huge double to int is undefined.
    if (!(f >= 0.0)) return 0;
    if (f >= static_cast<double>(n - 1)) return n - 1;
    return static_cast<int>(f);
  }
};

}  // namespace rilbed::environment

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
struct GridGeometry {
  Vec2 origin_m;       ///< lower-left corner of cell (0, 0)
  double cell_m = 0.1; ///< side of a cell
  int nx = 1;          ///< columns
  int ny = 1;          ///< rows

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
  /// Linear index of (column, row).
  int cell(int col, int row_index) const { return row_index * nx + col; }
  /// Linear index of the cell holding p.
  int cell_of(Vec2 p) const { return cell(column(p.x), row(p.y)); }
  /// Number of cells.
  std::size_t cell_count() const { return static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny); }

 private:
  static int clamp_index(double f, int n) {
    // Clamp in floating point first: casting a huge double to int is undefined.
    if (!(f >= 0.0)) return 0;
    if (f >= static_cast<double>(n - 1)) return n - 1;
    return static_cast<int>(f);
  }
};

}  // namespace rilbed::environment

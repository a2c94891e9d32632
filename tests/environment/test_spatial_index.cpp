#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "environment/random.hpp"
#include "environment/segment_index.hpp"
#include "environment/spatial_grid.hpp"

using namespace rilbed;
using namespace rilbed::environment;

namespace {
Vec2 random_point(std::mt19937_64& rng, double lo, double hi) {
  return {lo + (hi - lo) * uniform01(rng), lo + (hi - lo) * uniform01(rng)};
}
}  // namespace

TEST(GridGeometry, ClampsPointsOutsideIntoBorderCells) {
  const GridGeometry g = GridGeometry::covering({{0, 0}, {1, 0.5}}, 0.1, 1000);
  EXPECT_EQ(g.nx, 10);
  EXPECT_EQ(g.ny, 5);
  EXPECT_EQ(g.column(-5.0), 0);
  EXPECT_EQ(g.column(1e300), 9);
  EXPECT_EQ(g.row(0.25), 2);
  // Too many cells for the cap: cells grow.
  const GridGeometry big = GridGeometry::covering({{0, 0}, {100, 100}}, 0.01, 10000);
  EXPECT_LE(big.nx * big.ny, 10201);
  EXPECT_GE(big.cell_m, 1.0 - 1e-9);
  // Indices pad the cells to whole blocks of 8 x 8, no more.
  EXPECT_LT(big.cell_count(), static_cast<std::size_t>((big.nx + 8) * (big.ny + 8)));
}

TEST(GridGeometry, EveryCellHasItsOwnIndexAndNeighboursShareBlocks) {
  for (const double width_m : {0.3, 1.0, 2.37, 17.0}) {
    const GridGeometry g = GridGeometry::covering({{0, 0}, {width_m, 0.61 * width_m}}, 0.1, 1 << 20);
    std::vector<int> seen(g.cell_count(), 0);
    for (int r = 0; r < g.ny; ++r) {
      for (int c = 0; c < g.nx; ++c) {
        const int cell = g.cell(c, r);
        ASSERT_GE(cell, 0);
        ASSERT_LT(static_cast<std::size_t>(cell), g.cell_count());
        ASSERT_EQ(seen[static_cast<std::size_t>(cell)]++, 0) << "cell (" << c << ", " << r << ") shares an index";
        ASSERT_EQ(g.cell_of({g.origin_m.x + (c + 0.5) * g.cell_m, g.origin_m.y + (r + 0.5) * g.cell_m}), cell);
      }
    }
    if (g.nx >= 8 && g.ny >= 8) {
      // The 8 x 8 cells of a block are 64 consecutive indices.
      EXPECT_EQ(g.cell(7, 7) - g.cell(0, 0), 63);
    }
  }
}

TEST(SpatialGrid, BoxQueriesFindEveryItemInTheBoxAfterMovesAndRebuilds) {
  std::mt19937_64 rng(7);
  SpatialGrid grid(GridGeometry::covering({{0, 0}, {2, 2}}, 0.1, 1 << 20));
  std::vector<Vec2> points;
  for (int i = 0; i < 500; ++i) {
    points.push_back(random_point(rng, -0.5, 2.5));  // some outside the grid
    grid.push_back(points.back());
  }
  auto check = [&] {
    for (int q = 0; q < 200; ++q) {
      const Vec2 c = random_point(rng, -0.5, 2.5);
      const Box box = box_around(c, 0.15);
      std::set<int> found;
      grid.for_each_in_box(box, [&](int i) { EXPECT_TRUE(found.insert(i).second) << "item listed twice"; });
      for (int i = 0; i < static_cast<int>(points.size()); ++i) {
        const Vec2 p = points[static_cast<std::size_t>(i)];
        const bool inside = p.x >= box.lo_m.x && p.x <= box.hi_m.x && p.y >= box.lo_m.y && p.y <= box.hi_m.y;
        if (inside) {
          EXPECT_TRUE(found.contains(i)) << "item " << i << " missed";
        }
      }
    }
  };
  check();
  for (std::size_t i = 0; i < points.size(); i += 3) {
    points[i] = random_point(rng, -0.5, 2.5);
    grid.move(i, points[i]);
  }
  check();
  for (Vec2& p : points) p = random_point(rng, -0.5, 2.5);
  grid.rebuild(points);
  EXPECT_EQ(grid.size(), points.size());
  check();
  // A step's small moves (most stay in their cell), then a refresh; then a big shuffle.
  for (Vec2& p : points) p = p + Vec2{0.03 * (uniform01(rng) - 0.5), 0.03 * (uniform01(rng) - 0.5)};
  grid.refresh(points.size(), [&](std::size_t i) { return points[i]; });
  check();
  for (Vec2& p : points) p = random_point(rng, -0.5, 2.5);
  grid.refresh(points.size(), [&](std::size_t i) { return points[i]; });
  check();
  // A different count rebuilds.
  points.resize(300);
  grid.refresh(points.size(), [&](std::size_t i) { return points[i]; });
  EXPECT_EQ(grid.size(), points.size());
  check();
}

TEST(SegmentIndex, NearQueriesTrackLookupsAndSightLinesMatchBruteForce) {
  std::mt19937_64 rng(11);
  const GridGeometry g = GridGeometry::covering({{0, 0}, {3, 3}}, 0.1, 1 << 20);
  std::vector<IndexedSegment> segments;
  for (int i = 0; i < 60; ++i) {
    const Vec2 a = random_point(rng, 0, 3);
    const Vec2 b = a + Vec2{uniform01(rng) - 0.5, uniform01(rng) - 0.5} * (i % 5 == 0 ? 2.5 : 0.4);
    segments.push_back({a, b, {BodyKind::kObstacle, i}, 0.02 * uniform01(rng)});
  }
  const SegmentIndex index(g, segments);
  for (int q = 0; q < 400; ++q) {
    const Vec2 p = random_point(rng, 0, 3);
    const double reach = 0.2 * uniform01(rng);
    std::set<int> near;
    index.for_each_in_box(box_around(p, reach), [&](const IndexedSegment& s) { near.insert(s.owner.id); });
    std::set<int> at;
    index.for_each_at(p, [&](const IndexedSegment& s) { at.insert(s.owner.id); });
    for (const IndexedSegment& s : segments) {
      const double d_sq = distance_sq_to_segment(p, s.a_m, s.b_m);
      if (d_sq <= reach * reach) {
        EXPECT_TRUE(near.contains(s.owner.id)) << "segment " << s.owner.id << " missed";
      }
      if (d_sq <= s.half_width_m * s.half_width_m) {
        EXPECT_TRUE(at.contains(s.owner.id));
      }
    }
    const Vec2 to = random_point(rng, 0, 3);
    bool brute = false;
    for (const IndexedSegment& s : segments) brute = brute || segment_blocks_sight(p, to, s.a_m, s.b_m);
    EXPECT_EQ(index.blocks_sight(p, to), brute);
  }
}

TEST(SegmentIndex, SegmentsOnCellBordersAreFoundFromBothSides) {
  // Cells of 0.1 from -0.1: x = 0.3 is a border, where -0.1 + 4 * 0.1 rounds above 0.3.
  const GridGeometry g = GridGeometry::covering({{-0.1, -0.1}, {1.6, 1.3}}, 0.1, 1 << 20);
  std::vector<IndexedSegment> segments;
  int id = 0;
  for (int k = 0; k <= 12; ++k) {
    const double v = k * 0.1;
    segments.push_back({{v, 0.0}, {v, 1.2}, {BodyKind::kObstacle, id++}, 0.0});  // vertical borders
    segments.push_back({{0.0, v}, {1.5, v}, {BodyKind::kObstacle, id++}, 0.0});  // horizontal borders
  }
  segments.push_back({{0.0, 0.0}, {1.2, 1.2}, {BodyKind::kObstacle, id++}, 0.0});  // through cell corners
  const SegmentIndex index(g, segments);
  std::mt19937_64 rng(5);
  for (int q = 0; q < 3000; ++q) {
    const Vec2 p = random_point(rng, 0.0, 1.2);
    const double reach = 0.03;
    std::set<int> near;
    index.for_each_in_box(box_around(p, reach), [&](const IndexedSegment& s) { near.insert(s.owner.id); });
    for (const IndexedSegment& s : segments) {
      if (distance_sq_to_segment(p, s.a_m, s.b_m) <= reach * reach) {
        EXPECT_TRUE(near.contains(s.owner.id))
            << "segment " << s.owner.id << " missed from (" << p.x << ", " << p.y << ")";
      }
    }
  }
}

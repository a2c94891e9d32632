#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "environment/shapes.hpp"

using namespace rilbed;
using namespace rilbed::environment;

namespace {
Wedge wedge_along_x(double half_deg) {
  return make_wedge({0, 0}, {1, 0}, std::cos(deg_to_rad(half_deg)), std::sin(deg_to_rad(half_deg)));
}
}  // namespace

TEST(Wedge, SegmentAcrossTheAxisIsAtItsPerpendicularDistance) {
  const Wedge w = wedge_along_x(30);
  EXPECT_DOUBLE_EQ(wedge_distance_to_segment(w, {1, -5}, {1, 5}), 1.0);
  EXPECT_DOUBLE_EQ(wedge_distance_to_segment(w, {1, 5}, {1, -5}), 1.0);  // either direction
}

TEST(Wedge, SegmentOutsideTheConeIsNotSeen) {
  const Wedge w = wedge_along_x(30);
  // From the apex, (1, 2)..(1, 3) lies at 63..72 degrees: outside +-30.
  EXPECT_EQ(wedge_distance_to_segment(w, {1, 2}, {1, 3}), kNoHit);
  // Behind the apex.
  EXPECT_EQ(wedge_distance_to_segment(w, {-1, -1}, {-1, 1}), kNoHit);
}

TEST(Wedge, SegmentPartlyInsideIsSeenAtItsNearestInsidePoint) {
  const Wedge w = wedge_along_x(30);
  // (1, 0.5)..(1, 3): only y in [0.5, tan 30] lies inside; nearest is (1, 0.5).
  EXPECT_NEAR(wedge_distance_to_segment(w, {1, 0.5}, {1, 3}), std::sqrt(1.25), 1e-12);
  // A wall running away at an angle: x = 1 + y for y >= 0... nearest inside point is
  // (1, 0), on the axis.
  EXPECT_NEAR(wedge_distance_to_segment(w, {1, 0}, {3, 2}), 1.0, 1e-12);
}

TEST(Wedge, DiscAlongTheAxisAndOffTheEdges) {
  const Wedge w = wedge_along_x(30);
  EXPECT_NEAR(wedge_distance_to_disc(w, {1, 0}, 0.2), 0.8, 1e-12);
  // Centre at 40 degrees (outside), radius 0.3 at distance 1: its angular half size is
  // asin(0.3) = 17.5 degrees, so it reaches into the wedge and the +30 degree edge ray
  // enters it first. Along that ray: cos(10 deg) - sqrt(0.09 - sin^2(10 deg)).
  const Vec2 c{std::cos(deg_to_rad(40)), std::sin(deg_to_rad(40))};
  const double s10 = std::sin(deg_to_rad(10)), c10 = std::cos(deg_to_rad(10));
  EXPECT_NEAR(wedge_distance_to_disc(w, c, 0.3), c10 - std::sqrt(0.09 - s10 * s10), 1e-12);
  // The same disc at 60 degrees does not reach 30 degrees.
  EXPECT_EQ(wedge_distance_to_disc(w, {std::cos(deg_to_rad(60)), std::sin(deg_to_rad(60))}, 0.3), kNoHit);
  // Apex inside the disc.
  EXPECT_EQ(wedge_distance_to_disc(w, {0.1, 0.0}, 0.2), 0.0);
}

TEST(Segments, PathCrossingAndSightBlocking) {
  EXPECT_TRUE(path_crosses_segment({0, 0}, {2, 0}, {1, -1}, {1, 1}));
  EXPECT_FALSE(path_crosses_segment({0, 0}, {0.9, 0}, {1, -1}, {1, 1}));
  EXPECT_FALSE(path_crosses_segment({0, 2}, {2, 2}, {1, -1}, {1, 1}));  // passes beyond its end
  EXPECT_TRUE(path_crosses_segment({0, 0}, {1, 0}, {1, -1}, {1, 1}));   // ends on it: counts
  EXPECT_FALSE(path_crosses_segment({1, 0}, {2, 0}, {1, -1}, {1, 1}));  // starts on it: does not

  EXPECT_TRUE(segment_blocks_sight({0, 0}, {2, 0}, {1, -1}, {1, 1}));
  EXPECT_FALSE(segment_blocks_sight({1, 0}, {2, 0}, {1, -1}, {1, 1}));     // viewer mounted on it
  EXPECT_FALSE(segment_blocks_sight({0, 0}, {2, 0}, {0, 0.5}, {2, 0.5}));  // parallel
}

TEST(Polygons, AreaInsideConvexAndCrossing) {
  const std::vector<Vec2> square{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const std::vector<Vec2> ell{{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  const std::vector<Vec2> bow{{0, 0}, {1, 1}, {1, 0}, {0, 1}};
  EXPECT_DOUBLE_EQ(polygon_signed_area(square), 1.0);
  EXPECT_DOUBLE_EQ(polygon_signed_area(std::vector<Vec2>(square.rbegin(), square.rend())), -1.0);
  EXPECT_DOUBLE_EQ(polygon_signed_area(ell), 3.0);
  EXPECT_TRUE(point_in_polygon({0.5, 0.5}, square));
  EXPECT_FALSE(point_in_polygon({1.5, 0.5}, square));
  EXPECT_TRUE(point_in_polygon({0.5, 1.5}, ell));
  EXPECT_FALSE(point_in_polygon({1.5, 1.5}, ell));  // the notch of the L
  EXPECT_TRUE(polygon_is_convex(square));
  EXPECT_FALSE(polygon_is_convex(ell));
  EXPECT_FALSE(polygon_is_convex(bow));
  EXPECT_FALSE(polygon_self_intersects(ell));
  EXPECT_TRUE(polygon_self_intersects(bow));
}

TEST(Contacts, DiscAgainstSegmentDiscAndPolygon) {
  const Contact s = disc_segment_contact({0.5, 0.1}, 0.25, {0, 0}, {1, 0});
  EXPECT_NEAR(s.separation_m, -0.15, 1e-12);
  EXPECT_NEAR(s.normal.y, 1.0, 1e-12);
  const Contact d = disc_disc_contact({0, 0}, 0.5, {0.8, 0}, 0.5);
  EXPECT_NEAR(d.separation_m, -0.2, 1e-12);
  EXPECT_NEAR(d.normal.x, -1.0, 1e-12);  // from b towards a
  const std::vector<Vec2> square{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  // Centre inside, nearest the right edge (0.1 away): pushed out right by 0.1 + r.
  const Contact in = disc_convex_polygon_contact({0.9, 0.5}, 0.05, square);
  EXPECT_NEAR(in.separation_m, -0.15, 1e-12);
  EXPECT_NEAR(in.normal.x, 1.0, 1e-12);
  // Outside near the corner (1, 1).
  const Contact corner = disc_convex_polygon_contact({1.03, 1.04}, 0.1, square);
  EXPECT_NEAR(corner.separation_m, 0.05 - 0.1, 1e-12);
  EXPECT_NEAR(corner.normal.x, 0.6, 1e-12);
  EXPECT_NEAR(corner.normal.y, 0.8, 1e-12);
}

TEST(Contacts, ConvexPolygonAgainstSegment) {
  const std::vector<Vec2> square{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  // A wall at x = 0.9 cutting the square: least push is left by 0.1.
  const Contact c = convex_polygon_segment_contact(square, {0.9, -1}, {0.9, 2});
  EXPECT_NEAR(c.separation_m, -0.1, 1e-12);
  EXPECT_NEAR(c.normal.x, -1.0, 1e-12);
  const Contact apart = convex_polygon_segment_contact(square, {1.5, -1}, {1.5, 2});
  EXPECT_NEAR(apart.separation_m, 0.5, 1e-12);
}

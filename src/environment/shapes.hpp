// Plane geometry the world model needs beyond core/geometry.hpp: segments, polygons,
// circles, the penetration of one shape into another, and the sensing wedge (the 2-D
// cone of an IR or ultrasonic sensor). All lengths are metres in the field frame.
#pragma once

#include <limits>
#include <span>

#include "core/geometry.hpp"

namespace rilbed::environment {

/// "Nothing found" for distance queries.
inline constexpr double kNoHit = std::numeric_limits<double>::infinity();

/// An axis-aligned box, metres.
struct Box {
  Vec2 lo_m;  ///< lower-left corner
  Vec2 hi_m;  ///< upper-right corner
};

/// Whether p lies in `box` (borders included).
inline bool contains(const Box& box, Vec2 p) {
  return p.x >= box.lo_m.x && p.x <= box.hi_m.x && p.y >= box.lo_m.y && p.y <= box.hi_m.y;
}

/// Whether two boxes share any point (borders included).
inline bool overlap(const Box& a, const Box& b) {
  return a.lo_m.x <= b.hi_m.x && b.lo_m.x <= a.hi_m.x && a.lo_m.y <= b.hi_m.y && b.lo_m.y <= a.hi_m.y;
}

/// The square box of half side `half_m` around p.
inline Box box_around(Vec2 p, double half_m) { return {{p.x - half_m, p.y - half_m}, {p.x + half_m, p.y + half_m}}; }

/// Squared distance between two points (no square root: the hot loops compare squares).
inline double distance_sq(Vec2 a, Vec2 b) {
  const Vec2 d = b - a;
  return d.dot(d);
}

/// The point of segment [a, b] closest to p (a if the segment is a point).
inline Vec2 closest_point_on_segment(Vec2 p, Vec2 a, Vec2 b) {
  const Vec2 ab = b - a;
  const double len_sq = ab.dot(ab);
  if (len_sq <= 0.0) return a;
  double t = (p - a).dot(ab) / len_sq;
  t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
  return a + ab * t;
}

/// Squared distance from p to segment [a, b].
inline double distance_sq_to_segment(Vec2 p, Vec2 a, Vec2 b) {
  return distance_sq(p, closest_point_on_segment(p, a, b));
}

/// True when the moving point's path [from, to] passes from one side of segment [a, b]
/// to the other through the segment: `from` strictly on one side of the segment's line,
/// `to` on the other side or on the line, the crossing point within [a, b].
bool path_crosses_segment(Vec2 from, Vec2 to, Vec2 a, Vec2 b);

/// True when segment [a, b] blocks the sight line [from, to]: they intersect at a point
/// strictly between the sight line's ends (so a beacon mounted on a wall is not hidden
/// by that wall). Parallel segments never block.
bool segment_blocks_sight(Vec2 from, Vec2 to, Vec2 a, Vec2 b);

/// Signed area of a closed polygon (positive when its vertices run counter-clockwise).
double polygon_signed_area(std::span<const Vec2> vertices);

/// Whether p lies inside the closed polygon (even–odd rule; points on an edge may go
/// either way).
bool point_in_polygon(Vec2 p, std::span<const Vec2> vertices);

/// Whether the closed polygon is convex (collinear vertices allowed), either orientation.
bool polygon_is_convex(std::span<const Vec2> vertices);

/// Whether two non-adjacent edges of the closed polygon intersect (a figure-eight, say).
bool polygon_self_intersects(std::span<const Vec2> vertices);

/// Bounding box of a set of points (empty input gives a degenerate box at the origin).
Box bounding_box(std::span<const Vec2> points);

/// How two shapes touch: the unit normal along which the first shape must move to
/// separate from the second, and the signed gap between their surfaces along it
/// (negative: they overlap by -separation_m).
struct Contact {
  Vec2 normal;                ///< unit
  double separation_m = 0.0;  ///< gap; negative is overlap
};

/// Contact of the disc (centre, radius_m) with segment [a, b]. The normal points from
/// the segment towards the centre; a centre lying on the segment gets the segment's
/// left normal.
Contact disc_segment_contact(Vec2 centre, double radius_m, Vec2 a, Vec2 b);

/// Contact of two discs; the normal points from b towards a. Coincident centres get +x.
Contact disc_disc_contact(Vec2 centre_a, double radius_a_m, Vec2 centre_b, double radius_b_m);

/// Contact of a disc with a convex polygon (either orientation). The normal points from
/// the polygon towards the disc; a centre inside the polygon is pushed out through the
/// nearest edge.
Contact disc_convex_polygon_contact(Vec2 centre, double radius_m, std::span<const Vec2> polygon);

/// Contact of a convex polygon with segment [a, b] by the separating-axis test: the
/// normal is the axis of least overlap, pointing from the segment towards the polygon.
/// For separated shapes separation_m is the largest gap over the axes tried (a lower
/// bound of the true distance).
Contact convex_polygon_segment_contact(std::span<const Vec2> polygon, Vec2 a, Vec2 b);

/// A sensing wedge: the 2-D cone of directions within half_angle of the axis, from the
/// apex. The half angle must be below 90 degrees so that the wedge is convex (the
/// intersection of the two half-planes bounded by its edges).
struct Wedge {
  Vec2 apex_m;      ///< where the sensor is
  Vec2 axis;        ///< unit vector along the middle of the wedge
  Vec2 left_edge;   ///< unit vector, axis turned counter-clockwise by the half angle
  Vec2 right_edge;  ///< unit vector, axis turned clockwise by the half angle
};

/// Builds the wedge with apex `apex_m`, unit axis `axis`, and half angle given by its
/// cosine and sine (precomputed by the caller, who usually has them).
inline Wedge make_wedge(Vec2 apex_m, Vec2 axis, double cos_half, double sin_half) {
  return Wedge{apex_m, axis, Vec2{axis.x * cos_half - axis.y * sin_half, axis.x * sin_half + axis.y * cos_half},
               Vec2{axis.x * cos_half + axis.y * sin_half, -axis.x * sin_half + axis.y * cos_half}};
}

/// Whether the direction `v` (from the apex) lies inside the wedge, edges included.
inline bool wedge_contains_direction(const Wedge& w, Vec2 v) {
  return w.right_edge.cross(v) >= 0.0 && v.cross(w.left_edge) >= 0.0;
}

/// Distance from the apex to the nearest point of segment [a, b] inside the wedge, or
/// kNoHit when no part of the segment is inside.
double wedge_distance_to_segment(const Wedge& wedge, Vec2 a, Vec2 b);

/// Distance from the apex to the nearest point of the disc inside the wedge, or kNoHit.
/// 0 when the apex is inside the disc.
double wedge_distance_to_disc(const Wedge& wedge, Vec2 centre, double radius_m);

/// Distance along the ray (origin, unit direction) to where it enters the disc, or
/// kNoHit when it misses (or starts inside it, which callers check first).
double ray_disc_entry(Vec2 origin, Vec2 direction, Vec2 centre, double radius_m);

}  // namespace rilbed::environment

// A robot's body as the collision resolver and the world's placement checks see it: a
// disc, or a convex outline that turns with the robot. Discs keep the resolver's fast
// path; outlines live in a side table (BodyOutline) that only their robots point into.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "core/geometry.hpp"
#include "environment/moving_obstacle.hpp"
#include "environment/shapes.hpp"

namespace rilbed::environment {

/// Most vertices an outline may have: the narrow phase copies an outline to the stack, so
/// that threads that look for contacts ahead share no scratch (32 vertices: 512 bytes).
inline constexpr std::size_t kMaxOutlineVertices = 32;

/// A convex outline in the robot's frame (x forward, y left, metres), counter-clockwise,
/// with the robot's centre (its wheel axle's middle) strictly inside.
/// The outline is placed where it is needed (place_body, on the caller's stack), from its
/// heading: turning a robot costs a store, not a vertex each.
struct BodyOutline {
  std::vector<Vec2> local_m;  ///< robot frame, as configured (made counter-clockwise)
  Vec2 heading{1.0, 0.0};     ///< the body's current heading: cosine and sine
  /// The substep's start: where the resolver's fallback puts an outline back, since a
  /// body put back at its start place with its new heading may overlap (a disc may not).
  Vec2 start_heading{1.0, 0.0};
  /// Set by turn_back(); the world turns its robot back too, and clears it.
  bool turned_back = false;

  /// Starts a substep that ends at heading `h` (a unit vector): the current heading
  /// becomes the start.
  void turn_to(Vec2 h) {
    start_heading = heading;
    heading = h;
  }
  /// Back to the substep's start heading (the resolver's fallback).
  void turn_back() {
    heading = start_heading;
    turned_back = true;
  }
};

/// Checks an outline and returns it counter-clockwise: 3 to kMaxOutlineVertices finite
/// vertices, convex, not self-intersecting, with a positive area and the origin strictly
/// inside. Throws std::invalid_argument naming `what` and the cause.
std::vector<Vec2> checked_outline(std::vector<Vec2> outline_m, const std::string& what);

/// The radius of the smallest disc about the origin that holds the outline (its farthest
/// vertex): what the broad phase, the grid and the sensors of other robots use.
double outline_bounding_radius_m(std::span<const Vec2> outline_m);

/// The distance from the origin to the outline's nearest edge: the largest disc about the
/// centre inside the body, which bounds how far a robot may move in one substep.
double outline_inner_radius_m(std::span<const Vec2> outline_m);

/// A body at its current place: a disc (polygon_m empty), or a convex polygon in the
/// field frame. Views: the vertices belong to the caller.
struct BodyShape {
  Vec2 centre_m;
  double radius_m = 0.0;            ///< the disc; for a polygon, its bounding radius
  std::span<const Vec2> polygon_m;  ///< field frame, counter-clockwise; empty: a disc
};

/// Room for one polygon's field-frame vertices, on the caller's stack.
using OutlineBuffer = std::array<Vec2, kMaxOutlineVertices>;

/// The shape of a body centred at centre_m: its disc, or (outline non-null) its outline
/// placed there, written into `buffer`.
BodyShape place_body(Vec2 centre_m, double radius_m, const BodyOutline* outline, OutlineBuffer& buffer);

/// Contact of shape a with shape b; the normal points from b towards a. For two discs
/// this is disc_disc_contact; with a polygon, the separating-axis test (for separated
/// shapes separation_m is then a lower bound of the gap).
Contact shape_shape_contact(const BodyShape& a, const BodyShape& b);

/// Contact of a shape with segment [p, q]; the normal points from the segment towards it.
Contact shape_segment_contact(const BodyShape& a, Vec2 p, Vec2 q);

/// Contact of a shape with a moving obstacle; the normal points towards the shape.
Contact shape_mover_contact(const BodyShape& a, const MovingObstacle& m);

/// How far the shape reaches from its centre against unit direction n (along -n): the
/// radius for a disc, the farthest vertex's projection for a polygon. A body whose centre
/// crossed a wall is put back this far on the side it came from.
double shape_reach_against(const BodyShape& a, Vec2 n);

/// Contact of two convex polygons (either orientation) by the separating-axis test; the
/// normal points from b towards a. For separated polygons separation_m is the largest gap
/// over the edge normals (a lower bound of the true distance).
Contact convex_polygon_polygon_contact(std::span<const Vec2> a, std::span<const Vec2> b);

}  // namespace rilbed::environment

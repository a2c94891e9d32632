#include "environment/body_shape.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rilbed::environment {

std::vector<Vec2> checked_outline(std::vector<Vec2> outline_m, const std::string& what) {
  const std::string head = what + ": outline ";
  if (outline_m.size() < 3 || outline_m.size() > kMaxOutlineVertices)
    throw std::invalid_argument(head + "must have 3 to " + std::to_string(kMaxOutlineVertices) + " vertices, not " +
                                std::to_string(outline_m.size()));
  for (const Vec2 v : outline_m)
    if (!std::isfinite(v.x) || !std::isfinite(v.y))
      throw std::invalid_argument(head + "has a vertex that is not finite");
  if (polygon_self_intersects(outline_m)) throw std::invalid_argument(head + "crosses itself");
  if (!polygon_is_convex(outline_m)) throw std::invalid_argument(head + "is not convex");
  const double area = polygon_signed_area(outline_m);
  if (std::abs(area) < 1e-8) throw std::invalid_argument(head + "has (almost) no area");
  if (area < 0.0) std::reverse(outline_m.begin(), outline_m.end());
  // Strictly inside: the robot turns about its centre, and a body whose centre is on or
  // outside its outline has no inside for the walls' crossing test to keep it on.
  const std::size_t n = outline_m.size();
  for (std::size_t k = 0; k < n; ++k) {
    const Vec2 a = outline_m[k], b = outline_m[(k + 1) % n];
    if ((b - a).cross(Vec2{} - a) <= 1e-9)
      throw std::invalid_argument(head + "must hold the robot's centre (0, 0) strictly inside");
  }
  return outline_m;
}

double outline_bounding_radius_m(std::span<const Vec2> outline_m) {
  double r_sq = 0.0;
  for (const Vec2 v : outline_m) r_sq = std::max(r_sq, v.dot(v));
  return std::sqrt(r_sq);
}

double outline_inner_radius_m(std::span<const Vec2> outline_m) {
  double inner = kNoHit;
  for (std::size_t k = 0; k < outline_m.size(); ++k)
    inner = std::min(inner, std::sqrt(distance_sq_to_segment({}, outline_m[k], outline_m[(k + 1) % outline_m.size()])));
  return inner;
}

BodyShape place_body(Vec2 centre_m, double radius_m, const BodyOutline* outline, OutlineBuffer& buffer) {
  if (!outline) return {centre_m, radius_m, {}};
  const std::size_t n = std::min(outline->local_m.size(), buffer.size());
  const Vec2 h = outline->heading;
  for (std::size_t k = 0; k < n; ++k) {
    const Vec2 v = outline->local_m[k];
    buffer[k] = {centre_m.x + h.x * v.x - h.y * v.y, centre_m.y + h.y * v.x + h.x * v.y};
  }
  return {centre_m, radius_m, std::span<const Vec2>(buffer.data(), n)};
}

Contact convex_polygon_polygon_contact(std::span<const Vec2> a, std::span<const Vec2> b) {
  Contact best{{1.0, 0.0}, -kNoHit};
  auto project = [](std::span<const Vec2> poly, Vec2 axis, double& lo, double& hi) {
    lo = kNoHit, hi = -kNoHit;
    for (const Vec2 v : poly) {
      const double p = v.dot(axis);
      lo = std::min(lo, p);
      hi = std::max(hi, p);
    }
  };
  auto try_axis = [&](Vec2 axis) {
    double amin, amax, bmin, bmax;
    project(a, axis, amin, amax);
    project(b, axis, bmin, bmax);
    // Moving a along +axis by (bmax - amin), or along -axis by (amax - bmin), separates
    // the projections; the smaller move is this axis's answer.
    const double push_plus = bmax - amin, push_minus = amax - bmin;
    const Contact c = push_plus < push_minus ? Contact{axis, -push_plus} : Contact{axis * -1.0, -push_minus};
    if (c.separation_m > best.separation_m) best = c;
  };
  for (const std::span<const Vec2> poly : {a, b}) {
    const std::size_t n = poly.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2 e = poly[(i + 1) % n] - poly[i];
      const double len = e.norm();
      if (len > 0.0) try_axis(Vec2{-e.y / len, e.x / len});
    }
  }
  return best;
}

Contact shape_shape_contact(const BodyShape& a, const BodyShape& b) {
  const bool a_disc = a.polygon_m.empty(), b_disc = b.polygon_m.empty();
  if (a_disc && b_disc) return disc_disc_contact(a.centre_m, a.radius_m, b.centre_m, b.radius_m);
  if (a_disc) return disc_convex_polygon_contact(a.centre_m, a.radius_m, b.polygon_m);
  if (b_disc) {
    const Contact c = disc_convex_polygon_contact(b.centre_m, b.radius_m, a.polygon_m);
    return {c.normal * -1.0, c.separation_m};
  }
  return convex_polygon_polygon_contact(a.polygon_m, b.polygon_m);
}

Contact shape_segment_contact(const BodyShape& a, Vec2 p, Vec2 q) {
  if (a.polygon_m.empty()) return disc_segment_contact(a.centre_m, a.radius_m, p, q);
  return convex_polygon_segment_contact(a.polygon_m, p, q);
}

Contact shape_mover_contact(const BodyShape& a, const MovingObstacle& m) {
  if (m.shape() == MovingShape::kDisc) return shape_shape_contact(a, {m.position_m(), m.bounding_radius_m(), {}});
  return shape_shape_contact(a, {m.position_m(), m.bounding_radius_m(), m.world_vertices_m()});
}

double shape_reach_against(const BodyShape& a, Vec2 n) {
  if (a.polygon_m.empty()) return a.radius_m;
  double reach = 0.0;
  for (const Vec2 v : a.polygon_m) reach = std::max(reach, -(v - a.centre_m).dot(n));
  return reach;
}

}  // namespace rilbed::environment

#include "environment/shapes.hpp"

#include <algorithm>
#include <cmath>

namespace rilbed::environment {

bool path_crosses_segment(Vec2 from, Vec2 to, Vec2 a, Vec2 b) {
  const Vec2 ab = b - a;
  const double len_sq = ab.dot(ab);
  if (len_sq <= 0.0) return false;
  const double side_from = ab.cross(from - a);
  const double side_to = ab.cross(to - a);
  if (side_from == 0.0) return false;  // starting on the line is touching, not crossing
  if ((side_from > 0.0 && side_to > 0.0) || (side_from < 0.0 && side_to < 0.0)) return false;
  const double t = side_from / (side_from - side_to);
  const Vec2 x = from + (to - from) * t;
  const double u = (x - a).dot(ab) / len_sq;
  return u >= 0.0 && u <= 1.0;
}

bool segment_blocks_sight(Vec2 from, Vec2 to, Vec2 a, Vec2 b) {
  const Vec2 r = to - from;
  const Vec2 s = b - a;
  const double denom = r.cross(s);
  // Parallel (or degenerate) segments: a wall seen edge-on hides nothing behind it.
  if (std::abs(denom) <= 1e-15 * std::sqrt(r.dot(r) * s.dot(s))) return false;
  const Vec2 qp = a - from;
  const double t = qp.cross(s) / denom;
  const double u = qp.cross(r) / denom;
  constexpr double kEndSlack = 1e-9;
  return t > kEndSlack && t < 1.0 - kEndSlack && u >= 0.0 && u <= 1.0;
}

double polygon_signed_area(std::span<const Vec2> v) {
  double twice = 0.0;
  for (std::size_t i = 0, n = v.size(); i < n; ++i) twice += v[i].cross(v[(i + 1) % n]);
  return 0.5 * twice;
}

bool point_in_polygon(Vec2 p, std::span<const Vec2> v) {
  bool inside = false;
  for (std::size_t i = 0, n = v.size(), j = n - 1; i < n; j = i++) {
    const Vec2 a = v[i], b = v[j];
    if ((a.y > p.y) != (b.y > p.y)) {
      const double x_cross = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
      if (p.x < x_cross) inside = !inside;
    }
  }
  return inside;
}

bool polygon_is_convex(std::span<const Vec2> v) {
  const std::size_t n = v.size();
  if (n < 3) return false;
  int sign = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 e0 = v[(i + 1) % n] - v[i];
    const Vec2 e1 = v[(i + 2) % n] - v[(i + 1) % n];
    const double turn = e0.cross(e1);
    if (turn == 0.0) continue;
    const int s = turn > 0.0 ? 1 : -1;
    if (sign == 0)
      sign = s;
    else if (s != sign)
      return false;
  }
  return sign != 0 && !polygon_self_intersects(v);
}

namespace {

// Orientation of c relative to the directed line a->b: +1 left, -1 right, 0 on it.
int orientation(Vec2 a, Vec2 b, Vec2 c) {
  const double o = (b - a).cross(c - a);
  return o > 0.0 ? 1 : (o < 0.0 ? -1 : 0);
}

bool on_segment(Vec2 a, Vec2 b, Vec2 p) {
  return std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= p.y &&
         p.y <= std::max(a.y, b.y);
}

bool segments_intersect(Vec2 p1, Vec2 p2, Vec2 q1, Vec2 q2) {
  const int o1 = orientation(p1, p2, q1), o2 = orientation(p1, p2, q2);
  const int o3 = orientation(q1, q2, p1), o4 = orientation(q1, q2, p2);
  if (o1 != o2 && o3 != o4) return true;
  return (o1 == 0 && on_segment(p1, p2, q1)) || (o2 == 0 && on_segment(p1, p2, q2)) ||
         (o3 == 0 && on_segment(q1, q2, p1)) || (o4 == 0 && on_segment(q1, q2, p2));
}

}  // namespace

bool polygon_self_intersects(std::span<const Vec2> v) {
  const std::size_t n = v.size();
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      // Adjacent edges share a vertex by construction; that is not an intersection.
      if (j == i + 1 || (i == 0 && j == n - 1)) continue;
      if (segments_intersect(v[i], v[(i + 1) % n], v[j], v[(j + 1) % n])) return true;
    }
  }
  return false;
}

Box bounding_box(std::span<const Vec2> points) {
  if (points.empty()) return {};
  Box box{points[0], points[0]};
  for (const Vec2 p : points) {
    box.lo_m = {std::min(box.lo_m.x, p.x), std::min(box.lo_m.y, p.y)};
    box.hi_m = {std::max(box.hi_m.x, p.x), std::max(box.hi_m.y, p.y)};
  }
  return box;
}

Contact disc_segment_contact(Vec2 centre, double radius_m, Vec2 a, Vec2 b) {
  const Vec2 q = closest_point_on_segment(centre, a, b);
  const Vec2 d = centre - q;
  const double dist = std::sqrt(d.dot(d));
  if (dist > 0.0) return {d / dist, dist - radius_m};
  const Vec2 ab = b - a;
  const double len = ab.norm();
  const Vec2 left = len > 0.0 ? Vec2{-ab.y / len, ab.x / len} : Vec2{1.0, 0.0};
  return {left, -radius_m};
}

Contact disc_disc_contact(Vec2 centre_a, double radius_a_m, Vec2 centre_b, double radius_b_m) {
  const Vec2 d = centre_a - centre_b;
  const double dist = std::sqrt(d.dot(d));
  if (dist > 0.0) return {d / dist, dist - radius_a_m - radius_b_m};
  return {{1.0, 0.0}, -radius_a_m - radius_b_m};
}

Contact disc_convex_polygon_contact(Vec2 centre, double radius_m, std::span<const Vec2> poly) {
  const std::size_t n = poly.size();
  const double orient = polygon_signed_area(poly) >= 0.0 ? 1.0 : -1.0;
  // Signed distance of the centre to each edge's line along the edge's outward normal:
  // all non-positive means the centre is inside.
  bool inside = true;
  double best_edge_dist = -kNoHit;
  Vec2 best_edge_normal{1.0, 0.0};
  double best_sq = kNoHit;
  Vec2 best_point = poly.empty() ? centre : poly[0];
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 a = poly[i], b = poly[(i + 1) % n];
    const Vec2 ab = b - a;
    const double len = ab.norm();
    if (len <= 0.0) continue;
    const Vec2 outward = Vec2{ab.y, -ab.x} * (orient / len);
    const double signed_dist = (centre - a).dot(outward);
    if (signed_dist > 0.0) inside = false;
    if (signed_dist > best_edge_dist) {
      best_edge_dist = signed_dist;
      best_edge_normal = outward;
    }
    const Vec2 q = closest_point_on_segment(centre, a, b);
    const double sq = distance_sq(centre, q);
    if (sq < best_sq) {
      best_sq = sq;
      best_point = q;
    }
  }
  if (inside) return {best_edge_normal, best_edge_dist - radius_m};
  const double dist = std::sqrt(best_sq);
  if (dist > 0.0) return {(centre - best_point) / dist, dist - radius_m};
  return {best_edge_normal, -radius_m};
}

Contact convex_polygon_segment_contact(std::span<const Vec2> poly, Vec2 a, Vec2 b) {
  const std::size_t n = poly.size();
  Contact best{{1.0, 0.0}, -kNoHit};
  auto try_axis = [&](Vec2 axis) {
    double pmin = kNoHit, pmax = -kNoHit;
    for (const Vec2 v : poly) {
      const double p = v.dot(axis);
      pmin = std::min(pmin, p);
      pmax = std::max(pmax, p);
    }
    const double sa = a.dot(axis), sb = b.dot(axis);
    const double smin = std::min(sa, sb), smax = std::max(sa, sb);
    // Moving the polygon along +axis by (smax - pmin), or along -axis by (pmax - smin),
    // separates the projections; the smaller move is this axis's answer.
    const double push_plus = smax - pmin, push_minus = pmax - smin;
    const Contact c = push_plus < push_minus ? Contact{axis, -push_plus} : Contact{axis * -1.0, -push_minus};
    if (c.separation_m > best.separation_m) best = c;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 e = poly[(i + 1) % n] - poly[i];
    const double len = e.norm();
    if (len > 0.0) try_axis(Vec2{-e.y / len, e.x / len});
  }
  const Vec2 s = b - a;
  const double slen = s.norm();
  if (slen > 0.0) try_axis(Vec2{-s.y / slen, s.x / slen});
  return best;
}

double wedge_distance_to_segment(const Wedge& w, Vec2 a, Vec2 b) {
  const Vec2 ra = a - w.apex_m;
  const Vec2 ab = b - a;
  // Clip t in [0, 1] to both half-planes: cross(right_edge, p) >= 0 and
  // cross(p, left_edge) >= 0 for p = ra + t ab. Each is linear in t.
  double t_lo = 0.0, t_hi = 1.0;
  auto clip = [&](double g0, double g1) {
    if (g1 == 0.0) {
      if (g0 < 0.0) t_hi = -1.0;
      return;
    }
    const double root = -g0 / g1;
    if (g1 > 0.0)
      t_lo = std::max(t_lo, root);
    else
      t_hi = std::min(t_hi, root);
  };
  clip(w.right_edge.cross(ra), w.right_edge.cross(ab));
  clip(ra.cross(w.left_edge), ab.cross(w.left_edge));
  if (t_lo > t_hi) return kNoHit;
  const double len_sq = ab.dot(ab);
  double t = len_sq > 0.0 ? -ra.dot(ab) / len_sq : t_lo;
  t = std::clamp(t, t_lo, t_hi);
  return (ra + ab * t).norm();
}

double ray_disc_entry(Vec2 origin, Vec2 direction, Vec2 centre, double radius_m) {
  const Vec2 w = centre - origin;
  const double along = w.dot(direction);
  if (along < 0.0) return kNoHit;
  const double perp_sq = w.dot(w) - along * along;
  const double r_sq = radius_m * radius_m;
  if (perp_sq > r_sq) return kNoHit;
  return std::max(0.0, along - std::sqrt(r_sq - perp_sq));
}

double wedge_distance_to_disc(const Wedge& w, Vec2 centre, double radius_m) {
  const Vec2 v = centre - w.apex_m;
  const double dist_sq = v.dot(v);
  if (dist_sq <= radius_m * radius_m) return 0.0;
  // If the direction to the centre is inside the wedge, so is the disc's nearest point.
  // Otherwise the nearest point of disc-and-wedge (a convex set) lies on an edge ray.
  if (wedge_contains_direction(w, v)) return std::sqrt(dist_sq) - radius_m;
  return std::min(ray_disc_entry(w.apex_m, w.left_edge, centre, radius_m),
                  ray_disc_entry(w.apex_m, w.right_edge, centre, radius_m));
}

}  // namespace rilbed::environment

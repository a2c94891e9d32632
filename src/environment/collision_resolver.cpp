#include "environment/collision_resolver.hpp"

#include <algorithm>
#include <cmath>

namespace rilbed::environment {

namespace {

// Unit normal of segment [a, b] pointing to the side `from` is on.
Vec2 normal_towards(Vec2 a, Vec2 b, Vec2 from) {
  const Vec2 ab = b - a;
  const double len = ab.norm();
  Vec2 n{-ab.y / len, ab.x / len};
  if (ab.cross(from - a) < 0.0) n = n * -1.0;
  return n;
}

Box path_box(Vec2 from, Vec2 to, double margin) {
  return {{std::min(from.x, to.x) - margin, std::min(from.y, to.y) - margin},
          {std::max(from.x, to.x) + margin, std::max(from.y, to.y) + margin}};
}

Contact mover_segment_contact(const MovingObstacle& m, Vec2 a, Vec2 b) {
  if (m.shape() == MovingShape::kDisc) return disc_segment_contact(m.position_m(), m.bounding_radius_m(), a, b);
  return convex_polygon_segment_contact(m.world_vertices_m(), a, b);
}

// Contact of a robot's disc with a moving obstacle; the normal points towards the robot.
Contact body_mover_contact(const Body& b, const MovingObstacle& m) {
  if (m.shape() == MovingShape::kDisc)
    return disc_disc_contact(b.position_m, b.radius_m, m.position_m(), m.bounding_radius_m());
  return disc_convex_polygon_contact(b.position_m, b.radius_m, m.world_vertices_m());
}

BodyRef robot_ref(const CollisionScene& s, std::size_t i) { return {BodyKind::kRobot, s.body_ids[i]}; }

// Body b's shape where it is now (its outline placed in `buffer`, or its disc).
BodyShape shape_of(const CollisionScene& s, const Body& b, OutlineBuffer& buffer) {
  const BodyOutline* outline = b.outline >= 0 ? &s.outlines[static_cast<std::size_t>(b.outline)] : nullptr;
  return place_body(b.position_m, b.radius_m, outline, buffer);
}

// Contact of body i with body j, the normal from j towards i (either with an outline).
Contact outlined_contact(const CollisionScene& s, const Body& bi, const Body& bj) {
  OutlineBuffer buffer_i, buffer_j;
  return shape_shape_contact(shape_of(s, bi, buffer_i), shape_of(s, bj, buffer_j));
}

Contact robot_segment_contact(const CollisionScene& s, const Body& b, Vec2 a, Vec2 c) {
  if (b.outline < 0) return disc_segment_contact(b.position_m, b.radius_m, a, c);
  OutlineBuffer buffer;
  return shape_segment_contact(shape_of(s, b, buffer), a, c);
}

Contact robot_mover_contact(const CollisionScene& s, const Body& b, const MovingObstacle& m) {
  if (b.outline < 0) return body_mover_contact(b, m);
  OutlineBuffer buffer;
  return shape_mover_contact(shape_of(s, b, buffer), m);
}

}  // namespace

CollisionResolver::CollisionResolver(CollisionConfig config) : config_(config) {}

void CollisionResolver::begin_step() { contacts_.clear(); }

void CollisionResolver::record(BodyRef a, BodyRef b) { contacts_.push_back({a, b, now_us_}); }

void CollisionResolver::record_robot_pair(const CollisionScene& s, std::size_t i, std::size_t j) {
  if (s.bodies[i].pushable && s.bodies[j].pushable) {
    const int a = s.body_ids[i], b = s.body_ids[j];
    record({BodyKind::kRobot, std::min(a, b)}, {BodyKind::kRobot, std::max(a, b)});
  } else {
    record(robot_ref(s, i), robot_ref(s, j));
  }
}

void CollisionResolver::mark_moved(CollisionScene& s, std::size_t body) {
  // Its cell at once, not after the pass: a later visit in the same pass then finds it
  // where it is, so that what a pass finds depends on the bodies alone, never on where
  // the grid's cell boundaries fall (WorldConfig::cell_size_m).
  s.grid.move(body, s.bodies[body].position_m);
  if (moved_[body]) return;
  moved_[body] = 1;
  moved_list_.push_back(static_cast<int>(body));
  pushed_.push_back(static_cast<int>(body));
}

void CollisionResolver::resolve(CollisionScene& s, TimeUs t_us) {
  now_us_ = t_us;
  const std::size_t n = s.bodies.size();
  is_active_.assign(n, 0);
  moved_.assign(n, 0);
  pushed_.clear();
  active_.clear();
  all_active_ = true;
  s.grid.refresh(n, [&](std::size_t i) { return s.bodies[i].position_m; });
  find_contacts_ahead(s);

  for (int pass = 0; pass < config_.max_passes; ++pass) {
    moved_list_.clear();
    // Statics last, so that a robot pushed by another towards a wall ends the pass
    // outside the wall; the next pass settles what that push-back disturbed.
    bool corrected = movers_vs_statics(s);
    corrected |= robots_vs_robots(s);
    corrected |= robots_vs_movers(s);
    corrected |= robots_vs_statics(s);
    if (!corrected) return;
    // Only the bodies moved in this pass can be in new overlaps with each other, with
    // unmoved bodies or with statics; pairs of unmoved bodies were checked already.
    for (const int i : active_) is_active_[static_cast<std::size_t>(i)] = 0;
    for (const int i : moved_list_) {
      is_active_[static_cast<std::size_t>(i)] = 1;
      moved_[static_cast<std::size_t>(i)] = 0;
    }
    active_.swap(moved_list_);
    all_active_ = false;
  }
  fall_back(s);
}

void CollisionResolver::find_contacts_ahead(const CollisionScene& s) {
  const std::size_t n = s.bodies.size();
  const std::uint8_t visit_all = config_.search_ahead ? 0 : 1;
  near_robot_.assign(n, visit_all);
  near_static_.assign(n, visit_all);
  dirty_.assign(n, 0);
  if (visit_all) return;
  // In slot order, which the World keeps by place: neighbours are still in cache, and
  // each thread writes its own stretch of the flags.
  auto check = [&](std::size_t begin, std::size_t end) {
    constexpr std::size_t kAhead = 8;
    for (std::size_t i = begin; i < end; ++i) {
      if (i + kAhead < end) s.grid.prefetch_around(i + kAhead);
      near_robot_[i] = s.bodies[i].pushable && near_another_robot(s, i) ? 1 : 0;
      near_static_[i] = near_a_static(s, i) ? 1 : 0;
    }
  };
  if (workers_ && workers_->threads() > 1 && n > 1)
    workers_->for_chunks(n, check);
  else
    check(0, n);
}

template <class Visit>
void CollisionResolver::for_each_by_id(const CollisionScene& s, Visit&& visit) const {
  if (s.id_order.size() == s.bodies.size()) {
    for (const std::uint32_t i : s.id_order) visit(static_cast<std::size_t>(i));
  } else {
    for (std::size_t i = 0; i < s.bodies.size(); ++i) visit(i);
  }
}

// The robots whose centre is in `box`, by ascending id (valid until the next call). Not
// every robot of the box's cells: the list must not depend on the cell size, since a
// visit moves the robot it visits between the list's entries.
std::span<const std::uint32_t> CollisionResolver::robots_in_box_by_id(const CollisionScene& s, const Box& box) {
  in_box_.clear();
  s.grid.for_each_in_box(box, [&](int j) {
    if (contains(box, s.bodies[static_cast<std::size_t>(j)].position_m))
      in_box_.push_back(static_cast<std::uint32_t>(j));
  });
  if (in_box_.size() > 1)
    std::sort(in_box_.begin(), in_box_.end(),
              [&](std::uint32_t a, std::uint32_t b) { return s.body_ids[a] < s.body_ids[b]; });
  return in_box_;
}

// Whether the first pass's visit of robot i would find another robot within contact
// (the same test as robots_vs_robots, before any push).
bool CollisionResolver::near_another_robot(const CollisionScene& s, std::size_t i) const {
  const Body& bi = s.bodies[i];
  const double margin = config_.contact_margin_m;
  bool near = false;
  s.grid.for_each_in_box(box_around(bi.position_m, bi.radius_m + s.max_body_radius_m + margin), [&](int jj) {
    const auto j = static_cast<std::size_t>(jj);
    if (j == i || near) return;
    const Body& bj = s.bodies[j];
    const double sum = bi.radius_m + bj.radius_m + margin;
    if (distance_sq(bi.position_m, bj.position_m) >= sum * sum) return;
    near = (bi.outline < 0 && bj.outline < 0) || outlined_contact(s, bi, bj).separation_m < margin;
  });
  return near;
}

// Whether robots_vs_statics's visit of robot i, unmoved since, would do anything.
bool CollisionResolver::near_a_static(const CollisionScene& s, std::size_t i) const {
  const Body& b = s.bodies[i];
  const double margin = config_.contact_margin_m;
  bool near = false;
  const Box box = path_box(b.pushable ? b.previous_m : b.position_m, b.position_m, b.radius_m + margin);
  s.statics.for_each_in_box(box, [&](const IndexedSegment& seg) {
    if (near) return;
    if (b.pushable && path_crosses_segment(b.previous_m, b.position_m, seg.a_m, seg.b_m))
      near = true;
    else if (robot_segment_contact(s, b, seg.a_m, seg.b_m).separation_m < margin)
      near = true;
  });
  return near;
}

// After a push in the first pass: the robots near the pushed one's new place must be
// visited even if nothing was near them at the start (their grid cells are current;
// the pushed robot's is not, but it is visited anyway).
void CollisionResolver::mark_near_dirty(const CollisionScene& s, std::size_t moved) {
  const Body& b = s.bodies[moved];
  dirty_[moved] = 1;
  const Box box = box_around(b.position_m, b.radius_m + s.max_body_radius_m + config_.contact_margin_m);
  s.grid.for_each_in_box(box, [&](int j) {
    if (contains(box, s.bodies[static_cast<std::size_t>(j)].position_m)) dirty_[static_cast<std::size_t>(j)] = 1;
  });
}

bool CollisionResolver::robots_vs_robots(CollisionScene& s) {
  bool corrected = false;
  const double margin = config_.contact_margin_m, tol = config_.tolerance_m;
  auto visit = [&](std::size_t i) {
    Body& bi = s.bodies[i];
    if (!bi.pushable) return;  // real robots start nothing; their virtual partners do
    const double reach = bi.radius_m + s.max_body_radius_m + margin;
    for (const std::uint32_t jj : robots_in_box_by_id(s, box_around(bi.position_m, reach))) {
      const auto j = static_cast<std::size_t>(jj);
      if (j == i) continue;
      Body& bj = s.bodies[j];
      // A pair of virtual robots both active in this pass is handled by the lower id,
      // visited first (in the first pass the lower one may have been skipped, which means
      // it touched nothing then: the pair was apart).
      if (bj.pushable && s.body_ids[j] < s.body_ids[i] && (all_active_ || is_active_[j])) continue;
      const Vec2 d = bi.position_m - bj.position_m;
      const double dist_sq = d.dot(d);
      const double sum = bi.radius_m + bj.radius_m;
      if (dist_sq >= (sum + margin) * (sum + margin)) continue;
      Vec2 normal{1.0, 0.0};  // from j towards i
      double overlap = 0.0;
      if (bi.outline < 0 && bj.outline < 0) {
        record_robot_pair(s, i, j);
        if (dist_sq >= (sum - tol) * (sum - tol)) continue;
        const double dist = std::sqrt(dist_sq);
        if (dist > 1e-12) {
          normal = d / dist;
        } else {
          // Coincident centres: separate along where they came from.
          const Vec2 back = bi.previous_m - bj.previous_m;
          const double len = back.norm();
          if (len > 0.0) normal = back / len;
        }
        overlap = sum - dist;
      } else {
        // Within the bounding discs: the outlines decide.
        const Contact c = outlined_contact(s, bi, bj);
        if (c.separation_m >= margin) continue;
        record_robot_pair(s, i, j);
        if (c.separation_m >= -tol) continue;
        normal = c.normal;
        overlap = -c.separation_m;
      }
      if (bj.pushable) {
        bi.position_m = bi.position_m + normal * (0.5 * overlap);
        bj.position_m = bj.position_m - normal * (0.5 * overlap);
        mark_moved(s, j);
        if (all_active_) mark_near_dirty(s, j);
      } else {
        bi.position_m = bi.position_m + normal * overlap;
      }
      mark_moved(s, i);
      if (all_active_) mark_near_dirty(s, i);
      corrected = true;
    }
  };
  if (all_active_) {
    // Only those that something is near: a visit of any other finds nothing to do.
    for_each_by_id(s, [&](std::size_t i) {
      if (near_robot_[i] || dirty_[i]) visit(i);
    });
  } else {
    for (const int i : active_) visit(static_cast<std::size_t>(i));
  }
  return corrected;
}

bool CollisionResolver::robots_vs_movers(CollisionScene& s) {
  bool corrected = false;
  const double margin = config_.contact_margin_m, tol = config_.tolerance_m;
  for (std::size_t m = 0; m < s.movers.size(); ++m) {
    MovingObstacle& mover = s.movers[m];
    const double reach = mover.bounding_radius_m() + s.max_body_radius_m + margin;
    for (const std::uint32_t jj : robots_in_box_by_id(s, box_around(mover.position_m(), reach))) {
      const auto j = static_cast<std::size_t>(jj);
      Body& b = s.bodies[j];
      const Contact c = robot_mover_contact(s, b, mover);
      if (c.separation_m >= margin) continue;
      record(robot_ref(s, j), {BodyKind::kMovingObstacle, static_cast<int>(m)});
      if (c.separation_m >= -tol) continue;
      const double depth = -c.separation_m;
      if (b.pushable) {
        b.position_m = b.position_m + c.normal * depth;
        mark_moved(s, j);
      } else {
        mover.translate(c.normal * -depth);
        mover.reflect_off(c.normal * -1.0);
      }
      corrected = true;
    }
  }
  return corrected;
}

bool CollisionResolver::robots_vs_statics(CollisionScene& s) {
  bool corrected = false;
  const double margin = config_.contact_margin_m, tol = config_.tolerance_m;
  auto visit = [&](std::size_t i) {
    Body& b = s.bodies[i];
    const Box box = path_box(b.pushable ? b.previous_m : b.position_m, b.position_m, b.radius_m + margin);
    // Each segment once, by index: a push off one changes what the next one sees.
    s.statics.segments_in_box(box, in_segments_);
    for (const std::uint32_t k : in_segments_) {
      const IndexedSegment& seg = s.statics.segments()[k];
      if (b.pushable && path_crosses_segment(b.previous_m, b.position_m, seg.a_m, seg.b_m)) {
        // The centre went through the segment (a fast robot, or a push): put it back on
        // the side it came from, touching.
        const Vec2 n = normal_towards(seg.a_m, seg.b_m, b.previous_m);
        const double signed_dist = (b.position_m - seg.a_m).dot(n);
        double reach_m = b.radius_m;
        if (b.outline >= 0) {
          OutlineBuffer buffer;
          reach_m = shape_reach_against(shape_of(s, b, buffer), n);
        }
        b.position_m = b.position_m + n * (reach_m - signed_dist);
        record(robot_ref(s, i), seg.owner);
        mark_moved(s, i);
        corrected = true;
        continue;
      }
      const Contact c = robot_segment_contact(s, b, seg.a_m, seg.b_m);
      if (c.separation_m >= margin) continue;
      record(robot_ref(s, i), seg.owner);
      if (!b.pushable || c.separation_m >= -tol) continue;
      b.position_m = b.position_m + c.normal * -c.separation_m;
      mark_moved(s, i);
      corrected = true;
    }
  };
  if (all_active_) {
    // Only those near a static at the start, or moved since (by a push or a mover).
    for_each_by_id(s, [&](std::size_t i) {
      if (near_static_[i] || moved_[i]) visit(i);
    });
  } else {
    for (const int i : active_) visit(static_cast<std::size_t>(i));
  }
  return corrected;
}

bool CollisionResolver::movers_vs_statics(CollisionScene& s) {
  bool corrected = false;
  const double margin = config_.contact_margin_m, tol = config_.tolerance_m;
  for (std::size_t m = 0; m < s.movers.size(); ++m) {
    MovingObstacle& mover = s.movers[m];
    const BodyRef self{BodyKind::kMovingObstacle, static_cast<int>(m)};
    const Box box = path_box(mover.previous_m(), mover.position_m(), mover.bounding_radius_m() + margin);
    s.statics.segments_in_box(box, in_segments_);  // each once, by index (see robots_vs_statics)
    for (const std::uint32_t k : in_segments_) {
      const IndexedSegment& seg = s.statics.segments()[k];
      if (path_crosses_segment(mover.previous_m(), mover.position_m(), seg.a_m, seg.b_m)) {
        // Went through: mirror the reference point back across the segment's line.
        const Vec2 n = normal_towards(seg.a_m, seg.b_m, mover.previous_m());
        const double signed_dist = (mover.position_m() - seg.a_m).dot(n);
        mover.translate(n * (-2.0 * signed_dist));
        mover.reflect_off(n);
        record(self, seg.owner);
        corrected = true;
        continue;
      }
      const Contact c = mover_segment_contact(mover, seg.a_m, seg.b_m);
      if (c.separation_m >= margin) continue;
      record(self, seg.owner);
      if (c.separation_m >= -tol) continue;
      const double depth = -c.separation_m;
      // An elastic bounce: the overshoot into the wall is mirrored out of it.
      const bool bounced = mover.reflect_off(c.normal);
      mover.translate(c.normal * (bounced ? 2.0 * depth : depth));
      corrected = true;
    }
  }
  return corrected;
}

bool CollisionResolver::body_overlaps(const CollisionScene& s, std::size_t i) const {
  const Body& b = s.bodies[i];
  const double tol = config_.tolerance_m;
  bool overlaps = false;
  s.grid.for_each_in_box(box_around(b.position_m, b.radius_m + s.max_body_radius_m), [&](int jj) {
    const auto j = static_cast<std::size_t>(jj);
    if (j == i || overlaps) return;
    const Body& bj = s.bodies[j];
    const double sum = b.radius_m + bj.radius_m - tol;
    if (distance_sq(b.position_m, bj.position_m) >= sum * sum) return;
    overlaps = (b.outline < 0 && bj.outline < 0) || outlined_contact(s, b, bj).separation_m < -tol;
  });
  for (const MovingObstacle& m : s.movers)
    if (!overlaps && robot_mover_contact(s, b, m).separation_m < -tol) overlaps = true;
  s.statics.for_each_in_box(box_around(b.position_m, b.radius_m), [&](const IndexedSegment& seg) {
    if (!overlaps && robot_segment_contact(s, b, seg.a_m, seg.b_m).separation_m < -tol) overlaps = true;
  });
  return overlaps;
}

bool CollisionResolver::mover_overlaps(const CollisionScene& s, std::size_t m) const {
  const MovingObstacle& mover = s.movers[m];
  const double tol = config_.tolerance_m;
  bool overlaps = false;
  s.grid.for_each_in_box(box_around(mover.position_m(), mover.bounding_radius_m() + s.max_body_radius_m), [&](int j) {
    if (!overlaps && robot_mover_contact(s, s.bodies[static_cast<std::size_t>(j)], mover).separation_m < -tol)
      overlaps = true;
  });
  s.statics.for_each_in_box(box_around(mover.position_m(), mover.bounding_radius_m()), [&](const IndexedSegment& seg) {
    if (!overlaps && mover_segment_contact(mover, seg.a_m, seg.b_m).separation_m < -tol) overlaps = true;
  });
  return overlaps;
}

void CollisionResolver::fall_back(CollisionScene& s) {
  // Everything was free at the start of the substep, so putting overlapping bodies back
  // there converges. Only bodies moved in the last pass can still overlap (pairs of
  // unmoved bodies were checked in earlier passes), so the search starts from them and
  // spreads to the neighbours of each body put back, which it may now overlap.
  const std::size_t n = s.bodies.size();
  reverted_.assign(n + s.movers.size(), 0);
  std::vector<int>& queue = moved_list_;  // free at this point; reused to avoid allocating
  queue.assign(active_.begin(), active_.end());
  auto enqueue_neighbours = [&](Vec2 p, double reach) {
    for (const std::uint32_t j : robots_in_box_by_id(s, box_around(p, reach + s.max_body_radius_m)))
      if (!reverted_[j]) queue.push_back(static_cast<int>(j));
  };
  for (;;) {
    while (!queue.empty()) {
      const auto i = static_cast<std::size_t>(queue.back());
      queue.pop_back();
      Body& b = s.bodies[i];
      if (!b.pushable || reverted_[i] || !body_overlaps(s, i)) continue;
      b.position_m = b.previous_m;
      if (b.outline >= 0) s.outlines[static_cast<std::size_t>(b.outline)].turn_back();
      s.grid.move(i, b.position_m);
      pushed_.push_back(static_cast<int>(i));
      reverted_[i] = 1;
      enqueue_neighbours(b.position_m, b.radius_m);
    }
    bool mover_reverted = false;
    for (std::size_t m = 0; m < s.movers.size(); ++m) {
      if (reverted_[n + m] || !mover_overlaps(s, m)) continue;
      MovingObstacle& mover = s.movers[m];
      mover.revert();
      mover.set_velocity(mover.velocity_mps() * -1.0);  // blocked: it bounces back the way it came
      reverted_[n + m] = 1;
      mover_reverted = true;
      enqueue_neighbours(mover.position_m(), mover.bounding_radius_m());
    }
    if (!mover_reverted && queue.empty()) break;
  }
  queue.clear();
}

std::span<const CollisionEvent> CollisionResolver::end_step() {
  std::sort(contacts_.begin(), contacts_.end(), [](const ContactRecord& a, const ContactRecord& b) {
    if (a.first != b.first) return a.first < b.first;
    if (a.second != b.second) return a.second < b.second;
    return a.t_us < b.t_us;
  });
  current_pairs_.clear();
  events_.clear();
  for (std::size_t k = 0; k < contacts_.size(); ++k) {
    const ContactRecord& c = contacts_[k];
    if (k > 0 && contacts_[k - 1].first == c.first && contacts_[k - 1].second == c.second) continue;
    const Pair pair{c.first, c.second};
    current_pairs_.push_back(pair);
    if (!std::binary_search(previous_pairs_.begin(), previous_pairs_.end(), pair))
      events_.push_back({c.t_us, c.first, c.second});
  }
  previous_pairs_.swap(current_pairs_);
  std::sort(events_.begin(), events_.end(), [](const CollisionEvent& a, const CollisionEvent& b) {
    if (a.t_us != b.t_us) return a.t_us < b.t_us;
    if (a.first != b.first) return a.first < b.first;
    return a.second < b.second;
  });
  return events_;
}

}  // namespace rilbed::environment

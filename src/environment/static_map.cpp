#include "environment/static_map.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

namespace rilbed::environment {

namespace {

std::string label(const char* what, std::size_t index, const std::string& name) {
  std::string s = std::string(what) + " " + std::to_string(index);
  if (!name.empty()) s += " (" + name + ")";
  return s;
}

bool finite(Vec2 v) { return std::isfinite(v.x) && std::isfinite(v.y); }

[[noreturn]] void fail(const std::string& what, const std::string& why) {
  throw std::invalid_argument(what + ": " + why);
}

void check_points_finite(const std::string& what, const std::vector<Vec2>& points, const char* noun) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!finite(points[i])) fail(what, std::string(noun) + " " + std::to_string(i) + " is not finite");
  }
}

}  // namespace

StaticMap::StaticMap(StaticMapConfig config) : config_(std::move(config)) {
  const FieldConfig& f = config_.field;
  if (!std::isfinite(f.width_m) || f.width_m <= 0.0) fail("field", "width_m must be a positive number");
  if (!std::isfinite(f.height_m) || f.height_m <= 0.0) fail("field", "height_m must be a positive number");

  for (std::size_t i = 0; i < config_.obstacles.size(); ++i) {
    ObstacleConfig& o = config_.obstacles[i];
    const std::string what = label("obstacle", i, o.name);
    check_points_finite(what, o.vertices_m, "vertex");
    if (o.vertices_m.size() >= 2 && o.vertices_m.front() == o.vertices_m.back()) o.vertices_m.pop_back();
    if (o.vertices_m.size() < 3) fail(what, "needs at least three distinct vertices");
    if (std::abs(polygon_signed_area(o.vertices_m)) <= 1e-12) fail(what, "has zero area");
    if (polygon_self_intersects(o.vertices_m)) fail(what, "has crossing edges");
    obstacle_boxes_.push_back(bounding_box(o.vertices_m));
  }

  for (std::size_t i = 0; i < config_.tracks.size(); ++i) {
    const TrackConfig& t = config_.tracks[i];
    const std::string what = label("track", i, t.name);
    check_points_finite(what, t.points_m, "point");
    if (t.points_m.size() < 2) fail(what, "needs at least two points");
    if (!std::isfinite(t.width_m) || t.width_m <= 0.0) fail(what, "width_m must be a positive number");
  }

  std::set<int> beacon_ids;
  for (std::size_t i = 0; i < config_.beacons.size(); ++i) {
    const BeaconConfig& b = config_.beacons[i];
    const std::string what = "beacon " + std::to_string(i) + " (id " + std::to_string(b.id) + ")";
    if (!finite(b.position_m)) fail(what, "position is not finite");
    if (!std::isfinite(b.facing_rad)) fail(what, "facing_rad is not finite");
    if (!(b.aperture_rad > 0.0 && b.aperture_rad <= 2.0 * kPi + 1e-12)) fail(what, "aperture_rad must be in (0, 2 pi]");
    if (!std::isfinite(b.range_m) || b.range_m <= 0.0) fail(what, "range_m must be a positive number");
    if (!beacon_ids.insert(b.id).second) fail(what, "another beacon has the same id");
  }
}

std::array<std::array<Vec2, 2>, 4> StaticMap::wall_segments() const {
  const double w = config_.field.width_m, h = config_.field.height_m;
  return {{{Vec2{0, 0}, Vec2{w, 0}}, {Vec2{w, 0}, Vec2{w, h}}, {Vec2{w, h}, Vec2{0, h}}, {Vec2{0, h}, Vec2{0, 0}}}};
}

int StaticMap::obstacle_containing(Vec2 p) const {
  for (std::size_t i = 0; i < config_.obstacles.size(); ++i) {
    const Box& b = obstacle_boxes_[i];
    if (p.x < b.lo_m.x || p.x > b.hi_m.x || p.y < b.lo_m.y || p.y > b.hi_m.y) continue;
    if (point_in_polygon(p, config_.obstacles[i].vertices_m)) return static_cast<int>(i);
  }
  return -1;
}

Box StaticMap::extent() const {
  Box box{{0.0, 0.0}, {config_.field.width_m, config_.field.height_m}};
  auto grow = [&](Vec2 p, double margin) {
    box.lo_m = {std::min(box.lo_m.x, p.x - margin), std::min(box.lo_m.y, p.y - margin)};
    box.hi_m = {std::max(box.hi_m.x, p.x + margin), std::max(box.hi_m.y, p.y + margin)};
  };
  for (const ObstacleConfig& o : config_.obstacles)
    for (const Vec2 v : o.vertices_m) grow(v, 0.0);
  for (const TrackConfig& t : config_.tracks)
    for (const Vec2 p : t.points_m) grow(p, 0.5 * t.width_m);
  for (const BeaconConfig& b : config_.beacons) grow(b.position_m, 0.0);
  return box;
}

}  // namespace rilbed::environment

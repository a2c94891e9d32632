#include "environment/moving_obstacle.hpp"

#include <cmath>
#include <stdexcept>

namespace rilbed::environment {

namespace {
bool finite(Vec2 v) { return std::isfinite(v.x) && std::isfinite(v.y); }
}  // namespace

MovingObstacle::MovingObstacle(MovingObstacleConfig config, const std::string& what) : config_(std::move(config)) {
  const std::string label = config_.name.empty() ? what : what + " (" + config_.name + ")";
  auto fail = [&](const std::string& why) { throw std::invalid_argument(label + ": " + why); };
  if (!finite(config_.position_m)) fail("position is not finite");
  if (!finite(config_.velocity_mps)) fail("velocity is not finite");
  if (config_.shape == MovingShape::kDisc) {
    if (!std::isfinite(config_.radius_m) || config_.radius_m <= 0.0) fail("radius_m must be a positive number");
    bounding_radius_m_ = config_.radius_m;
  } else {
    std::vector<Vec2>& v = config_.vertices_m;
    for (std::size_t i = 0; i < v.size(); ++i)
      if (!finite(v[i])) fail("vertex " + std::to_string(i) + " is not finite");
    if (v.size() >= 2 && v.front() == v.back()) v.pop_back();
    if (v.size() < 3) fail("needs at least three distinct vertices");
    if (std::abs(polygon_signed_area(v)) <= 1e-12) fail("has zero area");
    if (!polygon_is_convex(v)) fail("must be convex");
    if (!point_in_polygon({0.0, 0.0}, v)) fail("its reference point (0, 0 of vertices_m) must lie inside it");
    for (const Vec2 p : v) bounding_radius_m_ = std::max(bounding_radius_m_, p.norm());
  }
  position_m_ = previous_m_ = config_.position_m;
  velocity_mps_ = config_.velocity_mps;
  if (config_.shape == MovingShape::kPolygon) {
    for (const Vec2 p : config_.vertices_m) world_vertices_m_.push_back(position_m_ + p);
  }
}

void MovingObstacle::translate(Vec2 delta_m) {
  position_m_ = position_m_ + delta_m;
  for (Vec2& v : world_vertices_m_) v = v + delta_m;
}

bool MovingObstacle::reflect_off(Vec2 n) {
  const double vn = velocity_mps_.dot(n);
  if (vn >= 0.0) return false;
  velocity_mps_ = velocity_mps_ - n * (2.0 * vn);
  return true;
}

}  // namespace rilbed::environment

// Moving obstacles (paper 000 §6.9): simple bodies that drift at constant velocity and
// bounce elastically off the boundary walls and static obstacles. They push virtual
// robots out of their way; they bounce off real robots (which nothing virtual can move)
// and off a virtual robot that is pinned and cannot give way. Two moving obstacles pass
// through each other.
#pragma once

#include <string>
#include <vector>

#include "core/geometry.hpp"
#include "environment/shapes.hpp"

namespace rilbed::environment {

/// Shape of a moving obstacle.
enum class MovingShape { kDisc, kPolygon };

/// A moving obstacle as configured.
struct MovingObstacleConfig {
  MovingShape shape = MovingShape::kDisc;  ///< which of the two below applies
  double radius_m = 0.05;                  ///< Disc: its radius
  /// Polygon: convex, either orientation, relative to position_m, which must lie inside
  /// it (its centre, say). The polygon translates; it does not rotate.
  std::vector<Vec2> vertices_m;
  Vec2 position_m;    ///< the disc's centre / the polygon's reference point
  Vec2 velocity_mps;  ///< constant between bounces
  std::string name;   ///< optional, for error messages
};

/// The live state of one moving obstacle.
class MovingObstacle {
 public:
  /// Validates `config` (finite numbers, positive radius, convex polygon of at least
  /// three vertices around its reference point); throws std::invalid_argument naming
  /// `what` (e.g. "moving obstacle 2").
  MovingObstacle(MovingObstacleConfig config, const std::string& what);

  /// Disc or polygon.
  MovingShape shape() const { return config_.shape; }
  /// Disc radius, or the distance from the reference point to the farthest vertex.
  double bounding_radius_m() const { return bounding_radius_m_; }
  /// Current reference point (the disc's centre), field frame.
  Vec2 position_m() const { return position_m_; }
  /// Current velocity (changes only when it bounces).
  Vec2 velocity_mps() const { return velocity_mps_; }
  /// Where it was at the start of the current substep (a place known to be free).
  Vec2 previous_m() const { return previous_m_; }
  /// Polygon: the vertices in the field frame at the current position; empty for a disc.
  const std::vector<Vec2>& world_vertices_m() const { return world_vertices_m_; }
  /// The configuration it was made from (initial position and velocity).
  const MovingObstacleConfig& config() const { return config_; }

  /// Moves by `delta_m` (vertices follow).
  void translate(Vec2 delta_m);
  /// Puts it back where the substep started.
  void revert() { translate(previous_m_ - position_m_); }
  /// Records the current position as the start of a substep.
  void begin_substep() { previous_m_ = position_m_; }
  /// Replaces the velocity.
  void set_velocity(Vec2 velocity_mps) { velocity_mps_ = velocity_mps; }
  /// Reflects the velocity off a surface with unit normal n if it is heading into it.
  /// Returns whether it was.
  bool reflect_off(Vec2 n);

 private:
  MovingObstacleConfig config_;
  Vec2 position_m_;
  Vec2 previous_m_;
  Vec2 velocity_mps_;
  double bounding_radius_m_ = 0.0;
  std::vector<Vec2> world_vertices_m_;
};

}  // namespace rilbed::environment

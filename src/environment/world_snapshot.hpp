// A copy of the world's moving state at one instant, for displays and recorders (paper
// 000 §6.4). The static map is sent once, separately (World::map()).
#pragma once

#include <vector>

#include "core/time.hpp"
#include "environment/collision_event.hpp"
#include "environment/moving_obstacle.hpp"
#include "environment/robot_state.hpp"

namespace rilbed::environment {

/// One robot as displays need it.
struct RobotSnapshot {
  int id = 0;                            ///< robot id
  RobotKind kind = RobotKind::kVirtual;  ///< virtual or real
  Pose2 pose;                            ///< field frame
  double radius_m = 0.0;                 ///< body disc (with an outline: its bounding radius)
  int left_speed_units = 0;              ///< commanded
  int right_speed_units = 0;
  std::vector<Vec2> outline_m;  ///< convex outline, robot frame, counter-clockwise; empty: the disc
};

/// One moving obstacle as displays need it.
struct MovingObstacleSnapshot {
  MovingShape shape = MovingShape::kDisc;  ///< disc or polygon
  Vec2 position_m;                         ///< reference point (disc centre)
  Vec2 velocity_mps;                       ///< current
  double radius_m = 0.0;                   ///< disc radius (bounding radius for a polygon)
  std::vector<Vec2> vertices_m;            ///< polygon outline in the field frame; empty for a disc
};

/// The world at time t_us. A value: owns all its data.
struct WorldSnapshot {
  TimeUs t_us = 0;                                       ///< world time of the copy
  std::vector<RobotSnapshot> robots;                     ///< in the world's robot order
  std::vector<MovingObstacleSnapshot> moving_obstacles;  ///< by index
  std::vector<CollisionEvent> collisions;                ///< events of the step that ended at t_us
};

}  // namespace rilbed::environment

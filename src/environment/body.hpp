// The hot part of a robot's state, kept in one contiguous array for the collision and
// sensing loops (the full RobotState, with its configuration, lives elsewhere).
#pragma once

#include <cstdint>

#include "core/geometry.hpp"

namespace rilbed::environment {

/// A robot as the collision resolver and the sensors see it: a disc, or a convex outline
/// (see body_shape.hpp) inside the disc, which the broad phase and the sensors use.
struct Body {
  Vec2 position_m;        ///< centre, field frame
  Vec2 previous_m;        ///< centre at the start of the current substep (a free place)
  double radius_m = 0.0;  ///< the disc; with an outline, its bounding radius
  bool pushable = true;   ///< virtual robots are moved by collisions; real robots never
  /// Index of its outline in the scene's outlines (CollisionScene::outlines); -1: the
  /// disc. (In the padding after `pushable`: a body stays 48 bytes.)
  std::int32_t outline = -1;
};
static_assert(sizeof(Body) == 48, "the outline index fits the padding");

}  // namespace rilbed::environment

// The hot part of a robot's state, kept in one contiguous array for the collision and
// sensing loops (the full RobotState, with its configuration, lives elsewhere).
#pragma once

#include "core/geometry.hpp"

namespace rilbed::environment {

/// A robot as the collision resolver and the sensors see it: a disc.
struct Body {
  Vec2 position_m;  ///< centre, field frame
  Vec2 previous_m;  ///< centre at the start of the current substep (a free place)
  double radius_m = 0.0;
  bool pushable = true;  ///< virtual robots are moved by collisions; real robots never
};

}  // namespace rilbed::environment

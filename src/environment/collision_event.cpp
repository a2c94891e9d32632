#include "environment/collision_event.hpp"

namespace rilbed::environment {

std::string to_string(BodyRef body) {
  switch (body.kind) {
    case BodyKind::kRobot: return "robot " + std::to_string(body.id);
    case BodyKind::kWall: {
      static const char* const kSides[] = {"bottom", "right", "top", "left"};
      const char* side = body.id >= 0 && body.id < 4 ? kSides[body.id] : "?";
      return "wall " + std::to_string(body.id) + " (" + side + ")";
    }
    case BodyKind::kObstacle: return "obstacle " + std::to_string(body.id);
    case BodyKind::kMovingObstacle: return "moving obstacle " + std::to_string(body.id);
  }
  return "?";
}

}  // namespace rilbed::environment

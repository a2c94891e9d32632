// Who touched whom, and when: the vocabulary of the world's collision reports.
#pragma once

#include <compare>
#include <cstdint>
#include <string>

#include "core/time.hpp"

namespace rilbed::environment {

/// The kinds of things that can touch in the world.
enum class BodyKind : std::uint8_t {
  kRobot,           ///< a robot, named by its robot id
  kWall,            ///< a boundary wall of the field: 0 bottom (y = 0), 1 right, 2 top, 3 left
  kObstacle,        ///< a static obstacle, named by its index in the map's obstacle list
  kMovingObstacle,  ///< a moving obstacle, named by the index add_moving_obstacle returned
};

/// One party of a contact: a kind and the id (robot) or index (the others) within it.
struct BodyRef {
  BodyKind kind = BodyKind::kRobot;                  ///< what it is
  int id = 0;                                        ///< robot id, wall side, or obstacle index
  auto operator<=>(const BodyRef&) const = default;  ///< by kind, then id (for sorting)
};

/// Text for messages and logs: "robot 3", "wall 1 (right)", "obstacle 0",
/// "moving obstacle 2".
std::string to_string(BodyRef body);

/// A contact that began during a step. The world reports each touching pair once per
/// contact episode: the pair is reported in the step where it starts touching (their
/// surfaces come within WorldConfig::contact_margin_m of each other, or overlap) and not
/// again until it has been apart for at least one whole step.
struct CollisionEvent {
  TimeUs t_us = 0;  ///< end of the substep in which the contact was first found
  /// The moving party: the robot (for robot–robot contacts, the lower id) or the moving
  /// obstacle (for its bounces off walls and obstacles).
  BodyRef first;
  BodyRef second;  ///< the other party
  bool operator==(const CollisionEvent&) const = default;
};

}  // namespace rilbed::environment

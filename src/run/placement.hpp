// Putting the real robots at a run's start poses before the run, so that a run with real
// robots starts where its all-virtual twin starts (the sim-to-real comparison of paper
// 001, seed by seed). An emulated robot is put there as a hand would (unless its link says
// `placement: drive`); a physical robot is driven there slowly under the camera, avoiding
// the other real robots (a run of its own: the GoToPoseController on the robots' real
// bodies, with all their safety), and where that fails within the time allowed the
// operator is asked to place it by hand.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/geometry.hpp"
#include "run/real_robots.hpp"
#include "run/scenario.hpp"
#include "serial/khepera_link.hpp"

namespace rilbed::run {

/// How to place.
struct PlacementOptions {
  /// Time the robots get to drive to their poses, seconds (wall clock).
  double timeout_s = 90.0;
  /// Top speed while driving there, m/s.
  double speed_mps = 0.04;
  /// Close enough, metres and degrees (the camera sees a tenth of a millimetre; one speed
  /// unit for one control step moves a Khepera 0.8 mm).
  double tolerance_m = 0.005;
  double tolerance_deg = 3.0;
  /// Asked, with a message naming each robot and where it must go, when driving did not
  /// get every robot there; returns once the operator has placed them (true) or gave up
  /// (false). Empty: nobody to ask, so the placement fails.
  std::function<bool(const std::string& message)> ask_operator;
  /// Set (from a signal handler) to give up at once; only read.
  const std::atomic<bool>* interrupt = nullptr;
  /// Where progress messages go; may be empty.
  serial::LogCallback log;
};

/// What placing came to.
struct PlacementResult {
  bool ok = false;
  std::string error;                    ///< why not, naming the robots
  std::map<int, double> offset_m;       ///< each robot driven there: its distance from its pose at the end
  std::vector<int> placed_by_operator;  ///< robots the operator placed by hand
  double wall_s = 0.0;
};

/// Places every real robot of `robots.scenario()` at its pose in `targets` (by robot ID;
/// robots without one are left where they are). Connects robots not connected yet (an
/// emulated one starts at its target). Returns when all are placed, the operator gave
/// up, or the interrupt was set.
PlacementResult place_real_robots(RealRobots& robots, const std::map<int, Pose2>& targets,
                                  const PlacementOptions& options);

}  // namespace rilbed::run

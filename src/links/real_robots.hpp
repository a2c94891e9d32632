// The real robots of one run: a serial link per robot, and for `link: {emulate: true}`
// an emulated Khepera on a pseudo-terminal that the link reaches through the same serial
// code. Supplies the run with real bodies and the emulated camera with the emulated
// robots' true poses.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "agents/scenario.hpp"
#include "agents/simulation.hpp"
#include "links/khepera_emulator.hpp"
#include "links/khepera_link.hpp"
#include "links/real_body.hpp"

namespace rilbed::links {

/// Owns the emulators of a run (they must outlive the bodies, which the run owns).
/// Construct before run_scenario(), keep until it returns.
class RealRobots {
 public:
  /// `log` receives every link's and emulator's messages (may be empty).
  RealRobots(const agents::Scenario& scenario, LogCallback log);
  ~RealRobots();
  RealRobots(const RealRobots&) = delete;
  RealRobots& operator=(const RealRobots&) = delete;

  /// Makes a robot's body: starts its emulator if it is emulated (at the world's initial
  /// pose for it), opens its link and waits up to 2 s for the robot to answer. Throws
  /// agents::ScenarioError naming the robot and port when the port cannot be opened.
  agents::RealBodyFactory body_factory();
  /// The emulated robots' markers at their true poses now (for the emulated camera).
  std::vector<vision::SceneMarker> emulated_markers() const;
  /// The emulators, by robot ID (for tests and reports: their last commanded speeds).
  std::map<int, const KheperaEmulator*> emulators() const;

 private:
  const agents::Scenario& scenario_;
  LogCallback log_;
  mutable std::mutex mutex_;
  std::map<int, std::unique_ptr<KheperaEmulator>> emulators_;
};

}  // namespace rilbed::links

// The real robots of a run, or of a batch of runs: a serial link per robot, and for
// `link: {emulate: true}` an emulated Khepera on a pseudo-terminal that the link reaches
// through the same serial code. The links stay open from one run of a batch to the next
// (each run's bodies share them); the robots are stopped at the end of every run and
// again when this object goes. Supplies the runs with real bodies and the emulated camera
// with the emulated robots' true poses.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "run/real_body.hpp"
#include "run/scenario.hpp"
#include "run/simulation.hpp"
#include "serial/khepera_emulator.hpp"
#include "serial/khepera_link.hpp"

namespace rilbed::run {

/// Owns the links and emulators of one or more runs (they must outlive the bodies, which
/// each run owns). Construct before the first run_scenario(), keep until the last returns.
class RealRobots {
 public:
  /// `scenario` must outlive this object. `log` receives every link's and emulator's
  /// messages (may be empty).
  RealRobots(const run::Scenario& scenario, serial::LogCallback log);
  /// Stops every robot (acknowledged if its line allows) and closes the links, then the
  /// emulators.
  ~RealRobots();
  RealRobots(const RealRobots&) = delete;
  RealRobots& operator=(const RealRobots&) = delete;

  /// Opens robot `spec.id`'s link if it is not open yet: starts its emulator first if it
  /// is emulated (at `pose_if_new`, its true pose from then on), and waits up to 2 s for
  /// the robot to answer. Returns the link. Throws agents::ScenarioError naming the robot
  /// and port when the port cannot be opened or the robot does not answer.
  std::shared_ptr<serial::KheperaLink> connect(const run::RobotSpec& spec, const Pose2& pose_if_new);
  /// Makes a robot's body over its link (connect() at the world's initial pose for it).
  run::RealBodyFactory body_factory();
  /// The emulated robots' markers at their true poses now (for the emulated camera).
  std::vector<vision::SceneMarker> emulated_markers() const;
  /// The emulators, by robot ID (for tests and reports: their last commanded speeds).
  std::map<int, const serial::KheperaEmulator*> emulators() const;
  /// Robot `id`'s emulator, or nullptr (not emulated, or not connected yet).
  serial::KheperaEmulator* emulator(int id);
  /// The scenario the robots belong to.
  const run::Scenario& scenario() const { return scenario_; }

 private:
  // The stable device path for emulated robot `id` (makes emulator_dir_ if needed).
  std::string emulator_link_path(int id);

  const run::Scenario& scenario_;
  serial::LogCallback log_;
  mutable std::mutex mutex_;
  // A private folder for the emulated robots' stable device links ("robot-4" -> /dev/pts/N),
  // made on the first emulated robot and removed with this object. Declared first: it
  // outlives the emulators, which remove their links.
  std::filesystem::path emulator_dir_;
  // Declared before the links: the links close (and stop their robots) first.
  std::map<int, std::unique_ptr<serial::KheperaEmulator>> emulators_;
  std::map<int, std::shared_ptr<serial::KheperaLink>> links_;
};

}  // namespace rilbed::run

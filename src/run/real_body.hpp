// A real Khepera (or e-puck) as an agent's body: wheel commands (Khepera units, converted
// to the robot model's own) go out as `D` over its serial link,
// its proximity readings combine the real `N` values with the world's virtual ones (so a
// real robot feels virtual robots and walls), and its pose is the camera's.
//
// Safety (ARCHITECTURE.md, section 5): the robot is stopped instead of driven while its link is not
// healthy (lost, unresponsive, or not yet answering), while the camera has not
// seen it for lost_timeout_ms, and when a command would take its centre further beyond
// the geofence (geofence_margin_m inside the field's edge; turning on the spot and
// driving back in stay allowed); stop() and the destructor stop it too (the destructor
// waits for the robot to acknowledge, within the link's retry budget). The link may be
// shared with whoever keeps it open between runs (RealRobots in a batch); the last owner
// closes it, with a stop of its own.
#pragma once

#include <memory>
#include <random>
#include <string>

#include "agents/body.hpp"
#include "environment/world.hpp"
#include "serial/khepera_link.hpp"

namespace rilbed::run {

/// Knobs of a real body.
struct RealBodyConfig {
  /// Stop a robot the camera has not seen for this long, milliseconds of simulated time.
  int lost_timeout_ms = 500;
  /// Stop a robot whose centre is nearer than this to the field's edge, metres (0: only
  /// outside the field).
  double geofence_margin_m = 0.0;
};

/// One real robot. Not thread-safe (the run's thread calls it); the link it owns has its
/// own thread.
class RealBody final : public agents::Body {
 public:
  /// `world` must outlive the body; the robot `id` must be in the world as a
  /// real robot. `link` must be started.
  RealBody(int id, environment::World& world, std::shared_ptr<serial::KheperaLink> link, RealBodyConfig config);
  /// Stops the robot and waits for its acknowledgement if the line allows (the link stays
  /// open for its other owners; it closes, with another stop, when the last one lets go).
  ~RealBody() override;
  RealBody(const RealBody&) = delete;
  RealBody& operator=(const RealBody&) = delete;

  int id() const override { return id_; }
  environment::SensorReadings sense(TimeUs t_us) override;
  /// The camera's pose while it is fresh (seen within lost_timeout_ms); nullopt otherwise.
  std::optional<Pose2> pose() const override;
  /// Drives the robot, unless it is lost or the command leads out through the geofence:
  /// then stops it.
  void drive(const agents::WheelCommand& wheels) override;
  void stop() override;
  std::string_view health() const override;

  /// Why the last drive() was refused ("link", "lost", "geofence"), or empty.
  const std::string& held_by() const { return held_by_; }
  const serial::KheperaLink& link() const { return *link_; }

 private:
  bool seen_recently() const;
  bool heading_out(const agents::WheelCommand& wheels) const;

  int id_;
  environment::World& world_;
  std::shared_ptr<serial::KheperaLink> link_;
  RealBodyConfig config_;
  std::string held_by_;
};

}  // namespace rilbed::run

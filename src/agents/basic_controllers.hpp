// The controllers a lab starts with, besides the convoy: a Braitenberg wanderer, a track
// follower (with the track sensor of paper 000 §8) and a beacon homer (with the IR beacon
// direction finder of paper 000 §6.10). Each reads only its ControlInput.
#pragma once

#include <optional>

#include "agents/controller.hpp"
#include "agents/steering.hpp"

namespace rilbed::agents {

/// Knobs of the wanderer.
struct WanderConfig {
  /// Cruising speed in the open, m/s.
  double speed_mps = 0.1;
  /// Proximity level (fraction of full scale) above which it turns away.
  double avoid_low = 0.1;
  double avoid_high = 0.5;
  SteeringConfig steering;
};

/// Wander with obstacle avoidance: straight ahead in the open, a Braitenberg turn away
/// from whatever the proximity sensors see. Behaviours: "cruise", "avoid".
class WanderController final : public Controller {
 public:
  explicit WanderController(WanderConfig config = {});
  ControlOutput step(const ControlInput& input) override;

 private:
  WanderConfig config_;
};

/// Knobs of the track follower.
struct TrackFollowConfig {
  double speed_mps = 0.06;             ///< speed along the track, m/s
  double search_speed_mps = 0.08;      ///< speed while looking for a track, m/s
  double search_turn_radps = 0.6;      ///< turn rate of the search arc, rad/s (a wide spiral)
  double correction_turn_radps = 2.0;  ///< turn rate when one side loses the track, rad/s
  /// A track sensor counts as on the track at or above this fraction of its readings' maximum.
  double on_track_fraction = 0.5;
  int max_value = 255;      ///< the track sensors' Max Value (full scale)
  double avoid_low = 0.35;  ///< proximity level where avoidance starts
  double avoid_high = 0.7;
  SteeringConfig steering;
};

/// Follows a floor track with two or more track sensors, ordered left to right across the
/// robot's front: steers towards the side that sees the track, arcs in search of it when
/// none does, and avoids obstacles first. Behaviours: "search", "follow", "avoid".
class TrackFollowController final : public Controller {
 public:
  explicit TrackFollowController(TrackFollowConfig config = {});
  ControlOutput step(const ControlInput& input) override;

 private:
  TrackFollowConfig config_;
  double last_turn_sign_ = 1.0;  // which way the track was lost, to turn back to it
};

/// Knobs of the beacon homer.
struct BeaconHomingConfig {
  std::optional<int> beacon_id;    ///< home on this beacon; nullopt: the first one seen
  double speed_mps = 0.1;          ///< speed towards the beacon, m/s
  double search_turn_radps = 1.0;  ///< turn rate while no beacon is in view, rad/s
  double avoid_low = 0.35;
  double avoid_high = 0.7;
  /// Proximity level straight ahead at which it considers itself arrived and stops.
  double arrive_level = 0.5;
  SteeringConfig steering;
};

/// Turns towards the beacon's bearing and drives to it; turns on the spot while none is in
/// view; avoids obstacles except straight ahead once the beacon is dead ahead (that is the
/// beacon's base), where it stops. Behaviours: "search", "home", "avoid", "arrived".
class BeaconHomingController final : public Controller {
 public:
  explicit BeaconHomingController(BeaconHomingConfig config = {});
  ControlOutput step(const ControlInput& input) override;

 private:
  BeaconHomingConfig config_;
};

/// Knobs of going to a pose (placing a real robot at a run's start pose).
struct GoToPoseConfig {
  Pose2 target;                         ///< where to end, field frame
  double speed_mps = 0.04;              ///< top speed: slow, so the camera keeps up and a bump is harmless
  double position_tolerance_m = 0.01;   ///< close enough (the camera's error is far below this)
  double heading_tolerance_rad = 0.07;  ///< about 4 degrees
  /// Another robot nearer than this, ahead of it, makes it yield (a higher ID waits for a
  /// lower one; the lower one steers around it), metres between centres.
  double yield_distance_m = 0.13;
  /// Robots nearer than this push its course away (as the convoy's repulsion), metres.
  double repulse_radius_m = 0.12;
  /// Waiting longer than this for another robot, it steers around it too, seconds.
  double patience_s = 3.0;
  SteeringConfig steering;
};

/// Drives to a pose slowly: turns towards the target, drives there avoiding the other
/// robots of the team (repulsion, and yielding by ID when one is ahead), then turns on
/// the spot to the target heading, and holds. Stands still while its pose is unknown.
/// done() once it is within both tolerances (it starts again if pushed away by more than
/// twice the position tolerance). Behaviours: "wait", "place", "yield", "align", "placed".
class GoToPoseController final : public Controller {
 public:
  explicit GoToPoseController(GoToPoseConfig config);
  ControlOutput step(const ControlInput& input) override;
  bool wants_team() const override { return true; }
  bool done() const override { return placed_; }

 private:
  // The nearest other robot ahead of `self` within the yield distance, if any.
  const TeamMessage* blocker(const ControlInput& input, const Pose2& self) const;
  Vec2 repulsion(const ControlInput& input, const Pose2& self) const;

  GoToPoseConfig config_;
  bool placed_ = false;
  std::optional<TimeUs> waiting_since_us_;
};

}  // namespace rilbed::agents

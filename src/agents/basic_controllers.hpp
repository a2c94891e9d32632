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
  double speed_mps = 0.06;            ///< speed along the track, m/s
  double search_speed_mps = 0.08;     ///< speed while looking for a track, m/s
  double search_turn_radps = 0.6;     ///< turn rate of the search arc, rad/s (a wide spiral)
  double correction_turn_radps = 2.0; ///< turn rate when one side loses the track, rad/s
  /// A track sensor counts as on the track at or above this fraction of its readings' maximum.
  double on_track_fraction = 0.5;
  int max_value = 255;                ///< the track sensors' Max Value (full scale)
  double avoid_low = 0.35;            ///< proximity level where avoidance starts
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
  std::optional<int> beacon_id;     ///< home on this beacon; nullopt: the first one seen
  double speed_mps = 0.1;           ///< speed towards the beacon, m/s
  double search_turn_radps = 1.0;   ///< turn rate while no beacon is in view, rad/s
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

}  // namespace rilbed::agents

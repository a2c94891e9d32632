#include "agents/basic_controllers.hpp"

#include <algorithm>
#include <cmath>

namespace rilbed::agents {

WanderController::WanderController(WanderConfig config) : config_(config) {}

ControlOutput WanderController::step(const ControlInput& input) {
  const auto& prox = input.sensors.proximity;
  if (prox && obstacle_level(*prox, config_.avoid_low, config_.avoid_high) > 0.0) {
    return {steer_away(*prox, config_.steering), "avoid"};
  }
  return {wheels_from_twist(config_.speed_mps, 0.0), "cruise"};
}

TrackFollowController::TrackFollowController(TrackFollowConfig config) : config_(config) {}

ControlOutput TrackFollowController::step(const ControlInput& input) {
  const auto& prox = input.sensors.proximity;
  if (prox && obstacle_level(*prox, config_.avoid_low, config_.avoid_high) > 0.0) {
    return {steer_away(*prox, config_.steering), "avoid"};
  }
  const auto& track = input.sensors.track;
  const double on = config_.on_track_fraction * config_.max_value;
  // Centre of the sensors on the track, from -1 (leftmost) to +1 (rightmost).
  double weight = 0.0, centre = 0.0;
  const std::size_t n = track.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (track[i] < on) continue;
    const double position = n > 1 ? 2.0 * static_cast<double>(i) / (n - 1) - 1.0 : 0.0;
    weight += 1.0;
    centre += position;
  }
  if (weight == 0.0) {
    // Lost: arc towards where the track was last seen; a wide spiral when it never was.
    return {wheels_from_twist(config_.search_speed_mps, last_turn_sign_ * config_.search_turn_radps), "search"};
  }
  centre /= weight;
  // Track on the left (centre < 0) means turn left (counter-clockwise, positive).
  const double turn = -centre * config_.correction_turn_radps;
  if (std::abs(centre) > 0.2) last_turn_sign_ = centre < 0 ? 1.0 : -1.0;
  return {wheels_from_twist(config_.speed_mps * (1.0 - 0.5 * std::abs(centre)), turn), "follow"};
}

BeaconHomingController::BeaconHomingController(BeaconHomingConfig config) : config_(config) {}

ControlOutput BeaconHomingController::step(const ControlInput& input) {
  const environment::BeaconSighting* target = nullptr;
  for (const auto& b : input.sensors.beacons) {
    if (!config_.beacon_id || b.id == *config_.beacon_id) {
      target = &b;
      break;
    }
  }
  const auto& prox = input.sensors.proximity;
  const double level = prox ? obstacle_level(*prox, config_.avoid_low, config_.avoid_high) : 0.0;
  if (target && prox && std::abs(target->bearing_rad) < 0.35) {
    // Beacon ahead and something right in front: the beacon's own base. Stop there.
    const double ahead = static_cast<double>(std::max((*prox)[2], (*prox)[3])) / environment::kProximityMax;
    if (ahead >= config_.arrive_level) return {{}, "arrived"};
  }
  if (level > 0.0 && prox) return {steer_away(*prox, config_.steering), "avoid"};
  if (!target) return {wheels_from_twist(0.0, config_.search_turn_radps), "search"};
  const double turn = std::clamp(config_.steering.turn_gain * target->bearing_rad, -config_.steering.max_turn_radps,
                                 config_.steering.max_turn_radps);
  const double speed = config_.speed_mps * std::max(0.0, std::cos(target->bearing_rad));
  return {wheels_from_twist(speed, turn), "home"};
}

}  // namespace rilbed::agents

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

GoToPoseController::GoToPoseController(GoToPoseConfig config) : config_(config) {
  config_.steering.max_speed_mps = config_.speed_mps;
  config_.steering.max_reverse_mps = std::min(config_.steering.max_reverse_mps, config_.speed_mps);
  // Turning slowly too: the camera must not blur the marker, and the final heading is
  // within tolerance without overshooting.
  config_.steering.max_turn_radps = std::min(config_.steering.max_turn_radps, 1.2);
}

const TeamMessage* GoToPoseController::blocker(const ControlInput& input, const Pose2& self) const {
  const TeamMessage* nearest = nullptr;
  double nearest_m = config_.yield_distance_m;
  const Vec2 heading{std::cos(self.heading_rad), std::sin(self.heading_rad)};
  for (const TeamMessage& m : input.team) {
    if (m.id == input.robot_id) continue;
    const Vec2 to = m.pose.position_m - self.position_m;
    const double d = to.norm();
    // Ahead: within 60 degrees either side of the heading.
    if (d < nearest_m && d > 1e-9 && heading.dot(to) > 0.5 * d) {
      nearest = &m;
      nearest_m = d;
    }
  }
  return nearest;
}

Vec2 GoToPoseController::repulsion(const ControlInput& input, const Pose2& self) const {
  Vec2 push;
  for (const TeamMessage& m : input.team) {
    if (m.id == input.robot_id) continue;
    const Vec2 away = self.position_m - m.pose.position_m;
    const double d = away.norm();
    if (d < 1e-9 || d >= config_.repulse_radius_m) continue;
    push = push + away / d * ((config_.repulse_radius_m - d) / config_.repulse_radius_m);
  }
  return push;
}

ControlOutput GoToPoseController::step(const ControlInput& input) {
  if (!input.pose) return {{}, "wait"};
  const Pose2& self = *input.pose;
  const double distance = (config_.target.position_m - self.position_m).norm();
  const double heading_error = wrap_rad_pi(config_.target.heading_rad - self.heading_rad);
  if (placed_ && distance > 2.0 * config_.position_tolerance_m) placed_ = false;
  if (placed_ ||
      (distance <= config_.position_tolerance_m && std::abs(heading_error) <= config_.heading_tolerance_rad)) {
    placed_ = true;
    waiting_since_us_.reset();
    return {{}, "placed"};
  }
  if (distance <= config_.position_tolerance_m) {
    // There: turn on the spot, slower as the heading comes right (1 unit is 17 deg/s).
    const double turn =
        std::clamp(2.0 * heading_error, -config_.steering.max_turn_radps, config_.steering.max_turn_radps);
    WheelCommand w = wheels_from_twist(0.0, turn);
    if (w.left == 0 && w.right == 0) w = heading_error > 0 ? WheelCommand{-1, 1} : WheelCommand{1, -1};
    return {w, "align"};
  }
  const Vec2 push = repulsion(input, self);
  if (const TeamMessage* other = blocker(input, self)) {
    if (!waiting_since_us_) waiting_since_us_ = input.t_us;
    const bool patient = us_to_seconds(input.t_us - *waiting_since_us_) < config_.patience_s;
    if (other->id < input.robot_id && patient) return {{}, "yield"};
    // Its turn (or it waited long enough): steer around, keeping the other on its right.
    const Vec2 to = other->pose.position_m - self.position_m;
    const Vec2 left_of_it = Vec2{-to.y, to.x} / std::max(to.norm(), 1e-9);
    return {steer_to(self, self.position_m + left_of_it * 0.1, 0.0, config_.steering), "yield"};
  }
  waiting_since_us_.reset();
  // Near the target the push of a neighbour standing at its own target must not keep it
  // from arriving: the push fades out over the last 5 cm.
  const double fade = std::clamp(distance / 0.05, 0.0, 1.0);
  WheelCommand w = steer_to(self, config_.target.position_m, 0.0, config_.steering, push * fade);
  if (w.left == 0 && w.right == 0) {
    // Rounded to nothing this close: creep at one unit (8 mm/s) towards it.
    const Vec2 to = config_.target.position_m - self.position_m;
    const double error = wrap_rad_pi(std::atan2(to.y, to.x) - self.heading_rad);
    w = std::abs(error) < 0.5 ? WheelCommand{1, 1} : (error > 0 ? WheelCommand{-1, 1} : WheelCommand{1, -1});
  }
  return {w, "place"};
}

}  // namespace rilbed::agents

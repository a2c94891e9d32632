// A pose from the wheel counters alone (dead reckoning), as a robot keeps it on board.
#pragma once

#include <cmath>
#include <optional>

#include "core/geometry.hpp"
#include "environment/kinematics.hpp"
#include "environment/sensor_readings.hpp"

namespace rilbed::agents {

/// Integrates a differential-drive robot's wheel counters into a pose. A value.
class DeadReckoning {
 public:
  /// `wheel_base_m`: distance between the wheels; `metres_per_pulse`: wheel travel per
  /// counter pulse (the Khepera's 0.08 mm by default).
  explicit DeadReckoning(double wheel_base_m, double metres_per_pulse = environment::kKheperaPulse_m)
      : wheel_base_m_(wheel_base_m), metres_per_pulse_(metres_per_pulse) {}

  /// Advances by the counters' change since the last call (the first call only takes
  /// the counters as its start). Each change is driven as one arc.
  void update(const environment::OdometryReading& counters) {
    if (last_) {
      const double left = static_cast<double>(counters.left_pulses - last_->left_pulses) * metres_per_pulse_;
      const double right = static_cast<double>(counters.right_pulses - last_->right_pulses) * metres_per_pulse_;
      const double ds = 0.5 * (left + right), dh = (right - left) / wheel_base_m_;
      // Along the chord of the arc: the mid-heading.
      const double mid = pose_.heading_rad + 0.5 * dh;
      pose_.position_m = pose_.position_m + Vec2{std::cos(mid), std::sin(mid)} * ds;
      pose_.heading_rad = wrap_rad_pi(pose_.heading_rad + dh);
      travelled_m_ += std::abs(ds);
      signed_travel_m_ += ds;
    }
    last_ = counters;
  }
  /// The pose now, in the frame set by set_pose (the start: the origin, heading +x).
  Pose2 pose() const { return pose_; }
  /// Replaces the pose (a correction, or the known start).
  void set_pose(Pose2 pose) { pose_ = pose; }
  /// Distance the centre has driven, forwards or backwards, metres.
  double travelled_m() const { return travelled_m_; }
  /// Distance the centre has driven, forwards positive, metres.
  double signed_travel_m() const { return signed_travel_m_; }
  /// Whether it has had counters yet.
  bool started() const { return last_.has_value(); }

 private:
  double wheel_base_m_;
  double metres_per_pulse_;
  std::optional<environment::OdometryReading> last_;
  Pose2 pose_;
  double travelled_m_ = 0.0;
  double signed_travel_m_ = 0.0;
};

}  // namespace rilbed::agents

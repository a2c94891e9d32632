// Differential-drive forward kinematics of a Khepera-like robot, in the robot's own
// units (wheel speeds in pulses per 10 ms, wheel counters in pulses) and in SI units.
// Integration is exact for constant wheel speeds (the robot drives a circular arc), so
// the step length changes nothing but the collision resolution's granularity.
#pragma once

#include <algorithm>

#include "core/geometry.hpp"

namespace rilbed::environment {

/// Khepera II: one speed unit is one encoder pulse per 10 ms, i.e. 8 mm/s.
inline constexpr double kKheperaSpeedUnit_mps = 0.008;
/// Khepera II: the firmware accepts wheel speeds in [-127, 127] units.
inline constexpr int kKheperaMaxSpeedUnits = 127;
/// Khepera II: one encoder pulse is 0.08 mm of wheel travel.
inline constexpr double kKheperaPulse_m = 0.08e-3;
/// Khepera II: 55 mm across.
inline constexpr double kKheperaRadius_m = 0.0275;
/// Khepera II: 53 mm between the wheels' contact points.
inline constexpr double kKheperaWheelBase_m = 0.053;

/// A wheel speed command clamped to the firmware's range [-127, 127].
constexpr int clamp_speed_units(int units) { return std::clamp(units, -kKheperaMaxSpeedUnits, kKheperaMaxSpeedUnits); }

/// Speed units (pulses per 10 ms) to metres per second.
constexpr double speed_units_to_mps(int units) { return units * kKheperaSpeedUnit_mps; }

/// How far a robot with wheel speeds (left, right) moves over dt_s, in the frame of its
/// pose at the start (x forward, y left), and how much it turns.
struct ArcStep {
  Vec2 local_displacement_m;        ///< x forward, y left of the start pose
  double heading_change_rad = 0.0;  ///< counter-clockwise turn
  double cos_heading_change = 1.0;  ///< cos(heading_change_rad), computed anyway
  double sin_heading_change = 0.0;  ///< sin(heading_change_rad)
};

/// Exact arc of a differential drive with constant wheel ground speeds: linear speed
/// v = (l + r) / 2, turn rate w = (r - l) / wheel_base, over dt_s seconds.
ArcStep diff_drive_arc(double left_mps, double right_mps, double wheel_base_m, double dt_s);

/// The pose after driving `start` for dt_s seconds with constant wheel ground speeds.
/// Heading wrapped into [-pi, pi).
Pose2 integrate_diff_drive(Pose2 start, double left_mps, double right_mps, double wheel_base_m, double dt_s);

/// Radius of the arc the robot's centre drives (positive: turning left), infinite for
/// equal wheel speeds, 0 for spinning in place.
double arc_radius_m(double left_mps, double right_mps, double wheel_base_m);

/// Wheel errors of one virtual robot. Each step, each wheel's ground speed is its
/// commanded speed times (1 + bias + slip_sd * N(0, 1)), with one normal draw per wheel
/// per step from the caller's generator (none when slip_sd is 0).
struct WheelNoiseConfig {
  /// Relative standard deviation of each wheel's speed, per step (0.05 = 5 %). Costs two
  /// normal draws per robot per step when non-zero.
  double slip_sd = 0.0;
  /// Systematic relative error of the left wheel (0.01: it goes 1 % faster than told),
  /// e.g. unequal wheel diameters. Makes a "straight" run curve.
  double left_bias = 0.0;
  /// Systematic relative error of the right wheel.
  double right_bias = 0.0;
  /// true: the wheel counters follow each wheel's actual travel (slip and bias included),
  /// as when the motor itself misses its speed. false: the counters follow the commanded
  /// travel while the ground motion has the errors, as when the wheels slip on the floor;
  /// then odometry drifts from the true pose.
  bool odometer_counts_slip = true;
};

}  // namespace rilbed::environment

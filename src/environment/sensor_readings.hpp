// What a robot's sensors report, as plain values. The world's virtual sensors fill
// them for a virtual robot; a real Khepera's link fills the proximity and odometry for
// a real one. Controllers read them through the agents module's body interface and never
// learn which filled them.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "core/geometry.hpp"
#include "core/time.hpp"

namespace rilbed::environment {

/// The Khepera II has eight IR proximity sensors.
inline constexpr int kProximityCount = 8;

/// Mounting angles of the Khepera II's proximity sensors, radians counter-clockwise from
/// the robot's forward direction, in the firmware's order (0 = left, 2 and 3 = front,
/// 5 = right, 6 and 7 = back).
inline constexpr std::array<double, kProximityCount> kProximityAngles_rad = {
    deg_to_rad(90.0),  deg_to_rad(45.0),  deg_to_rad(10.0),   deg_to_rad(-10.0),
    deg_to_rad(-45.0), deg_to_rad(-90.0), deg_to_rad(-170.0), deg_to_rad(170.0)};

/// Largest proximity value (an object touching the sensor); 0 is nothing in range.
inline constexpr int kProximityMax = 1023;

/// One reading of the eight proximity sensors, 0..1023 each (higher is nearer), in the
/// order of kProximityAngles_rad.
using ProximityValues = std::array<int, kProximityCount>;

/// An ultrasonic range finder's reading: the distance to the nearest object in its cone.
struct RangeReading {
  bool hit = false;         ///< false: nothing within range
  double distance_m = 0.0;  ///< distance to the nearest object, metres (the range when !hit)
};

/// An IR beacon seen by the direction finder (paper 000 §6.10): its ID and bearing, no
/// distance.
struct BeaconSighting {
  int id = 0;
  double bearing_rad = 0.0;  ///< counter-clockwise from the robot's forward direction, [-pi, pi)
};

/// Wheel position counters, as the Khepera's `H` command reports them: pulses, 1 pulse =
/// 0.08 mm of wheel travel.
struct OdometryReading {
  std::int64_t left_pulses = 0;
  std::int64_t right_pulses = 0;
};

/// One sensor model's readings (a plug-in's, sensor_model.hpp), under its mount's name.
struct ModelReading {
  std::string_view name;       ///< the mount's name; valid while the run's scenario lives
  std::vector<double> values;  ///< as many as the model writes
};

/// A shape a sensor model drew for the displays (paper 000 §8.3), in the robot's frame
/// (metres, x forward, y left).
struct SensorMark {
  enum class Shape : std::uint8_t { kCircle, kLine };
  Shape shape = Shape::kCircle;
  Vec2 a_m;                          ///< the circle's centre, or the line's start
  Vec2 b_m;                          ///< the line's end
  double radius_m = 0.0;             ///< the circle's radius
  std::uint32_t rgba = 0xffffffffu;  ///< 0xRRGGBBAA
};

/// Everything one robot sensed at one instant. Sensors a robot does not carry are left
/// empty (empty vectors, nullopt).
struct SensorReadings {
  TimeUs t_us = 0;                           ///< when the readings were taken
  std::optional<ProximityValues> proximity;  ///< the eight IR proximity sensors
  std::vector<RangeReading> ranges;          ///< one per ultrasonic range finder, in configured order
  std::vector<BeaconSighting> beacons;       ///< beacons in view of the direction finder
  std::vector<int> track;                    ///< one value per track sensor, 0..its max value
  std::optional<OdometryReading> odometry;   ///< wheel counters
  std::vector<ModelReading> models;          ///< sensor models' readings, in mount order (not those providing track)
  std::vector<SensorMark> marks;             ///< what its sensor models drew, when the world collects marks
};

}  // namespace rilbed::environment

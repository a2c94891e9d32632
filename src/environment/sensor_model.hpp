// Sensor models from outside the environment module (a plug-in library's, through
// agents::library_sensor_models): what the world asks of one, and how a robot's sensor
// suite carries it. The world calls a mounted model at each control instant after its own
// sensors, with the robot's noise stream in the same state a built-in sensor after them
// would see, so that a model that does what a built-in does gives the same readings.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/geometry.hpp"
#include "core/time.hpp"
#include "environment/mobile_pose.hpp"
#include "environment/random.hpp"
#include "environment/scene.hpp"
#include "environment/sensor_readings.hpp"

namespace rilbed::environment {

/// Everything one call of a model sees. Valid during the call only.
struct SensorModelCall {
  const Scene& scene;
  std::span<const MobilePose> mobiles;  ///< every robot and moving obstacle now
  TimeUs t_us = 0;
  int robot_id = 0;
  Pose2 pose;     ///< the robot's
  Vec2 heading;   ///< cos and sin of pose.heading_rad, as the world computed them
  NoiseRng& rng;  ///< the robot's noise stream at this instant, after the built-in sensors' draws
  std::vector<SensorMark>* marks = nullptr;  ///< where to draw, when someone watches; else null
};

/// One mounted model: a model with its parameters and its place on the robot, shared by
/// every robot that carries that mount. Implementations are immutable after construction
/// (sense() is const) unless concurrent() is false.
class SensorModel {
 public:
  virtual ~SensorModel() = default;
  /// The name the robot's readings carry (the mount's).
  virtual const std::string& name() const = 0;
  /// How many values sense() writes.
  virtual std::size_t value_count() const = 0;
  /// Whether its values are floor-track readings (appended to SensorReadings::track).
  virtual bool provides_track() const = 0;
  /// Whether sense() may run for several robots at once.
  virtual bool concurrent() const = 0;
  /// The robot's readings into `values` (value_count() of them). Throws std::runtime_error,
  /// naming the model and the robot, when the model fails.
  virtual void sense(const SensorModelCall& call, std::span<double> values) const = 0;
};

/// A model on a robot, as a sensor suite's configuration holds it. Equal when it is the
/// same mounted model (robots from one scenario entry share one).
struct SensorModelMount {
  std::shared_ptr<const SensorModel> model;
  bool operator==(const SensorModelMount& other) const { return model == other.model; }
};

}  // namespace rilbed::environment

// The set of virtual sensors one robot carries, configured per robot, and the code that
// reads all of them at once into a SensorReadings.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>
#include "environment/random.hpp"

#include "environment/beacon_finder.hpp"
#include "environment/proximity_sensor.hpp"
#include "environment/range_finder.hpp"
#include "environment/sensor_model.hpp"
#include "environment/track_sensor.hpp"

namespace rilbed::environment {

/// Which sensors a robot carries and how each is set. The default is a stock Khepera II:
/// the eight IR proximity sensors and the wheel counters.
struct SensorSuiteConfig {
  std::optional<ProximityConfig> proximity = ProximityConfig{};  ///< nullopt: no IR ring
  std::vector<RangeFinderConfig> range_finders;                  ///< ultrasonic, in reading order
  std::optional<BeaconFinderConfig> beacon_finder;               ///< nullopt: none
  std::vector<TrackSensorConfig> track_sensors;                  ///< elements, in reading order
  bool odometer = true;                                          ///< report the wheel counters
  std::vector<SensorModelMount> models;                          ///< sensor models (plug-ins'), in mount order
  bool operator==(const SensorSuiteConfig&) const = default;
};

/// A robot's sensors, validated and precomputed (footprints, directions).
class SensorSuite {
 public:
  /// Validates every sensor's configuration; throws std::invalid_argument prefixed with
  /// `what` (e.g. "robot 3").
  SensorSuite(const SensorSuiteConfig& config, const std::string& what);

  /// Reads every sensor of the robot in slot `body` at `pose` into `out` (fields of
  /// sensors it does not carry are emptied; vectors keep their capacity). `odometry` is
  /// reported when the suite has an odometer and it is given. Noise draws come from `rng`
  /// in a fixed order: proximity, range finders, beacons, track sensors.
  void sense(const Scene& scene, int body, Pose2 pose, std::optional<OdometryReading> odometry, TimeUs t_us,
             NoiseRng& rng, SensorReadings& out) const {
    sense(scene, body, pose, Vec2{std::cos(pose.heading_rad), std::sin(pose.heading_rad)}, odometry, t_us, rng, out);
  }
  /// As above, with the heading's unit vector (cos, sin of pose.heading_rad) given, and the
  /// robot's ID for its sensor models (which are called last, in mount order, and may throw
  /// std::runtime_error) and whether they draw (`marks`, into out.marks).
  void sense(const Scene& scene, int body, Pose2 pose, Vec2 heading, std::optional<OdometryReading> odometry,
             TimeUs t_us, NoiseRng& rng, SensorReadings& out, int robot_id = 0, bool marks = false) const;

  /// The IR ring, if carried.
  const std::optional<ProximitySensor>& proximity() const { return proximity_; }
  /// The range finders (possibly none).
  const RangeFinders& range_finders() const { return range_finders_; }
  /// The track sensor elements (possibly none), with their footprints.
  const std::vector<TrackSensor>& track_sensors() const { return track_sensors_; }
  /// The sensor models it carries, in mount order.
  const std::vector<std::shared_ptr<const SensorModel>>& models() const { return models_; }
  /// Whether its readings may fill any of SensorReadings' lists (ranges, beacons, track, models).
  bool has_lists() const {
    return range_finders_.size() > 0 || beacon_finder_ || !track_sensors_.empty() || !models_.empty();
  }
  /// Whether every model it carries may sense for several robots at once.
  bool models_concurrent() const {
    return std::all_of(models_.begin(), models_.end(), [](const auto& m) { return m->concurrent(); });
  }

 private:
  void sense_models(const Scene& scene, Pose2 pose, Vec2 heading, TimeUs t_us, NoiseRng& rng, SensorReadings& out,
                    int robot_id, bool marks) const;
  std::optional<ProximitySensor> proximity_;
  RangeFinders range_finders_;
  std::optional<BeaconFinderConfig> beacon_finder_;
  std::vector<TrackSensor> track_sensors_;
  std::vector<std::shared_ptr<const SensorModel>> models_;
  bool odometer_ = true;
};

}  // namespace rilbed::environment

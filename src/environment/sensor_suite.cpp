#include "environment/sensor_suite.hpp"

#include <cmath>

namespace rilbed::environment {

namespace {
std::vector<TrackSensor> make_track_sensors(const std::vector<TrackSensorConfig>& configs, const std::string& what) {
  std::vector<TrackSensor> sensors;
  sensors.reserve(configs.size());
  for (std::size_t k = 0; k < configs.size(); ++k)
    sensors.emplace_back(configs[k], what + ": track sensor " + std::to_string(k));
  return sensors;
}
}  // namespace

SensorSuite::SensorSuite(const SensorSuiteConfig& config, const std::string& what)
    : range_finders_(config.range_finders, what),
      beacon_finder_(config.beacon_finder),
      track_sensors_(make_track_sensors(config.track_sensors, what)),
      odometer_(config.odometer) {
  if (config.proximity) proximity_.emplace(*config.proximity, what);
  if (beacon_finder_) validate(*beacon_finder_, what);
}

void SensorSuite::sense(const Scene& scene, int body, Pose2 pose, Vec2 heading, std::optional<OdometryReading> odometry,
                        TimeUs t_us, NoiseRng& rng, SensorReadings& out) const {
  out.t_us = t_us;
  if (proximity_) {
    if (!out.proximity) out.proximity.emplace();
    proximity_->sense(scene, body, heading, rng, *out.proximity);
  } else {
    out.proximity.reset();
  }
  range_finders_.sense(scene, body, heading, rng, out.ranges);
  if (beacon_finder_)
    sense_beacons(*beacon_finder_, scene, pose, rng, out.beacons);
  else
    out.beacons.clear();
  out.track.resize(track_sensors_.size());
  for (std::size_t k = 0; k < track_sensors_.size(); ++k) {
    const TrackSensor& t = track_sensors_[k];
    out.track[k] = t.reading(t.covered_segments(scene, pose.position_m, heading), rng);
  }
  if (odometer_ && odometry)
    out.odometry = *odometry;
  else
    out.odometry.reset();
}

}  // namespace rilbed::environment

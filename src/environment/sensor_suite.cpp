#include "environment/sensor_suite.hpp"

#include <cmath>
#include <stdexcept>

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
  for (const SensorModelMount& m : config.models) {
    if (!m.model) throw std::invalid_argument(what + ": a sensor model mount without its model");
    models_.push_back(m.model);
  }
  if (config.proximity) proximity_.emplace(*config.proximity, what);
  if (beacon_finder_) validate(*beacon_finder_, what);
}

void SensorSuite::sense(const Scene& scene, int body, Pose2 pose, Vec2 heading, std::optional<OdometryReading> odometry,
                        TimeUs t_us, NoiseRng& rng, SensorReadings& out, int robot_id, bool marks) const {
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
  sense_models(scene, pose, heading, t_us, rng, out, robot_id, marks);
}

void SensorSuite::sense_models(const Scene& scene, Pose2 pose, Vec2 heading, TimeUs t_us, NoiseRng& rng,
                               SensorReadings& out, int robot_id, bool marks) const {
  std::size_t listed = 0;
  for (const auto& model : models_) {
    if (!model->provides_track()) ++listed;
  }
  out.models.resize(listed);
  out.marks.clear();
  if (models_.empty()) return;
  const SensorModelCall call{scene, scene.mobiles, t_us, robot_id, pose, heading, rng, marks ? &out.marks : nullptr};
  std::size_t next = 0;
  for (const auto& model : models_) {
    if (model->provides_track()) {
      // Track readings are whole numbers: the model's values, rounded, after the built-in elements'.
      double values[64];
      const std::size_t n = std::min<std::size_t>(model->value_count(), 64);
      model->sense(call, std::span<double>(values, n));
      for (std::size_t k = 0; k < n; ++k) out.track.push_back(static_cast<int>(std::lround(values[k])));
      continue;
    }
    ModelReading& reading = out.models[next++];
    reading.name = model->name();
    reading.values.resize(model->value_count());
    model->sense(call, reading.values);
  }
}

}  // namespace rilbed::environment

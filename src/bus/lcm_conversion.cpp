#include "bus/lcm_conversion.hpp"

#include "bus/lcm_checked.hpp"
#include "environment/body_shape.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <type_traits>
#include <utility>

namespace rilbed::bus {

void fill(rilbed::poses_t& m, TimeUs t_us, std::span<const run::PoseReport> poses) {
  m.utime = t_us;
  m.num_robots = static_cast<std::int32_t>(poses.size());
  // Resized, not rebuilt: a message kept between steps keeps its strings' storage, so a
  // step of 10,000 robots does not allocate 20,000 strings.
  m.robots.resize(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const run::PoseReport& p = poses[i];
    rilbed::robot_pose_t& r = m.robots[i];
    r.id = p.id;
    r.real = p.real;
    r.seen = p.seen;
    r.x_m = p.pose.position_m.x;
    r.y_m = p.pose.position_m.y;
    r.theta_rad = p.pose.heading_rad;
    r.behaviour.assign(p.behaviour);
    r.health.assign(p.health);
  }
}

rilbed::poses_t to_lcm(TimeUs t_us, std::span<const run::PoseReport> poses) {
  rilbed::poses_t m;
  fill(m, t_us, poses);
  return m;
}

rilbed::event_t to_lcm(const run::RunEvent& event) {
  rilbed::event_t m;
  m.utime = event.t_us;
  m.kind = event.kind;
  m.id = event.id;
  m.other = event.other;
  m.detail = event.detail;
  return m;
}

rilbed::status_t to_lcm(const run::StatusReport& s) {
  rilbed::status_t m;
  m.utime = s.t_us;
  m.wall_utime = static_cast<std::int64_t>(s.wall_s * 1e6);
  m.scenario = s.scenario;
  m.seed = static_cast<std::int64_t>(s.seed);
  m.mode = s.mode;
  m.realtime = s.realtime;
  m.rt_factor = s.rt_factor;
  m.state = s.state;
  m.ended_by = s.ended_by;
  m.num_robots = s.robots;
  m.num_real = s.real_robots;
  m.formed = s.formed;
  m.formation_time_s = s.formation_time_s.value_or(-1.0);
  m.collisions = s.collisions;
  m.loop_latency_ms = s.loop_latency_ms;
  m.camera_fps = s.camera_fps;
  m.frames = s.frames;
  return m;
}

void fill(rilbed::wheels_t& m, TimeUs t_us, std::span<const run::WheelReport> wheels) {
  m.utime = t_us;
  m.num_robots = static_cast<std::int32_t>(wheels.size());
  m.robots.resize(wheels.size());
  for (std::size_t i = 0; i < wheels.size(); ++i) {
    rilbed::robot_wheels_t& r = m.robots[i];
    r.id = wheels[i].id;
    r.left_units = static_cast<std::int16_t>(wheels[i].wheels.left);
    r.right_units = static_cast<std::int16_t>(wheels[i].wheels.right);
    r.left_mps = wheels[i].wheels.left * agents::kMetresPerSecondPerUnit;
    r.right_mps = wheels[i].wheels.right * agents::kMetresPerSecondPerUnit;
  }
}

void fill(rilbed::robot_sensors_t& r, int id, const environment::SensorReadings& s) {
  r.id = id;
  r.proximity.clear();
  if (s.proximity) {
    for (const int v : *s.proximity) r.proximity.push_back(static_cast<std::int16_t>(v));
  }
  r.num_proximity = static_cast<std::int8_t>(r.proximity.size());
  // Counts are int8/int16 on the wire: a robot carries a handful of each sensor.
  const std::size_t ranges = std::min<std::size_t>(s.ranges.size(), 127);
  r.range_m.resize(ranges);
  r.range_hit.resize(ranges);
  for (std::size_t k = 0; k < ranges; ++k) {
    r.range_m[k] = s.ranges[k].distance_m;
    r.range_hit[k] = s.ranges[k].hit;
  }
  r.num_ranges = static_cast<std::int8_t>(ranges);
  const std::size_t beacons = std::min<std::size_t>(s.beacons.size(), 127);
  r.beacon_id.resize(beacons);
  r.beacon_bearing_rad.resize(beacons);
  for (std::size_t k = 0; k < beacons; ++k) {
    r.beacon_id[k] = s.beacons[k].id;
    r.beacon_bearing_rad[k] = s.beacons[k].bearing_rad;
  }
  r.num_beacons = static_cast<std::int8_t>(beacons);
  const std::size_t track = std::min<std::size_t>(s.track.size(), 32767);
  r.track.assign(s.track.begin(), s.track.begin() + static_cast<std::ptrdiff_t>(track));
  r.num_track = static_cast<std::int16_t>(track);
  r.has_odometry = s.odometry.has_value();
  r.left_pulses = s.odometry ? s.odometry->left_pulses : 0;
  r.right_pulses = s.odometry ? s.odometry->right_pulses : 0;
}

void fill(rilbed::sensors_t& m, TimeUs t_us, std::span<const run::SensorReport> sensors) {
  m.utime = t_us;
  m.num_robots = static_cast<std::int32_t>(sensors.size());
  m.robots.resize(sensors.size());
  for (std::size_t i = 0; i < sensors.size(); ++i) fill(m.robots[i], sensors[i].id, *sensors[i].readings);
}

rilbed::robot_models_t models_to_lcm(int id, const environment::SensorReadings& r, bool with_marks) {
  rilbed::robot_models_t out;
  out.id = id;
  for (const environment::ModelReading& model : r.models) {
    rilbed::model_reading_t reading;
    reading.name = std::string(model.name);
    reading.values = model.values;
    reading.num_values = static_cast<std::int16_t>(reading.values.size());
    out.readings.push_back(std::move(reading));
  }
  out.num_readings = static_cast<std::int16_t>(out.readings.size());
  if (with_marks) {
    for (const environment::SensorMark& mark : r.marks) {
      rilbed::sensor_mark_t x;
      x.shape = mark.shape == environment::SensorMark::Shape::kCircle ? 0 : 1;
      x.x_m = mark.a_m.x;
      x.y_m = mark.a_m.y;
      x.radius_m = mark.radius_m;
      x.x2_m = mark.b_m.x;
      x.y2_m = mark.b_m.y;
      x.rgba = static_cast<std::int32_t>(mark.rgba);
      out.marks.push_back(x);
    }
  }
  out.num_marks = static_cast<std::int16_t>(out.marks.size());
  return out;
}

bool fill(rilbed::sensor_models_t& m, TimeUs t_us, std::span<const run::SensorReport> sensors) {
  m.utime = t_us;
  m.robots.clear();
  for (const run::SensorReport& s : sensors) {
    const environment::SensorReadings& r = *s.readings;
    if (!r.models.empty() || !r.marks.empty()) m.robots.push_back(models_to_lcm(s.id, r, true));
  }
  m.num_robots = static_cast<std::int32_t>(m.robots.size());
  return !m.robots.empty();
}

std::optional<std::string> models_problem(const rilbed::robot_models_t& m) {
  constexpr std::size_t kMostValues = 64, kLongestName = 64;
  for (const rilbed::model_reading_t& r : m.readings) {
    const bool printable = std::all_of(r.name.begin(), r.name.end(), [](char c) { return c >= 0x20 && c < 0x7f; });
    if (r.name.empty() || r.name.size() > kLongestName || !printable)
      return "a model reading's name is empty, longer than 64 bytes or not printable ASCII";
    if (r.values.size() > kMostValues)
      return "model '" + r.name + "' has " + std::to_string(r.values.size()) + " values";
    if (!std::all_of(r.values.begin(), r.values.end(), [](double v) { return std::isfinite(v); }))
      return "model '" + r.name + "' has a value that is not finite";
  }
  for (const rilbed::sensor_mark_t& x : m.marks) {
    if (x.shape != 0 && x.shape != 1) return "a mark of shape " + std::to_string(x.shape);
    for (const double v : {x.x_m, x.y_m, x.radius_m, x.x2_m, x.y2_m})
      if (!std::isfinite(v)) return "a mark that is not finite";
    if (x.radius_m < 0.0) return "a circle of negative radius";
  }
  return std::nullopt;
}

std::optional<std::string> merge_models(const rilbed::robot_models_t& m, environment::SensorReadings& readings,
                                        std::set<std::string, std::less<>>& names) {
  if (auto problem = models_problem(m)) return problem;
  constexpr std::size_t kMostNames = 1024;
  std::vector<environment::ModelReading> models;
  for (const rilbed::model_reading_t& r : m.readings) {
    auto name = names.find(r.name);
    if (name == names.end()) {
      // A hostile stream of new names must not grow the decoder without bound.
      if (names.size() >= kMostNames) return "more than 1024 distinct model names";
      name = names.insert(r.name).first;
    }
    models.push_back({*name, r.values});
  }
  std::vector<environment::SensorMark> marks;
  for (const rilbed::sensor_mark_t& x : m.marks) {
    marks.push_back({x.shape == 0 ? environment::SensorMark::Shape::kCircle : environment::SensorMark::Shape::kLine,
                     {x.x_m, x.y_m},
                     {x.x2_m, x.y2_m},
                     x.radius_m,
                     static_cast<std::uint32_t>(x.rgba)});
  }
  readings.models = std::move(models);
  readings.marks = std::move(marks);
  return std::nullopt;
}

rilbed::detections_t to_lcm(const run::FrameReport& f) {
  rilbed::detections_t m;
  m.utime = f.t_us;
  m.frame = f.frame;
  m.process_ms = f.process_ms;
  m.num_detections = static_cast<std::int32_t>(f.detections.size());
  for (const run::DetectionReport& d : f.detections) {
    rilbed::detection_t x;
    x.id = d.id;
    x.u_px = d.u_px;
    x.v_px = d.v_px;
    x.heading_deg = d.heading_deg;
    x.score = d.score;
    x.diameter_px = d.diameter_px;
    x.x_m = d.pose.position_m.x;
    x.y_m = d.pose.position_m.y;
    x.theta_rad = d.pose.heading_rad;
    m.detections.push_back(x);
  }
  return m;
}

rilbed::vision_settings_t to_lcm(TimeUs t_us, const vision::VisionSettings& s) {
  rilbed::vision_settings_t m;
  m.utime = t_us;
  m.brightness_grey = s.brightness;
  m.contrast = s.contrast;
  m.threshold_grey = s.threshold;
  m.min_diameter_px = s.min_diameter_px;
  m.max_diameter_px = s.max_diameter_px;
  m.min_score = s.min_score;
  return m;
}

vision::VisionSettings from_lcm(const rilbed::vision_settings_t& m) {
  vision::VisionSettings s;
  s.brightness = m.brightness_grey;
  s.contrast = m.contrast;
  s.threshold = m.threshold_grey;
  s.min_diameter_px = m.min_diameter_px;
  s.max_diameter_px = m.max_diameter_px;
  s.min_score = m.min_score;
  return s;
}

rilbed::camera_t to_lcm(TimeUs t_us, const run::CameraReport& c) {
  rilbed::camera_t m;
  m.utime = t_us;
  m.width_px = c.width_px;
  m.height_px = c.height_px;
  std::copy(c.image_to_field.begin(), c.image_to_field.end(), std::begin(m.image_to_field));
  m.lens_distortion = c.lens_distortion;
  m.source = c.source;
  return m;
}

rilbed::sensor_layout_t sensor_layout(TimeUs t_us, const run::WorldReport& world) {
  rilbed::sensor_layout_t m;
  m.utime = t_us;
  for (const run::SensorGeometry& g : world.sensor_geometries) {
    rilbed::sensor_geometry_t out;
    out.ir_range_m = g.ir_range_m;
    for (const auto& r : g.ranges) {
      out.range_mount_rad.push_back(r.mount_rad);
      out.range_opening_rad.push_back(r.opening_rad);
      out.range_max_m.push_back(r.max_m);
    }
    out.num_ranges = static_cast<std::int32_t>(g.ranges.size());
    out.beacon_finder = g.beacon_finder;
    out.beacon_fov_rad = g.beacon_fov_rad;
    for (std::size_t k = 0; k < g.track_points_m.size(); ++k) {
      for (const Vec2& p : g.track_points_m[k]) {
        out.track_sensor.push_back(static_cast<std::int32_t>(k));
        out.track_x_m.push_back(p.x);
        out.track_y_m.push_back(p.y);
      }
    }
    out.num_track_points = static_cast<std::int32_t>(out.track_sensor.size());
    m.geometries.push_back(std::move(out));
  }
  m.num_geometries = static_cast<std::int32_t>(m.geometries.size());
  for (const auto& [id, index] : world.sensor_geometry_of) {
    m.robot_ids.push_back(id);
    m.geometry_of.push_back(index);
  }
  m.num_robots = static_cast<std::int32_t>(m.robot_ids.size());
  return m;
}

rilbed::robot_bodies_t robot_bodies(TimeUs t_us, const run::WorldReport& world) {
  rilbed::robot_bodies_t m;
  m.utime = t_us;
  for (const run::BodyDrawing& b : world.bodies) {
    rilbed::robot_body_t out;
    out.name = b.name;
    out.radius_m = b.outline_m.empty() ? b.radius_m : environment::outline_bounding_radius_m(b.outline_m);
    for (const Vec2& v : b.outline_m) {
      out.outline_x_m.push_back(v.x);
      out.outline_y_m.push_back(v.y);
    }
    out.num_outline = static_cast<std::int32_t>(b.outline_m.size());
    out.wheel_base_m = b.wheel_base_m;
    out.wheel_radius_m = b.wheel_radius_m;
    m.bodies.push_back(std::move(out));
  }
  m.num_bodies = static_cast<std::int32_t>(m.bodies.size());
  for (const auto& [id, index] : world.body_of) {
    m.robot_ids.push_back(id);
    m.body_of.push_back(index);
  }
  m.num_robots = static_cast<std::int32_t>(m.robot_ids.size());
  return m;
}

core::Result<std::pair<std::vector<run::BodyDrawing>, std::map<int, int>>> from_lcm(const rilbed::robot_bodies_t& m) {
  std::vector<run::BodyDrawing> bodies;
  auto positive = [](double v, double most) { return std::isfinite(v) && v > 0.0 && v <= most; };
  for (std::size_t k = 0; k < m.bodies.size(); ++k) {
    const rilbed::robot_body_t& b = m.bodies[k];
    const std::string which = "body " + std::to_string(k);
    if (!positive(b.radius_m, 1.0))
      return core::Failure{which + " has a radius of " + std::to_string(b.radius_m) + " m"};
    if (!positive(b.wheel_base_m, 2.0) || !positive(b.wheel_radius_m, 0.5))
      return core::Failure{which + " has wheels of base " + std::to_string(b.wheel_base_m) + " m, radius " +
                           std::to_string(b.wheel_radius_m) + " m"};
    run::BodyDrawing out{b.name, b.radius_m, {}, b.wheel_base_m, b.wheel_radius_m};
    if (b.num_outline > 0) {
      std::vector<Vec2> outline;
      for (std::int32_t v = 0; v < b.num_outline; ++v) outline.push_back({b.outline_x_m[v], b.outline_y_m[v]});
      try {
        out.outline_m = environment::checked_outline(std::move(outline), which);
      } catch (const std::invalid_argument& e) {
        return core::Failure{e.what()};
      }
      if (environment::outline_bounding_radius_m(out.outline_m) > 1.0)
        return core::Failure{which + " reaches beyond 1 m"};
    }
    bodies.push_back(std::move(out));
  }
  std::map<int, int> of;
  for (std::size_t k = 0; k < m.robot_ids.size(); ++k) {
    if (m.body_of[k] < 0 || m.body_of[k] >= m.num_bodies)
      return core::Failure{"robot " + std::to_string(m.robot_ids[k]) + " has body " + std::to_string(m.body_of[k]) +
                           " of " + std::to_string(m.num_bodies)};
    of[m.robot_ids[k]] = m.body_of[k];
  }
  return std::pair{std::move(bodies), std::move(of)};
}

rilbed::frame_t to_lcm(TimeUs t_us, std::int64_t frame, const cv::Mat& image, int quality) {
  rilbed::frame_t m;
  m.utime = t_us;
  m.frame = frame;
  m.width_px = image.cols;
  m.height_px = image.rows;
  m.format = "jpeg";
  if (!image.empty()) cv::imencode(".jpg", image, m.data, {cv::IMWRITE_JPEG_QUALITY, std::clamp(quality, 1, 100)});
  m.size = static_cast<std::int32_t>(m.data.size());
  return m;
}

namespace {

rilbed::polyline_t polyline(const std::vector<Vec2>& points, bool closed, double width_m) {
  rilbed::polyline_t p;
  p.num_points = static_cast<std::int32_t>(points.size());
  for (const Vec2& v : points) {
    p.x_m.push_back(v.x);
    p.y_m.push_back(v.y);
  }
  p.closed = closed;
  p.width_m = width_m;
  return p;
}

}  // namespace

rilbed::world_t to_lcm(TimeUs t_us, const run::WorldReport& w) {
  rilbed::world_t m;
  m.utime = t_us;
  m.scenario = w.scenario;
  m.width_m = w.field.width_m;
  m.height_m = w.field.height_m;
  m.walls = w.walls;
  for (const auto& o : w.field.obstacles) m.obstacles.push_back(polyline(o, true, 0.0));
  m.num_obstacles = static_cast<std::int32_t>(m.obstacles.size());
  for (const auto& [points, width_m] : w.field.tracks) m.tracks.push_back(polyline(points, false, width_m));
  m.num_tracks = static_cast<std::int32_t>(m.tracks.size());
  for (const Vec2& b : w.field.beacons) {
    m.beacon_x_m.push_back(b.x);
    m.beacon_y_m.push_back(b.y);
  }
  m.num_beacons = static_cast<std::int32_t>(w.field.beacons.size());
  for (const int id : w.robot_ids) {
    m.robot_ids.push_back(id);
    m.robot_real.push_back(w.field.real_robot_ids.contains(id));
  }
  m.num_robots = static_cast<std::int32_t>(w.robot_ids.size());
  return m;
}

rilbed::summary_t to_lcm(TimeUs t_us, const nlohmann::json& summary) {
  rilbed::summary_t m;
  m.utime = t_us;
  m.json = summary.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  return m;
}

run::WorldReport from_lcm(const rilbed::world_t& m) {
  run::WorldReport w;
  w.scenario = m.scenario;
  w.field.width_m = m.width_m;
  w.field.height_m = m.height_m;
  w.walls = m.walls;
  auto points = [](const rilbed::polyline_t& p) {
    std::vector<Vec2> v;
    for (std::size_t i = 0; i < p.x_m.size() && i < p.y_m.size(); ++i) v.push_back({p.x_m[i], p.y_m[i]});
    return v;
  };
  for (const auto& o : m.obstacles) w.field.obstacles.push_back(points(o));
  for (const auto& t : m.tracks) w.field.tracks.emplace_back(points(t), t.width_m);
  for (std::size_t i = 0; i < m.beacon_x_m.size() && i < m.beacon_y_m.size(); ++i) {
    w.field.beacons.push_back({m.beacon_x_m[i], m.beacon_y_m[i]});
  }
  for (std::size_t i = 0; i < m.robot_ids.size(); ++i) {
    w.robot_ids.push_back(m.robot_ids[i]);
    if (i < m.robot_real.size() && m.robot_real[i]) w.field.real_robot_ids.insert(m.robot_ids[i]);
  }
  return w;
}

run::StatusReport from_lcm(const rilbed::status_t& m) {
  run::StatusReport s;
  s.t_us = m.utime;
  s.wall_s = static_cast<double>(m.wall_utime) * 1e-6;
  s.scenario = m.scenario;
  s.seed = static_cast<std::uint64_t>(m.seed);
  s.mode = m.mode;
  s.realtime = m.realtime;
  s.rt_factor = m.rt_factor;
  s.state = m.state;
  s.ended_by = m.ended_by;
  s.robots = m.num_robots;
  s.real_robots = m.num_real;
  s.formed = m.formed;
  if (m.formation_time_s >= 0.0) s.formation_time_s = m.formation_time_s;
  s.collisions = m.collisions;
  s.loop_latency_ms = m.loop_latency_ms;
  s.camera_fps = m.camera_fps;
  s.frames = m.frames;
  return s;
}

environment::SensorReadings from_lcm(const rilbed::robot_sensors_t& m, TimeUs t_us) {
  environment::SensorReadings s;
  s.t_us = t_us;
  if (m.proximity.size() == environment::kProximityCount) {
    environment::ProximityValues values{};
    std::copy(m.proximity.begin(), m.proximity.end(), values.begin());
    s.proximity = values;
  }
  for (std::size_t k = 0; k < m.range_m.size() && k < m.range_hit.size(); ++k)
    s.ranges.push_back({m.range_hit[k] != 0, m.range_m[k]});
  for (std::size_t k = 0; k < m.beacon_id.size() && k < m.beacon_bearing_rad.size(); ++k) {
    s.beacons.push_back({m.beacon_id[k], m.beacon_bearing_rad[k]});
  }
  s.track.assign(m.track.begin(), m.track.end());
  if (m.has_odometry) s.odometry = environment::OdometryReading{m.left_pulses, m.right_pulses};
  return s;
}

}  // namespace rilbed::bus

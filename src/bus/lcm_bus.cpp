#include "bus/lcm_bus.hpp"

#include "bus/lcm_checked.hpp"

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

LcmSubscription::LcmSubscription(lcm::LCM& lcm, const std::string& channel, Handler handler)
    : lcm_(lcm.getUnderlyingLCM()), handler_(std::move(handler)) {
  if (lcm_) subscription_ = lcm_subscribe(lcm_, channel.c_str(), &LcmSubscription::dispatch, this);
}

LcmSubscription::~LcmSubscription() {
  if (lcm_ && subscription_) lcm_unsubscribe(lcm_, subscription_);
}

void LcmSubscription::dispatch(const lcm_recv_buf_t* rbuf, const char* channel, void* self) {
  auto* s = static_cast<LcmSubscription*>(self);
  s->handler_(channel, rbuf->data, static_cast<std::size_t>(rbuf->data_size));
}

std::string agent_reply_url(const std::string& url) {
  // udpm://GROUP:PORT?OPTIONS, or udpm:// (LCM's default 239.255.76.67:7667), or empty (the same).
  std::string u = url.empty() ? "udpm://239.255.76.67:7667" : url;
  if (u.rfind("udpm://", 0) != 0) return url;
  const std::size_t opts = u.find('?');
  std::string address = u.substr(7, opts == std::string::npos ? std::string::npos : opts - 7);
  const std::string rest = opts == std::string::npos ? "" : u.substr(opts);
  if (address.empty()) address = "239.255.76.67:7667";
  const std::size_t colon = address.rfind(':');
  int port = 7667;
  if (colon != std::string::npos) {
    try {
      port = std::stoi(address.substr(colon + 1));
    } catch (const std::exception&) {
      return url;  // LCM will refuse it itself
    }
    address.resize(colon);
  }
  if (port < 1 || port >= 65535) return url;
  return "udpm://" + address + ":" + std::to_string(port + 1) + rest;
}

Channels Channels::with_prefix(const std::string& prefix) {
  Channels c;
  c.poses = prefix + c.poses;
  c.events = prefix + c.events;
  c.status = prefix + c.status;
  c.world = prefix + c.world;
  c.summary = prefix + c.summary;
  c.console = prefix + c.console;
  c.console_reply = prefix + c.console_reply;
  c.agent_hello = prefix + c.agent_hello;
  c.quantum = prefix + c.quantum;
  c.quantum_reply = prefix + c.quantum_reply;
  c.wheels = prefix + c.wheels;
  c.sensors = prefix + c.sensors;
  c.detections = prefix + c.detections;
  c.frames = prefix + c.frames;
  c.camera = prefix + c.camera;
  c.vision = prefix + c.vision;
  c.sensor_layout = prefix + c.sensor_layout;
  return c;
}

std::optional<std::string> check_channel_prefix(const std::string& prefix) {
  for (const char c : prefix) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') {
      return "channel prefix '" + prefix + "' may hold only letters, digits and '_'";
    }
  }
  // The longest channel, RILBED_CONSOLE_REPLY, is 20 bytes; LCM allows 63.
  if (prefix.size() > 50) return "channel prefix '" + prefix + "' is longer than 50 characters";
  return std::nullopt;
}

std::unique_ptr<lcm::LCM> open_lcm(const std::string& url, std::string& error) {
  auto lcm = std::make_unique<lcm::LCM>(url);
  if (!lcm->good()) {
    error = "cannot open the LCM bus '" + url + "' (a URL such as memq:// or udpm://239.255.76.67:7667?ttl=0)";
    return nullptr;
  }
  return lcm;
}

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

namespace {

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

}  // namespace

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

RunReportDecoder::RunReportDecoder(Channels channels, run::RunObserver& observer)
    : channels_(std::move(channels)), observer_(observer) {}

std::optional<std::string> RunReportDecoder::decode(const std::string& channel, const void* data, std::size_t size) {
  auto bad = [&](const char* type) {
    return std::optional<std::string>(channel + ": " + std::to_string(size) + " bytes that are not a rilbed." + type);
  };
  if (channel == channels_.poses) {
    rilbed::poses_t m;
    if (!decode_checked(data, size, m)) return bad("poses_t");
    poses_.clear();
    for (const rilbed::robot_pose_t& r : m.robots) {
      poses_.push_back({r.id, r.real != 0, r.seen != 0, Pose2{{r.x_m, r.y_m}, r.theta_rad}, r.behaviour, r.health});
    }
    observer_.on_poses(m.utime, poses_);
  } else if (channel == channels_.events) {
    rilbed::event_t m;
    if (!decode_checked(data, size, m)) return bad("event_t");
    observer_.on_event({m.utime, m.kind, m.id, m.other, m.detail});
  } else if (channel == channels_.status) {
    rilbed::status_t m;
    if (!decode_checked(data, size, m)) return bad("status_t");
    last_status_ = m;
    run::StatusReport status = from_lcm(m);
    status.vision = std::exchange(vision_, std::nullopt);
    observer_.on_status(status);
  } else if (channel == channels_.world) {
    rilbed::world_t m;
    if (!decode_checked(data, size, m)) return bad("world_t");
    run::WorldReport world = from_lcm(m);
    world.camera = camera_;
    world.sensor_geometries = sensor_geometries_;
    world.sensor_geometry_of = sensor_geometry_of_;
    observer_.on_world(m.utime, world);
  } else if (channel == channels_.sensor_layout) {
    rilbed::sensor_layout_t m;
    if (!decode_checked(data, size, m)) return bad("sensor_layout_t");
    std::vector<run::SensorGeometry> geometries;
    for (const rilbed::sensor_geometry_t& g : m.geometries) {
      run::SensorGeometry out;
      out.ir_range_m = g.ir_range_m;
      for (std::size_t k = 0; k < g.range_mount_rad.size(); ++k) {
        out.ranges.push_back({g.range_mount_rad[k], g.range_opening_rad[k], g.range_max_m[k]});
      }
      out.beacon_finder = g.beacon_finder != 0;
      out.beacon_fov_rad = g.beacon_fov_rad;
      for (std::size_t k = 0; k < g.track_sensor.size(); ++k) {
        const std::int32_t element = g.track_sensor[k];
        // Elements in reading order, each point naming its own: a jump ahead is a bad message.
        if (element < 0 || static_cast<std::size_t>(element) > out.track_points_m.size() ||
            (static_cast<std::size_t>(element) + 1 < out.track_points_m.size())) {
          return channel + ": track point " + std::to_string(k) + " names element " + std::to_string(element) +
                 " out of order";
        }
        if (static_cast<std::size_t>(element) == out.track_points_m.size()) out.track_points_m.emplace_back();
        out.track_points_m.back().push_back({g.track_x_m[k], g.track_y_m[k]});
      }
      geometries.push_back(std::move(out));
    }
    std::map<int, int> of;
    for (std::size_t k = 0; k < m.robot_ids.size(); ++k) {
      if (m.geometry_of[k] < 0 || m.geometry_of[k] >= m.num_geometries) {
        return channel + ": robot " + std::to_string(m.robot_ids[k]) + " has geometry " +
               std::to_string(m.geometry_of[k]) + " of " + std::to_string(m.num_geometries);
      }
      of[m.robot_ids[k]] = m.geometry_of[k];
    }
    sensor_geometries_ = std::move(geometries);
    sensor_geometry_of_ = std::move(of);
  } else if (channel == channels_.vision) {
    rilbed::vision_settings_t m;
    if (!decode_checked(data, size, m)) return bad("vision_settings_t");
    const vision::VisionSettings s = from_lcm(m);
    if (auto why = vision::check_vision_settings(s)) return channel + ": " + *why;
    vision_ = s;
  } else if (channel == channels_.camera) {
    rilbed::camera_t m;
    if (!decode_checked(data, size, m)) return bad("camera_t");
    if (m.width_px <= 0 || m.height_px <= 0 || m.width_px > 100000 || m.height_px > 100000) {
      return channel + ": a camera of " + std::to_string(m.width_px) + " x " + std::to_string(m.height_px) + " pixels";
    }
    run::CameraReport c;
    c.width_px = m.width_px;
    c.height_px = m.height_px;
    std::copy(std::begin(m.image_to_field), std::end(m.image_to_field), c.image_to_field.begin());
    c.lens_distortion = m.lens_distortion != 0;
    c.source = m.source;
    camera_ = c;
  } else if (channel == channels_.wheels) {
    rilbed::wheels_t m;
    if (!decode_checked(data, size, m)) return bad("wheels_t");
    wheels_.clear();
    for (const rilbed::robot_wheels_t& r : m.robots) wheels_.push_back({r.id, {r.left_units, r.right_units}});
    observer_.on_wheels(m.utime, wheels_);
  } else if (channel == channels_.sensors) {
    rilbed::sensors_t m;
    if (!decode_checked(data, size, m)) return bad("sensors_t");
    readings_.resize(m.robots.size());
    sensors_.clear();
    for (std::size_t i = 0; i < m.robots.size(); ++i) {
      readings_[i] = from_lcm(m.robots[i], m.utime);
      sensors_.push_back({m.robots[i].id, &readings_[i]});
    }
    observer_.on_sensors(m.utime, sensors_);
  } else if (channel == channels_.detections) {
    rilbed::detections_t m;
    if (!decode_checked(data, size, m)) return bad("detections_t");
    detections_.clear();
    for (const rilbed::detection_t& d : m.detections) {
      detections_.push_back(
          {d.id, d.u_px, d.v_px, d.heading_deg, d.score, d.diameter_px, Pose2{{d.x_m, d.y_m}, d.theta_rad}});
    }
    observer_.on_detections({m.utime, m.frame, m.process_ms, detections_});
  } else if (channel == channels_.frames) {
    if (!observer_.wants_frame_images() && !observer_.wants_frame_jpegs()) return std::nullopt;
    rilbed::frame_t m;
    if (!decode_checked(data, size, m)) return bad("frame_t");
    if (m.format != "jpeg") return channel + ": frame " + std::to_string(m.frame) + " is '" + m.format + "', not jpeg";
    if (observer_.wants_frame_jpegs()) {
      if (m.width_px <= 0 || m.height_px <= 0) return channel + ": frame " + std::to_string(m.frame) + " has no size";
      observer_.on_frame_jpeg(m.utime, m.frame, m.width_px, m.height_px, m.data);
      if (!observer_.wants_frame_images()) return std::nullopt;
    }
    cv::Mat image;
    try {
      image = cv::imdecode(m.data, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception&) {
      image.release();
    }
    if (image.empty() || image.cols != m.width_px || image.rows != m.height_px) {
      return channel + ": frame " + std::to_string(m.frame) + " is not a JPEG image of its stated size";
    }
    observer_.on_frame_image(m.utime, m.frame, image);
  } else if (channel == channels_.summary) {
    rilbed::summary_t m;
    if (!decode_checked(data, size, m)) return bad("summary_t");
    const nlohmann::json summary = nlohmann::json::parse(m.json, nullptr, false);
    if (summary.is_discarded() || !summary.is_object()) return channel + ": the summary is not a JSON object";
    summary_seen_ = true;
    observer_.on_summary(m.utime, summary);
  }
  return std::nullopt;
}

nlohmann::json RunReportDecoder::cut_short_summary() const {
  nlohmann::json summary;
  summary["truncated"] = true;
  if (last_status_) {
    summary["scenario"] = last_status_->scenario;
    summary["seed"] = last_status_->seed;
    summary["simulated_s"] = static_cast<double>(last_status_->utime) * 1e-6;
  }
  return summary;
}

LcmLogReader::LcmLogReader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return;
  bytes_.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  good_ = !in.bad();
}

std::optional<LcmLogReader::Event> LcmLogReader::next() {
  constexpr std::uint32_t kSync = 0xEDA1DA01;
  constexpr std::size_t kHeader = 4 + 8 + 8 + 4 + 4;
  auto u32 = [this](std::size_t at) {
    return (std::uint32_t{bytes_[at]} << 24) | (std::uint32_t{bytes_[at + 1]} << 16) |
           (std::uint32_t{bytes_[at + 2]} << 8) | std::uint32_t{bytes_[at + 3]};
  };
  auto u64 = [&](std::size_t at) { return (std::uint64_t{u32(at)} << 32) | u32(at + 4); };
  while (pos_ + 4 <= bytes_.size()) {
    if (u32(pos_) != kSync) {  // not an event here: look for the next one
      ++pos_;
      ++skipped_;
      continue;
    }
    if (pos_ + kHeader > bytes_.size()) break;
    const auto channel_length = static_cast<std::int32_t>(u32(pos_ + 20));
    const auto data_length = static_cast<std::int32_t>(u32(pos_ + 24));
    const std::size_t left = bytes_.size() - pos_ - kHeader;
    if (channel_length < 1 || channel_length > 255 || data_length < 0) {  // a sync word by chance: go on looking
      ++pos_;
      ++skipped_;
      continue;
    }
    if (static_cast<std::size_t>(channel_length) + static_cast<std::size_t>(data_length) > left) break;  // cut short
    Event e;
    e.eventnum = static_cast<std::int64_t>(u64(pos_ + 4));
    e.timestamp_us = static_cast<std::int64_t>(u64(pos_ + 12));
    const std::size_t channel_at = pos_ + kHeader;
    e.channel.assign(reinterpret_cast<const char*>(&bytes_[channel_at]), static_cast<std::size_t>(channel_length));
    const std::size_t data_at = channel_at + static_cast<std::size_t>(channel_length);
    e.data.assign(bytes_.begin() + static_cast<std::ptrdiff_t>(data_at),
                  bytes_.begin() + static_cast<std::ptrdiff_t>(data_at + static_cast<std::size_t>(data_length)));
    pos_ = data_at + static_cast<std::size_t>(data_length);
    return e;
  }
  truncated_ = pos_ < bytes_.size();
  if (truncated_) skipped_ += bytes_.size() - pos_;
  pos_ = bytes_.size();
  return std::nullopt;
}

// Hands what the publisher decodes to every local subscriber.
class LcmRunPublisher::Fanout final : public run::RunObserver {
 public:
  std::vector<run::RunObserver*> observers;
  bool wants_frame_images() const override {
    return std::any_of(observers.begin(), observers.end(), [](auto* o) { return o->wants_frame_images(); });
  }
  void on_world(TimeUs t, const run::WorldReport& w) override {
    each([&](auto& o) { o.on_world(t, w); });
  }
  void on_poses(TimeUs t, std::span<const run::PoseReport> p) override {
    each([&](auto& o) { o.on_poses(t, p); });
  }
  void on_wheels(TimeUs t, std::span<const run::WheelReport> w) override {
    each([&](auto& o) { o.on_wheels(t, w); });
  }
  void on_sensors(TimeUs t, std::span<const run::SensorReport> s) override {
    each([&](auto& o) { o.on_sensors(t, s); });
  }
  void on_detections(const run::FrameReport& f) override {
    each([&](auto& o) { o.on_detections(f); });
  }
  void on_frame_image(TimeUs t, std::int64_t n, const cv::Mat& image) override {
    each([&](auto& o) {
      if (o.wants_frame_images()) o.on_frame_image(t, n, image);
    });
  }
  bool wants_frame_jpegs() const override {
    return std::any_of(observers.begin(), observers.end(), [](auto* o) { return o->wants_frame_jpegs(); });
  }
  void on_frame_jpeg(TimeUs t, std::int64_t n, int w, int h, std::span<const std::uint8_t> jpeg) override {
    each([&](auto& o) {
      if (o.wants_frame_jpegs()) o.on_frame_jpeg(t, n, w, h, jpeg);
    });
  }
  void on_event(const run::RunEvent& e) override {
    each([&](auto& o) { o.on_event(e); });
  }
  void on_status(const run::StatusReport& s) override {
    each([&](auto& o) { o.on_status(s); });
  }
  void on_summary(TimeUs t, const nlohmann::json& j) override {
    each([&](auto& o) { o.on_summary(t, j); });
  }

 private:
  template <typename F>
  void each(F f) {
    for (run::RunObserver* o : observers) f(*o);
  }
};

LcmRunPublisher::LcmRunPublisher(lcm::LCM& lcm, Channels channels, Options options)
    : lcm_(lcm), channels_(std::move(channels)), options_(options) {}

LcmRunPublisher::~LcmRunPublisher() = default;

void LcmRunPublisher::add_local_subscriber(run::RunObserver& observer) {
  if (!fanout_) {
    fanout_ = std::make_unique<Fanout>();
    local_decoder_ = std::make_unique<RunReportDecoder>(channels_, *fanout_);
  }
  fanout_->observers.push_back(&observer);
}

std::unique_ptr<LcmSubscription> LcmRunPublisher::subscribe(const std::string& channel,
                                                            LcmSubscription::Handler handler) {
  auto subscription = std::make_unique<LcmSubscription>(lcm_, channel, std::move(handler));
  ++bus_subscribers_;
  return subscription;
}

template <typename Message>
void LcmRunPublisher::publish(const std::string& channel, const Message& message, bool local_only) {
  std::lock_guard lock(mutex_);
  // Encoded once: the same bytes go on the bus, into the log and to the local subscribers.
  const int room = message.getEncodedSize();
  buffer_.resize(static_cast<std::size_t>(room));
  // encode() stops a string at a NUL byte, so it may write fewer bytes than the room
  // getEncodedSize() asked for: send what it wrote.
  const int size = message.encode(buffer_.data(), 0, room);
  ChannelCount& c = counts_[channel];
  if (size < 0) {
    ++c.failures;
    return;
  }
  if (local_only) {
    if (local_decoder_) local_decoder_->decode(channel, buffer_.data(), static_cast<std::size_t>(size));
    return;
  }
  if (channel == channels_.world) last_world_.assign(buffer_.begin(), buffer_.begin() + size);
  if (channel == channels_.status) last_status_.assign(buffer_.begin(), buffer_.begin() + size);
  if (channel == channels_.summary) last_summary_.assign(buffer_.begin(), buffer_.begin() + size);
  const bool to_bus = !options_.in_process || bus_subscribers_ > 0;
  if (to_bus) {
    const int status = lcm_.publish(channel, buffer_.data(), static_cast<unsigned>(size));
    if (status != 0) ++c.failures;  // lost, as on a lossy network; the run goes on
  }
  ++c.messages;
  c.bytes += static_cast<std::uint64_t>(size);
  if (options_.log) {
    lcm::LogEvent event;
    event.eventnum = log_events_++;
    event.timestamp =
        std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
            .count();
    event.channel = channel;
    event.datalen = size;
    event.data = buffer_.data();
    options_.log->writeEvent(&event);
  }
  if (local_decoder_) local_decoder_->decode(channel, buffer_.data(), static_cast<std::size_t>(size));
  if (to_bus && options_.in_process) {
    // memq:// queues every message until handled: deliver to the in-process subscribers now.
    while (lcm_.handleTimeout(0) > 0) {}
  }
}

void LcmRunPublisher::republish_world_and_status() {
  std::lock_guard lock(mutex_);
  if (options_.in_process && bus_subscribers_ == 0) return;
  if (!last_world_.empty())
    lcm_.publish(channels_.world, last_world_.data(), static_cast<unsigned>(last_world_.size()));
  if (!last_status_.empty())
    lcm_.publish(channels_.status, last_status_.data(), static_cast<unsigned>(last_status_.size()));
}

void LcmRunPublisher::repeat_end() {
  std::lock_guard lock(mutex_);
  if (options_.in_process && bus_subscribers_ == 0) return;
  if (!last_status_.empty())
    lcm_.publish(channels_.status, last_status_.data(), static_cast<unsigned>(last_status_.size()));
  if (!last_summary_.empty()) {
    lcm_.publish(channels_.summary, last_summary_.data(), static_cast<unsigned>(last_summary_.size()));
  }
  if (options_.in_process) {
    while (lcm_.handleTimeout(0) > 0) {}
  }
}

void LcmRunPublisher::on_world(TimeUs t_us, const run::WorldReport& world) {
  if (!heard()) return;
  // The camera first: a viewer draws the world over the camera's frames.
  if (world.camera) publish(channels_.camera, to_lcm(t_us, *world.camera));
  if (!world.sensor_geometries.empty()) publish(channels_.sensor_layout, sensor_layout(t_us, world));
  publish(channels_.world, to_lcm(t_us, world));
}

void LcmRunPublisher::on_poses(TimeUs t_us, std::span<const run::PoseReport> poses) {
  if (!heard()) return;
  fill(poses_message_, t_us, poses);
  publish(channels_.poses, poses_message_);
}

void LcmRunPublisher::on_wheels(TimeUs t_us, std::span<const run::WheelReport> wheels) {
  if (!heard()) return;
  fill(wheels_message_, t_us, wheels);
  publish(channels_.wheels, wheels_message_);
}

void LcmRunPublisher::on_sensors(TimeUs t_us, std::span<const run::SensorReport> sensors) {
  if (!heard()) return;
  fill(sensors_message_, t_us, sensors);
  publish(channels_.sensors, sensors_message_);
}

void LcmRunPublisher::on_detections(const run::FrameReport& frame) {
  if (heard()) publish(channels_.detections, to_lcm(frame));
}

void LcmRunPublisher::on_frame_image(TimeUs t_us, std::int64_t frame, const cv::Mat& image) {
  if (options_.frames) {
    if (heard()) publish(channels_.frames, to_lcm(t_us, frame, image, options_.jpeg_quality));
    return;
  }
  // Only for the local subscribers (a web panel), and only as often as they show them.
  if (options_.local_frame_period_ms <= 0 || !fanout_ || !fanout_->wants_frame_jpegs()) return;
  const auto now = std::chrono::steady_clock::now();
  if (now < next_local_frame_) return;
  next_local_frame_ = now + std::chrono::milliseconds(options_.local_frame_period_ms);
  publish(channels_.frames, to_lcm(t_us, frame, image, options_.jpeg_quality), /*local_only=*/true);
}

void LcmRunPublisher::on_event(const run::RunEvent& event) {
  if (heard()) publish(channels_.events, to_lcm(event));
}

void LcmRunPublisher::on_status(const run::StatusReport& status) {
  if (!heard()) return;
  // The settings first: a decoder hands them on with the status that follows.
  if (status.vision) publish(channels_.vision, to_lcm(status.t_us, *status.vision));
  publish(channels_.status, to_lcm(status));
  if (options_.log) std::fflush(options_.log->getFilePtr());  // a run cut short keeps its log up to the last second
}

void LcmRunPublisher::on_summary(TimeUs t_us, const nlohmann::json& summary) {
  if (!heard()) return;
  publish(channels_.summary, to_lcm(t_us, summary));
  if (options_.log) std::fflush(options_.log->getFilePtr());  // the whole run is on disk once it has ended
}

std::map<std::string, ChannelCount> LcmRunPublisher::counts() const {
  std::lock_guard lock(mutex_);
  return counts_;
}

}  // namespace rilbed::bus

#include "bus/report_decoder.hpp"

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

#include "bus/lcm_conversion.hpp"

namespace rilbed::bus {

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
    world.bodies = bodies_;
    world.body_of = body_of_;
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
  } else if (channel == channels_.sensor_models) {
    rilbed::sensor_models_t m;
    if (!decode_checked(data, size, m)) return bad("sensor_models_t");
    models_ = std::move(m);
  } else if (channel == channels_.robot_bodies) {
    rilbed::robot_bodies_t m;
    if (!decode_checked(data, size, m)) return bad("robot_bodies_t");
    auto bodies = from_lcm(m);
    if (!bodies) return channel + ": " + bodies.error();
    bodies_ = std::move(bodies->first);
    body_of_ = std::move(bodies->second);
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
    std::map<int, std::size_t> slot_of;
    for (std::size_t i = 0; i < m.robots.size(); ++i) {
      readings_[i] = from_lcm(m.robots[i], m.utime);
      sensors_.push_back({m.robots[i].id, &readings_[i]});
      slot_of.emplace(m.robots[i].id, i);
    }
    // The models' readings and marks of the same step (sent just before), robot by robot;
    // a robot's bad ones are left out, and said so, and the step's sensors still go on.
    std::optional<std::string> problem;
    if (models_ && models_->utime == m.utime) {
      for (const rilbed::robot_models_t& r : models_->robots) {
        const auto slot = slot_of.find(r.id);
        if (slot == slot_of.end()) continue;  // a robot this step does not report
        if (auto why = merge_models(r, readings_[slot->second], model_names_); why && !problem)
          problem = channels_.sensor_models + ": robot " + std::to_string(r.id) + ": " + *why;
      }
    }
    models_.reset();
    observer_.on_sensors(m.utime, sensors_);
    return problem;
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

}  // namespace rilbed::bus

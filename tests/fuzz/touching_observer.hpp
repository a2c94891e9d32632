// A RunObserver for the LCM fuzz targets (fuzz_lcm_messages, fuzz_lcm_log): it reads every
// byte of every field it is handed (so that AddressSanitizer sees a read of memory the
// decoder should not have handed over: freed, out of bounds, a string_view to a dead
// string), counts the calls, and keeps a copy of the last report of each kind for the
// targets to compare with what lcm-gen's decoder made of the same bytes.
#pragma once

#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "run/run_observer.hpp"

namespace rilbed_fuzz {

/// A PoseReport with its own strings (a PoseReport's views live only during the call).
struct OwnedPose {
  int id = 0;
  bool real = false;
  bool seen = false;
  rilbed::Pose2 pose;
  std::string behaviour;
  std::string health;
};

class TouchingObserver : public rilbed::run::RunObserver {
 public:
  struct Calls {
    int world = 0, poses = 0, event = 0, status = 0, summary = 0, wheels = 0, sensors = 0, detections = 0, frames = 0;
    int total() const { return world + poses + event + status + summary + wheels + sensors + detections + frames; }
  };

  void on_world(rilbed::TimeUs t_us, const rilbed::run::WorldReport& w) override {
    ++calls.world;
    touch(t_us);
    touch(w.scenario);
    touch(w.walls);
    touch(w.field.width_m);
    touch(w.field.height_m);
    for (const auto& polygon : w.field.obstacles) touch(polygon);
    for (const auto& [points, width_m] : w.field.tracks) {
      touch(points);
      touch(width_m);
    }
    touch(w.field.beacons);
    for (const int id : w.field.real_robot_ids) touch(id);
    for (const int id : w.robot_ids) touch(id);
    last_world_t_us = t_us;
    last_world = w;
  }

  void on_poses(rilbed::TimeUs t_us, std::span<const rilbed::run::PoseReport> poses) override {
    ++calls.poses;
    touch(t_us);
    last_poses_t_us = t_us;
    last_poses.clear();
    for (const rilbed::run::PoseReport& p : poses) {
      touch(p.id);
      touch(p.real);
      touch(p.seen);
      touch(p.pose);
      touch(p.behaviour);
      touch(p.health);
      last_poses.push_back({p.id, p.real, p.seen, p.pose, std::string(p.behaviour), std::string(p.health)});
    }
  }

  void on_event(const rilbed::run::RunEvent& e) override {
    ++calls.event;
    touch(e.t_us);
    touch(e.kind);
    touch(e.id);
    touch(e.other);
    touch(e.detail);
    last_event = e;
  }

  void on_status(const rilbed::run::StatusReport& s) override {
    ++calls.status;
    touch(s.t_us);
    touch(s.wall_s);
    touch(s.scenario);
    touch(s.seed);
    touch(s.mode);
    touch(s.realtime);
    touch(s.rt_factor);
    touch(s.state);
    touch(s.ended_by);
    touch(s.robots);
    touch(s.real_robots);
    touch(s.formed);
    if (s.formation_time_s) touch(*s.formation_time_s);
    touch(s.collisions);
    touch(s.loop_latency_ms);
    touch(s.camera_fps);
    touch(s.frames);
    last_status = s;
  }

  void on_wheels(rilbed::TimeUs t_us, std::span<const rilbed::run::WheelReport> wheels) override {
    ++calls.wheels;
    touch(t_us);
    last_wheels.assign(wheels.begin(), wheels.end());
    for (const auto& w : wheels) {
      touch(w.id);
      touch(w.wheels.left);
      touch(w.wheels.right);
    }
  }

  void on_sensors(rilbed::TimeUs t_us, std::span<const rilbed::run::SensorReport> sensors) override {
    ++calls.sensors;
    touch(t_us);
    last_sensors.clear();
    for (const auto& r : sensors) {
      touch(r.id);
      const rilbed::environment::SensorReadings& s = *r.readings;
      touch(s.t_us);
      if (s.proximity) {
        for (const int v : *s.proximity) touch(v);
      }
      for (const auto& range : s.ranges) {
        touch(range.hit);
        touch(range.distance_m);
      }
      for (const auto& b : s.beacons) {
        touch(b.id);
        touch(b.bearing_rad);
      }
      for (const int v : s.track) touch(v);
      if (s.odometry) {
        touch(s.odometry->left_pulses);
        touch(s.odometry->right_pulses);
      }
      last_sensors.emplace_back(r.id, s);
    }
  }

  void on_detections(const rilbed::run::FrameReport& f) override {
    ++calls.detections;
    touch(f.t_us);
    touch(f.frame);
    touch(f.process_ms);
    last_frame_number = f.frame;
    last_detections.assign(f.detections.begin(), f.detections.end());
    for (const auto& d : f.detections) {
      touch(d.id);
      touch(d.u_px);
      touch(d.v_px);
      touch(d.heading_deg);
      touch(d.score);
      touch(d.diameter_px);
      touch(d.pose);
    }
  }

  bool wants_frame_images() const override { return true; }
  void on_frame_image(rilbed::TimeUs t_us, std::int64_t frame, const cv::Mat& image) override {
    ++calls.frames;
    touch(t_us);
    touch(frame);
    last_frame_number = frame;
    last_image_size = image.size();
    // Every byte of the decoded image.
    for (int y = 0; y < image.rows; ++y) {
      const auto* row = image.ptr<std::uint8_t>(y);
      for (std::size_t x = 0; x < static_cast<std::size_t>(image.cols) * image.elemSize(); ++x) sink += row[x];
    }
  }

  void on_summary(rilbed::TimeUs t_us, const nlohmann::json& summary) override {
    ++calls.summary;
    touch(t_us);
    touch(summary.dump());  // every value of the object, at any depth
    last_summary_t_us = t_us;
    last_summary = summary;
  }

  Calls calls;
  rilbed::TimeUs last_world_t_us = 0, last_poses_t_us = 0, last_summary_t_us = 0;
  rilbed::run::WorldReport last_world;
  std::vector<OwnedPose> last_poses;
  rilbed::run::RunEvent last_event;
  rilbed::run::StatusReport last_status;
  nlohmann::json last_summary;
  std::vector<rilbed::run::WheelReport> last_wheels;
  std::vector<std::pair<int, rilbed::environment::SensorReadings>> last_sensors;
  std::vector<rilbed::run::DetectionReport> last_detections;
  std::int64_t last_frame_number = 0;
  cv::Size last_image_size;
  /// What was read, summed, so that no read can be optimised away.
  std::uint64_t sink = 0;

 private:
  void touch(std::string_view text) {
    sink += text.size();
    for (const char c : text) sink = sink * 31 + static_cast<unsigned char>(c);
  }
  void touch(double v) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &v, sizeof bits);
    sink ^= bits;
  }
  void touch(std::int64_t v) { sink += static_cast<std::uint64_t>(v); }
  void touch(std::uint64_t v) { sink += v; }
  void touch(int v) { sink += static_cast<std::uint64_t>(static_cast<std::int64_t>(v)); }
  void touch(bool v) { sink += v ? 1 : 2; }
  void touch(rilbed::Vec2 v) {
    touch(v.x);
    touch(v.y);
  }
  void touch(const rilbed::Pose2& p) {
    touch(p.position_m);
    touch(p.heading_rad);
  }
  void touch(const std::vector<rilbed::Vec2>& points) {
    sink += points.size();
    for (const rilbed::Vec2& v : points) touch(v);
  }
};

}  // namespace rilbed_fuzz

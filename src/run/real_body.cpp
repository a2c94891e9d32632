#include "run/real_body.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>

namespace rilbed::run {

RealBody::RealBody(int id, environment::World& world, std::shared_ptr<serial::KheperaLink> link, RealBodyConfig config)
    : id_(id), world_(world), link_(std::move(link)), config_(config) {
  if (!link_) throw std::invalid_argument("robot " + std::to_string(id) + ": no link");
  if (!world_.has_robot(id) || world_.robot(id).kind != environment::RobotKind::kReal) {
    throw std::invalid_argument("robot " + std::to_string(id) + " is not a real robot of the world");
  }
  // The robot's own sensors are read as often as the controller could use them.
  link_->request_proximity();
}

RealBody::~RealBody() {
  // The run is over: the robot must stand before anything else happens (the next run of a
  // batch, placement, the end of the program). D's reply ("d") carries nothing, so a late
  // reply to an earlier D can pass for the stop's on a slow line: the robot's own speeds,
  // read back (E), tell. A port lost just now (a cable pulled) is reopened by the link
  // every reopen interval: wait for it, within a bound, so that the stop can go out.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < deadline) {
    if (link_->state() == serial::LinkState::kLost) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      continue;
    }
    link_->halt(3000);
    const auto speeds = link_->query(serial::Command::read_speeds(), std::chrono::milliseconds(1500));
    if (speeds && speeds->wheels.left == 0 && speeds->wheels.right == 0) return;
  }
  // Nothing more software can do: say so loudly, so that someone goes to the robot.
  if (const serial::LogCallback& log = link_->config().log) {
    log(serial::LogLevel::kError,
        "could not confirm that the robot stopped (its speeds never read back 0 0 within 10 s): "
        "switch it off by hand");
  }
}

environment::SensorReadings RealBody::sense(TimeUs t_us) {
  // Virtual sensors at the camera's pose: walls, obstacles and every robot, virtual or real.
  environment::SensorReadings r = world_.sense(id_, t_us);
  if (const auto real = link_->latest_proximity()) {
    if (!r.proximity) r.proximity = environment::ProximityValues{};
    // On the Khepera's scale (an e-puck's sensors read 0..4095), then a real obstacle and
    // a virtual one are both "near": the nearer wins, per sensor.
    const int full_scale = link_->config().model.max_sensor_value;
    for (int i = 0; i < environment::kProximityCount; ++i) {
      const int value = full_scale == environment::kProximityMax
                            ? real->value[i]
                            : static_cast<int>(std::lround(static_cast<double>(real->value[i]) *
                                                           environment::kProximityMax / full_scale));
      (*r.proximity)[i] = std::max((*r.proximity)[i], value);
    }
  }
  if (const auto counters = link_->latest_counters()) {
    // In the controllers' pulses of 0.08 mm, whatever the firmware counts (an e-puck's
    // motor steps are 0.129 mm; a Khepera's pass unchanged).
    const double pulse_m = link_->config().model.counter_pulse_m;
    auto in_pulses = [pulse_m](std::int64_t counts) {
      return pulse_m == environment::kKheperaPulse_m
                 ? counts
                 : static_cast<std::int64_t>(
                       std::llround(static_cast<double>(counts) * pulse_m / environment::kKheperaPulse_m));
    };
    r.odometry =
        environment::OdometryReading{in_pulses(counters->value.left_pulses), in_pulses(counters->value.right_pulses)};
  }
  link_->request_proximity();  // fresh for the next step (ignored if one is queued)
  return r;
}

bool RealBody::seen_recently() const {
  const environment::RobotState& s = world_.robot(id_);
  return s.observed && world_.time_us() - s.pose_t_us <= static_cast<TimeUs>(config_.lost_timeout_ms) * 1000;
}

bool RealBody::heading_out(const agents::WheelCommand& wheels) const {
  const environment::RobotState& s = world_.robot(id_);
  const auto& field = world_.map().config().field;
  const double m = config_.geofence_margin_m;
  const Vec2 p = s.pose.position_m;
  // Outward direction of every edge the robot is beyond (the margin's line).
  Vec2 out;
  if (p.x < m) out.x -= 1.0;
  if (p.x > field.width_m - m) out.x += 1.0;
  if (p.y < m) out.y -= 1.0;
  if (p.y > field.height_m - m) out.y += 1.0;
  if (out.x == 0.0 && out.y == 0.0) return false;
  // Beyond the fence only turning on the spot and driving back in are allowed.
  const double forward = 0.5 * (wheels.left + wheels.right);
  const Vec2 heading{std::cos(s.pose.heading_rad), std::sin(s.pose.heading_rad)};
  // A hair of tolerance: a heading parallel to the edge (cos = 6e-17) is not "out".
  return forward * heading.dot(out) > 1e-9;
}

std::optional<Pose2> RealBody::pose() const {
  if (!seen_recently()) return std::nullopt;
  return world_.robot(id_).pose;
}

void RealBody::drive(const agents::WheelCommand& wheels) {
  held_by_.clear();
  if (link_->state() != serial::LinkState::kOk) {
    // A robot whose line failed or vanished is stopped as soon as the line allows (the
    // first command after a replug is a stop); it drives again once the link is healthy.
    held_by_ = "link";
  } else if (!seen_recently()) {
    held_by_ = "lost";
  } else if (heading_out(wheels)) {
    held_by_ = "geofence";
  }
  if (!held_by_.empty()) {
    link_->set_speeds(0, 0);
    return;
  }
  // Controllers speak Khepera units (8 mm/s); another model's firmware takes its own.
  const double per_unit = agents::kMetresPerSecondPerUnit / link_->config().model.speed_unit_mps;
  link_->set_speeds(static_cast<int>(std::lround(wheels.left * per_unit)),
                    static_cast<int>(std::lround(wheels.right * per_unit)));
}

void RealBody::stop() { link_->set_speeds(0, 0); }

std::string_view RealBody::health() const {
  switch (link_->state()) {
    case serial::LinkState::kLost: return "link lost";
    case serial::LinkState::kUnresponsive: return "link unresponsive";
    default: break;
  }
  if (held_by_ == "lost") return "unseen";
  if (held_by_ == "geofence") return "geofence";
  return "ok";
}

}  // namespace rilbed::run

#include "links/lcm_bus.hpp"

#include <cctype>

namespace rilbed::links {

Channels Channels::with_prefix(const std::string& prefix) {
  Channels c;
  c.poses = prefix + c.poses;
  c.events = prefix + c.events;
  c.status = prefix + c.status;
  c.world = prefix + c.world;
  return c;
}

std::optional<std::string> check_channel_prefix(const std::string& prefix) {
  for (const char c : prefix) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') {
      return "channel prefix '" + prefix + "' may hold only letters, digits and '_'";
    }
  }
  // The longest channel, RILBED_EVENTS/RILBED_STATUS, is 13 bytes; LCM allows 63.
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

rilbed::poses_t to_lcm(TimeUs t_us, std::span<const agents::PoseReport> poses) {
  rilbed::poses_t m;
  m.utime = t_us;
  m.num_robots = static_cast<std::int32_t>(poses.size());
  m.robots.reserve(poses.size());
  for (const agents::PoseReport& p : poses) {
    rilbed::robot_pose_t r;
    r.id = p.id;
    r.real = p.real;
    r.seen = p.seen;
    r.x_m = p.pose.position_m.x;
    r.y_m = p.pose.position_m.y;
    r.theta_rad = p.pose.heading_rad;
    r.behaviour = std::string(p.behaviour);
    r.health = std::string(p.health);
    m.robots.push_back(std::move(r));
  }
  return m;
}

rilbed::event_t to_lcm(const agents::RunEvent& event) {
  rilbed::event_t m;
  m.utime = event.t_us;
  m.kind = event.kind;
  m.id = event.id;
  m.other = event.other;
  m.detail = event.detail;
  return m;
}

rilbed::status_t to_lcm(const agents::StatusReport& s) {
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

rilbed::world_t to_lcm(TimeUs t_us, const agents::WorldReport& w) {
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

LcmRunPublisher::LcmRunPublisher(lcm::LCM& lcm, Channels channels, bool in_process)
    : lcm_(lcm), channels_(std::move(channels)), in_process_(in_process) {}

template <typename Message>
void LcmRunPublisher::publish(const std::string& channel, const Message& message) {
  const int status = lcm_.publish(channel, &message);
  {
    std::lock_guard lock(mutex_);
    ChannelCount& c = counts_[channel];
    if (status == 0) {
      ++c.messages;
      c.bytes += static_cast<std::uint64_t>(message.getEncodedSize());
    } else {
      ++c.failures;  // lost, as on a lossy network; the run goes on
    }
  }
  if (in_process_) {
    // memq:// queues every message until handled: deliver to the in-process subscribers now.
    while (lcm_.handleTimeout(0) > 0) {
    }
  }
}

void LcmRunPublisher::on_world(TimeUs t_us, const agents::WorldReport& world) { publish(channels_.world, to_lcm(t_us, world)); }

void LcmRunPublisher::on_poses(TimeUs t_us, std::span<const agents::PoseReport> poses) {
  publish(channels_.poses, to_lcm(t_us, poses));
}

void LcmRunPublisher::on_event(const agents::RunEvent& event) { publish(channels_.events, to_lcm(event)); }

void LcmRunPublisher::on_status(const agents::StatusReport& status) { publish(channels_.status, to_lcm(status)); }

std::map<std::string, ChannelCount> LcmRunPublisher::counts() const {
  std::lock_guard lock(mutex_);
  return counts_;
}

}  // namespace rilbed::links

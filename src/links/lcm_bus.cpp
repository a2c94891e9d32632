#include "links/lcm_bus.hpp"

#include "links/lcm_checked.hpp"

#include <cctype>
#include <fstream>
#include <iterator>
#include <chrono>
#include <cstdio>
#include <limits>
#include <type_traits>

namespace rilbed::links {

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

Channels Channels::with_prefix(const std::string& prefix) {
  Channels c;
  c.poses = prefix + c.poses;
  c.events = prefix + c.events;
  c.status = prefix + c.status;
  c.world = prefix + c.world;
  c.summary = prefix + c.summary;
  c.console = prefix + c.console;
  c.console_reply = prefix + c.console_reply;
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

void fill(rilbed::poses_t& m, TimeUs t_us, std::span<const agents::PoseReport> poses) {
  m.utime = t_us;
  m.num_robots = static_cast<std::int32_t>(poses.size());
  // Resized, not rebuilt: a message kept between steps keeps its strings' storage, so a
  // step of 10,000 robots does not allocate 20,000 strings.
  m.robots.resize(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const agents::PoseReport& p = poses[i];
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

rilbed::poses_t to_lcm(TimeUs t_us, std::span<const agents::PoseReport> poses) {
  rilbed::poses_t m;
  fill(m, t_us, poses);
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

rilbed::summary_t to_lcm(TimeUs t_us, const nlohmann::json& summary) {
  rilbed::summary_t m;
  m.utime = t_us;
  m.json = summary.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  return m;
}

namespace {

agents::WorldReport from_lcm(const rilbed::world_t& m) {
  agents::WorldReport w;
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

agents::StatusReport from_lcm(const rilbed::status_t& m) {
  agents::StatusReport s;
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
  return s;
}

}  // namespace

RunReportDecoder::RunReportDecoder(Channels channels, agents::RunObserver& observer)
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
    observer_.on_status(from_lcm(m));
  } else if (channel == channels_.world) {
    rilbed::world_t m;
    if (!decode_checked(data, size, m)) return bad("world_t");
    observer_.on_world(m.utime, from_lcm(m));
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
    return (std::uint32_t{bytes_[at]} << 24) | (std::uint32_t{bytes_[at + 1]} << 16) | (std::uint32_t{bytes_[at + 2]} << 8) |
           std::uint32_t{bytes_[at + 3]};
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

LcmRunPublisher::LcmRunPublisher(lcm::LCM& lcm, Channels channels, bool in_process, lcm::LogFile* log)
    : lcm_(lcm), channels_(std::move(channels)), in_process_(in_process), log_(log) {}

template <typename Message>
void LcmRunPublisher::publish(const std::string& channel, const Message& message) {
  std::lock_guard lock(mutex_);
  // Encoded once: the same bytes go on the bus and into the log.
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
  const int status = lcm_.publish(channel, buffer_.data(), static_cast<unsigned>(size));
  if (status == 0) {
    ++c.messages;
    c.bytes += static_cast<std::uint64_t>(size);
  } else {
    ++c.failures;  // lost, as on a lossy network; the run goes on
  }
  if (log_) {
    lcm::LogEvent event;
    event.eventnum = log_events_++;
    event.timestamp = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::system_clock::now().time_since_epoch()).count();
    event.channel = channel;
    event.datalen = size;
    event.data = buffer_.data();
    log_->writeEvent(&event);
  }
  if (in_process_) {
    // memq:// queues every message until handled: deliver to the in-process subscribers now.
    while (lcm_.handleTimeout(0) > 0) {
    }
  }
}

void LcmRunPublisher::on_world(TimeUs t_us, const agents::WorldReport& world) { publish(channels_.world, to_lcm(t_us, world)); }

void LcmRunPublisher::on_poses(TimeUs t_us, std::span<const agents::PoseReport> poses) {
  fill(poses_message_, t_us, poses);
  publish(channels_.poses, poses_message_);
}

void LcmRunPublisher::on_event(const agents::RunEvent& event) { publish(channels_.events, to_lcm(event)); }

void LcmRunPublisher::on_status(const agents::StatusReport& status) {
  publish(channels_.status, to_lcm(status));
  if (log_) std::fflush(log_->getFilePtr());  // a run cut short keeps its log up to the last second
}

void LcmRunPublisher::on_summary(TimeUs t_us, const nlohmann::json& summary) {
  publish(channels_.summary, to_lcm(t_us, summary));
  if (log_) std::fflush(log_->getFilePtr());  // the whole run is on disk once it has ended
}

std::map<std::string, ChannelCount> LcmRunPublisher::counts() const {
  std::lock_guard lock(mutex_);
  return counts_;
}

}  // namespace rilbed::links

// Fuzz target for the LCM messages of a run (src/bus/lcm_bus.hpp): the first input byte
// picks one of the run's channels (Channels::with_prefix(""): poses, events, status, world,
// summary, or a channel that is none of them), the rest are the message's bytes, as they
// would come off the bus, for RunReportDecoder::decode. The observer reads every field it
// is handed (touching_observer.hpp), so that ASan sees any read the decoder should not make.
//
// Whatever the bytes, decode never throws. Beyond that, what is checked holds whatever
// messages the decoder accepts:
//   - it accepts the bytes exactly when lcm-gen's decoder of the channel's type reads all
//     of them (for the summary: and its text is a JSON object); an accepted message makes
//     exactly one call of the observer, a refused one none, with a reason that names the
//     channel; a channel that is not the run's is ignored;
//   - the observer gets what lcm-gen's decoder read (every field, as from_lcm maps it);
//   - the message round-trips: encoding what was decoded gives the input again, except
//     that a string's terminating byte is written as 0 (the decoder does not look at it)
//     and a string holding a 0 byte is cut there (LCM strings are C strings): then the
//     encoding is shorter than the input, and than getEncodedSize() (which counts the
//     whole string); in either case decoding the encoding and encoding that again gives
//     the same bytes.
// (The decoder refuses a message whose counts or string lengths its bytes cannot hold before lcm-gen's
// decoder sees it; such bytes are not shown to lcm-gen's decoder here either.)
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "bus/lcm_bus.hpp"
#include "bus/lcm_checked.hpp"
#include "bus/lcm_conversion.hpp"
#include "bus/report_decoder.hpp"
#include "environment/shapes.hpp"
#include "touching_observer.hpp"

namespace {

using namespace rilbed;

std::string g_channel;  // the channel of the input being checked, for the report

[[noreturn]] void broken(const char* what) {
  std::fprintf(stderr, "\nfuzz_lcm_messages: invariant broken on channel %s: %s\n", g_channel.c_str(), what);
  std::abort();
}
#define FUZZ_CHECK(condition)             \
  do {                                    \
    if (!(condition)) broken(#condition); \
  } while (false)

// The channels the first byte picks from: the run's five and one it does not use.
const std::vector<std::string>& channel_names() {
  static const std::vector<std::string> names = [] {
    const bus::Channels c = bus::Channels::with_prefix("");
    return std::vector<std::string>{c.poses,         c.events,  c.status,         c.world,        c.summary,
                                    c.wheels,        c.sensors, c.detections,     c.frames,       c.camera,
                                    c.sensor_layout, c.vision,  "RILBED_UNKNOWN", c.robot_bodies, c.sensor_models};
  }();
  return names;
}
enum Pick {
  kPoses,
  kEvents,
  kStatus,
  kWorld,
  kSummary,
  kWheels,
  kSensors,
  kDetections,
  kFrames,
  kCamera,
  kSensorLayout,
  kVision,
  kUnknown,  // (before the later channels: the seeds' first bytes keep their channels)
  kRobotBodies,
  kSensorModels,
  kPicks
};

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

bool has_nul(const std::string& s) { return s.find('\0') != std::string::npos; }
// Whether a message holds a string with a 0 byte (which LCM's encoder cuts there).
bool has_nul(const rilbed::event_t& m) { return has_nul(m.kind) || has_nul(m.detail); }
bool has_nul(const rilbed::status_t& m) {
  return has_nul(m.scenario) || has_nul(m.mode) || has_nul(m.state) || has_nul(m.ended_by);
}
bool has_nul(const rilbed::world_t& m) { return has_nul(m.scenario); }
bool has_nul(const rilbed::summary_t& m) { return has_nul(m.json); }
bool has_nul(const rilbed::wheels_t&) { return false; }
bool has_nul(const rilbed::sensors_t&) { return false; }
bool has_nul(const rilbed::detections_t&) { return false; }
bool has_nul(const rilbed::frame_t& m) { return has_nul(m.format); }
bool has_nul(const rilbed::camera_t& m) { return has_nul(m.source); }
bool has_nul(const rilbed::vision_settings_t&) { return false; }
bool has_nul(const rilbed::sensor_layout_t&) { return false; }
bool has_nul(const rilbed::sensor_models_t& m) {
  for (const rilbed::robot_models_t& r : m.robots)
    for (const rilbed::model_reading_t& reading : r.readings)
      if (has_nul(reading.name)) return true;
  return false;
}
bool has_nul(const rilbed::robot_bodies_t& m) {
  for (const rilbed::robot_body_t& b : m.bodies)
    if (has_nul(b.name)) return true;
  return false;
}
bool has_nul(const rilbed::poses_t& m) {
  for (const rilbed::robot_pose_t& r : m.robots) {
    if (has_nul(r.behaviour) || has_nul(r.health)) return true;
  }
  return false;
}

// lcm-gen's decoder on the bytes: whether it reads all of them (a count it cannot
// allocate for, or a negative one, throws: that is "no" too).
template <typename Message>
bool generated_decode(const std::uint8_t* data, std::size_t size, Message& m) {
  if (size > static_cast<std::size_t>(std::numeric_limits<int>::max())) return false;
  try {
    return m.decode(data, 0, static_cast<int>(size)) == static_cast<int>(size);
  } catch (const std::exception&) {
    return false;
  }
}

template <typename Message>
void check_round_trip(const Message& m, const std::uint8_t* data, std::size_t size) {
  // getEncodedSize counts a string's size(), encode writes it up to its first 0 byte.
  const int n = m.getEncodedSize();
  FUZZ_CHECK(n >= 8);
  std::vector<std::uint8_t> encoded(static_cast<std::size_t>(n));
  const int written = m.encode(encoded.data(), 0, n);
  FUZZ_CHECK(written >= 8 && written <= n);
  encoded.resize(static_cast<std::size_t>(written));
  if (!has_nul(m)) {
    FUZZ_CHECK(written == n && encoded.size() == size);
    for (std::size_t i = 0; i < size; ++i) FUZZ_CHECK(encoded[i] == data[i] || encoded[i] == 0);
  } else {
    FUZZ_CHECK(written < n && encoded.size() < size);
  }
  Message again;
  FUZZ_CHECK(again.decode(encoded.data(), 0, written) == written);
  FUZZ_CHECK(!has_nul(again) && again.getEncodedSize() == written);
  std::vector<std::uint8_t> reencoded(static_cast<std::size_t>(written));
  FUZZ_CHECK(again.encode(reencoded.data(), 0, written) == written);
  FUZZ_CHECK(reencoded == encoded);
}

void check_poses(const rilbed_fuzz::TouchingObserver& seen, const rilbed::poses_t& m) {
  FUZZ_CHECK(seen.calls.poses == 1);
  FUZZ_CHECK(seen.last_poses_t_us == m.utime);
  FUZZ_CHECK(m.num_robots >= 0 && static_cast<std::size_t>(m.num_robots) == m.robots.size());
  FUZZ_CHECK(seen.last_poses.size() == m.robots.size());
  for (std::size_t i = 0; i < m.robots.size(); ++i) {
    const rilbed::robot_pose_t& r = m.robots[i];
    const rilbed_fuzz::OwnedPose& p = seen.last_poses[i];
    FUZZ_CHECK(p.id == r.id && p.real == (r.real != 0) && p.seen == (r.seen != 0));
    FUZZ_CHECK(same_bits(p.pose.position_m.x, r.x_m) && same_bits(p.pose.position_m.y, r.y_m));
    FUZZ_CHECK(same_bits(p.pose.heading_rad, r.theta_rad));
    FUZZ_CHECK(p.behaviour == r.behaviour && p.health == r.health);
  }
}

void check_event(const rilbed_fuzz::TouchingObserver& seen, const rilbed::event_t& m) {
  FUZZ_CHECK(seen.calls.event == 1);
  const run::RunEvent& e = seen.last_event;
  FUZZ_CHECK(e.t_us == m.utime && e.kind == m.kind && e.id == m.id && e.other == m.other && e.detail == m.detail);
}

void check_status(const rilbed_fuzz::TouchingObserver& seen, const bus::RunReportDecoder& decoder,
                  const rilbed::status_t& m) {
  FUZZ_CHECK(seen.calls.status == 1);
  const run::StatusReport& s = seen.last_status;
  FUZZ_CHECK(s.t_us == m.utime && same_bits(s.wall_s, static_cast<double>(m.wall_utime) * 1e-6));
  FUZZ_CHECK(s.scenario == m.scenario && s.seed == static_cast<std::uint64_t>(m.seed) && s.mode == m.mode);
  FUZZ_CHECK(s.realtime == (m.realtime != 0) && same_bits(s.rt_factor, m.rt_factor));
  FUZZ_CHECK(s.state == m.state && s.ended_by == m.ended_by);
  FUZZ_CHECK(s.robots == m.num_robots && s.real_robots == m.num_real && s.formed == (m.formed != 0));
  // -1 (any negative, or NaN) while not formed.
  FUZZ_CHECK(s.formation_time_s.has_value() == (m.formation_time_s >= 0.0));
  if (s.formation_time_s) FUZZ_CHECK(same_bits(*s.formation_time_s, m.formation_time_s));
  FUZZ_CHECK(s.collisions == m.collisions);
  FUZZ_CHECK(same_bits(s.loop_latency_ms, m.loop_latency_ms) && same_bits(s.camera_fps, m.camera_fps));
  FUZZ_CHECK(s.frames == m.frames);
  // The decoder keeps the message itself as the last status.
  FUZZ_CHECK(decoder.last_status().has_value());
  const rilbed::status_t& kept = *decoder.last_status();
  const int n = m.getEncodedSize();
  FUZZ_CHECK(kept.getEncodedSize() == n);
  std::vector<std::uint8_t> a(static_cast<std::size_t>(n)), b(static_cast<std::size_t>(n));
  // A string holding a 0 byte is written up to it: compare what encode() wrote.
  const int wa = m.encode(a.data(), 0, n);
  const int wb = kept.encode(b.data(), 0, n);
  FUZZ_CHECK(wa > 0 && wa == wb && std::equal(a.begin(), a.begin() + wa, b.begin()));
}

void check_world(const rilbed_fuzz::TouchingObserver& seen, const rilbed::world_t& m) {
  FUZZ_CHECK(seen.calls.world == 1);
  FUZZ_CHECK(seen.last_world_t_us == m.utime);
  const run::WorldReport& w = seen.last_world;
  FUZZ_CHECK(w.scenario == m.scenario && w.walls == (m.walls != 0));
  FUZZ_CHECK(same_bits(w.field.width_m, m.width_m) && same_bits(w.field.height_m, m.height_m));
  auto same_points = [](const std::vector<Vec2>& points, const rilbed::polyline_t& p) {
    if (p.num_points < 0 || p.x_m.size() != static_cast<std::size_t>(p.num_points) || p.y_m.size() != p.x_m.size()) {
      return false;
    }
    if (points.size() != p.x_m.size()) return false;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!same_bits(points[i].x, p.x_m[i]) || !same_bits(points[i].y, p.y_m[i])) return false;
    }
    return true;
  };
  FUZZ_CHECK(w.field.obstacles.size() == m.obstacles.size());
  for (std::size_t i = 0; i < m.obstacles.size(); ++i) FUZZ_CHECK(same_points(w.field.obstacles[i], m.obstacles[i]));
  FUZZ_CHECK(w.field.tracks.size() == m.tracks.size());
  for (std::size_t i = 0; i < m.tracks.size(); ++i) {
    FUZZ_CHECK(same_points(w.field.tracks[i].first, m.tracks[i]));
    FUZZ_CHECK(same_bits(w.field.tracks[i].second, m.tracks[i].width_m));
  }
  FUZZ_CHECK(m.beacon_x_m.size() == m.beacon_y_m.size() && w.field.beacons.size() == m.beacon_x_m.size());
  for (std::size_t i = 0; i < m.beacon_x_m.size(); ++i) {
    FUZZ_CHECK(same_bits(w.field.beacons[i].x, m.beacon_x_m[i]) && same_bits(w.field.beacons[i].y, m.beacon_y_m[i]));
  }
  FUZZ_CHECK(m.robot_ids.size() == m.robot_real.size());
  FUZZ_CHECK(w.robot_ids == std::vector<int>(m.robot_ids.begin(), m.robot_ids.end()));
  std::set<int> real;
  for (std::size_t i = 0; i < m.robot_ids.size(); ++i) {
    if (m.robot_real[i]) real.insert(m.robot_ids[i]);
  }
  FUZZ_CHECK(w.field.real_robot_ids == real);
}

void check_wheels(const rilbed_fuzz::TouchingObserver& seen, const rilbed::wheels_t& m) {
  FUZZ_CHECK(seen.calls.wheels == 1 && seen.last_wheels.size() == m.robots.size());
  for (std::size_t i = 0; i < m.robots.size(); ++i) {
    const auto& w = seen.last_wheels[i];
    FUZZ_CHECK(w.id == m.robots[i].id && w.wheels.left == m.robots[i].left_units &&
               w.wheels.right == m.robots[i].right_units);
  }
}

void check_sensors(const rilbed_fuzz::TouchingObserver& seen, const rilbed::sensors_t& m) {
  FUZZ_CHECK(seen.calls.sensors == 1 && seen.last_sensors.size() == m.robots.size());
  for (std::size_t i = 0; i < m.robots.size(); ++i) {
    const rilbed::robot_sensors_t& r = m.robots[i];
    const auto& [id, s] = seen.last_sensors[i];
    FUZZ_CHECK(id == r.id && s.t_us == m.utime);
    // Eight proximity values or none (a robot without the Khepera's ring).
    FUZZ_CHECK(s.proximity.has_value() == (r.proximity.size() == 8));
    if (s.proximity) FUZZ_CHECK(std::equal(s.proximity->begin(), s.proximity->end(), r.proximity.begin()));
    FUZZ_CHECK(s.ranges.size() == r.range_m.size());
    for (std::size_t k = 0; k < s.ranges.size(); ++k) {
      FUZZ_CHECK(same_bits(s.ranges[k].distance_m, r.range_m[k]) && s.ranges[k].hit == (r.range_hit[k] != 0));
    }
    FUZZ_CHECK(s.beacons.size() == r.beacon_id.size());
    for (std::size_t k = 0; k < s.beacons.size(); ++k) {
      FUZZ_CHECK(s.beacons[k].id == r.beacon_id[k] && same_bits(s.beacons[k].bearing_rad, r.beacon_bearing_rad[k]));
    }
    FUZZ_CHECK(std::equal(s.track.begin(), s.track.end(), r.track.begin(), r.track.end()));
    FUZZ_CHECK(s.odometry.has_value() == (r.has_odometry != 0));
    if (s.odometry) FUZZ_CHECK(s.odometry->left_pulses == r.left_pulses && s.odometry->right_pulses == r.right_pulses);
  }
}

void check_detections(const rilbed_fuzz::TouchingObserver& seen, const rilbed::detections_t& m) {
  FUZZ_CHECK(seen.calls.detections == 1 && seen.last_frame_number == m.frame);
  FUZZ_CHECK(seen.last_detections.size() == m.detections.size());
  for (std::size_t i = 0; i < m.detections.size(); ++i) {
    const auto& d = seen.last_detections[i];
    const rilbed::detection_t& x = m.detections[i];
    FUZZ_CHECK(d.id == x.id && same_bits(d.u_px, x.u_px) && same_bits(d.v_px, x.v_px) && same_bits(d.score, x.score));
    FUZZ_CHECK(same_bits(d.heading_deg, x.heading_deg) && same_bits(d.pose.position_m.x, x.x_m));
  }
}

void check_summary(const rilbed_fuzz::TouchingObserver& seen, const bus::RunReportDecoder& decoder,
                   const rilbed::summary_t& m) {
  FUZZ_CHECK(seen.calls.summary == 1 && decoder.summary_seen());
  FUZZ_CHECK(seen.last_summary_t_us == m.utime);
  FUZZ_CHECK(seen.last_summary.is_object());
  FUZZ_CHECK(seen.last_summary == nlohmann::json::parse(m.json, nullptr, false));
}

// The decoder walks every message (links::well_formed) before lcm-gen's decoder sees it,
// refusing a count or a string length its bytes cannot hold: no point (and gigabytes, or
// a read far past the buffer) in asking lcm-gen's decoder about those.
template <typename Message>
bool refused_before_decoding(const std::uint8_t* data, std::size_t size) {
  return !bus::well_formed<Message>(data, size);
}

// What the decoder should have made of `data`, with lcm-gen's decoder of the channel's type.
template <typename Message, typename Check>
void check_channel(const std::optional<std::string>& problem, const std::uint8_t* data, std::size_t size,
                   const Check& check_accepted) {
  if (problem && refused_before_decoding<Message>(data, size)) return;
  Message m;
  const bool readable = generated_decode(data, size, m);
  if (problem) {
    FUZZ_CHECK(!readable);
    return;
  }
  FUZZ_CHECK(readable);
  check_accepted(m);
  check_round_trip(m, data, size);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const auto pick = static_cast<Pick>(data[0] % kPicks);
  g_channel = channel_names()[pick];
  // The message alone, so that ASan sees a read past its end.
  const std::uint8_t* message = data + 1;
  const std::size_t length = size - 1;

  rilbed_fuzz::TouchingObserver seen;
  bus::RunReportDecoder decoder(bus::Channels::with_prefix(""), seen);
  std::optional<std::string> problem;
  try {
    problem = decoder.decode(g_channel, message, length);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\nfuzz_lcm_messages: decode threw: %s\n", e.what());
    broken("RunReportDecoder::decode threw");
  } catch (...) {
    broken("RunReportDecoder::decode threw a non-std exception");
  }

  if (problem) {
    FUZZ_CHECK(seen.calls.total() == 0);
    FUZZ_CHECK(problem->rfind(g_channel + ": ", 0) == 0);
  } else {
    // A camera is kept for the next world (which carries it), sensor models for the next
    // sensors: no call of their own.
    const bool kept =
        pick == kCamera || pick == kSensorLayout || pick == kVision || pick == kRobotBodies || pick == kSensorModels;
    FUZZ_CHECK(seen.calls.total() == (pick == kUnknown || kept ? 0 : 1));
  }
  FUZZ_CHECK(decoder.summary_seen() == (seen.calls.summary == 1));
  FUZZ_CHECK(decoder.last_status().has_value() == (seen.calls.status == 1));

  switch (pick) {
    case kPoses:
      check_channel<rilbed::poses_t>(problem, message, length, [&](const rilbed::poses_t& m) { check_poses(seen, m); });
      break;
    case kEvents:
      check_channel<rilbed::event_t>(problem, message, length, [&](const rilbed::event_t& m) { check_event(seen, m); });
      break;
    case kStatus:
      check_channel<rilbed::status_t>(problem, message, length,
                                      [&](const rilbed::status_t& m) { check_status(seen, decoder, m); });
      break;
    case kWorld:
      check_channel<rilbed::world_t>(problem, message, length, [&](const rilbed::world_t& m) { check_world(seen, m); });
      break;
    case kSummary: {
      // Refused also when the bytes are a summary_t whose text is not a JSON object.
      rilbed::summary_t m;
      if (problem && refused_before_decoding<rilbed::summary_t>(message, length)) break;
      const bool readable = generated_decode(message, length, m);
      if (problem) {
        if (readable) {
          const nlohmann::json parsed = nlohmann::json::parse(m.json, nullptr, false);
          FUZZ_CHECK(parsed.is_discarded() || !parsed.is_object());
        }
      } else {
        FUZZ_CHECK(readable);
        check_summary(seen, decoder, m);
        check_round_trip(m, message, length);
      }
      break;
    }
    case kWheels:
      check_channel<rilbed::wheels_t>(problem, message, length,
                                      [&](const rilbed::wheels_t& m) { check_wheels(seen, m); });
      break;
    case kSensors:
      check_channel<rilbed::sensors_t>(problem, message, length,
                                       [&](const rilbed::sensors_t& m) { check_sensors(seen, m); });
      break;
    case kDetections:
      check_channel<rilbed::detections_t>(problem, message, length,
                                          [&](const rilbed::detections_t& m) { check_detections(seen, m); });
      break;
    case kFrames: {
      // Accepted exactly when the bytes are a frame_t whose data is a JPEG image of its
      // stated size; the observer then has that image.
      rilbed::frame_t m;
      if (problem && refused_before_decoding<rilbed::frame_t>(message, length)) break;
      const bool readable = generated_decode(message, length, m);
      if (!problem) {
        FUZZ_CHECK(readable && m.format == "jpeg");
        FUZZ_CHECK(seen.calls.frames == 1 && seen.last_frame_number == m.frame);
        FUZZ_CHECK(seen.last_image_size == cv::Size(m.width_px, m.height_px));
        check_round_trip(m, message, length);
      }
      break;
    }
    case kCamera: {
      // Accepted exactly when the bytes are a camera_t of a plausible size; the next world
      // then carries what it said.
      rilbed::camera_t m;
      if (problem && refused_before_decoding<rilbed::camera_t>(message, length)) break;
      const bool readable = generated_decode(message, length, m);
      const bool plausible = m.width_px > 0 && m.height_px > 0 && m.width_px <= 100000 && m.height_px <= 100000;
      if (problem) {
        FUZZ_CHECK(!readable || !plausible);
        break;
      }
      FUZZ_CHECK(readable && plausible);
      check_round_trip(m, message, length);
      rilbed::world_t world{};
      std::vector<std::uint8_t> bytes(static_cast<std::size_t>(world.getEncodedSize()));
      FUZZ_CHECK(world.encode(bytes.data(), 0, static_cast<int>(bytes.size())) > 0);
      FUZZ_CHECK(!decoder.decode(bus::Channels::with_prefix("").world, bytes.data(), bytes.size()));
      FUZZ_CHECK(seen.calls.world == 1 && seen.last_world.camera.has_value());
      const run::CameraReport& c = *seen.last_world.camera;
      FUZZ_CHECK(c.width_px == m.width_px && c.height_px == m.height_px &&
                 c.lens_distortion == (m.lens_distortion != 0));
      for (int i = 0; i < 9; ++i)
        FUZZ_CHECK(same_bits(c.image_to_field[static_cast<std::size_t>(i)], m.image_to_field[i]));
      FUZZ_CHECK(c.source == m.source);
      break;
    }
    case kVision: {
      // Accepted exactly when the bytes are a vision_settings_t that check_vision_settings
      // takes; the next status (and only it) then carries the settings.
      rilbed::vision_settings_t m;
      if (problem && refused_before_decoding<rilbed::vision_settings_t>(message, length)) break;
      const bool readable = generated_decode(message, length, m);
      const vision::VisionSettings s = bus::from_lcm(m);
      const bool usable = readable && !vision::check_vision_settings(s);
      FUZZ_CHECK(usable == !problem);
      if (problem) break;
      check_round_trip(m, message, length);
      rilbed::status_t status;
      std::vector<std::uint8_t> bytes(static_cast<std::size_t>(status.getEncodedSize()));
      FUZZ_CHECK(status.encode(bytes.data(), 0, static_cast<int>(bytes.size())) > 0);
      const std::string channel = bus::Channels::with_prefix("").status;
      FUZZ_CHECK(!decoder.decode(channel, bytes.data(), bytes.size()));
      FUZZ_CHECK(seen.calls.status == 1 && seen.last_status.vision == s);
      FUZZ_CHECK(!decoder.decode(channel, bytes.data(), bytes.size()));
      FUZZ_CHECK(seen.calls.status == 2 && !seen.last_status.vision);
      break;
    }
    case kSensorLayout: {
      // Accepted exactly when the bytes are a sensor_layout_t whose robots name geometries
      // it has and whose track points come element by element; the next world carries it.
      rilbed::sensor_layout_t m;
      if (problem && refused_before_decoding<rilbed::sensor_layout_t>(message, length)) break;
      const bool readable = generated_decode(message, length, m);
      bool consistent = readable;
      for (std::size_t k = 0; consistent && k < m.geometry_of.size(); ++k) {
        consistent = m.geometry_of[k] >= 0 && m.geometry_of[k] < m.num_geometries;
      }
      for (const auto& g : m.geometries) {
        std::int32_t next = 0;
        for (const std::int32_t e : g.track_sensor) {
          if (e == next)
            ++next;
          else if (e != next - 1)
            consistent = false;
        }
      }
      if (problem) {
        FUZZ_CHECK(!consistent);
        break;
      }
      FUZZ_CHECK(consistent);
      check_round_trip(m, message, length);
      rilbed::world_t world{};
      std::vector<std::uint8_t> bytes(static_cast<std::size_t>(world.getEncodedSize()));
      FUZZ_CHECK(world.encode(bytes.data(), 0, static_cast<int>(bytes.size())) > 0);
      FUZZ_CHECK(!decoder.decode(bus::Channels::with_prefix("").world, bytes.data(), bytes.size()));
      FUZZ_CHECK(seen.calls.world == 1);
      const run::WorldReport& w = seen.last_world;
      FUZZ_CHECK(w.sensor_geometries.size() == m.geometries.size());
      std::set<std::int32_t> ids(m.robot_ids.begin(), m.robot_ids.end());
      FUZZ_CHECK(w.sensor_geometry_of.size() == ids.size());
      for (std::size_t k = 0; k < m.geometries.size(); ++k) {
        const auto& in = m.geometries[k];
        const auto& out = w.sensor_geometries[k];
        FUZZ_CHECK(out.ranges.size() == in.range_mount_rad.size() && out.beacon_finder == (in.beacon_finder != 0));
        std::size_t points = 0;
        for (const auto& element : out.track_points_m) points += element.size();
        FUZZ_CHECK(points == in.track_sensor.size());
      }
      break;
    }
    case kRobotBodies: {
      // Accepted exactly when the bytes are a robot_bodies_t whose bodies are drawable (a
      // radius and wheels in range, no outline or a convex one around the centre) and whose
      // robots name bodies it has; the next world carries them.
      rilbed::robot_bodies_t m;
      if (problem && refused_before_decoding<rilbed::robot_bodies_t>(message, length)) break;
      const bool readable = generated_decode(message, length, m);
      const bool usable = readable && static_cast<bool>(bus::from_lcm(m));
      FUZZ_CHECK(usable == !problem);
      if (problem) break;
      check_round_trip(m, message, length);
      rilbed::world_t world{};
      std::vector<std::uint8_t> bytes(static_cast<std::size_t>(world.getEncodedSize()));
      FUZZ_CHECK(world.encode(bytes.data(), 0, static_cast<int>(bytes.size())) > 0);
      FUZZ_CHECK(!decoder.decode(bus::Channels::with_prefix("").world, bytes.data(), bytes.size()));
      const run::WorldReport& w = seen.last_world;
      FUZZ_CHECK(w.bodies.size() == m.bodies.size());
      for (const run::BodyDrawing& b : w.bodies) {
        FUZZ_CHECK(b.radius_m > 0.0 && b.wheel_base_m > 0.0 && b.wheel_radius_m > 0.0);
        FUZZ_CHECK(b.outline_m.empty() || environment::polygon_signed_area(b.outline_m) > 0.0);
      }
      for (const auto& [id, index] : w.body_of)
        FUZZ_CHECK(index >= 0 && static_cast<std::size_t>(index) < w.bodies.size());
      break;
    }
    case kSensorModels: {
      // Taken whenever the bytes are a sensor_models_t; the sensors_t of its utime carries
      // each of its robots' readings and marks, or says why a robot's are left out.
      rilbed::sensor_models_t m;
      if (problem && refused_before_decoding<rilbed::sensor_models_t>(message, length)) break;
      const bool readable = generated_decode(message, length, m);
      FUZZ_CHECK(readable == !problem);
      if (problem) break;
      check_round_trip(m, message, length);
      rilbed::sensors_t step{};
      step.utime = m.utime;
      std::set<std::int32_t> ids;
      for (const rilbed::robot_models_t& r : m.robots)
        if (ids.insert(r.id).second) step.robots.emplace_back().id = r.id;
      step.num_robots = static_cast<std::int32_t>(step.robots.size());
      std::vector<std::uint8_t> bytes(static_cast<std::size_t>(step.getEncodedSize()));
      FUZZ_CHECK(step.encode(bytes.data(), 0, static_cast<int>(bytes.size())) > 0);
      const auto merged = decoder.decode(bus::Channels::with_prefix("").sensors, bytes.data(), bytes.size());
      FUZZ_CHECK(seen.calls.sensors == 1);
      // Every entry is merged in turn (a robot's later entry replaces its earlier one): the
      // step says so exactly when one of them is bad.
      bool any_bad = false;
      for (const rilbed::robot_models_t& r : m.robots) {
        environment::SensorReadings scratch;
        std::set<std::string, std::less<>> names;
        any_bad = any_bad || bus::merge_models(r, scratch, names).has_value();
      }
      FUZZ_CHECK(any_bad == merged.has_value());
      break;
    }
    case kUnknown:
    case kPicks: FUZZ_CHECK(!problem); break;
  }
  // Keep the observer's reads.
  if (seen.sink == 0x5eed5eed5eed5eedULL) std::fputc('\0', stderr);
  return 0;
}

#include "bus/lcm_checked.hpp"

namespace rilbed::bus {

namespace {

// Reads an encoding front to back; any read past the end makes it fail for good.
class Walk {
 public:
  Walk(const void* data, std::size_t size) : p_(static_cast<const std::uint8_t*>(data)), left_(size) {}
  bool ok() const { return ok_; }
  bool done() const { return ok_ && left_ == 0; }
  void skip(std::size_t n) {
    if (!ok_ || n > left_) {
      ok_ = false;
      return;
    }
    p_ += n;
    left_ -= n;
  }
  std::int32_t i32() {
    if (!ok_ || left_ < 4) {
      ok_ = false;
      return 0;
    }
    const auto v = static_cast<std::int32_t>((std::uint32_t{p_[0]} << 24) | (std::uint32_t{p_[1]} << 16) |
                                             (std::uint32_t{p_[2]} << 8) | std::uint32_t{p_[3]});
    skip(4);
    return v;
  }
  std::int8_t i8() {
    if (!ok_ || left_ < 1) {
      ok_ = false;
      return 0;
    }
    const auto v = static_cast<std::int8_t>(p_[0]);
    skip(1);
    return v;
  }
  std::int16_t i16() {
    if (!ok_ || left_ < 2) {
      ok_ = false;
      return 0;
    }
    const auto v = static_cast<std::int16_t>((std::uint16_t{p_[0]} << 8) | std::uint16_t{p_[1]});
    skip(2);
    return v;
  }
  void i64() { skip(8); }
  void f64() { skip(8); }
  void boolean() { skip(1); }
  // A string: its length (terminator included, so at least 1), then that many bytes.
  void string() {
    const std::int32_t length = i32();
    if (length < 1) ok_ = false;
    if (ok_) skip(static_cast<std::size_t>(length));
  }
  // An array's count: not negative, and no more elements than bytes left (every element
  // takes at least `min_element_bytes`).
  std::int32_t count(std::int32_t n, std::size_t min_element_bytes) {
    if (n < 0 || static_cast<std::size_t>(n) > left_ / min_element_bytes) ok_ = false;
    return ok_ ? n : 0;
  }

 private:
  const std::uint8_t* p_;
  std::size_t left_;
  bool ok_ = true;
};

void robot_pose(Walk& w) {
  w.i32();
  w.boolean();
  w.boolean();
  w.f64();
  w.f64();
  w.f64();
  w.string();
  w.string();
}

void polyline(Walk& w) {
  const std::int32_t n = w.count(w.i32(), 16);
  for (std::int32_t i = 0; i < n && w.ok(); ++i) w.f64();
  for (std::int32_t i = 0; i < n && w.ok(); ++i) w.f64();
  w.boolean();
  w.f64();
}

// The message's fields after its 8-byte type hash (which lcm-gen's decoder checks).
void fields(Walk& w, const rilbed::poses_t*) {
  w.i64();
  const std::int32_t n = w.count(w.i32(), 4 + 2 + 24 + 10);
  for (std::int32_t i = 0; i < n && w.ok(); ++i) robot_pose(w);
}
void fields(Walk& w, const rilbed::event_t*) {
  w.i64();
  w.string();
  w.i32();
  w.i32();
  w.string();
}
void fields(Walk& w, const rilbed::status_t*) {
  w.i64();
  w.i64();
  w.string();
  w.i64();
  w.string();
  w.boolean();
  w.f64();
  w.string();
  w.string();
  w.i32();
  w.i32();
  w.boolean();
  w.f64();
  w.i32();
  w.f64();
  w.f64();
  w.i64();
}
void fields(Walk& w, const rilbed::world_t*) {
  w.i64();
  w.string();
  w.f64();
  w.f64();
  w.boolean();
  std::int32_t n = w.count(w.i32(), 4 + 1 + 8);
  for (std::int32_t i = 0; i < n && w.ok(); ++i) polyline(w);
  n = w.count(w.i32(), 4 + 1 + 8);
  for (std::int32_t i = 0; i < n && w.ok(); ++i) polyline(w);
  n = w.count(w.i32(), 16);
  w.skip(static_cast<std::size_t>(n) * 16);
  n = w.count(w.i32(), 5);
  w.skip(static_cast<std::size_t>(n) * 5);
}
void fields(Walk& w, const rilbed::summary_t*) {
  w.i64();
  w.string();
}
void fields(Walk& w, const rilbed::console_command_t*) {
  w.i64();
  w.string();
  w.string();
  w.string();
  const std::int32_t n = w.count(w.i32(), 5);
  for (std::int32_t i = 0; i < n && w.ok(); ++i) w.string();
}
void fields(Walk& w, const rilbed::console_reply_t*) {
  w.i64();
  w.string();
  w.boolean();
  w.string();
}

void fields(Walk& w, const rilbed::wheels_t*) {
  w.i64();
  const std::int32_t n = w.count(w.i32(), 4 + 2 + 2 + 8 + 8);
  w.skip(static_cast<std::size_t>(n) * (4 + 2 + 2 + 8 + 8));
}
void robot_sensors(Walk& w) {
  w.i32();
  std::int32_t n = w.count(w.i8(), 2);
  w.skip(static_cast<std::size_t>(n) * 2);
  n = w.count(w.i8(), 9);
  w.skip(static_cast<std::size_t>(n) * 9);
  n = w.count(w.i8(), 12);
  w.skip(static_cast<std::size_t>(n) * 12);
  n = w.count(w.i16(), 4);
  w.skip(static_cast<std::size_t>(n) * 4);
  w.boolean();
  w.i64();
  w.i64();
}
void fields(Walk& w, const rilbed::sensors_t*) {
  w.i64();
  const std::int32_t n = w.count(w.i32(), 4 + 1 + 1 + 1 + 2 + 1 + 16);
  for (std::int32_t i = 0; i < n && w.ok(); ++i) robot_sensors(w);
}
void fields(Walk& w, const rilbed::detections_t*) {
  w.i64();
  w.i64();
  w.f64();
  const std::int32_t n = w.count(w.i32(), 4 + 8 * 8);
  w.skip(static_cast<std::size_t>(n) * (4 + 8 * 8));
}
void fields(Walk& w, const rilbed::frame_t*) {
  w.i64();
  w.i64();
  w.i32();
  w.i32();
  w.string();
  const std::int32_t n = w.count(w.i32(), 1);
  w.skip(static_cast<std::size_t>(n));
}

void fields(Walk& w, const rilbed::camera_t*) {
  w.i64();
  w.i32();
  w.i32();
  w.skip(9 * 8);
  w.i8();
  w.string();
}

void fields(Walk& w, const rilbed::vision_settings_t*) {
  w.i64();
  w.skip(2 * 8);
  w.i32();
  w.skip(3 * 8);
}

void fields(Walk& w, const rilbed::sensor_geometry_t*) {
  w.f64();
  const std::int32_t ranges = w.count(w.i32(), 3 * 8);
  w.skip(static_cast<std::size_t>(ranges) * 3 * 8);
  w.i8();
  w.f64();
  const std::int32_t points = w.count(w.i32(), 4 + 2 * 8);
  w.skip(static_cast<std::size_t>(points) * (4 + 2 * 8));
}
void fields(Walk& w, const rilbed::sensor_layout_t*) {
  w.i64();
  const std::int32_t geometries = w.count(w.i32(), 8 + 4 + 1 + 8 + 4);  // the smallest geometry
  for (std::int32_t k = 0; k < geometries && w.ok(); ++k)
    fields(w, static_cast<const rilbed::sensor_geometry_t*>(nullptr));
  const std::int32_t robots = w.count(w.i32(), 2 * 4);
  w.skip(static_cast<std::size_t>(robots) * 2 * 4);
}

void fields(Walk& w, const rilbed::robot_body_t*) {
  w.string();
  w.f64();
  const std::int32_t vertices = w.count(w.i32(), 2 * 8);
  w.skip(static_cast<std::size_t>(vertices) * 2 * 8);
  w.f64();
  w.f64();
}
void fields(Walk& w, const rilbed::robot_bodies_t*) {
  w.i64();
  const std::int32_t bodies = w.count(w.i32(), 4 + 1 + 8 + 4 + 2 * 8);  // the smallest body: an empty name, a disc
  for (std::int32_t k = 0; k < bodies && w.ok(); ++k) fields(w, static_cast<const rilbed::robot_body_t*>(nullptr));
  const std::int32_t robots = w.count(w.i32(), 2 * 4);
  w.skip(static_cast<std::size_t>(robots) * 2 * 4);
}

void robot_models(Walk& w) {
  w.i32();
  const std::int32_t readings = w.count(w.i16(), 4 + 1 + 2);  // an empty name, no values
  for (std::int32_t k = 0; k < readings && w.ok(); ++k) {
    w.string();
    const std::int32_t values = w.count(w.i16(), 8);
    w.skip(static_cast<std::size_t>(values) * 8);
  }
  const std::int32_t marks = w.count(w.i16(), 1 + 5 * 8 + 4);
  w.skip(static_cast<std::size_t>(marks) * (1 + 5 * 8 + 4));
}
void fields(Walk& w, const rilbed::sensor_models_t*) {
  w.i64();
  const std::int32_t robots = w.count(w.i32(), 4 + 2 + 2);  // a robot with neither readings nor marks
  for (std::int32_t r = 0; r < robots && w.ok(); ++r) robot_models(w);
}

// The agent exchange (processes of their own, here or on other machines).
void fields(Walk& w, const rilbed::agent_hello_t*) {
  w.string();
  w.string();
  const std::int32_t n = w.count(w.i32(), 4);
  w.skip(static_cast<std::size_t>(n) * 4);
  w.string();
  w.i32();
}
void agent_input(Walk& w) {
  w.i32();
  w.boolean();
  w.f64();
  w.f64();
  w.f64();
  robot_sensors(w);
  robot_models(w);
}
void team_member(Walk& w) {
  w.i32();
  w.f64();
  w.f64();
  w.f64();
  w.string();
  w.i64();
}
void fields(Walk& w, const rilbed::quantum_t*) {
  w.string();
  w.i64();
  w.i64();
  w.boolean();
  std::int32_t n = w.count(w.i32(), 5);
  for (std::int32_t i = 0; i < n && w.ok(); ++i) w.string();
  n = w.count(w.i32(), 4 + 1 + 24 + 4 + 1 + 1 + 1 + 2 + 1 + 16);
  for (std::int32_t i = 0; i < n && w.ok(); ++i) agent_input(w);
  w.boolean();
  n = w.count(w.i32(), 4 + 24 + 5 + 8);
  for (std::int32_t i = 0; i < n && w.ok(); ++i) team_member(w);
}
void fields(Walk& w, const rilbed::quantum_reply_t*) {
  w.string();
  w.string();
  w.i64();
  const std::int32_t n = w.count(w.i32(), 4 + 2 + 2 + 5 + 1);
  for (std::int32_t i = 0; i < n && w.ok(); ++i) {
    w.i32();
    w.i16();
    w.i16();
    w.string();
    w.boolean();
  }
}

}  // namespace

template <typename Message>
bool well_formed(const void* data, std::size_t size) {
  Walk w(data, size);
  w.skip(8);  // the type hash
  fields(w, static_cast<const Message*>(nullptr));
  return w.done();
}

template bool well_formed<rilbed::poses_t>(const void*, std::size_t);
template bool well_formed<rilbed::event_t>(const void*, std::size_t);
template bool well_formed<rilbed::status_t>(const void*, std::size_t);
template bool well_formed<rilbed::world_t>(const void*, std::size_t);
template bool well_formed<rilbed::summary_t>(const void*, std::size_t);
template bool well_formed<rilbed::console_command_t>(const void*, std::size_t);
template bool well_formed<rilbed::console_reply_t>(const void*, std::size_t);
template bool well_formed<rilbed::wheels_t>(const void*, std::size_t);
template bool well_formed<rilbed::sensors_t>(const void*, std::size_t);
template bool well_formed<rilbed::detections_t>(const void*, std::size_t);
template bool well_formed<rilbed::frame_t>(const void*, std::size_t);
template bool well_formed<rilbed::camera_t>(const void*, std::size_t);
template bool well_formed<rilbed::sensor_layout_t>(const void*, std::size_t);
template bool well_formed<rilbed::robot_bodies_t>(const void*, std::size_t);
template bool well_formed<rilbed::sensor_models_t>(const void*, std::size_t);
template bool well_formed<rilbed::vision_settings_t>(const void*, std::size_t);
template bool well_formed<rilbed::agent_hello_t>(const void*, std::size_t);
template bool well_formed<rilbed::quantum_t>(const void*, std::size_t);
template bool well_formed<rilbed::quantum_reply_t>(const void*, std::size_t);

}  // namespace rilbed::bus

#include "gui_web/run_channels.hpp"

#include <array>
#include <cmath>
#include <optional>

namespace rilbed::gui_web {

namespace {

using nlohmann::json;

double seconds(TimeUs t_us) { return static_cast<double>(t_us) * 1e-6; }

// A JSON Schema of an object with these properties (name -> type or schema).
std::string object_schema(const std::string& title, const json& properties) {
  return json{{"title", title}, {"type", "object"}, {"properties", properties}}.dump();
}

json number() { return {{"type", "number"}}; }
json integer() { return {{"type", "integer"}}; }
json text() { return {{"type", "string"}}; }
json boolean() { return {{"type", "boolean"}}; }
// A sensor model's mark (environment::SensorMark), robot frame.
json mark_schema();
json array_of(const json& items) { return {{"type", "array"}, {"items", items}}; }
json object_of(const json& properties) { return {{"type", "object"}, {"properties", properties}}; }

json time_of(TimeUs t_us) {
  const TimeUs t = std::max<TimeUs>(0, t_us);
  return {{"sec", t / 1'000'000}, {"nsec", (t % 1'000'000) * 1000}};
}
json point(double x, double y, double z = 0.0) { return {{"x", x}, {"y", y}, {"z", z}}; }
json pose(double x, double y, double z, double yaw_rad) {
  return {{"position", point(x, y, z)},
          {"orientation", {{"x", 0.0}, {"y", 0.0}, {"z", std::sin(yaw_rad / 2)}, {"w", std::cos(yaw_rad / 2)}}}};
}
json color(double r, double g, double b, double a = 1.0) { return {{"r", r}, {"g", g}, {"b", b}, {"a", a}}; }

json entity(TimeUs t_us, const std::string& id) {
  return {{"timestamp", time_of(t_us)},
          {"frame_id", "field"},
          {"id", id},
          {"lifetime", {{"sec", 0}, {"nsec", 0}}},
          {"frame_locked", false},
          {"metadata", json::array()},
          {"arrows", json::array()},
          {"cubes", json::array()},
          {"spheres", json::array()},
          {"cylinders", json::array()},
          {"lines", json::array()},
          {"triangles", json::array()},
          {"texts", json::array()},
          {"models", json::array()}};
}

json mark_schema() {
  return object_of({{"shape", text()},
                    {"x_m", number()},
                    {"y_m", number()},
                    {"radius_m", number()},
                    {"x2_m", number()},
                    {"y2_m", number()},
                    {"rgba", integer()}});
}

json mark_json(const environment::SensorMark& m) {
  const bool circle = m.shape == environment::SensorMark::Shape::kCircle;
  return {{"shape", circle ? "circle" : "line"},
          {"x_m", m.a_m.x},
          {"y_m", m.a_m.y},
          {"radius_m", m.radius_m},
          {"x2_m", m.b_m.x},
          {"y2_m", m.b_m.y},
          {"rgba", m.rgba}};
}

json line(const std::vector<Vec2>& points, bool loop, double thickness_m, const json& c) {
  json pts = json::array();
  for (const Vec2& p : points) pts.push_back(point(p.x, p.y));
  return {{"type", loop ? 1 : 0},
          {"pose", pose(0, 0, 0, 0)},
          {"thickness", thickness_m},
          {"scale_invariant", false},
          {"points", pts},
          {"color", c},
          {"colors", json::array()},
          {"indices", json::array()}};
}

// The parts of foxglove.SceneUpdate this server fills (Foxglove reads the datatypes of
// what is there; the schema's name is what its 3D panel goes by).
std::string scene_schema() {
  const json vec3 = object_of({{"x", number()}, {"y", number()}, {"z", number()}});
  const json quat = object_of({{"x", number()}, {"y", number()}, {"z", number()}, {"w", number()}});
  const json pose_s = object_of({{"position", vec3}, {"orientation", quat}});
  const json color_s = object_of({{"r", number()}, {"g", number()}, {"b", number()}, {"a", number()}});
  const json time_s = object_of({{"sec", integer()}, {"nsec", integer()}});
  const json cylinder = object_of(
      {{"pose", pose_s}, {"size", vec3}, {"bottom_scale", number()}, {"top_scale", number()}, {"color", color_s}});
  const json text_s = object_of({{"pose", pose_s},
                                 {"billboard", boolean()},
                                 {"font_size", number()},
                                 {"scale_invariant", boolean()},
                                 {"color", color_s},
                                 {"text", text()}});
  const json line_s = object_of({{"type", integer()},
                                 {"pose", pose_s},
                                 {"thickness", number()},
                                 {"scale_invariant", boolean()},
                                 {"points", array_of(vec3)},
                                 {"color", color_s},
                                 {"colors", array_of(color_s)},
                                 {"indices", array_of(integer())}});
  const json arrow = object_of({{"pose", pose_s},
                                {"shaft_length", number()},
                                {"shaft_diameter", number()},
                                {"head_length", number()},
                                {"head_diameter", number()},
                                {"color", color_s}});
  const json triangles = object_of({{"pose", pose_s},
                                    {"points", array_of(vec3)},
                                    {"color", color_s},
                                    {"colors", array_of(color_s)},
                                    {"indices", array_of(integer())}});
  const json cube = object_of({{"pose", pose_s}, {"size", vec3}, {"color", color_s}});
  const json entity_s = object_of({{"timestamp", time_s},
                                   {"frame_id", text()},
                                   {"id", text()},
                                   {"lifetime", time_s},
                                   {"frame_locked", boolean()},
                                   {"cylinders", array_of(cylinder)},
                                   {"triangles", array_of(triangles)},
                                   {"cubes", array_of(cube)},
                                   {"texts", array_of(text_s)},
                                   {"lines", array_of(line_s)},
                                   {"arrows", array_of(arrow)}});
  const json deletion = object_of({{"timestamp", time_s}, {"type", integer()}, {"id", text()}});
  return object_schema("foxglove.SceneUpdate", {{"deletions", array_of(deletion)}, {"entities", array_of(entity_s)}});
}

// Base64 (RFC 4648, with padding), as JSON carries a Foxglove `bytes` field.
std::string base64(std::span<const std::uint8_t> bytes) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t v = (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8) | bytes[i + 2];
    out += kDigits[v >> 18];
    out += kDigits[(v >> 12) & 63];
    out += kDigits[(v >> 6) & 63];
    out += kDigits[v & 63];
  }
  if (const std::size_t rest = bytes.size() - i; rest > 0) {
    const std::uint32_t v = (std::uint32_t{bytes[i]} << 16) | (rest == 2 ? std::uint32_t{bytes[i + 1]} << 8 : 0u);
    out += kDigits[v >> 18];
    out += kDigits[(v >> 12) & 63];
    out += rest == 2 ? kDigits[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// The inverse of a 3x3 homography (row-major), or nullopt when it is singular.
std::optional<std::array<double, 9>> inverse(const std::array<double, 9>& m) {
  const double a = m[0], b = m[1], c = m[2], d = m[3], e = m[4], f = m[5], g = m[6], h = m[7], k = m[8];
  const double A = e * k - f * h, B = -(d * k - f * g), C = d * h - e * g;
  const double det = a * A + b * B + c * C;
  if (!std::isfinite(det) || std::abs(det) < 1e-300) return std::nullopt;
  return std::array<double, 9>{A / det, -(b * k - c * h) / det, (b * f - c * e) / det,
                               B / det, (a * k - c * g) / det,  -(a * f - c * d) / det,
                               C / det, -(a * h - b * g) / det, (a * e - b * d) / det};
}

foxglove::Channel channel(const std::string& topic, const std::string& schema_name, const std::string& schema) {
  return {0, topic, "json", schema_name, schema, "jsonschema"};
}

}  // namespace

RunChannels::RunChannels(WebServer& server) : server_(server) {
  const json robot_pose = object_of({{"id", integer()},
                                     {"real", boolean()},
                                     {"seen", boolean()},
                                     {"x_m", number()},
                                     {"y_m", number()},
                                     {"theta_rad", number()},
                                     {"behaviour", text()},
                                     {"health", text()}});
  const json polyline = array_of(object_of({{"x_m", number()}, {"y_m", number()}}));
  world_ = server_.add_channel(
      channel("/rilbed/world", "rilbed.world",
              object_schema(
                  "rilbed.world",
                  {{"t_s", number()},
                   {"scenario", text()},
                   {"width_m", number()},
                   {"height_m", number()},
                   {"walls", boolean()},
                   {"obstacles", array_of(polyline)},
                   {"tracks", array_of(object_of({{"points", polyline}, {"width_m", number()}}))},
                   {"beacons", polyline},
                   {"robots",
                    array_of(object_of({{"id", integer()},
                                        {"real", boolean()},
                                        {"body", object_of({{"name", text()},
                                                            {"radius_m", number()},
                                                            {"outline", polyline},
                                                            {"wheel_base_m", number()},
                                                            {"wheel_radius_m", number()}})},
                                        {"sensors", object_of({{"ir_range_m", number()},
                                                               {"ranges", array_of(object_of({{"mount_rad", number()},
                                                                                              {"opening_rad", number()},
                                                                                              {"max_m", number()}}))},
                                                               {"beacon_finder", boolean()},
                                                               {"beacon_fov_rad", number()},
                                                               {"tracks", array_of(polyline)}})}}))}})),
      /*latched=*/true);
  status_ = server_.add_channel(channel("/rilbed/status", "rilbed.status",
                                        object_schema("rilbed.status", {{"t_s", number()},
                                                                        {"wall_s", number()},
                                                                        {"scenario", text()},
                                                                        {"seed", integer()},
                                                                        {"mode", text()},
                                                                        {"realtime", boolean()},
                                                                        {"rt_factor", number()},
                                                                        {"state", text()},
                                                                        {"ended_by", text()},
                                                                        {"robots", integer()},
                                                                        {"real_robots", integer()},
                                                                        {"formed", boolean()},
                                                                        {"formation_time_s", number()},
                                                                        {"collisions", integer()},
                                                                        {"loop_latency_ms", number()},
                                                                        {"camera_fps", number()},
                                                                        {"frames", integer()}})),
                                /*latched=*/true);
  poses_ =
      server_.add_channel(channel("/rilbed/poses", "rilbed.poses",
                                  object_schema("rilbed.poses", {{"t_s", number()}, {"robots", array_of(robot_pose)}})),
                          /*latched=*/true);
  wheels_ = server_.add_channel(channel(
      "/rilbed/wheels", "rilbed.wheels",
      object_schema("rilbed.wheels",
                    {{"t_s", number()},
                     {"robots", array_of(object_of(
                                    {{"id", integer()}, {"left_units", integer()}, {"right_units", integer()}}))}})));
  sensors_ = server_.add_channel(channel(
      "/rilbed/sensors", "rilbed.sensors",
      object_schema(
          "rilbed.sensors",
          {{"t_s", number()},
           {"robots",
            array_of(object_of({{"id", integer()},
                                {"proximity", array_of(integer())},
                                {"range_m", array_of(number())},
                                {"range_hit", array_of(boolean())},
                                {"beacon_id", array_of(integer())},
                                {"beacon_bearing_rad", array_of(number())},
                                {"track", array_of(integer())},
                                {"models", array_of(object_of({{"name", text()}, {"values", array_of(number())}}))},
                                {"marks", array_of(mark_schema())}}))}})));
  detections_ = server_.add_channel(
      channel("/rilbed/detections", "rilbed.detections",
              object_schema("rilbed.detections", {{"t_s", number()},
                                                  {"frame", integer()},
                                                  {"process_ms", number()},
                                                  {"detections", array_of(object_of({{"id", integer()},
                                                                                     {"u_px", number()},
                                                                                     {"v_px", number()},
                                                                                     {"heading_deg", number()},
                                                                                     {"score", number()},
                                                                                     {"diameter_px", number()},
                                                                                     {"x_m", number()},
                                                                                     {"y_m", number()},
                                                                                     {"theta_rad", number()}}))}})));
  events_ = server_.add_channel(
      channel("/rilbed/events", "rilbed.event",
              object_schema(
                  "rilbed.event",
                  {{"t_s", number()}, {"kind", text()}, {"id", integer()}, {"other", integer()}, {"detail", text()}})));
  summary_ = server_.add_channel(
      channel("/rilbed/summary", "rilbed.summary", object_schema("rilbed.summary", json::object())));
  scene_ = server_.add_channel(channel("/rilbed/scene", "foxglove.SceneUpdate", scene_schema()), /*latched=*/true);
  const json time_s = object_of({{"sec", integer()}, {"nsec", integer()}});
  camera_ = server_.add_channel(
      channel("/rilbed/camera", "foxglove.CompressedImage",
              object_schema("foxglove.CompressedImage", {{"timestamp", time_s},
                                                         {"frame_id", text()},
                                                         {"data", {{"type", "string"}, {"contentEncoding", "base64"}}},
                                                         {"format", text()}})));
  camera_calibration_ =
      server_.add_channel(channel("/rilbed/camera_calibration", "rilbed.camera",
                                  object_schema("rilbed.camera", {{"t_s", number()},
                                                                  {"width_px", integer()},
                                                                  {"height_px", integer()},
                                                                  {"image_to_field", array_of(number())},
                                                                  {"field_to_image", array_of(number())},
                                                                  {"lens_distortion", boolean()},
                                                                  {"source", text()}})),
                          /*latched=*/true);
  console_reply_ = server_.add_channel(
      channel("/rilbed/console_reply", "rilbed.console_reply",
              object_schema("rilbed.console_reply",
                            {{"t_s", number()}, {"accepted", boolean()}, {"reason", text()}, {"client", text()}})));
  server_.set_latch_source(poses_, [latest = latest_](std::uint64_t& t_ns) { return latest->build(false, t_ns); });
  server_.set_latch_source(scene_, [latest = latest_](std::uint64_t& t_ns) { return latest->build(true, t_ns); });
  worker_ = std::thread([this] {
    yield_to_control_loop();
    work();
  });
}

void RunChannels::send(std::uint32_t channel, TimeUs t_us, const json& message) {
  server_.publish(channel, static_cast<std::uint64_t>(std::max<TimeUs>(0, t_us)) * 1000,
                  std::make_shared<const std::string>(message.dump(-1, ' ', false, json::error_handler_t::replace)));
}

json RunChannels::world_json(TimeUs t_us, const run::WorldReport& w) {
  auto points = [](const std::vector<Vec2>& ps) {
    json a = json::array();
    for (const Vec2& p : ps) a.push_back({{"x_m", p.x}, {"y_m", p.y}});
    return a;
  };
  json obstacles = json::array();
  for (const auto& o : w.field.obstacles) obstacles.push_back(points(o));
  json tracks = json::array();
  for (const auto& [ps, width_m] : w.field.tracks) tracks.push_back({{"points", points(ps)}, {"width_m", width_m}});
  // Each distinct sensor geometry once, as JSON; each robot refers to its own.
  std::vector<json> geometries;
  for (const run::SensorGeometry& g : w.sensor_geometries) {
    json ranges = json::array();
    for (const auto& r : g.ranges)
      ranges.push_back({{"mount_rad", r.mount_rad}, {"opening_rad", r.opening_rad}, {"max_m", r.max_m}});
    json tracks = json::array();
    for (const auto& element : g.track_points_m) tracks.push_back(points(element));
    geometries.push_back({{"ir_range_m", g.ir_range_m},
                          {"ranges", ranges},
                          {"beacon_finder", g.beacon_finder},
                          {"beacon_fov_rad", g.beacon_fov_rad},
                          {"tracks", tracks}});
  }
  std::vector<json> bodies;
  for (const run::BodyDrawing& b : w.bodies) {
    bodies.push_back({{"name", b.name},
                      {"radius_m", b.radius_m},
                      {"outline", points(b.outline_m)},
                      {"wheel_base_m", b.wheel_base_m},
                      {"wheel_radius_m", b.wheel_radius_m}});
  }
  json robots = json::array();
  for (const int id : w.robot_ids) {
    json robot = {{"id", id}, {"real", w.field.real_robot_ids.contains(id)}};
    if (const auto b = w.body_of.find(id);
        b != w.body_of.end() && b->second >= 0 && static_cast<std::size_t>(b->second) < bodies.size())
      robot["body"] = bodies[static_cast<std::size_t>(b->second)];
    const auto it = w.sensor_geometry_of.find(id);
    if (it != w.sensor_geometry_of.end() && it->second >= 0 &&
        static_cast<std::size_t>(it->second) < geometries.size()) {
      robot["sensors"] = geometries[static_cast<std::size_t>(it->second)];
    }
    robots.push_back(std::move(robot));
  }
  return {{"t_s", seconds(t_us)},
          {"scenario", w.scenario},
          {"width_m", w.field.width_m},
          {"height_m", w.field.height_m},
          {"walls", w.walls},
          {"obstacles", obstacles},
          {"tracks", tracks},
          {"beacons", points(w.field.beacons)},
          {"robots", robots}};
}

json RunChannels::poses_json(TimeUs t_us, std::span<const run::PoseReport> poses) {
  json robots = json::array();
  for (const auto& p : poses) {
    robots.push_back({{"id", p.id},
                      {"real", p.real},
                      {"seen", p.seen},
                      {"x_m", p.pose.position_m.x},
                      {"y_m", p.pose.position_m.y},
                      {"theta_rad", p.pose.heading_rad},
                      {"behaviour", p.behaviour},
                      {"health", p.health}});
  }
  return {{"t_s", seconds(t_us)}, {"robots", robots}};
}

json RunChannels::status_json(const run::StatusReport& s) {
  return {{"t_s", seconds(s.t_us)},
          {"wall_s", s.wall_s},
          {"scenario", s.scenario},
          {"seed", s.seed},
          {"mode", s.mode},
          {"realtime", s.realtime},
          {"rt_factor", s.rt_factor},
          {"state", s.state},
          {"ended_by", s.ended_by},
          {"robots", s.robots},
          {"real_robots", s.real_robots},
          {"formed", s.formed},
          {"formation_time_s", s.formation_time_s ? json(*s.formation_time_s) : json(nullptr)},
          {"collisions", s.collisions},
          {"loop_latency_ms", s.loop_latency_ms},
          {"camera_fps", s.camera_fps},
          {"frames", s.frames}};
}

namespace {

// A robot's sensor marks as lines in the field frame: a circle as a loop of 16 points.
void add_marks(json& entity, const Pose2& robot, const std::vector<environment::SensorMark>& marks) {
  const double c = std::cos(robot.heading_rad), s = std::sin(robot.heading_rad);
  auto field = [&](Vec2 p) {
    return Vec2{robot.position_m.x + c * p.x - s * p.y, robot.position_m.y + s * p.x + c * p.y};
  };
  for (const environment::SensorMark& m : marks) {
    const json colour = color(((m.rgba >> 24) & 0xff) / 255.0, ((m.rgba >> 16) & 0xff) / 255.0,
                              ((m.rgba >> 8) & 0xff) / 255.0, (m.rgba & 0xff) / 255.0);
    std::vector<Vec2> points;
    if (m.shape == environment::SensorMark::Shape::kLine) {
      points = {field(m.a_m), field(m.b_m)};
    } else {
      for (int k = 0; k < 16; ++k) {
        const double a = 2.0 * kPi * k / 16;
        points.push_back(field({m.a_m.x + m.radius_m * std::cos(a), m.a_m.y + m.radius_m * std::sin(a)}));
      }
    }
    entity["lines"].push_back(line(points, m.shape == environment::SensorMark::Shape::kCircle, 0.001, colour));
  }
}

// A robot's body at `at`: its disc as a cylinder 20 mm high, or its outline as a prism
// (a top face of triangles 20 mm up, and the outline's edge), and its two wheels.
void add_body(json& e, const Pose2& at, const run::BodyDrawing& body, const json& c) {
  const double x = at.position_m.x, y = at.position_m.y, h = at.heading_rad;
  constexpr double kHeight_m = 0.02;
  if (body.outline_m.empty()) {
    const double d = 2 * body.radius_m;
    e["cylinders"].push_back({{"pose", pose(x, y, kHeight_m / 2, h)},
                              {"size", point(d, d, kHeight_m)},
                              {"bottom_scale", 1.0},
                              {"top_scale", 1.0},
                              {"color", c}});
  } else {
    const double ch = std::cos(h), sh = std::sin(h);
    std::vector<Vec2> field;
    for (const Vec2& v : body.outline_m) field.push_back({x + ch * v.x - sh * v.y, y + sh * v.x + ch * v.y});
    json top = json::array();
    for (std::size_t k = 1; k + 1 < field.size(); ++k) {  // a fan: the outline is convex
      for (const Vec2& v : {field[0], field[k], field[k + 1]}) top.push_back(point(v.x, v.y, kHeight_m));
    }
    e["triangles"].push_back({{"pose", pose(0, 0, 0, 0)},
                              {"points", top},
                              {"color", c},
                              {"colors", json::array()},
                              {"indices", json::array()}});
    json edge = line(field, true, 0.002, color(0.1, 0.1, 0.1));
    for (json& pt : edge["points"]) pt["z"] = kHeight_m;
    e["lines"].push_back(std::move(edge));
  }
  // The wheels: discs on edge, across the axle at the wheel base's ends.
  for (const double side : {-0.5, 0.5}) {
    const double wx = x - std::sin(h) * side * body.wheel_base_m, wy = y + std::cos(h) * side * body.wheel_base_m;
    const double d = 2 * body.wheel_radius_m;
    e["cubes"].push_back({{"pose", pose(wx, wy, body.wheel_radius_m, h)},
                          {"size", point(d, 0.004, d)},
                          {"color", color(0.15, 0.15, 0.15)}});
  }
}

}  // namespace

json RunChannels::scene_json(TimeUs t_us, std::span<const run::PoseReport> poses,
                             const std::optional<run::WorldReport>& world,
                             const std::map<int, std::vector<environment::SensorMark>>& marks) {
  json entities = json::array();
  if (world) {
    json field = entity(t_us, "field");
    const double w = world->field.width_m, h = world->field.height_m;
    field["lines"].push_back(line({{0, 0}, {w, 0}, {w, h}, {0, h}}, true, 0.01, color(0.1, 0.7, 0.1)));
    for (const auto& o : world->field.obstacles) field["lines"].push_back(line(o, true, 0.01, color(0.3, 0.3, 0.3)));
    for (const auto& [ps, width_m] : world->field.tracks)
      field["lines"].push_back(line(ps, false, width_m, color(0.2, 0.2, 0.2, 0.6)));
    entities.push_back(std::move(field));
  }
  const run::BodyDrawing khepera;  // what a robot without a published body is
  for (const auto& p : poses) {
    json e = entity(t_us, "robot " + std::to_string(p.id));
    const json c = p.real ? color(0.15, 0.35, 0.9, p.seen ? 0.9 : 0.4) : color(0.9, 0.15, 0.15, 0.8);
    const double x = p.pose.position_m.x, y = p.pose.position_m.y;
    const run::BodyDrawing* body = &khepera;
    if (world) {
      if (const auto b = world->body_of.find(p.id);
          b != world->body_of.end() && b->second >= 0 && static_cast<std::size_t>(b->second) < world->bodies.size())
        body = &world->bodies[static_cast<std::size_t>(b->second)];
    }
    add_body(e, p.pose, *body, c);
    e["arrows"].push_back({{"pose", pose(x, y, 0.025, p.pose.heading_rad)},
                           {"shaft_length", 0.03},
                           {"shaft_diameter", 0.006},
                           {"head_length", 0.012},
                           {"head_diameter", 0.014},
                           {"color", color(0, 0, 0)}});
    e["texts"].push_back({{"pose", pose(x, y, 0.06, 0)},
                          {"billboard", true},
                          {"font_size", 12.0},
                          {"scale_invariant", true},
                          {"color", color(0, 0, 0)},
                          {"text", std::to_string(p.id) + " " + std::string(p.behaviour)}});
    if (const auto it = marks.find(p.id); it != marks.end()) add_marks(e, p.pose, it->second);
    entities.push_back(std::move(e));
  }
  return {{"deletions", json::array()}, {"entities", entities}};
}

RunChannels::~RunChannels() {
  {
    std::lock_guard lock(jobs_mutex_);
    stopping_ = true;
  }
  jobs_changed_.notify_all();
  worker_.join();  // after building what was handed over
}

void RunChannels::post(std::uint32_t channel, bool step, std::function<void()> build) {
  {
    std::lock_guard lock(jobs_mutex_);
    // A step's message still waiting is stale once the next one comes: newest state wins.
    if (step) {
      std::erase_if(jobs_, [channel](const Job& j) { return j.step && j.channel == channel; });
    }
    jobs_.push_back({channel, step, std::move(build)});
  }
  jobs_changed_.notify_all();
}

void RunChannels::work() {
  std::unique_lock lock(jobs_mutex_);
  for (;;) {
    jobs_changed_.wait(lock, [this] { return stopping_ || !jobs_.empty(); });
    if (jobs_.empty()) return;  // stopping, and everything built
    Job job = std::move(jobs_.front());
    jobs_.pop_front();
    building_ = true;
    lock.unlock();
    job.build();
    lock.lock();
    building_ = false;
    jobs_changed_.notify_all();
  }
}

bool RunChannels::flush(std::chrono::milliseconds timeout) {
  std::unique_lock lock(jobs_mutex_);
  return jobs_changed_.wait_for(lock, timeout, [this] { return jobs_.empty() && !building_; });
}

void RunChannels::on_world(TimeUs t_us, const run::WorldReport& world) {
  {
    std::lock_guard lock(latest_->mutex);
    latest_->world = world;
  }
  post(world_, false, [this, t_us, world] {
    if (world.camera) {
      const run::CameraReport& c = *world.camera;
      const auto to_image = inverse(c.image_to_field);
      send(camera_calibration_, t_us,
           {{"t_s", seconds(t_us)},
            {"width_px", c.width_px},
            {"height_px", c.height_px},
            {"image_to_field", c.image_to_field},
            {"field_to_image", to_image ? json(*to_image) : json(nullptr)},
            {"lens_distortion", c.lens_distortion},
            {"source", c.source}});
    }
    send(world_, t_us, world_json(t_us, world));
  });
}

void RunChannels::OwnedPoses::assign(std::span<const run::PoseReport> from) {
  poses.assign(from.begin(), from.end());
  strings.clear();
  strings.reserve(2 * poses.size());
  for (run::PoseReport& p : poses) {
    p.behaviour = strings.emplace_back(p.behaviour);
    p.health = strings.emplace_back(p.health);
  }
}

void RunChannels::on_poses(TimeUs t_us, std::span<const run::PoseReport> poses) {
  // Kept (and marked unsent) before anything else: a client subscribing meanwhile gets them
  // from the latch source, at worst twice.
  Latest& l = *latest_;
  {
    std::lock_guard lock(l.mutex);
    l.poses_t_us = t_us;
    l.poses.assign(poses);
    l.poses_unsent = l.scene_unsent = true;
  }
  if (!server_.subscribed(poses_) && !server_.subscribed(scene_)) return;
  auto owned = std::make_shared<OwnedPoses>();
  owned->assign(poses);
  post(poses_, true, [this, t_us, owned] {
    const std::vector<run::PoseReport>& copy = owned->poses;
    Latest& l = *latest_;
    if (server_.subscribed(poses_)) {
      send(poses_, t_us, poses_json(t_us, copy));
      std::lock_guard lock(l.mutex);
      if (l.poses_t_us == t_us) l.poses_unsent = false;
    }
    if (server_.subscribed(scene_)) {
      std::optional<run::WorldReport> world;
      std::map<int, std::vector<environment::SensorMark>> marks;
      {
        std::lock_guard lock(l.mutex);
        world = l.world;  // 1 Hz's copy, only while someone watches the scene
        marks = l.marks;
      }
      send(scene_, t_us, scene_json(t_us, copy, world, marks));
      std::lock_guard lock(l.mutex);
      if (l.poses_t_us == t_us) l.scene_unsent = false;
    }
  });
}

void RunChannels::keep_marks(std::span<const run::SensorReport> sensors) {
  if (!server_.subscribed(scene_)) return;
  std::map<int, std::vector<environment::SensorMark>> marks;
  for (const auto& r : sensors) {
    if (r.readings && !r.readings->marks.empty()) marks[r.id] = r.readings->marks;
  }
  std::lock_guard lock(latest_->mutex);
  latest_->marks = std::move(marks);
}

std::shared_ptr<const std::string> RunChannels::Latest::build(bool scene, std::uint64_t& t_ns) {
  std::lock_guard lock(mutex);
  bool& unsent = scene ? scene_unsent : poses_unsent;
  if (!unsent) return nullptr;
  unsent = false;
  t_ns = static_cast<std::uint64_t>(std::max<TimeUs>(0, poses_t_us)) * 1000;
  const json message = scene ? scene_json(poses_t_us, poses.poses, world, marks) : poses_json(poses_t_us, poses.poses);
  return std::make_shared<const std::string>(message.dump(-1, ' ', false, json::error_handler_t::replace));
}

void RunChannels::on_wheels(TimeUs t_us, std::span<const run::WheelReport> wheels) {
  if (!server_.subscribed(wheels_)) return;  // nobody would get it
  post(wheels_, true, [this, t_us, copy = std::vector<run::WheelReport>(wheels.begin(), wheels.end())] {
    json robots = json::array();
    for (const auto& w : copy)
      robots.push_back({{"id", w.id}, {"left_units", w.wheels.left}, {"right_units", w.wheels.right}});
    send(wheels_, t_us, {{"t_s", seconds(t_us)}, {"robots", robots}});
  });
}

json RunChannels::models_json(const environment::SensorReadings& s) {
  json list = json::array();
  for (const environment::ModelReading& m : s.models) list.push_back({{"name", m.name}, {"values", m.values}});
  return list;
}

json RunChannels::marks_json(const environment::SensorReadings& s) {
  json list = json::array();
  for (const environment::SensorMark& m : s.marks) list.push_back(mark_json(m));
  return list;
}

void RunChannels::on_sensors(TimeUs t_us, std::span<const run::SensorReport> sensors) {
  keep_marks(sensors);
  if (!server_.subscribed(sensors_)) return;  // nobody would get it
  std::vector<std::pair<int, environment::SensorReadings>> copy;
  copy.reserve(sensors.size());
  for (const auto& r : sensors) copy.emplace_back(r.id, *r.readings);
  post(sensors_, true, [this, t_us, copy = std::move(copy)] {
    json robots = json::array();
    for (const auto& [id, s] : copy) {
      json ranges = json::array(), hits = json::array(), ids = json::array(), bearings = json::array();
      for (const auto& x : s.ranges) {
        ranges.push_back(x.distance_m);
        hits.push_back(x.hit);
      }
      for (const auto& b : s.beacons) {
        ids.push_back(b.id);
        bearings.push_back(b.bearing_rad);
      }
      robots.push_back({{"id", id},
                        {"proximity", s.proximity ? json(*s.proximity) : json::array()},
                        {"range_m", ranges},
                        {"range_hit", hits},
                        {"beacon_id", ids},
                        {"beacon_bearing_rad", bearings},
                        {"track", s.track},
                        {"models", models_json(s)},
                        {"marks", marks_json(s)}});
    }
    send(sensors_, t_us, {{"t_s", seconds(t_us)}, {"robots", robots}});
  });
}

void RunChannels::on_detections(const run::FrameReport& f) {
  if (!server_.subscribed(detections_)) return;  // nobody would get it
  post(detections_, true,
       [this, t_us = f.t_us, frame = f.frame, process_ms = f.process_ms,
        copy = std::vector<run::DetectionReport>(f.detections.begin(), f.detections.end())] {
         json list = json::array();
         for (const auto& d : copy) {
           list.push_back({{"id", d.id},
                           {"u_px", d.u_px},
                           {"v_px", d.v_px},
                           {"heading_deg", d.heading_deg},
                           {"score", d.score},
                           {"diameter_px", d.diameter_px},
                           {"x_m", d.pose.position_m.x},
                           {"y_m", d.pose.position_m.y},
                           {"theta_rad", d.pose.heading_rad}});
         }
         send(detections_, t_us,
              {{"t_s", seconds(t_us)}, {"frame", frame}, {"process_ms", process_ms}, {"detections", list}});
       });
}

void RunChannels::on_event(const run::RunEvent& e) {
  post(events_, false, [this, e] {
    send(events_, e.t_us,
         {{"t_s", seconds(e.t_us)}, {"kind", e.kind}, {"id", e.id}, {"other", e.other}, {"detail", e.detail}});
  });
}

void RunChannels::on_status(const run::StatusReport& status) {
  post(status_, false, [this, status] { send(status_, status.t_us, status_json(status)); });
}

void RunChannels::on_summary(TimeUs t_us, const nlohmann::json& summary) {
  post(summary_, false, [this, t_us, summary] { send(summary_, t_us, summary); });
}

void RunChannels::camera_frame(TimeUs t_us, std::span<const std::uint8_t> jpeg) {
  post(camera_, true, [this, t_us, copy = std::vector<std::uint8_t>(jpeg.begin(), jpeg.end())] {
    send(camera_, t_us,
         {{"timestamp", time_of(t_us)}, {"frame_id", "camera"}, {"data", base64(copy)}, {"format", "jpeg"}});
  });
}

void RunChannels::console_reply(TimeUs t_us, bool accepted, const std::string& reason, const std::string& client) {
  post(console_reply_, false, [this, t_us, accepted, reason, client] {
    send(console_reply_, t_us,
         {{"t_s", seconds(t_us)}, {"accepted", accepted}, {"reason", reason}, {"client", client}});
  });
}

}  // namespace rilbed::gui_web

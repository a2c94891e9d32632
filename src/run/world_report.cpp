#include "run/world_report.hpp"

#include <algorithm>

#include "environment/track_sensor.hpp"

namespace rilbed::run {

namespace {}  // namespace

FieldDrawing field_drawing(const Scenario& scenario, const std::vector<int>& real_ids) {
  FieldDrawing drawing{scenario.map.field.width_m, scenario.map.field.height_m, {}, {}, {}, {}, {}, {}};
  for (const auto& o : scenario.map.obstacles) drawing.obstacles.push_back(o.vertices_m);
  for (const auto& t : scenario.map.tracks) {
    auto points = t.points_m;
    if (t.closed && !points.empty()) points.push_back(points.front());
    drawing.tracks.emplace_back(points, t.width_m);
  }
  for (const auto& b : scenario.map.beacons) drawing.beacons.push_back(b.position_m);
  drawing.real_robot_ids = {real_ids.begin(), real_ids.end()};
  for (const RobotSpec& r : scenario.robots) {
    drawing.body_radius_m[r.id] = r.body.radius_m;
    if (!r.body.outline_m.empty()) drawing.body_outline_m[r.id] = r.body.outline_m;
  }
  return drawing;
}

namespace {

// A robot's sensors as a viewer draws them.
SensorGeometry sensor_geometry(const environment::SensorSuiteConfig& c) {
  SensorGeometry g;
  if (c.proximity) g.ir_range_m = c.proximity->range_m;
  for (const auto& r : c.range_finders) g.ranges.push_back({r.mount_angle_rad, r.opening_angle_rad, r.max_range_m});
  if (c.beacon_finder) {
    g.beacon_finder = true;
    g.beacon_fov_rad = c.beacon_finder->field_of_view_rad;
  }
  for (const auto& t : c.track_sensors) g.track_points_m.push_back(environment::track_footprint(t).points_m);
  return g;
}

}  // namespace

WorldReport world_report(const Scenario& scenario, const std::vector<int>& real_ids) {
  WorldReport w;
  w.scenario = scenario.name;
  w.field = field_drawing(scenario, real_ids);
  w.walls = scenario.map.field.boundary_walls;
  for (const RobotSpec& r : scenario.robots) {
    w.robot_ids.push_back(r.id);
    const SensorGeometry g = sensor_geometry(r.sensors);
    auto it = std::find(w.sensor_geometries.begin(), w.sensor_geometries.end(), g);
    if (it == w.sensor_geometries.end()) it = w.sensor_geometries.insert(it, g);
    w.sensor_geometry_of[r.id] = static_cast<int>(it - w.sensor_geometries.begin());
    const BodyDrawing b{r.body.name, r.body.radius_m, r.body.outline_m, r.body.wheel_base_m, r.body.wheel_radius_m};
    auto body = std::find(w.bodies.begin(), w.bodies.end(), b);
    if (body == w.bodies.end()) body = w.bodies.insert(body, b);
    w.body_of[r.id] = static_cast<int>(body - w.bodies.begin());
  }
  return w;
}

}  // namespace rilbed::run

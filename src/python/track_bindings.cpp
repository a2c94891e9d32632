// What a robot can know of a tape network on board (agents/track_features.hpp), for
// Python controllers: the same classes and functions under the same names, so that a
// Python controller reads its track sensor row and turns on a node as track_explore does.
#include <pybind11/stl.h>

#include "agents/track_features.hpp"
#include "python/python_runtime.hpp"

namespace py = pybind11;

namespace rilbed::python {

namespace {

using agents::BranchScan;
using agents::BranchScanConfig;
using agents::ScanResult;
using agents::TrackArray;
using agents::TrackArrayReading;
using agents::TrackFeatureKind;
using agents::TrackReadingConfig;
using environment::TrackSensorConfig;

py::tuple xy(Vec2 v) { return py::make_tuple(v.x, v.y); }

void bind_sensor_config(py::module_& m) {
  py::class_<TrackSensorConfig>(m, "TrackSensorConfig",
                                "One track sensor element as a scenario's `sensors: track:` entry gives it (paper 000 "
                                "section 8.1): where it sits on the robot and its cone.")
      .def(py::init([](double mount_x_m, double mount_y_m, double height_mm, double inclination_deg,
                       double cone_angle_deg, int precision, double coverage_percent, int max_value,
                       double mount_yaw_deg, double error_level_percent, bool graded) {
             TrackSensorConfig c;
             c.mount_x_m = mount_x_m;
             c.mount_y_m = mount_y_m;
             c.mount_yaw_deg = mount_yaw_deg;
             c.error_level_percent = error_level_percent;
             c.graded = graded;
             c.height_mm = height_mm;
             c.inclination_deg = inclination_deg;
             c.cone_angle_deg = cone_angle_deg;
             c.precision = precision;
             c.coverage_percent = coverage_percent;
             c.max_value = max_value;
             return c;
           }),
           py::arg("mount_x_m") = 0.0, py::arg("mount_y_m") = 0.0, py::arg("height_mm") = 8.0,
           py::arg("inclination_deg") = 45.0, py::arg("cone_angle_deg") = 30.0, py::arg("precision") = 16,
           py::arg("coverage_percent") = 15.0, py::arg("max_value") = 255, py::arg("mount_yaw_deg") = 0.0,
           py::arg("error_level_percent") = 5.0, py::arg("graded") = false)
      .def_readwrite("mount_yaw_deg", &TrackSensorConfig::mount_yaw_deg)
      .def_readwrite("error_level_percent", &TrackSensorConfig::error_level_percent)
      .def_readwrite("graded", &TrackSensorConfig::graded)
      .def_readwrite("mount_x_m", &TrackSensorConfig::mount_x_m)
      .def_readwrite("mount_y_m", &TrackSensorConfig::mount_y_m)
      .def_readwrite("height_mm", &TrackSensorConfig::height_mm)
      .def_readwrite("inclination_deg", &TrackSensorConfig::inclination_deg)
      .def_readwrite("cone_angle_deg", &TrackSensorConfig::cone_angle_deg)
      .def_readwrite("precision", &TrackSensorConfig::precision)
      .def_readwrite("coverage_percent", &TrackSensorConfig::coverage_percent)
      .def_readwrite("max_value", &TrackSensorConfig::max_value);
}

void bind_array(py::module_& m) {
  py::class_<TrackArray>(m, "TrackArray", "Where a robot's track sensor elements look (robot frame, metres).")
      .def_static(
          "of",
          [](const std::vector<TrackSensorConfig>& elements) {
            try {  // the scenario parser's checks: a cone that meets the floor, ...
              for (const auto& e : elements) environment::TrackSensor(e, "TrackArray.of");
            } catch (const std::invalid_argument& e) {
              throw py::value_error(e.what());
            }
            return TrackArray::of(elements);
          },
          py::arg("elements"), "From the robot's elements, in the order of Input.track.")
      .def_property_readonly("points_m",
                             [](const TrackArray& a) {
                               py::list out;
                               for (const Vec2& p : a.points_m) out.append(xy(p));
                               return out;
                             })
      .def_readonly("footprint_radius_m", &TrackArray::footprint_radius_m)
      .def("centre_element", &TrackArray::centre_element);
  py::class_<TrackReadingConfig>(m, "TrackReadingConfig", "How the row is read.")
      .def(py::init([](int max_value, double on_fraction, double tape_width_m, double arm_clearance_m) {
             return TrackReadingConfig{max_value, on_fraction, tape_width_m, arm_clearance_m};
           }),
           py::arg("max_value") = 255, py::arg("on_fraction") = 0.5, py::arg("tape_width_m") = 0.02,
           py::arg("arm_clearance_m") = 0.003)
      .def_readwrite("max_value", &TrackReadingConfig::max_value)
      .def_readwrite("on_fraction", &TrackReadingConfig::on_fraction)
      .def_readwrite("tape_width_m", &TrackReadingConfig::tape_width_m)
      .def_readwrite("arm_clearance_m", &TrackReadingConfig::arm_clearance_m);
  py::class_<TrackArrayReading>(m, "TrackArrayReading", "One reading of the row.")
      .def_readonly("on_track", &TrackArrayReading::on_track)
      .def_readonly("elements_on", &TrackArrayReading::elements_on)
      .def_readonly("offset_m", &TrackArrayReading::offset_m, "where the tape lies across the row, left positive")
      .def_readonly("run_offset_m", &TrackArrayReading::run_offset_m)
      .def_readonly("arm_left", &TrackArrayReading::arm_left)
      .def_readonly("arm_right", &TrackArrayReading::arm_right);
  m.def("arm_sides", &agents::arm_sides, py::arg("array"), py::arg("config"),
        "Per element: +1 it can see a side arm on the left, -1 on the right, 0 neither.");
  m.def(
      "read_track_array",
      [](const TrackArray& array, const std::vector<int>& track, const TrackReadingConfig& config,
         const std::vector<int>& sides,
         double near_m) { return agents::read_track_array(array, track, config, sides, near_m); },
      py::arg("array"), py::arg("track"), py::arg("config"), py::arg("sides"), py::arg("near_m") = 0.0,
      "Reads one set of track values (Input.track).");
}

void bind_scan(py::module_& m) {
  py::enum_<TrackFeatureKind>(m, "TrackFeatureKind", "What a node is, seen from the way the robot came in.")
      .value("NONE", TrackFeatureKind::kNone)
      .value("END", TrackFeatureKind::kEnd)
      .value("CORNER_LEFT", TrackFeatureKind::kCornerLeft)
      .value("CORNER_RIGHT", TrackFeatureKind::kCornerRight)
      .value("TEE", TrackFeatureKind::kTee)
      .value("CROSS", TrackFeatureKind::kCross);
  m.def(
      "track_feature_name", [](TrackFeatureKind k) { return std::string(agents::track_feature_name(k)); },
      py::arg("kind"));
  py::class_<BranchScanConfig>(m, "BranchScanConfig", "Knobs of the turn on the spot.")
      .def(py::init<>())
      .def_readwrite("merge_deg", &BranchScanConfig::merge_deg)
      .def_readwrite("straight_deg", &BranchScanConfig::straight_deg)
      .def_readwrite("min_radius_share", &BranchScanConfig::min_radius_share);
  py::class_<ScanResult>(m, "ScanResult", "What a turn on the spot found (odometry frame).")
      .def_readonly("ways_rad", &ScanResult::ways_rad)
      .def_property_readonly("way_points_m",
                             [](const ScanResult& r) {
                               py::list out;
                               for (const Vec2& p : r.way_points_m) out.append(xy(p));
                               return out;
                             })
      .def_property_readonly("node_m", [](const ScanResult& r) { return xy(r.node_m); })
      .def_readonly("kind", &ScanResult::kind)
      .def_readonly("way_in", &ScanResult::way_in);
  py::class_<BranchScan>(m, "BranchScan",
                         "Collects the row's readings while the robot turns once on the spot, then tells the ways the "
                         "tape leaves by, the node's kind and where it is.")
      .def(py::init<TrackArray, TrackReadingConfig, BranchScanConfig>(), py::arg("array"), py::arg("reading"),
           py::arg("config") = BranchScanConfig{})
      .def("start", &BranchScan::start, py::arg("pose"), py::arg("arrival_heading_rad"))
      .def(
          "add", [](BranchScan& s, const Pose2& pose, const std::vector<int>& track) { s.add(pose, track); },
          py::arg("pose"), py::arg("track"))
      .def("turned_rad", &BranchScan::turned_rad)
      .def("complete", &BranchScan::complete)
      .def("result", &BranchScan::result);
}

}  // namespace

void bind_track_features(py::module_& m) {
  bind_sensor_config(m);
  bind_array(m);
  bind_scan(m);
}

}  // namespace rilbed::python

// The controller API as Python sees it: rilbed.Input, rilbed.SwarmInput, rilbed.Output,
// the readings' small types and the Khepera's constants. Names and units follow the C++
// ControlInput, so that one page of docs serves both.
#include <algorithm>
#include <cmath>
#include <limits>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "environment/sensor_readings.hpp"
#include "python/controller_api.hpp"
#include "python/python_runtime.hpp"

namespace py = pybind11;

namespace rilbed::python {

namespace {

py::object pose_or_none(const std::optional<Pose2>& pose) {
  if (!pose) return py::none();
  return py::cast(*pose);
}

py::list team_list(const std::vector<agents::TeamMessage>& team) {
  py::list out;
  for (const agents::TeamMessage& m : team) out.append(py::cast(m));
  return out;
}

py::dict models_dict(const environment::SensorReadings& s) {
  py::dict out;
  for (const environment::ModelReading& m : s.models) out[py::str(std::string(m.name))] = py::cast(m.values);
  return out;
}

void bind_readings(py::module_& m) {
  py::class_<Pose2>(m, "Pose", "A pose in the field frame: metres, heading in radians counter-clockwise from +x.")
      .def(py::init([](double x_m, double y_m, double theta_rad) {
             return Pose2{{x_m, y_m}, theta_rad};
           }),
           py::arg("x_m"), py::arg("y_m"), py::arg("theta_rad"))
      .def_property_readonly("x_m", [](const Pose2& p) { return p.position_m.x; })
      .def_property_readonly("y_m", [](const Pose2& p) { return p.position_m.y; })
      .def_property_readonly("theta_rad", [](const Pose2& p) { return p.heading_rad; })
      .def("__repr__", [](const Pose2& p) {
        return "Pose(x_m=" + std::to_string(p.position_m.x) + ", y_m=" + std::to_string(p.position_m.y) +
               ", theta_rad=" + std::to_string(p.heading_rad) + ")";
      });
  py::class_<environment::BeaconSighting>(m, "Beacon", "An IR beacon in view: its ID and bearing (no distance).")
      .def_readonly("id", &environment::BeaconSighting::id)
      .def_readonly("bearing_rad", &environment::BeaconSighting::bearing_rad, "counter-clockwise from forward")
      .def("__repr__", [](const environment::BeaconSighting& b) {
        return "Beacon(id=" + std::to_string(b.id) + ", bearing_rad=" + std::to_string(b.bearing_rad) + ")";
      });
  py::class_<environment::OdometryReading>(m, "Odometer", "Wheel counters in pulses (1 pulse = 0.08 mm).")
      .def_readonly("left_pulses", &environment::OdometryReading::left_pulses)
      .def_readonly("right_pulses", &environment::OdometryReading::right_pulses);
  py::class_<agents::TeamMessage>(m, "TeamMember", "One robot's team broadcast: who, where, doing what, when.")
      .def_readonly("id", &agents::TeamMessage::id)
      .def_readonly("pose", &agents::TeamMessage::pose)
      .def_property_readonly("behaviour", [](const agents::TeamMessage& t) { return std::string(t.behaviour); })
      .def_readonly("t_us", &agents::TeamMessage::t_us);
}

void bind_step_input(py::module_& m) {
  py::class_<StepInput>(m, "Input", "What a controller's step gets: one robot's readings at one control instant.")
      .def_property_readonly("t_us", [](const StepInput& s) { return s.input.t_us; })
      .def_property_readonly("robot_id", [](const StepInput& s) { return s.input.robot_id; })
      .def_property_readonly("proximity",
                             [](const StepInput& s) -> py::object {
                               if (!s.input.sensors.proximity) return py::none();
                               return py::cast(*s.input.sensors.proximity);
                             })
      .def_property_readonly("range_m",
                             [](const StepInput& s) {
                               std::vector<double> out;
                               for (const auto& r : s.input.sensors.ranges) {
                                 out.push_back(r.hit ? r.distance_m : std::numeric_limits<double>::infinity());
                               }
                               return out;
                             })
      .def_property_readonly("beacons", [](const StepInput& s) { return s.input.sensors.beacons; })
      .def_property_readonly("track", [](const StepInput& s) { return s.input.sensors.track; })
      .def_property_readonly("odometer",
                             [](const StepInput& s) -> py::object {
                               if (!s.input.sensors.odometry) return py::none();
                               return py::cast(*s.input.sensors.odometry);
                             })
      .def_property_readonly("pose", [](const StepInput& s) { return pose_or_none(s.input.pose); })
      .def_property_readonly("team", [](const StepInput& s) { return team_list(s.team); })
      .def_property_readonly("models", [](const StepInput& s) { return models_dict(s.input.sensors); })
      .def(
          "model",
          [](const StepInput& s, const std::string& name) -> py::object {
            for (const auto& r : s.input.sensors.models) {
              if (r.name == name) return py::cast(r.values);
            }
            return py::none();
          },
          py::arg("name"), "The readings of the sensor model mounted as `name`, or None.");
}

// An (n, width) array of a flat column.
py::array_t<double> flat_array(const std::vector<double>& data, std::size_t n, std::size_t width) {
  py::array_t<double> a({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(width)});
  std::copy(data.begin(), data.end(), a.mutable_data());
  return a;
}

// An (n, k) array of a per-row column (k: the longest row; NaN past a row's end and for
// rows past the column's end).
py::array_t<double> ragged_array(const std::vector<std::vector<double>>& rows, std::size_t n) {
  std::size_t width = 0;
  for (const auto& r : rows) width = std::max(width, r.size());
  py::array_t<double> a({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(width)});
  double* data = a.mutable_data();
  std::fill(data, data + n * width, std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < rows.size(); ++i) std::copy(rows[i].begin(), rows[i].end(), data + i * width);
  return a;
}

py::dict models_arrays(const SwarmColumns& c) {
  std::vector<std::string_view> names;
  for (const auto& row : c.models) {
    for (const auto& [name, values] : row) {
      if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
    }
  }
  py::dict out;
  for (const std::string_view name : names) {
    std::vector<std::vector<double>> rows(c.models.size());
    for (std::size_t i = 0; i < c.models.size(); ++i) {
      for (const auto& [n, values] : c.models[i]) {
        if (n == name) rows[i] = values;
      }
    }
    out[py::str(std::string(name))] = ragged_array(rows, c.rows());
  }
  return out;
}

py::list beacon_lists(const SwarmColumns& c) {
  py::list out;
  for (std::size_t i = 0; i < c.rows(); ++i) {
    out.append(i < c.beacons.size() ? py::cast(c.beacons[i]) : py::list());
  }
  return out;
}

// A property of SwarmInput made on first access and kept.
template <typename Make>
auto lazily(py::object SwarmInput::*field, Make make) {
  return [field, make](SwarmInput& s) {
    py::object& cached = s.*field;
    if (!cached) cached = make(*s.columns);
    return cached;
  };
}

void bind_swarm_input(py::module_& m) {
  py::class_<SwarmInput>(m, "SwarmInput", "What step_all gets: every robot of the class at once, a row per robot.")
      .def_property_readonly("t_us", [](const SwarmInput& s) { return s.columns->t_us; })
      .def_property_readonly("robot_id", lazily(&SwarmInput::robot_id,
                                                [](const SwarmColumns& c) -> py::object {
                                                  py::array_t<long long> a(static_cast<py::ssize_t>(c.rows()));
                                                  std::copy(c.robot_id.begin(), c.robot_id.end(), a.mutable_data());
                                                  return a;
                                                }))
      .def_property_readonly("proximity", lazily(&SwarmInput::proximity,
                                                 [](const SwarmColumns& c) -> py::object {
                                                   return flat_array(c.proximity, c.rows(),
                                                                     environment::kProximityCount);
                                                 }))
      .def_property_readonly(
          "pose", lazily(&SwarmInput::pose,
                         [](const SwarmColumns& c) -> py::object { return flat_array(c.pose, c.rows(), 3); }))
      .def_property_readonly(
          "odometer", lazily(&SwarmInput::odometer,
                             [](const SwarmColumns& c) -> py::object { return flat_array(c.odometer, c.rows(), 2); }))
      .def_property_readonly(
          "range_m", lazily(&SwarmInput::range_m,
                            [](const SwarmColumns& c) -> py::object { return ragged_array(c.range_m, c.rows()); }))
      .def_property_readonly(
          "track", lazily(&SwarmInput::track,
                          [](const SwarmColumns& c) -> py::object { return ragged_array(c.track, c.rows()); }))
      .def_property_readonly(
          "beacons", lazily(&SwarmInput::beacons, [](const SwarmColumns& c) -> py::object { return beacon_lists(c); }))
      .def_property_readonly(
          "models", lazily(&SwarmInput::models, [](const SwarmColumns& c) -> py::object { return models_arrays(c); }))
      .def_property_readonly(
          "team", lazily(&SwarmInput::team, [](const SwarmColumns& c) -> py::object { return team_list(c.team); }))
      .def("__len__", [](const SwarmInput& s) { return s.columns->rows(); });
}

void bind_output(py::module_& m) {
  py::class_<StepOutput>(m, "Output", "Wheel speeds in Khepera units (8 mm/s each, ±127) and the active behaviour.")
      .def(py::init<int, int, std::string>(), py::arg("left"), py::arg("right"), py::arg("behaviour") = "idle")
      .def_readwrite("left", &StepOutput::left)
      .def_readwrite("right", &StepOutput::right)
      .def_readwrite("behaviour", &StepOutput::behaviour)
      .def("__repr__", [](const StepOutput& o) {
        return "Output(left=" + std::to_string(o.left) + ", right=" + std::to_string(o.right) + ", behaviour='" +
               o.behaviour + "')";
      });
}

}  // namespace

void bind_controller_api(py::module_& m) {
  bind_readings(m);
  bind_step_input(m);
  bind_swarm_input(m);
  bind_output(m);
  bind_track_features(m);
  m.def(
      "wheels_from_twist",
      [](double speed_mps, double turn_rate_radps) {
        const agents::WheelCommand w = agents::wheels_from_twist(speed_mps, turn_rate_radps);
        return py::make_tuple(w.left, w.right);
      },
      py::arg("speed_mps"), py::arg("turn_rate_radps"),
      "Forward speed (m/s) and turn rate (rad/s, counter-clockwise) to (left, right) wheel units, rounded and "
      "clamped to ±127 with the curvature kept.");
  m.attr("METRES_PER_SECOND_PER_UNIT") = agents::kMetresPerSecondPerUnit;
  m.attr("MAX_WHEEL_UNITS") = agents::kMaxWheelUnits;
  m.attr("WHEEL_BASE_M") = agents::kWheelBase_m;
  m.attr("PROXIMITY_COUNT") = environment::kProximityCount;
  m.attr("PROXIMITY_MAX") = environment::kProximityMax;
}

}  // namespace rilbed::python

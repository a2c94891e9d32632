// The values a Python controller is handed and hands back, as C++ types for pybind11 to
// bind (controller_bindings.cpp): one robot's input, a swarm's input as NumPy arrays, and
// an output with its behaviour.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <pybind11/pybind11.h>

#include "agents/controller.hpp"
#include "python/swarm_columns.hpp"

namespace rilbed::python {

/// One robot's input, owned (a controller may keep it past its step): `rilbed.Input`.
struct StepInput {
  agents::ControlInput input;             ///< input.team is empty; see team
  std::vector<agents::TeamMessage> team;  ///< the latest team broadcast (wants_team classes)

  /// A copy of `in`, its team included.
  static StepInput copy_of(const agents::ControlInput& in) {
    StepInput s{in, {in.team.begin(), in.team.end()}};
    s.input.team = {};
    return s;
  }
};

/// Every robot of a vectorised class at one control instant: `rilbed.SwarmInput`. Each
/// field is a NumPy array (or a list, a dict) with a row per robot, in robot_id's order,
/// made from `columns` the first time it is read and kept.
struct SwarmInput {
  std::shared_ptr<const SwarmColumns> columns;  ///< never null
  pybind11::object robot_id;                    ///< (n,) int64
  pybind11::object proximity;                   ///< (n, 8) float64, 0..1023; NaN rows for robots without IR sensors
  pybind11::object pose;                        ///< (n, 3) float64: x_m, y_m, theta_rad; NaN rows when unknown
  pybind11::object range_m;                     ///< (n, k) float64; inf: nothing in range; NaN: no such range finder
  pybind11::object track;                       ///< (n, k) float64; NaN: no such track sensor
  pybind11::object odometer;                    ///< (n, 2) float64 pulses; NaN rows without an odometer
  pybind11::object beacons;                     ///< list of n lists of rilbed.Beacon
  pybind11::object models;                      ///< dict: a sensor model's name -> (n, k) float64
  pybind11::object team;                        ///< list of rilbed.TeamMember (the latest broadcast)
};

/// What a controller answers with when it names its behaviour: `rilbed.Output`.
struct StepOutput {
  int left = 0;                    ///< left wheel, Khepera units (8 mm/s), ±127
  int right = 0;                   ///< right wheel, Khepera units
  std::string behaviour = "idle";  ///< shown in the panel and written to trajectories.csv
};

}  // namespace rilbed::python

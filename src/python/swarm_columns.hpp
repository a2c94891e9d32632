// A vectorised class's robots at one control instant, gathered as columns (a row per
// robot) without touching Python: what rilbed.SwarmInput's arrays are made from, on first
// access (a class that reads only inp.proximity pays for no other array).
#pragma once

#include <string_view>
#include <utility>
#include <vector>

#include "agents/controller.hpp"

namespace rilbed::python {

/// The gathered rows. Fixed-width readings are flat (NaN rows where a robot lacks the
/// sensor); variable ones are kept per robot only once some robot has them.
struct SwarmColumns {
  TimeUs t_us = 0;
  std::vector<long long> robot_id;                                ///< one per row
  std::vector<double> proximity;                                  ///< 8 per row, 0..1023
  std::vector<double> pose;                                       ///< 3 per row: x_m, y_m, theta_rad
  std::vector<double> odometer;                                   ///< 2 per row: left, right pulses
  std::vector<std::vector<double>> range_m;                       ///< per row (inf: no hit); empty: none has one
  std::vector<std::vector<double>> track;                         ///< per row; empty: none has one
  std::vector<std::vector<environment::BeaconSighting>> beacons;  ///< per row; empty: none sees one
  std::vector<std::vector<std::pair<std::string_view, std::vector<double>>>> models;  ///< per row; empty: none
  std::vector<agents::TeamMessage> team;  ///< the latest broadcast (the first row's; every row has the same)

  std::size_t rows() const { return robot_id.size(); }
  /// Makes room for `n` rows of the fixed-width columns.
  void reserve(std::size_t n);
  /// Appends one robot's input as a row.
  void add(const agents::ControlInput& in);
};

}  // namespace rilbed::python

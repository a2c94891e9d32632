#include "python/swarm_columns.hpp"

#include <limits>

namespace rilbed::python {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Appends `value` as row `row` of a per-row column that is kept only once some row has a
// value (earlier rows become empty ones).
template <typename T>
void add_sparse(std::vector<T>& column, std::size_t row, T value) {
  column.resize(row);
  column.push_back(std::move(value));
}

}  // namespace

void SwarmColumns::reserve(std::size_t n) {
  robot_id.reserve(n);
  proximity.reserve(n * environment::kProximityCount);
  pose.reserve(n * 3);
  odometer.reserve(n * 2);
}

void SwarmColumns::add(const agents::ControlInput& in) {
  const std::size_t row = robot_id.size();
  if (row == 0) {
    t_us = in.t_us;
    team.assign(in.team.begin(), in.team.end());
  }
  robot_id.push_back(in.robot_id);
  const environment::SensorReadings& s = in.sensors;
  if (s.proximity) {
    proximity.insert(proximity.end(), s.proximity->begin(), s.proximity->end());
  } else {
    proximity.insert(proximity.end(), environment::kProximityCount, kNaN);
  }
  if (in.pose) {
    pose.insert(pose.end(), {in.pose->position_m.x, in.pose->position_m.y, in.pose->heading_rad});
  } else {
    pose.insert(pose.end(), 3, kNaN);
  }
  if (s.odometry) {
    odometer.insert(odometer.end(), {double(s.odometry->left_pulses), double(s.odometry->right_pulses)});
  } else {
    odometer.insert(odometer.end(), 2, kNaN);
  }
  if (!s.ranges.empty()) {
    std::vector<double> r;
    for (const environment::RangeReading& g : s.ranges) {
      r.push_back(g.hit ? g.distance_m : std::numeric_limits<double>::infinity());
    }
    add_sparse(range_m, row, std::move(r));
  }
  if (!s.track.empty()) add_sparse(track, row, std::vector<double>(s.track.begin(), s.track.end()));
  if (!s.beacons.empty()) add_sparse(beacons, row, s.beacons);
  if (!s.models.empty()) {
    std::vector<std::pair<std::string_view, std::vector<double>>> m;
    for (const environment::ModelReading& r : s.models) m.emplace_back(r.name, r.values);
    add_sparse(models, row, std::move(m));
  }
}

}  // namespace rilbed::python

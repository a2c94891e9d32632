#include "bus/agent_messages.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "agents/behaviour_names.hpp"
#include "bus/lcm_bus.hpp"
#include "bus/lcm_conversion.hpp"

namespace rilbed::bus {

rilbed::agent_input_t to_lcm(const agents::ControlInput& input) {
  rilbed::agent_input_t m;
  m.id = input.robot_id;
  m.has_pose = input.pose.has_value();
  m.x_m = input.pose ? input.pose->position_m.x : 0.0;
  m.y_m = input.pose ? input.pose->position_m.y : 0.0;
  m.theta_rad = input.pose ? input.pose->heading_rad : 0.0;
  fill(m.sensors, input.robot_id, input.sensors);
  m.models = models_to_lcm(input.robot_id, input.sensors, /*with_marks=*/false);  // marks are for displays
  return m;
}

agents::ControlInput from_lcm(const rilbed::agent_input_t& m, TimeUs t_us, std::set<std::string, std::less<>>& names) {
  agents::ControlInput input;
  input.t_us = t_us;
  input.robot_id = m.id;
  if (m.has_pose) input.pose = Pose2{{m.x_m, m.y_m}, m.theta_rad};
  input.sensors = from_lcm(m.sensors, t_us);
  // (Checked by plausible(); past the names' bound a robot's models are left out.)
  merge_models(m.models, input.sensors, names);
  return input;
}

rilbed::team_member_t to_lcm(const agents::TeamMessage& member) {
  rilbed::team_member_t m;
  m.id = member.id;
  m.x_m = member.pose.position_m.x;
  m.y_m = member.pose.position_m.y;
  m.theta_rad = member.pose.heading_rad;
  m.behaviour = std::string(member.behaviour);
  m.utime = member.t_us;
  return m;
}

agents::TeamMessage from_lcm(const rilbed::team_member_t& m) {
  return {m.id, Pose2{{m.x_m, m.y_m}, m.theta_rad}, agents::intern_behaviour(m.behaviour), m.utime};
}

rilbed::agent_output_t to_lcm(const run::RemoteOutput& output) {
  rilbed::agent_output_t m;
  m.id = output.robot_id;
  m.left_units =
      static_cast<std::int16_t>(std::clamp(output.output.wheels.left, -agents::kMaxWheelUnits, agents::kMaxWheelUnits));
  m.right_units = static_cast<std::int16_t>(
      std::clamp(output.output.wheels.right, -agents::kMaxWheelUnits, agents::kMaxWheelUnits));
  m.behaviour = std::string(output.output.behaviour);
  m.done = output.done;
  return m;
}

run::RemoteOutput from_lcm(const rilbed::agent_output_t& m) {
  run::RemoteOutput out;
  out.robot_id = m.id;
  out.output.wheels = {std::clamp<int>(m.left_units, -agents::kMaxWheelUnits, agents::kMaxWheelUnits),
                       std::clamp<int>(m.right_units, -agents::kMaxWheelUnits, agents::kMaxWheelUnits)};
  out.output.behaviour = agents::intern_behaviour(m.behaviour);
  out.done = m.done;
  return out;
}

bool plausible(const rilbed::quantum_t& q) {
  auto finite = [](double v) { return std::isfinite(v); };
  for (const rilbed::agent_input_t& in : q.inputs) {
    if (in.has_pose && !(finite(in.x_m) && finite(in.y_m) && finite(in.theta_rad))) return false;
    const rilbed::robot_sensors_t& s = in.sensors;
    if (!s.proximity.empty() && s.proximity.size() != static_cast<std::size_t>(environment::kProximityCount))
      return false;
    for (const std::int16_t v : s.proximity) {
      if (v < 0 || v > environment::kProximityMax) return false;
    }
    if (!std::all_of(s.range_m.begin(), s.range_m.end(), finite)) return false;
    if (!std::all_of(s.beacon_bearing_rad.begin(), s.beacon_bearing_rad.end(), finite)) return false;
    if (std::any_of(s.track.begin(), s.track.end(), [](std::int32_t v) { return v < 0; })) return false;
    if (models_problem(in.models)) return false;
  }
  for (const rilbed::team_member_t& m : q.team) {
    if (!(finite(m.x_m) && finite(m.y_m) && finite(m.theta_rad))) return false;
  }
  return true;
}

}  // namespace rilbed::bus

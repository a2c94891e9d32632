// The agent exchange's messages to and from rilbed's own types: a controller's
// input (sensors, pose, the team broadcast) and its output, exact to the bit, so that a
// controller stepped in another process decides exactly as it would in the run's.
#pragma once

#include <set>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "agents/controller.hpp"
#include "bus/lcm_conversion.hpp"
#include "rilbed/agent_input_t.hpp"
#include "rilbed/agent_output_t.hpp"
#include "rilbed/quantum_t.hpp"
#include "rilbed/team_member_t.hpp"
#include "run/agent_exchange.hpp"

namespace rilbed::bus {

/// `input`'s robot, pose, sensors and sensor models' readings (not their marks, nor its
/// team: see to_lcm(TeamMessage)).
rilbed::agent_input_t to_lcm(const agents::ControlInput& input);
/// Back to a ControlInput at `t_us` (its team left empty), its sensor models' names interned
/// in `model_names` (which must outlive the input).
agents::ControlInput from_lcm(const rilbed::agent_input_t& message, TimeUs t_us,
                              std::set<std::string, std::less<>>& model_names);

rilbed::team_member_t to_lcm(const agents::TeamMessage& member);
/// Its behaviour interned (agents::intern_behaviour).
agents::TeamMessage from_lcm(const rilbed::team_member_t& message);

rilbed::agent_output_t to_lcm(const run::RemoteOutput& output);
/// Wheel speeds clamped to +-kMaxWheelUnits; the behaviour interned (agents::intern_behaviour).
run::RemoteOutput from_lcm(const rilbed::agent_output_t& message);

/// Whether every input of a quantum from the network is one a controller can be handed:
/// every pose, range, bearing and team pose finite, proximity either absent or eight values
/// in 0..kProximityMax, track values not negative. (lcm-gen's decoder takes any bits; a NaN
/// pose would reach a controller's arithmetic.)
bool plausible(const rilbed::quantum_t& quantum);

}  // namespace rilbed::bus

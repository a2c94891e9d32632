#include "agents/convoy.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rilbed::agents {

ConvoyAgent::ConvoyAgent(int rank, ConvoyConfig config) : rank_(rank), config_(config), network_(config.network) {
  if (rank < 1) throw std::invalid_argument("convoy: rank must be >= 1, got " + std::to_string(rank));
  state_.active = Behaviour::kWait;
}

BehaviourInputs ConvoyAgent::inputs(const ConvoyPerception& p) const {
  BehaviourInputs in{};
  if (rank_ == 1 || !p.leader || !p.self) {
    // The head waits for the team to gather behind it; an agent that cannot place
    // itself or its leader has nothing better to do than stand still. Standing still,
    // neither needs to avoid: the robots gathering around it keep their own distance.
    in[static_cast<std::size_t>(Behaviour::kWait)] = 1.0;
    return in;
  }
  const double distance = (p.leader->position_m - p.self->position_m).norm();
  // Smooth hand-over between search (far) and follow (near) around engage_m.
  const double far = std::clamp((distance - config_.engage_m) / config_.engage_ramp_m + 0.5, 0.0, 1.0);
  in[static_cast<std::size_t>(Behaviour::kSearch)] = far;
  in[static_cast<std::size_t>(Behaviour::kFollow)] = 1.0 - far;
  // Avoidance matters only while driving on: a follower holding its standoff in a tight
  // convoy sees its neighbours all the time, and turning away from them would only break
  // the convoy up.
  const bool driving_on = distance > config_.standoff_m + config_.hold_tolerance_m;
  if (p.proximity && driving_on) {
    in[static_cast<std::size_t>(Behaviour::kAvoid)] =
        obstacle_level(*p.proximity, config_.avoid_low, config_.avoid_high);
  }
  return in;
}

Vec2 ConvoyAgent::repulsion(const ConvoyPerception& p) const {
  Vec2 push;
  if (!p.self) return push;
  for (const Vec2& other : p.others_m) {
    const Vec2 away = p.self->position_m - other;
    const double d = away.norm();
    if (d < 1e-9 || d >= config_.repulse_radius_m) continue;
    // Grows from 0 at the radius to repulse_gain at contact (two radii of 27.5 mm).
    const double contact = 0.055;
    const double strength = config_.repulse_gain *
                            std::clamp((config_.repulse_radius_m - d) / (config_.repulse_radius_m - contact), 0.0, 1.0);
    push = push + away / d * strength;
  }
  return push;
}

ControlOutput ConvoyAgent::step(const ConvoyPerception& p, double dt_s) {
  state_ = network_.update(state_, inputs(p), dt_s);
  ControlOutput out;
  out.behaviour = behaviour_name(state_.active);
  switch (state_.active) {
    case Behaviour::kAvoid:
      if (p.proximity) out.wheels = steer_away(*p.proximity, config_.steering);
      break;
    case Behaviour::kSearch:
      if (p.self && p.leader) {
        out.wheels = steer_to(*p.self, p.leader->position_m, config_.standoff_m, config_.steering, repulsion(p));
      }
      break;
    case Behaviour::kFollow:
      if (p.self && p.leader) {
        // Near the leader only the robots right beside matter; the standoff does the rest.
        out.wheels = steer_to(*p.self, p.leader->position_m, config_.standoff_m, config_.steering, repulsion(p) * 0.5);
      }
      break;
    case Behaviour::kWait: out.wheels = {}; break;
  }
  return out;
}

ConvoyController::ConvoyController(int rank, ConvoyConfig config) : agent_(rank, config) {}

ControlOutput ConvoyController::step(const ControlInput& input) {
  ConvoyPerception p;
  p.self = input.pose;
  p.proximity = input.sensors.proximity;
  for (const TeamMessage& m : input.team) {
    if (m.id == input.robot_id) continue;
    if (m.id == agent_.rank() - 1) {
      p.leader = m.pose;
    } else if (m.id != agent_.rank() + 1) {  // the follower keeps its own distance
      p.others_m.push_back(m.pose.position_m);
    }
  }
  const double dt_s = last_t_us_ ? std::max(1e-3, us_to_seconds(input.t_us - *last_t_us_)) : 0.1;
  last_t_us_ = input.t_us;
  return agent_.step(p, dt_s);
}

CentralConvoy::CentralConvoy(ConvoyConfig config) : config_(config) {}

std::map<int, ControlOutput> CentralConvoy::step(TimeUs t_us, const std::vector<AgentView>& agents,
                                                 const std::vector<Vec2>& obstacles_m) {
  const double dt_s = last_t_us_ ? std::max(1e-3, us_to_seconds(t_us - *last_t_us_)) : 0.1;
  last_t_us_ = t_us;
  std::map<int, const AgentView*> by_id;
  for (const AgentView& a : agents) by_id[a.id] = &a;
  std::map<int, ControlOutput> out;
  for (const AgentView& a : agents) {
    auto it = agents_.find(a.id);
    if (it == agents_.end()) it = agents_.emplace(a.id, ConvoyAgent(a.id, config_)).first;
    ConvoyPerception p;
    p.self = a.pose;
    p.proximity = a.proximity;
    p.others_m = obstacles_m;
    for (const AgentView& other : agents) {
      if (other.id == a.id || !other.pose) continue;
      if (other.id == a.id - 1) {
        p.leader = other.pose;
      } else if (other.id != a.id + 1) {  // the follower keeps its own distance
        p.others_m.push_back(other.pose->position_m);
      }
    }
    out[a.id] = it->second.step(p, dt_s);
  }
  return out;
}

FormationMonitor::FormationMonitor(int team_size, double hold_s, double min_gap_m, double max_gap_m)
    : team_size_(team_size), hold_us_(seconds_to_us(hold_s)), min_gap_m_(min_gap_m), max_gap_m_(max_gap_m) {
  if (team_size < 1) throw std::invalid_argument("formation monitor: team size must be >= 1");
}

bool FormationMonitor::condition(const std::vector<Sample>& team) const {
  std::vector<const Sample*> by_rank(team_size_ + 1, nullptr);
  for (const Sample& s : team) {
    if (s.id >= 1 && s.id <= team_size_) by_rank[s.id] = &s;
  }
  for (int k = 1; k <= team_size_; ++k) {
    if (!by_rank[k]) return false;
  }
  for (int k = 2; k <= team_size_; ++k) {
    if (by_rank[k]->behaviour != behaviour_name(Behaviour::kFollow)) return false;
    const double gap = (by_rank[k]->pose.position_m - by_rank[k - 1]->pose.position_m).norm();
    if (gap < min_gap_m_ || gap > max_gap_m_) return false;
  }
  return true;
}

bool FormationMonitor::update(TimeUs t_us, const std::vector<Sample>& team) {
  if (!condition(team)) {
    holding_since_us_.reset();
    return false;
  }
  if (!holding_since_us_) holding_since_us_ = t_us;
  if (!formed_at_us_ && t_us - *holding_since_us_ >= hold_us_) {
    formation_time_us_ = holding_since_us_;
    formed_at_us_ = t_us;
    return true;
  }
  return false;
}

}  // namespace rilbed::agents

// Convoy team formation (paper 001 §5): agents 1..N, agent k follows agent k-1. Each
// agent's behaviour network chooses between search (drive to the leader while it is
// far), follow (keep a standoff behind the leader), wait (the head, and any agent that
// does not know where its leader is, stands still for the team to gather) and avoid
// (turn away from what the proximity sensors see). Sub-teams form where a run of agents
// has found its leaders, and break when a crossing robot makes one of them avoid.
//
// The same logic serves both modes of the paper:
// - central: a coordinator knows every pose exactly at every step and sends each agent
//   its wheel command (CentralConvoy);
// - distributed: each agent decides alone from its own sensors, its own pose and the
//   team messages broadcast to it, which may be stale (ConvoyController).
#pragma once

#include <map>
#include <optional>
#include <vector>

#include "agents/behaviour_network.hpp"
#include "agents/controller.hpp"
#include "agents/steering.hpp"
#include "core/geometry.hpp"
#include "environment/sensor_readings.hpp"

namespace rilbed::agents {

/// Knobs of the convoy.
struct ConvoyConfig {
  /// Distance (centre to centre) a follower keeps behind its leader, metres. Within the
  /// "formed" window of 0.06-0.30 m and beyond the IR sensors' reach of the leader.
  double standoff_m = 0.12;
  /// A leader nearer than this is followed, farther is searched for, metres. Smaller
  /// than the formed window's 0.30 m so that a follower counts as formed while following.
  double engage_m = 0.22;
  /// Width of the ramp between search and follow around engage_m, metres.
  double engage_ramp_m = 0.04;
  /// A follower within this of its standoff holds its place and does not avoid, metres.
  double hold_tolerance_m = 0.015;
  /// Proximity level (fraction of full scale) at which avoidance starts, and at which it
  /// is fully called for.
  double avoid_low = 0.35;
  double avoid_high = 0.7;
  /// Other robots (not the leader) nearer than this bend the course away, metres.
  double repulse_radius_m = 0.12;
  /// Strength of that bend (1: as strong as the pull to the target at contact).
  double repulse_gain = 1.0;
  SteeringConfig steering;
  BehaviourNetworkConfig network;
};

/// What one agent knows at one step, however it came to know it.
struct ConvoyPerception {
  std::optional<Pose2> self;                              ///< own pose (field frame)
  std::optional<Pose2> leader;                            ///< agent k-1's pose, if k > 1 and known
  std::optional<environment::ProximityValues> proximity;  ///< own IR sensors
  std::vector<Vec2> others_m;  ///< positions of the other robots known (not self, the leader or the follower)
};

/// One agent's convoy decision, as a pure step on an explicit state.
class ConvoyAgent {
 public:
  /// Agent `rank` (1 = head) of a convoy. Throws std::invalid_argument if rank < 1.
  ConvoyAgent(int rank, ConvoyConfig config = {});

  /// Decides this step's wheels and behaviour from the perception; dt_s is the time since
  /// the previous step (the network's integration step), seconds.
  ControlOutput step(const ConvoyPerception& perception, double dt_s);

  int rank() const { return rank_; }
  Behaviour behaviour() const { return state_.active; }
  const BehaviourNetworkState& network_state() const { return state_; }

 private:
  BehaviourInputs inputs(const ConvoyPerception& p) const;
  Vec2 repulsion(const ConvoyPerception& p) const;

  int rank_;
  ConvoyConfig config_;
  BehaviourNetwork network_;
  BehaviourNetworkState state_;
};

/// Distributed mode: one agent's own controller. Its leader is the team member with ID
/// rank - 1 (agents are numbered by their robot IDs, 1..N); it knows the others only
/// from the team messages it receives.
class ConvoyController final : public Controller {
 public:
  ConvoyController(int rank, ConvoyConfig config = {});
  ControlOutput step(const ControlInput& input) override;
  bool wants_team() const override { return true; }

 private:
  ConvoyAgent agent_;
  std::optional<TimeUs> last_t_us_;
};

/// Central mode: one coordinator that sees every agent's pose and proximity readings at
/// every step and sends each its command.
class CentralConvoy {
 public:
  /// One agent's state as the coordinator sees it.
  struct AgentView {
    int id = 0;                                             ///< the robot's ID = its rank
    std::optional<Pose2> pose;                              ///< nullopt: not localised
    std::optional<environment::ProximityValues> proximity;  ///< its sensors
  };
  explicit CentralConvoy(ConvoyConfig config = {});
  /// Commands for every agent in `agents` (any order) at time t_us, keyed by ID.
  /// Other robots (not in the convoy) can be listed in `obstacles_m` for the repulsion.
  std::map<int, ControlOutput> step(TimeUs t_us, const std::vector<AgentView>& agents,
                                    const std::vector<Vec2>& obstacles_m = {});

 private:
  ConvoyConfig config_;
  std::map<int, ConvoyAgent> agents_;
  std::optional<TimeUs> last_t_us_;
};

/// Watches for the convoy being formed: every agent k > 1 in follow behaviour, 0.06 to
/// 0.30 m (centre to centre) from agent k-1, held for hold_s seconds.
class FormationMonitor {
 public:
  /// One agent at one instant.
  struct Sample {
    int id = 0;
    Pose2 pose;
    std::string_view behaviour;
  };
  explicit FormationMonitor(int team_size, double hold_s = 5.0, double min_gap_m = 0.06, double max_gap_m = 0.30);
  /// Feeds the team's state at t_us (every agent 1..N should be present; a missing one
  /// means not formed). Returns true on the step at which the hold completes.
  bool update(TimeUs t_us, const std::vector<Sample>& team);
  /// Whether the condition holds at the last update.
  bool holding() const { return holding_since_us_.has_value(); }
  /// Whether the convoy has formed (held for hold_s) at some point of the run.
  bool formed() const { return formed_at_us_.has_value(); }
  /// When the hold that formed the convoy began (the formation time), if formed.
  std::optional<TimeUs> formation_time_us() const { return formation_time_us_; }
  /// When that hold completed (formation time + hold).
  std::optional<TimeUs> formed_at_us() const { return formed_at_us_; }
  /// Whether the condition holds for a snapshot (no hold time).
  bool condition(const std::vector<Sample>& team) const;

 private:
  int team_size_;
  TimeUs hold_us_;
  double min_gap_m_, max_gap_m_;
  std::optional<TimeUs> holding_since_us_, formation_time_us_, formed_at_us_;
};

}  // namespace rilbed::agents

// How well a robot explored a tape network (paper 000 §9): the run's true path against
// the network's edges (what it visited), and the map it reported (track_node events)
// against the network's nodes (what it found, how far off, and what it made up). The
// measure behind track_explore's CTest, the tape-width experiment and the feature counts.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/geometry.hpp"
#include "environment/track_layouts.hpp"
#include "environment/track_network.hpp"
#include "run/run_recorder.hpp"

namespace rilbed::run {

/// The nodes robot `robot_id` reported, latest per ID, from a run's events. Details that
/// do not parse are skipped.
std::vector<ReportedTrackNode> reported_track_nodes(const std::vector<RunEvent>& events, int robot_id);

/// Knobs of the scoring.
struct ExplorationScoring {
  /// A node is found when a reported node lies within this of it, metres.
  double node_tolerance_m = 0.03;
  /// An edge is visited when the robot's centre came within this of at least
  /// `edge_cover` of the points along it (every centimetre, its end `end_margin_m` left
  /// out, where the nodes' other tapes are). Metres.
  double path_tolerance_m = 0.025;
  double edge_cover = 0.9;
  double end_margin_m = 0.04;
  /// A reported node within this of a vertex of a tape (a bend too gentle to be a node of
  /// the network) is a bend, not a false node. Metres.
  double bend_tolerance_m = 0.03;
};

/// The score of one robot's exploration.
struct ExplorationScore {
  int edges = 0;          ///< edges of the network
  double tape_m = 0.0;    ///< the network's length of tape
  int edges_visited = 0;  ///< of them, visited
  int nodes = 0;          ///< nodes a robot can sense (kind loop left out)
  int nodes_found = 0;    ///< of them, with a reported node within tolerance
  int kinds_right = 0;    ///< of those found, reported with the right kind
  /// The farthest any sensable node is from its nearest reported node, metres (infinity
  /// when none was reported).
  double worst_node_error_m = 0.0;
  int false_nodes = 0;  ///< reported nodes near no node of the network and no bend of a tape
  int bends = 0;        ///< reported nodes at a gentle bend of a tape
  /// When the robot had visited every edge, seconds; nullopt when it did not.
  std::optional<double> all_visited_s;
  std::vector<int> missed_edges;  ///< indices of edges not visited
  std::vector<int> missed_nodes;  ///< ids of nodes not found
};

/// The robot an exploration experiment puts on a network.
struct ExplorerSetup {
  int elements = 5;               ///< track sensor elements in a row across the front
  double spacing_m = 0.012;       ///< between neighbouring elements
  double ahead_m = 0.02;          ///< the row's distance ahead of the robot's centre
  double slip_sd = 0.0;           ///< wheel slip per step (relative sd), which the odometer does not count
  double wheel_bias = 0.0;        ///< the left wheel's systematic error (relative)
  double speed_mps = 0.1;         ///< track_explore's speed_mps
  double duration_s = 600.0;      ///< simulated seconds at most
  bool correct_odometry = false;  ///< track_explore's correct_odometry
};

/// A scenario (YAML text) of one track_explore robot at `start` on a 2 x 2 m field whose
/// tape network is make_track_layout(`layout_seed`, `kind`) at `tape_width_m`, with
/// paper 000's track sensor block (8 mm high, 30 degree cone, 16 segments, 15 % coverage,
/// 5 % noise) and a 50 ms control period.
std::string exploration_scenario_yaml(environment::TrackLayoutKind kind, int layout_seed, double tape_width_m,
                                      Pose2 start, const ExplorerSetup& setup = {});

/// Scores robot `robot_id`'s trajectory and reported nodes against `network` (built from
/// `tracks`, whose vertices are the bends).
ExplorationScore score_exploration(const environment::TrackNetwork& network,
                                   const std::vector<environment::TrackConfig>& tracks,
                                   const std::vector<TrajectorySample>& trajectory,
                                   const std::vector<ReportedTrackNode>& reported, int robot_id,
                                   const ExplorationScoring& scoring = {});

}  // namespace rilbed::run

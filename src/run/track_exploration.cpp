#include "run/track_exploration.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace rilbed::run {

std::vector<ReportedTrackNode> reported_track_nodes(const std::vector<RunEvent>& events, int robot_id) {
  std::vector<ReportedTrackNode> nodes;
  for (const RunEvent& e : events) {
    if (e.id != robot_id) continue;
    const auto node = reported_track_node(e);
    if (!node) continue;
    const auto same = std::find_if(nodes.begin(), nodes.end(), [&](const auto& n) { return n.id == node->id; });
    if (same != nodes.end())
      *same = *node;
    else
      nodes.push_back(*node);
  }
  return nodes;
}

namespace {

// Points every centimetre along an edge's centre line, its ends left out.
std::vector<Vec2> edge_points(const environment::TrackEdge& edge, double end_margin_m) {
  std::vector<Vec2> points;
  double along = 0.0;
  for (std::size_t k = 1; k < edge.path_m.size(); ++k) {
    const Vec2 a = edge.path_m[k - 1], b = edge.path_m[k];
    const double length = (b - a).norm();
    for (double s = 0.0; s < length; s += 0.01) {
      const double at = along + s;
      if (at >= end_margin_m && at <= edge.length_m - end_margin_m) points.push_back(a + (b - a) * (s / length));
    }
    along += length;
  }
  if (points.empty() && edge.path_m.size() >= 2) points.push_back((edge.path_m.front() + edge.path_m.back()) * 0.5);
  return points;
}

std::string number(double v) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.6g", v);
  return buffer;
}

}  // namespace

std::string exploration_scenario_yaml(environment::TrackLayoutKind kind, int layout_seed, double tape_width_m,
                                      Pose2 start, const ExplorerSetup& setup) {
  std::string y =
      "name: explore\nfield: {width_m: 2.0, height_m: 2.0}\nduration_s: " + number(setup.duration_s) +
      "\ntiming: {physics_step_ms: 10, control_period_ms: 50}\ntrack_layout: {kind: " +
      std::string(environment::track_layout_kind_name(kind)) + ", seed: " + std::to_string(layout_seed) +
      ", tape_width_m: " + number(tape_width_m) + "}\nrobots:\n  - id: 1\n    pose: [" + number(start.position_m.x) +
      ", " + number(start.position_m.y) + ", " + number(rad_to_deg(start.heading_rad)) +
      "]\n    controller: track_explore\n    params: {speed_mps: " + number(setup.speed_mps) +
      ", tape_width_m: " + number(tape_width_m) + ", correct_odometry: " + (setup.correct_odometry ? "1" : "0") +
      "}\n    noise: {slip_sd: " + number(setup.slip_sd) + ", left_bias: " + number(setup.wheel_bias) +
      ", odometer_counts_slip: false}\n    sensors:\n      proximity: true\n      track:\n";
  for (int k = 0; k < setup.elements; ++k) {
    const double lateral = (0.5 * (setup.elements - 1) - k) * setup.spacing_m;  // left to right
    y += "        - {mount_x_m: " + number(setup.ahead_m) + ", mount_y_m: " + number(lateral) +
         ", height_mm: 8, inclination_deg: 0, cone_angle_deg: 30, precision: 16, coverage_percent: 15, "
         "max_value: 255, error_level_percent: 5}\n";
  }
  return y;
}

ExplorationScore score_exploration(const environment::TrackNetwork& network,
                                   const std::vector<environment::TrackConfig>& tracks,
                                   const std::vector<TrajectorySample>& trajectory,
                                   const std::vector<ReportedTrackNode>& reported, int robot_id,
                                   const ExplorationScoring& scoring) {
  ExplorationScore score;
  std::vector<const TrajectorySample*> path;
  for (const TrajectorySample& s : trajectory)
    if (s.id == robot_id) path.push_back(&s);
  // Edges: when each point along it was first passed; visited once edge_cover of them were.
  const double tolerance_sq = scoring.path_tolerance_m * scoring.path_tolerance_m;
  double last_visit_s = 0.0;
  score.edges = static_cast<int>(network.edges().size());
  score.tape_m = network.total_length_m();
  for (std::size_t e = 0; e < network.edges().size(); ++e) {
    const std::vector<Vec2> points = edge_points(network.edges()[e], scoring.end_margin_m);
    std::vector<double> first_s;
    for (const Vec2& p : points) {
      for (const TrajectorySample* s : path) {
        const Vec2 d = s->pose.position_m - p;
        if (d.dot(d) <= tolerance_sq) {
          first_s.push_back(us_to_seconds(s->t_us));
          break;
        }
      }
    }
    const std::size_t needed = static_cast<std::size_t>(std::ceil(scoring.edge_cover * points.size()));
    if (first_s.size() >= needed && needed > 0) {
      std::sort(first_s.begin(), first_s.end());
      last_visit_s = std::max(last_visit_s, first_s[needed - 1]);
      ++score.edges_visited;
    } else {
      score.missed_edges.push_back(static_cast<int>(e));
    }
  }
  if (score.edges_visited == score.edges) score.all_visited_s = last_visit_s;
  // Nodes: each sensable node against its nearest report.
  for (const environment::TrackNode& n : network.nodes()) {
    if (n.kind == environment::TrackNodeKind::kLoop) continue;
    ++score.nodes;
    double best = std::numeric_limits<double>::infinity();
    const ReportedTrackNode* nearest = nullptr;
    for (const ReportedTrackNode& r : reported) {
      const double d = (r.position_m - n.position_m).norm();
      if (d < best) {
        best = d;
        nearest = &r;
      }
    }
    score.worst_node_error_m = std::max(score.worst_node_error_m, best);
    if (nearest && best <= scoring.node_tolerance_m) {
      ++score.nodes_found;
      score.kinds_right += nearest->kind == environment::track_node_kind_name(n.kind);
    } else {
      score.missed_nodes.push_back(n.id);
    }
  }
  // Reports near nothing: made up, or a bend.
  for (const ReportedTrackNode& r : reported) {
    const bool near_node = std::any_of(network.nodes().begin(), network.nodes().end(), [&](const auto& n) {
      return (n.position_m - r.position_m).norm() <= scoring.node_tolerance_m;
    });
    if (near_node) continue;
    bool near_bend = false;
    for (const environment::TrackConfig& t : tracks)
      for (const Vec2& v : t.points_m) near_bend = near_bend || (v - r.position_m).norm() <= scoring.bend_tolerance_m;
    if (near_bend)
      ++score.bends;
    else
      ++score.false_nodes;
  }
  return score;
}

}  // namespace rilbed::run

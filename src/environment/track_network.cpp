#include "environment/track_network.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace rilbed::environment {

std::string_view track_node_kind_name(TrackNodeKind kind) {
  switch (kind) {
    case TrackNodeKind::kEnd: return "end";
    case TrackNodeKind::kCorner: return "corner";
    case TrackNodeKind::kTee: return "tee";
    case TrackNodeKind::kCross: return "cross";
    case TrackNodeKind::kLoop: return "loop";
  }
  return "?";
}

namespace {

// One straight piece of a tape's centre line.
struct Piece {
  Vec2 a, b;
  double width_m = 0.0;
  int track = 0;
  int index = 0;               // along its track
  std::vector<double> splits;  // parameters in [0, 1] where something joins it
};

// The planar graph the network is read from: points, and the straight links between them.
class PlanarGraph {
 public:
  explicit PlanarGraph(double merge_distance_m) : merge2_(merge_distance_m * merge_distance_m) {}

  // The vertex at `p`: an existing one within the merge distance, or a new one.
  int vertex_at(Vec2 p) {
    for (std::size_t i = 0; i < points_.size(); ++i) {
      const Vec2 d = points_[i] - p;
      if (d.dot(d) <= merge2_) return static_cast<int>(i);
    }
    points_.push_back(p);
    links_.emplace_back();
    return static_cast<int>(points_.size()) - 1;
  }

  // A link between two distinct vertices (once, however many tapes lie along it).
  void link(int u, int v, double width_m) {
    if (u == v) return;
    for (auto& l : links_[static_cast<std::size_t>(u)]) {
      if (l.to == v) {
        l.width_m = std::min(l.width_m, width_m);
        for (auto& back : links_[static_cast<std::size_t>(v)])
          if (back.to == u) back.width_m = l.width_m;
        return;
      }
    }
    links_[static_cast<std::size_t>(u)].push_back({v, width_m, false});
    links_[static_cast<std::size_t>(v)].push_back({u, width_m, false});
  }

  struct Link {
    int to;
    double width_m;
    bool walked;
  };

  int size() const { return static_cast<int>(points_.size()); }
  Vec2 point(int v) const { return points_[static_cast<std::size_t>(v)]; }
  std::vector<Link>& links(int v) { return links_[static_cast<std::size_t>(v)]; }
  const std::vector<Link>& links(int v) const { return links_[static_cast<std::size_t>(v)]; }

  // Marks the link u-v walked, both ways.
  void mark_walked(int u, int v) {
    for (auto& l : links(u))
      if (l.to == v) l.walked = true;
    for (auto& l : links(v))
      if (l.to == u) l.walked = true;
  }

 private:
  double merge2_;
  std::vector<Vec2> points_;
  std::vector<std::vector<Link>> links_;
};

// The pieces of every tape, a closed tape's closing piece included.
std::vector<Piece> pieces_of(const std::vector<TrackConfig>& tracks) {
  std::vector<Piece> pieces;
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    const auto& pts = tracks[t].points_m;
    const std::size_t n = pts.size();
    const std::size_t count = tracks[t].closed ? n : n - 1;
    for (std::size_t i = 0; i < count; ++i) {
      pieces.push_back({pts[i], pts[(i + 1) % n], tracks[t].width_m, static_cast<int>(t), static_cast<int>(i), {}});
    }
  }
  return pieces;
}

// Whether two pieces of one tape are neighbours along it (they share a vertex already).
bool neighbours(const Piece& p, const Piece& q, const std::vector<TrackConfig>& tracks) {
  if (p.track != q.track) return false;
  const auto& track = tracks[static_cast<std::size_t>(p.track)];
  const int count = static_cast<int>(track.closed ? track.points_m.size() : track.points_m.size() - 1);
  const int gap = std::abs(p.index - q.index);
  return gap <= 1 || (track.closed && gap == count - 1);
}

// The parameter along `piece` nearest to `p`, in [0, 1].
double nearest_parameter(const Piece& piece, Vec2 p) {
  const Vec2 d = piece.b - piece.a;
  const double len2 = d.dot(d);
  if (len2 <= 0.0) return 0.0;
  return std::clamp((p - piece.a).dot(d) / len2, 0.0, 1.0);
}

Vec2 at(const Piece& piece, double t) { return piece.a + (piece.b - piece.a) * t; }

// Centre lines that cross: each piece gets a split where they do (ends included, within
// the merge distance).
void split_at_crossings(std::vector<Piece>& pieces, const std::vector<TrackConfig>& tracks, double merge_m) {
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    for (std::size_t j = i + 1; j < pieces.size(); ++j) {
      Piece& p = pieces[i];
      Piece& q = pieces[j];
      if (neighbours(p, q, tracks)) continue;
      const Vec2 r = p.b - p.a, s = q.b - q.a;
      const double denom = r.cross(s);
      // Parallel pieces do not cross (tape laid along tape is drawn once, where the
      // pieces' vertices meet).
      if (std::abs(denom) <= 1e-12 * r.norm() * s.norm()) continue;
      const Vec2 qp = q.a - p.a;
      const double t = qp.cross(s) / denom, u = qp.cross(r) / denom;
      const double slack_t = merge_m / r.norm(), slack_u = merge_m / s.norm();
      if (t < -slack_t || t > 1 + slack_t || u < -slack_u || u > 1 + slack_u) continue;
      p.splits.push_back(std::clamp(t, 0.0, 1.0));
      q.splits.push_back(std::clamp(u, 0.0, 1.0));
    }
  }
}

// A tape's end on another tape (within that tape's half width of its centre line, as
// laid by hand) joins it there: the end moves onto the centre line and splits it.
void join_touching_ends(std::vector<Piece>& pieces, const std::vector<TrackConfig>& tracks, double merge_m) {
  for (std::size_t e = 0; e < pieces.size(); ++e) {
    const auto& track = tracks[static_cast<std::size_t>(pieces[e].track)];
    if (track.closed) continue;
    const int last = static_cast<int>(track.points_m.size()) - 2;
    for (const bool at_start : {true, false}) {
      if ((at_start && pieces[e].index != 0) || (!at_start && pieces[e].index != last)) continue;
      const Vec2 end = at_start ? pieces[e].a : pieces[e].b;
      std::size_t best = pieces.size();
      double best_distance = std::numeric_limits<double>::infinity(), best_t = 0.0;
      for (std::size_t k = 0; k < pieces.size(); ++k) {
        if (k == e || neighbours(pieces[e], pieces[k], tracks)) continue;
        const double t = nearest_parameter(pieces[k], end);
        const double distance = (at(pieces[k], t) - end).norm();
        if (distance <= 0.5 * pieces[k].width_m + merge_m && distance < best_distance) {
          best = k;
          best_distance = distance;
          best_t = t;
        }
      }
      if (best == pieces.size() || best_distance <= merge_m) continue;  // free, or on it already
      const Vec2 joined = at(pieces[best], best_t);
      (at_start ? pieces[e].a : pieces[e].b) = joined;
      pieces[best].splits.push_back(best_t);
    }
  }
}

// The graph of the pieces, cut at their splits.
PlanarGraph graph_of(std::vector<Piece>& pieces, double merge_m) {
  PlanarGraph graph(merge_m);
  // Vertices first in the tapes' own order, so that node ids follow the scenario.
  for (const Piece& p : pieces) {
    graph.vertex_at(p.a);
    graph.vertex_at(p.b);
  }
  for (Piece& p : pieces) {
    p.splits.push_back(0.0);
    p.splits.push_back(1.0);
    std::sort(p.splits.begin(), p.splits.end());
    int previous = graph.vertex_at(p.a);
    for (std::size_t k = 1; k < p.splits.size(); ++k) {
      const int v = graph.vertex_at(at(p, p.splits[k]));
      graph.link(previous, v, p.width_m);
      previous = v;
    }
  }
  return graph;
}

// Degrees the tape turns at a vertex of degree two (0 straight on, 180 back).
double turn_deg(const PlanarGraph& graph, int v) {
  const auto& links = graph.links(v);
  const Vec2 in = graph.point(v) - graph.point(links[0].to), out = graph.point(links[1].to) - graph.point(v);
  return rad_to_deg(std::atan2(std::abs(in.cross(out)), in.dot(out)));
}

}  // namespace

TrackNetwork TrackNetwork::build(const std::vector<TrackConfig>& tracks, const TrackNetworkConfig& config) {
  if (!(config.corner_min_turn_deg > 0.0 && config.corner_min_turn_deg < 180.0))
    throw std::invalid_argument("track network: corner_min_turn_deg must lie in (0, 180)");
  if (!(config.merge_distance_m > 0.0 && std::isfinite(config.merge_distance_m)))
    throw std::invalid_argument("track network: merge_distance_m must be positive");
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    if (tracks[t].points_m.size() < 2 || !(tracks[t].width_m > 0.0))
      throw std::invalid_argument("track network: track " + std::to_string(t) +
                                  " needs two points and a positive width");
  }
  std::vector<Piece> pieces = pieces_of(tracks);
  join_touching_ends(pieces, tracks, config.merge_distance_m);
  split_at_crossings(pieces, tracks, config.merge_distance_m);
  PlanarGraph graph = graph_of(pieces, config.merge_distance_m);

  TrackNetwork network;
  std::vector<int> node_of(static_cast<std::size_t>(graph.size()), -1);
  auto add_node = [&](int v, TrackNodeKind kind) {
    node_of[static_cast<std::size_t>(v)] = static_cast<int>(network.nodes_.size());
    const int degree = static_cast<int>(graph.links(v).size());
    network.nodes_.push_back({static_cast<int>(network.nodes_.size()), kind, graph.point(v), degree});
  };
  for (int v = 0; v < graph.size(); ++v) {
    const std::size_t degree = graph.links(v).size();
    if (degree == 1) add_node(v, TrackNodeKind::kEnd);
    if (degree == 2 && turn_deg(graph, v) > config.corner_min_turn_deg) add_node(v, TrackNodeKind::kCorner);
    if (degree == 3) add_node(v, TrackNodeKind::kTee);
    if (degree >= 4) add_node(v, TrackNodeKind::kCross);
  }

  // From a node along one link to the next node: one edge.
  auto walk = [&](int start, std::size_t first_link) {
    TrackEdge edge;
    edge.from = node_of[static_cast<std::size_t>(start)];
    edge.path_m.push_back(graph.point(start));
    edge.width_m = std::numeric_limits<double>::infinity();
    int previous = start;
    const PlanarGraph::Link* link = &graph.links(start)[first_link];
    while (true) {
      const int current = link->to;
      edge.width_m = std::min(edge.width_m, link->width_m);
      graph.mark_walked(previous, current);
      edge.length_m += (graph.point(current) - graph.point(previous)).norm();
      edge.path_m.push_back(graph.point(current));
      if (node_of[static_cast<std::size_t>(current)] >= 0) {
        edge.to = node_of[static_cast<std::size_t>(current)];
        break;
      }
      // A plain point has two links; the one come by is walked now, so on by the other.
      const auto& links = graph.links(current);
      link = links[0].walked ? &links[1] : &links[0];
      previous = current;
    }
    network.edges_.push_back(std::move(edge));
  };
  auto walk_all_from = [&](int v) {
    for (std::size_t k = 0; k < graph.links(v).size(); ++k)
      if (!graph.links(v)[k].walked) walk(v, k);
  };
  for (int v = 0; v < graph.size(); ++v)
    if (node_of[static_cast<std::size_t>(v)] >= 0) walk_all_from(v);
  // What is left are closed tapes without a node: one loop node each.
  for (int v = 0; v < graph.size(); ++v) {
    const auto& links = graph.links(v);
    if (links.empty() || std::all_of(links.begin(), links.end(), [](const auto& l) { return l.walked; })) continue;
    add_node(v, TrackNodeKind::kLoop);
    walk_all_from(v);
  }
  return network;
}

double TrackNetwork::total_length_m() const {
  double sum = 0.0;
  for (const TrackEdge& e : edges_) sum += e.length_m;
  return sum;
}

std::string TrackNetwork::to_json() const {
  std::string out = "{\"nodes\": [";
  char buffer[160];
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const TrackNode& n = nodes_[i];
    std::snprintf(buffer, sizeof buffer, "%s{\"id\": %d, \"kind\": \"%s\", \"x_m\": %.4f, \"y_m\": %.4f}",
                  i == 0 ? "" : ", ", n.id, std::string(track_node_kind_name(n.kind)).c_str(), n.position_m.x,
                  n.position_m.y);
    out += buffer;
  }
  out += "], \"edges\": [";
  for (std::size_t i = 0; i < edges_.size(); ++i) {
    const TrackEdge& e = edges_[i];
    std::snprintf(buffer, sizeof buffer, "%s{\"from\": %d, \"to\": %d, \"length_m\": %.4f}", i == 0 ? "" : ", ", e.from,
                  e.to, e.length_m);
    out += buffer;
  }
  out += "]}";
  return out;
}

}  // namespace rilbed::environment

// The floor's tracks as one network (paper 000 §8-9): where tapes meet or cross they
// form junctions, where a tape turns sharply a corner, where it stops an end. The nodes
// are the places a robot's track sensor can tell apart on board; the edges are the tape
// between them. This is the ground truth that exploring controllers' maps and the
// feature detector are measured against, and what the panel and Foxglove draw.
//
// Built from the scenario's polylines (StaticMapConfig::tracks) by pure geometry:
//   1. every polyline vertex and every point where two centre lines cross, or where a
//      tape's end touches another tape (within that tape's half width), becomes a
//      vertex of a planar graph, vertices closer than `merge_distance_m` merged;
//   2. a vertex with one tape leaving it is an end, with three a T junction, with four
//      or more a crossing; with two it is a corner when the tape turns there by more
//      than `corner_min_turn_deg`, else a plain point on an edge;
//   3. the edges run from node to node along the plain points.
// A closed tape with no node on it (a smooth loop) gets one node of kind loop at its
// first vertex, so that it still has an edge; a robot cannot sense that node.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "core/geometry.hpp"
#include "environment/static_map.hpp"

namespace rilbed::environment {

/// What a node of the network is, as a robot's sensors could tell it.
enum class TrackNodeKind {
  kEnd,     ///< a tape stops (one way on)
  kCorner,  ///< a tape turns by more than the corner angle (two ways on)
  kTee,     ///< three ways on: one tape ends on another, or two tapes meet a third
  kCross,   ///< four or more ways on: tapes cross
  kLoop,    ///< the one node given to a closed tape without any other (not sensed)
};

/// The kind's name in files and messages: "end", "corner", "tee", "cross", "loop".
std::string_view track_node_kind_name(TrackNodeKind kind);

/// A node of the network.
struct TrackNode {
  int id = 0;  ///< index in TrackNetwork::nodes()
  TrackNodeKind kind = TrackNodeKind::kEnd;
  Vec2 position_m;  ///< field frame
  int degree = 0;   ///< tape directions leaving it (1 end, 2 corner or loop, 3 tee, 4+ cross)
};

/// An edge: the tape between two nodes (the same node for a loop closed on itself).
struct TrackEdge {
  int from = 0;              ///< node id
  int to = 0;                ///< node id
  double length_m = 0.0;     ///< along the tape's centre line
  std::vector<Vec2> path_m;  ///< centre line from `from` to `to`, both included
  double width_m = 0.0;      ///< the tape's width (the narrowest, where tapes of several widths join)
};

/// Knobs of the network's construction.
struct TrackNetworkConfig {
  /// A tape turning by more than this at a vertex makes a corner there; gentler bends
  /// (a curve drawn as a polyline) stay inside an edge. Degrees, in (0, 180).
  double corner_min_turn_deg = 30.0;
  /// Vertices, crossings and touching ends closer than this are one node, metres.
  double merge_distance_m = 0.005;
};

/// The network of a set of tapes; a value (nodes and edges), built once per scenario.
class TrackNetwork {
 public:
  TrackNetwork() = default;

  /// Builds the network of `tracks` (each with at least two points and a positive
  /// width, as StaticMap validates them). Throws std::invalid_argument for a config out
  /// of range.
  static TrackNetwork build(const std::vector<TrackConfig>& tracks, const TrackNetworkConfig& config = {});

  const std::vector<TrackNode>& nodes() const { return nodes_; }
  const std::vector<TrackEdge>& edges() const { return edges_; }

  /// Total length of the tape in the network, metres.
  double total_length_m() const;

  /// The network as JSON, the format `track_map.json` uses: {"nodes": [{id, kind, x_m,
  /// y_m}], "edges": [{from, to, length_m}]}.
  std::string to_json() const;

 private:
  std::vector<TrackNode> nodes_;
  std::vector<TrackEdge> edges_;
};

}  // namespace rilbed::environment

// The track network read from tapes as a scenario gives them: each case a small layout a
// lab would tape down, with the nodes and edges a person would count on it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "environment/track_layouts.hpp"
#include "environment/track_network.hpp"

namespace rilbed::environment {
namespace {

TrackConfig tape(std::vector<Vec2> points, bool closed = false, double width_m = 0.02) {
  TrackConfig t;
  t.points_m = std::move(points);
  t.closed = closed;
  t.width_m = width_m;
  return t;
}

std::map<std::string, int> kinds(const TrackNetwork& n) {
  std::map<std::string, int> count;
  for (const TrackNode& node : n.nodes()) ++count[std::string(track_node_kind_name(node.kind))];
  return count;
}

const TrackNode* node_near(const TrackNetwork& n, Vec2 p) {
  for (const TrackNode& node : n.nodes())
    if ((node.position_m - p).norm() < 1e-6) return &node;
  return nullptr;
}

// Every edge's ends are nodes, its path runs from one to the other, its length is its
// path's, and the lengths add up to the tape laid.
void expect_consistent(const TrackNetwork& n, double tape_length_m) {
  for (const TrackEdge& e : n.edges()) {
    ASSERT_GE(e.from, 0);
    ASSERT_LT(e.from, static_cast<int>(n.nodes().size()));
    ASSERT_GE(e.to, 0);
    ASSERT_LT(e.to, static_cast<int>(n.nodes().size()));
    ASSERT_GE(e.path_m.size(), 2u);
    EXPECT_EQ(e.path_m.front(), n.nodes()[static_cast<std::size_t>(e.from)].position_m);
    EXPECT_EQ(e.path_m.back(), n.nodes()[static_cast<std::size_t>(e.to)].position_m);
    double length = 0.0;
    for (std::size_t i = 1; i < e.path_m.size(); ++i) length += (e.path_m[i] - e.path_m[i - 1]).norm();
    EXPECT_NEAR(e.length_m, length, 1e-12);
  }
  EXPECT_NEAR(n.total_length_m(), tape_length_m, 1e-9);
  // Each node's degree is the number of edge ends on it.
  std::vector<int> ends(n.nodes().size(), 0);
  for (const TrackEdge& e : n.edges()) ++ends[static_cast<std::size_t>(e.from)], ++ends[static_cast<std::size_t>(e.to)];
  for (const TrackNode& node : n.nodes()) EXPECT_EQ(ends[static_cast<std::size_t>(node.id)], node.degree) << node.id;
}

TEST(TrackNetwork, TwoTapesCrossingMakeACrossAndFourEnds) {
  const auto n = TrackNetwork::build({tape({{0, 0.5}, {1, 0.5}}), tape({{0.3, 0}, {0.3, 1}})});
  EXPECT_EQ(kinds(n), (std::map<std::string, int>{{"cross", 1}, {"end", 4}}));
  const TrackNode* cross = node_near(n, {0.3, 0.5});
  ASSERT_NE(cross, nullptr);
  EXPECT_EQ(cross->degree, 4);
  ASSERT_EQ(n.edges().size(), 4u);
  std::vector<double> lengths;
  for (const TrackEdge& e : n.edges()) lengths.push_back(e.length_m);
  std::sort(lengths.begin(), lengths.end());
  EXPECT_NEAR(lengths[0], 0.3, 1e-12);
  EXPECT_NEAR(lengths[1], 0.5, 1e-12);
  EXPECT_NEAR(lengths[2], 0.5, 1e-12);
  EXPECT_NEAR(lengths[3], 0.7, 1e-12);
  expect_consistent(n, 2.0);
}

// A tape laid to end on another, its end at the other tape's edge (8 mm off the centre
// line of a 20 mm tape), joins it there: a T junction on the other's centre line.
TEST(TrackNetwork, ATapeEndingOnAnotherMakesATee) {
  const auto n = TrackNetwork::build({tape({{0, 0}, {1, 0}}), tape({{0.4, 0.6}, {0.4, 0.008}})});
  EXPECT_EQ(kinds(n), (std::map<std::string, int>{{"end", 3}, {"tee", 1}}));
  const TrackNode* tee = node_near(n, {0.4, 0.0});
  ASSERT_NE(tee, nullptr);
  EXPECT_EQ(tee->degree, 3);
  EXPECT_EQ(n.edges().size(), 3u);
  // The stem reaches the centre line: 0.6 m.
  expect_consistent(n, 1.6);
  // 3 cm short of it, it stays a separate tape: no junction.
  const auto apart = TrackNetwork::build({tape({{0, 0}, {1, 0}}), tape({{0.4, 0.6}, {0.4, 0.03}})});
  EXPECT_EQ(kinds(apart), (std::map<std::string, int>{{"end", 4}}));
}

// A right angle is a corner; a gentle bend of a curve drawn as a polyline is not, and its
// edge runs on through it.
TEST(TrackNetwork, SharpTurnsAreCornersGentleBendsAreNot) {
  const auto l = TrackNetwork::build({tape({{0, 0}, {0.5, 0}, {0.5, 0.5}})});
  EXPECT_EQ(kinds(l), (std::map<std::string, int>{{"corner", 1}, {"end", 2}}));
  EXPECT_EQ(l.edges().size(), 2u);
  expect_consistent(l, 1.0);

  const double bend = 10.0 * 3.141592653589793 / 180.0;
  const auto gentle =
      TrackNetwork::build({tape({{0, 0}, {0.5, 0}, {0.5 + 0.5 * std::cos(bend), 0.5 * std::sin(bend)}})});
  EXPECT_EQ(kinds(gentle), (std::map<std::string, int>{{"end", 2}}));
  ASSERT_EQ(gentle.edges().size(), 1u);
  EXPECT_EQ(gentle.edges()[0].path_m.size(), 3u);
  expect_consistent(gentle, 1.0);
}

// Two tapes laid end to end in a straight line are one edge; end to end at a right angle,
// a corner.
TEST(TrackNetwork, TapesJoinedEndToEndContinueOrTurn) {
  const auto straight = TrackNetwork::build({tape({{0, 0}, {0.5, 0}}), tape({{0.502, 0}, {1, 0}})});
  EXPECT_EQ(kinds(straight), (std::map<std::string, int>{{"end", 2}}));
  EXPECT_EQ(straight.edges().size(), 1u);
  const auto turned = TrackNetwork::build({tape({{0, 0}, {0.5, 0}}), tape({{0.5, 0.004}, {0.5, 0.5}})});
  EXPECT_EQ(kinds(turned), (std::map<std::string, int>{{"corner", 1}, {"end", 2}}));
}

// A closed square is four corners and four edges; a circle drawn with 36 vertices has
// no feature at all and gets its one loop node, on an edge from it back to it.
TEST(TrackNetwork, ClosedTapesMakeCornersOrALoop) {
  const auto square = TrackNetwork::build({tape({{0, 0}, {1, 0}, {1, 1}, {0, 1}}, true)});
  EXPECT_EQ(kinds(square), (std::map<std::string, int>{{"corner", 4}}));
  EXPECT_EQ(square.edges().size(), 4u);
  expect_consistent(square, 4.0);

  std::vector<Vec2> circle;
  double perimeter = 0.0;
  for (int k = 0; k < 36; ++k) {
    const double a = 2 * 3.141592653589793 * k / 36;
    circle.push_back({0.5 * std::cos(a), 0.5 * std::sin(a)});
  }
  for (int k = 0; k < 36; ++k)
    perimeter += (circle[static_cast<std::size_t>((k + 1) % 36)] - circle[static_cast<std::size_t>(k)]).norm();
  const auto loop = TrackNetwork::build({tape(circle, true)});
  EXPECT_EQ(kinds(loop), (std::map<std::string, int>{{"loop", 1}}));
  ASSERT_EQ(loop.edges().size(), 1u);
  EXPECT_EQ(loop.edges()[0].from, loop.edges()[0].to);
  expect_consistent(loop, perimeter);
}

// A loop with a spur: a tee where the spur leaves the loop, the loop's corners, and an
// end; a tape that crosses itself makes a cross.
TEST(TrackNetwork, SpursAndSelfCrossings) {
  const auto spur = TrackNetwork::build({tape({{0, 0}, {1, 0}, {1, 1}, {0, 1}}, true), tape({{0.5, 1.0}, {0.5, 1.4}})});
  EXPECT_EQ(kinds(spur), (std::map<std::string, int>{{"corner", 4}, {"end", 1}, {"tee", 1}}));
  EXPECT_EQ(spur.edges().size(), 6u);
  expect_consistent(spur, 4.4);

  // A figure of eight as one closed tape through a crossing at its middle.
  const auto eight = TrackNetwork::build({tape({{0, 0}, {1, 1}, {1, 0}, {0, 1}}, true)});
  EXPECT_EQ(kinds(eight).count("cross"), 1u);
  const TrackNode* cross = node_near(eight, {0.5, 0.5});
  ASSERT_NE(cross, nullptr);
  EXPECT_EQ(cross->degree, 4);
}

// Three tapes across and three down, each running 10 cm past the others: nine crossings,
// twelve ends, and each tape cut into four edges.
TEST(TrackNetwork, AGridOfTapes) {
  std::vector<TrackConfig> tapes;
  for (int k = 0; k < 3; ++k) {
    tapes.push_back(tape({{-0.1, 0.5 * k}, {1.1, 0.5 * k}}));
    tapes.push_back(tape({{0.5 * k, -0.1}, {0.5 * k, 1.1}}));
  }
  const auto grid = TrackNetwork::build(tapes);
  EXPECT_EQ(kinds(grid), (std::map<std::string, int>{{"cross", 9}, {"end", 12}}));
  EXPECT_EQ(grid.edges().size(), 24u);
  expect_consistent(grid, 6 * 1.2);
}

TEST(TrackNetwork, JsonListsNodesAndEdges) {
  const auto n = TrackNetwork::build({tape({{0, 0}, {0.5, 0}, {0.5, 0.25}})});
  EXPECT_EQ(n.to_json(),
            "{\"nodes\": [{\"id\": 0, \"kind\": \"end\", \"x_m\": 0.0000, \"y_m\": 0.0000}, "
            "{\"id\": 1, \"kind\": \"corner\", \"x_m\": 0.5000, \"y_m\": 0.0000}, "
            "{\"id\": 2, \"kind\": \"end\", \"x_m\": 0.5000, \"y_m\": 0.2500}], "
            "\"edges\": [{\"from\": 0, \"to\": 1, \"length_m\": 0.5000}, "
            "{\"from\": 1, \"to\": 2, \"length_m\": 0.2500}]}");
}

TEST(TrackNetwork, RefusesBadInput) {
  EXPECT_THROW(TrackNetwork::build({tape({{0, 0}})}), std::invalid_argument);
  EXPECT_THROW(TrackNetwork::build({tape({{0, 0}, {1, 0}}, false, 0.0)}), std::invalid_argument);
  TrackNetworkConfig bad;
  bad.corner_min_turn_deg = 0.0;
  EXPECT_THROW(TrackNetwork::build({tape({{0, 0}, {1, 0}})}, bad), std::invalid_argument);
}

}  // namespace
}  // namespace rilbed::environment

namespace rilbed::environment {
namespace {

// Nodes reached from node 0 along the edges.
std::size_t reached(const TrackNetwork& n) {
  std::vector<bool> seen(n.nodes().size(), false);
  std::vector<int> stack = {0};
  seen[0] = true;
  std::size_t count = 1;
  while (!stack.empty()) {
    const int v = stack.back();
    stack.pop_back();
    for (const TrackEdge& e : n.edges()) {
      for (const auto& [a, b] : {std::pair{e.from, e.to}, std::pair{e.to, e.from}}) {
        if (a != v || seen[static_cast<std::size_t>(b)]) continue;
        seen[static_cast<std::size_t>(b)] = true;
        ++count;
        stack.push_back(b);
      }
    }
  }
  return count;
}

// Every layout drawn is one network inside the field's margins; a tree has no cycle
// (one edge fewer than nodes), a loop with spurs exactly one, a grid at least one more
// node than a tree of its links would need to span. The same seed draws the same tapes.
TEST(TrackLayouts, DrawnLayoutsAreConnectedNetworksOfTheirKind) {
  const TrackLayoutOptions options;
  for (const TrackLayoutKind kind : {TrackLayoutKind::kGrid, TrackLayoutKind::kTree, TrackLayoutKind::kLoopWithSpurs}) {
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
      SCOPED_TRACE(std::string(track_layout_kind_name(kind)) + " seed " + std::to_string(seed));
      const auto tapes = make_track_layout(seed, kind, options);
      ASSERT_FALSE(tapes.empty());
      for (const TrackConfig& t : tapes) {
        for (const Vec2& p : t.points_m) {
          EXPECT_GE(p.x, options.margin_m - 1e-9);
          EXPECT_LE(p.x, options.field_width_m - options.margin_m + 1e-9);
          EXPECT_GE(p.y, options.margin_m - 1e-9);
          EXPECT_LE(p.y, options.field_height_m - options.margin_m + 1e-9);
        }
      }
      const auto n = TrackNetwork::build(tapes);
      ASSERT_FALSE(n.nodes().empty());
      EXPECT_EQ(reached(n), n.nodes().size());
      if (kind == TrackLayoutKind::kTree) EXPECT_EQ(n.edges().size() + 1, n.nodes().size());
      if (kind == TrackLayoutKind::kLoopWithSpurs) {
        EXPECT_EQ(n.edges().size(), n.nodes().size());
        EXPECT_GE(kinds(n)["tee"], 2);
        EXPECT_EQ(kinds(n)["tee"], kinds(n)["end"]);
      }
      if (kind == TrackLayoutKind::kGrid) EXPECT_GE(n.edges().size(), n.nodes().size() - 1);
      for (const TrackNode& node : n.nodes()) EXPECT_NE(node.kind, TrackNodeKind::kLoop);
      const auto again = make_track_layout(seed, kind, options);
      ASSERT_EQ(again.size(), tapes.size());
      for (std::size_t t = 0; t < tapes.size(); ++t) EXPECT_EQ(again[t].points_m, tapes[t].points_m);
    }
  }
}

}  // namespace
}  // namespace rilbed::environment

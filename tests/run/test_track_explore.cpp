// track_explore on tape networks nobody designed it for: random layouts from seeds that
// were drawn after its last change (layout seeds 301-303, start seed 13; its tuning used
// layout seeds 1-4 and start seed 1), each explored from 20 random starts through real
// runs, scored against the network.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "environment/random.hpp"
#include "run/simulation.hpp"
#include "run/track_exploration.hpp"

namespace rilbed::run {
namespace {

struct Explored {
  RunResult result;
  ExplorationScore score;
};

Explored explore(environment::TrackLayoutKind kind, int layout, Pose2 start,
                 const std::optional<std::filesystem::path>& out = std::nullopt) {
  const Scenario scenario = parse_scenario(exploration_scenario_yaml(kind, layout, 0.02, start), "explore.yaml");
  RunOptions options;
  options.keep_in_memory = true;
  options.stop_when_done = true;
  options.out_dir = out;
  Explored e{run_scenario(scenario, options), {}};
  const auto network = environment::TrackNetwork::build(scenario.map.tracks);
  e.score =
      score_exploration(network, scenario.map.tracks, e.result.trajectory, reported_track_nodes(e.result.events, 1), 1);
  return e;
}

Pose2 random_start(environment::NoiseRng& rng) {
  return {{0.1 + 1.8 * environment::uniform01(rng), 0.1 + 1.8 * environment::uniform01(rng)},
          2 * kPi * environment::uniform01(rng)};
}

}  // namespace

// Issue target, met for grids (with exact wheel counters): every edge visited within 10
// simulated minutes from each of 20 random starts, every node mapped within 3 cm.
TEST(TrackExplore, ExploresRandomGridsFromAnywhere) {
  int false_nodes = 0;
  double tape_m = 0.0;
  for (int layout : {301, 302, 303}) {
    environment::NoiseRng starts(environment::mix64(13 * 1000003 + static_cast<std::uint64_t>(layout)));
    for (int s = 0; s < 20; ++s) {
      const Pose2 start = random_start(starts);
      const Explored e = explore(environment::TrackLayoutKind::kGrid, layout, start);
      SCOPED_TRACE("grid layout " + std::to_string(layout) + ", start " + std::to_string(s));
      ASSERT_TRUE(e.score.all_visited_s.has_value()) << e.score.edges_visited << " of " << e.score.edges;
      EXPECT_LE(*e.score.all_visited_s, 600.0);
      EXPECT_EQ(e.score.nodes_found, e.score.nodes) << "worst " << e.score.worst_node_error_m << " m";
      EXPECT_LE(e.score.worst_node_error_m, 0.03);
      false_nodes += e.score.false_nodes;
      tape_m += e.score.tape_m;
    }
  }
  // Nodes made up: at most one per 10 m of tape driven over, pooled.
  EXPECT_LE(false_nodes, tape_m / 10.0) << false_nodes << " in " << tape_m << " m";
}

TEST(TrackExplore, WritesTheMapItReportedToTheRunFolder) {
  const auto dir = std::filesystem::temp_directory_path() / "rilbed_track_explore_map";
  std::filesystem::remove_all(dir);
  const Explored e = explore(environment::TrackLayoutKind::kGrid, 303, {{0.5, 0.5}, 0.3}, dir);
  EXPECT_EQ(e.result.ended_by, "done");
  std::ifstream in(dir / "track_map.json");
  ASSERT_TRUE(in) << "no track_map.json";
  const auto map = nlohmann::json::parse(in);
  EXPECT_EQ(map["robot"], 1);
  const auto reported = reported_track_nodes(e.result.events, 1);
  ASSERT_EQ(map["nodes"].size(), reported.size());
  int edges = 0;
  for (const RunEvent& ev : e.result.events) edges += ev.kind == "track_edge";
  EXPECT_EQ(static_cast<int>(map["edges"].size()), edges);
  // The file holds each node's latest place, as the events do.
  for (const auto& node : map["nodes"]) {
    const int id = node["id"];
    const auto r = std::find_if(reported.begin(), reported.end(), [&](const auto& n) { return n.id == id; });
    ASSERT_NE(r, reported.end());
    EXPECT_NEAR(node["x_m"].get<double>(), r->position_m.x, 1e-9);
    EXPECT_EQ(node["kind"], r->kind);
  }
  // A grid explored: as many edges as the network has.
  EXPECT_EQ(static_cast<int>(map["edges"].size()), e.score.edges);
  std::filesystem::remove_all(dir);
}

// track_map.json from events that may come from any program on the bus: what does not
// parse, or lacks a field, is left out; a node reported again keeps its latest place.
TEST(TrackExplore, TheRunFolderKeepsOnlyWellFormedTrackEvents) {
  const auto dir = std::filesystem::temp_directory_path() / "rilbed_track_map_events";
  std::filesystem::remove_all(dir);
  {
    RunRecorder recorder(dir, FieldDrawing{});
    for (const char* detail : {"not json", "[1, 2]", "{\"kind\": 3, \"x_m\": 0, \"y_m\": 0}",
                               "{\"kind\": \"tee\", \"x_m\": \"a\", \"y_m\": 0}", "{\"kind\": \"tee\"}"})
      recorder.add_event({1, "track_node", 2, 9, detail});
    recorder.add_event({1, "track_edge", 2, 4, "{\"from\": 0.5, \"to\": 1, \"length_m\": 1}"});
    recorder.add_event({1, "track_node", 2, 0, "{\"kind\": \"end\", \"x_m\": 0.1, \"y_m\": 0.2}"});
    recorder.add_event({2, "track_node", 2, 1, "{\"kind\": \"tee\", \"x_m\": 0.5, \"y_m\": 0.2}"});
    recorder.add_event({3, "track_node", 2, 0, "{\"kind\": \"end\", \"x_m\": 0.12, \"y_m\": 0.2}"});
    recorder.add_event({3, "track_edge", 2, 0, "{\"from\": 0, \"to\": 1, \"length_m\": 0.38}"});
    recorder.finish(nlohmann::json::object());
  }
  std::ifstream in(dir / "track_map.json");
  ASSERT_TRUE(in);
  const auto map = nlohmann::json::parse(in);
  EXPECT_EQ(map["robot"], 2);
  ASSERT_EQ(map["nodes"].size(), 2u);
  EXPECT_EQ(map["nodes"][0]["id"], 0);
  EXPECT_NEAR(map["nodes"][0]["x_m"].get<double>(), 0.12, 1e-12);
  EXPECT_EQ(map["nodes"][1]["kind"], "tee");
  ASSERT_EQ(map["edges"].size(), 1u);
  EXPECT_EQ(map["edges"][0]["to"], 1);
  std::filesystem::remove_all(dir);
}

}  // namespace rilbed::run

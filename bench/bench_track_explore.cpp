// track_explore on random tape networks (paper 000 §9): for each layout (grid, tree,
// loop with spurs, from a seed) and each random start, one real run of the controller
// (rilbed's run, fast clock), scored against the network: edges visited within the
// duration, nodes found within 3 cm, worst node error, false nodes per 10 m of tape.
// With --tape-mm several widths, the tape-width experiment of §9.
//
//   bench_track_explore [--kinds grid,tree,loop] [--layouts 1-5] [--starts 20]
//                       [--tape-mm 20] [--elements 5] [--spacing-mm 12] [--explain]
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/id_list.hpp"
#include "environment/random.hpp"
#include "run/simulation.hpp"
#include "run/track_exploration.hpp"

using namespace rilbed;

namespace {

struct Tally {
  int runs = 0, all_visited = 0, done = 0, maps_within = 0, edges = 0, edges_visited = 0;
  int nodes = 0, nodes_found = 0, kinds_right = 0, false_nodes = 0, bends = 0;
  double tape_m = 0.0, worst_error_m = 0.0;
  std::vector<double> times_s;
};

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"track_explore on random tape networks"};
  std::string kinds_text = "grid,tree,loop", layouts_text = "1-5", widths_text = "20";
  int starts = 20;
  bool explain = false;
  run::ExplorerSetup setup;
  double spacing_mm = 12.0;
  std::uint64_t start_seed = 1;
  app.add_option("--kinds", kinds_text, "Layout kinds, comma separated");
  app.add_option("--layouts", layouts_text, "Layout seeds (an ID list: 1-5,9)");
  app.add_option("--starts", starts, "Random starts per layout");
  app.add_option("--start-seed", start_seed, "Seed of the random starts");
  app.add_option("--tape-mm", widths_text, "Tape widths, mm, comma separated");
  app.add_option("--elements", setup.elements, "Track sensor elements across the front");
  app.add_option("--spacing-mm", spacing_mm, "Between neighbouring elements, mm");
  app.add_option("--slip", setup.slip_sd, "Wheel slip sd per step (the odometer does not count it)");
  app.add_option("--bias", setup.wheel_bias, "Left wheel's systematic error");
  app.add_flag("--correct-odometry", setup.correct_odometry, "track_explore's correct_odometry 1 (experimental)");
  app.add_flag("--explain", explain, "A line per run that missed something");
  std::string dump, csv_path;
  app.add_option("--dump", dump, "Write each run's folder (and scenario) under this folder");
  app.add_option("--csv", csv_path,
                 "Also write a row per run here (tape_mm,kind,layout,start,edges,edges_visited,all_visited_s,nodes,"
                 "nodes_found,kinds_right,false_nodes,tape_m,worst_node_error_m,ended_by); tools/plot_tape_width.py "
                 "plots it");
  CLI11_PARSE(app, argc, argv);
  setup.spacing_m = spacing_mm * 1e-3;
  const IdListResult layouts = parse_id_list(layouts_text, 0, 1 << 30, "--layouts");
  if (!layouts.ok()) {
    std::fprintf(stderr, "%s\n", layouts.error.c_str());
    return 2;
  }
  std::vector<double> widths_mm;
  {
    std::stringstream in(widths_text);
    for (std::string w; std::getline(in, w, ',');) widths_mm.push_back(std::stod(w));
  }
  std::vector<environment::TrackLayoutKind> kinds;
  {
    std::stringstream in(kinds_text);
    for (std::string k; std::getline(in, k, ',');)
      kinds.push_back(k == "tree"   ? environment::TrackLayoutKind::kTree
                      : k == "loop" ? environment::TrackLayoutKind::kLoopWithSpurs
                                    : environment::TrackLayoutKind::kGrid);
  }
  std::printf(
      "# track_explore: %d elements %.0f mm apart, %.0f mm ahead; slip sd %.3f, left bias %.3f (odometer "
      "blind to both); %d random starts per layout; 50 ms control, 10 ms physics, %.0f s at most\n",
      setup.elements, spacing_mm, setup.ahead_m * 1e3, setup.slip_sd, setup.wheel_bias, starts, setup.duration_s);
  std::printf("%-6s %-5s %5s %5s %5s %6s %9s %8s %8s %9s %8s %9s %6s %7s\n", "tape", "kind", "lay", "edges", "nodes",
              "runs", "visited", "done", "map3cm", "t50_s", "tmax_s", "found", "kinds", "false/10m");
  const auto wall = std::chrono::steady_clock::now();
  std::ofstream csv;
  if (!csv_path.empty()) {
    csv.open(csv_path);
    if (!csv) {
      std::fprintf(stderr, "cannot write %s\n", csv_path.c_str());
      return 1;
    }
    csv << "tape_mm,kind,layout,start,edges,edges_visited,all_visited_s,nodes,nodes_found,kinds_right,false_nodes,"
           "tape_m,worst_node_error_m,ended_by\n";
  }
  std::vector<std::pair<double, Tally>> per_width;
  for (double width_mm : widths_mm) {
    Tally width_tally;
    for (environment::TrackLayoutKind kind : kinds) {
      for (int layout : layouts.ids) {
        Tally t;
        environment::NoiseRng starts_rng(environment::mix64(start_seed * 1000003 + static_cast<std::uint64_t>(layout)));
        int edges = 0, nodes = 0;
        for (int s = 0; s < starts; ++s) {
          const Pose2 start{
              {0.1 + 1.8 * environment::uniform01(starts_rng), 0.1 + 1.8 * environment::uniform01(starts_rng)},
              2 * kPi * environment::uniform01(starts_rng)};
          const std::string yaml = run::exploration_scenario_yaml(kind, layout, width_mm * 1e-3, start, setup);
          const run::Scenario scenario = run::parse_scenario(yaml, "explore.yaml");
          run::RunOptions options;
          options.seed = static_cast<std::uint64_t>(s + 1);
          options.keep_in_memory = true;
          options.stop_when_done = true;
          if (!dump.empty()) {
            const std::filesystem::path dir =
                std::filesystem::path(dump) / (std::string(environment::track_layout_kind_name(kind)) + "_" +
                                               std::to_string(layout) + "_" + std::to_string(s));
            options.out_dir = dir;
            std::filesystem::create_directories(dir);
            std::ofstream(dir / "scenario.yaml") << yaml;
          }
          const run::RunResult r = run::run_scenario(scenario, options);
          const auto network = environment::TrackNetwork::build(scenario.map.tracks);
          const auto score = run::score_exploration(network, scenario.map.tracks, r.trajectory,
                                                    run::reported_track_nodes(r.events, 1), 1);
          edges = score.edges;
          nodes = score.nodes;
          if (csv.is_open()) {
            csv << width_mm << ',' << environment::track_layout_kind_name(kind) << ',' << layout << ',' << s << ','
                << score.edges << ',' << score.edges_visited << ','
                << (score.all_visited_s ? std::to_string(*score.all_visited_s) : "") << ',' << score.nodes << ','
                << score.nodes_found << ',' << score.kinds_right << ',' << score.false_nodes << ',' << score.tape_m
                << ',' << score.worst_node_error_m << ',' << r.ended_by << '\n';
          }
          t.edges += score.edges;
          t.edges_visited += score.edges_visited;
          ++t.runs;
          t.tape_m += network.total_length_m();
          t.all_visited += score.all_visited_s.has_value();
          if (score.all_visited_s) t.times_s.push_back(*score.all_visited_s);
          t.done += r.ended_by == "done";
          t.maps_within += score.nodes_found == score.nodes;
          t.nodes += score.nodes;
          t.nodes_found += score.nodes_found;
          t.kinds_right += score.kinds_right;
          t.false_nodes += score.false_nodes;
          t.bends += score.bends;
          t.worst_error_m = std::max(t.worst_error_m, score.worst_node_error_m);
          if (explain && (!score.all_visited_s || score.nodes_found < score.nodes || score.false_nodes > 0)) {
            std::printf(
                "  %s layout %d start %d (%.2f, %.2f, %.0f deg): visited %d/%d, nodes %d/%d (worst %.3f m), "
                "false %d, ended by %s at %.0f s; missed nodes",
                std::string(environment::track_layout_kind_name(kind)).c_str(), layout, s, start.position_m.x,
                start.position_m.y, rad_to_deg(start.heading_rad), score.edges_visited, score.edges, score.nodes_found,
                score.nodes, score.worst_node_error_m, score.false_nodes, r.ended_by.c_str(), r.simulated_s);
            for (int id : score.missed_nodes) {
              const auto& n = network.nodes()[static_cast<std::size_t>(id)];
              std::printf(" %s(%.3f,%.3f)", std::string(environment::track_node_kind_name(n.kind)).c_str(),
                          n.position_m.x, n.position_m.y);
            }
            std::printf("\n");
          }
        }
        std::printf("%-6.0f %-5s %5d %5d %5d %6d %8.0f%% %7.0f%% %7.0f%% %9.0f %8.0f %8.1f%% %5.1f%% %9.2f\n", width_mm,
                    std::string(environment::track_layout_kind_name(kind)).c_str(), layout, edges, nodes, t.runs,
                    100.0 * t.all_visited / t.runs, 100.0 * t.done / t.runs, 100.0 * t.maps_within / t.runs,
                    median(t.times_s), t.times_s.empty() ? 0.0 : *std::max_element(t.times_s.begin(), t.times_s.end()),
                    t.nodes ? 100.0 * t.nodes_found / t.nodes : 0.0,
                    t.nodes_found ? 100.0 * t.kinds_right / t.nodes_found : 0.0,
                    t.tape_m > 0 ? 10.0 * t.false_nodes / t.tape_m : 0.0);
        std::fflush(stdout);
        width_tally.runs += t.runs;
        width_tally.edges += t.edges;
        width_tally.edges_visited += t.edges_visited;
        width_tally.all_visited += t.all_visited;
        width_tally.nodes += t.nodes;
        width_tally.nodes_found += t.nodes_found;
        width_tally.false_nodes += t.false_nodes;
        width_tally.tape_m += t.tape_m;
      }
    }
    per_width.emplace_back(width_mm, width_tally);
  }
  // Per tape width, every layout and start pooled: paper 000's question, how narrow a tape
  // is still reliable.
  std::printf("\n| tape mm | runs | edges found | runs with every edge | nodes found | false nodes per 10 m |\n");
  std::printf("| --- | --- | --- | --- | --- | --- |\n");
  for (const auto& [width_mm, w] : per_width)
    std::printf("| %.0f | %d | %.1f %% | %.0f %% | %.1f %% | %.2f |\n", width_mm, w.runs,
                w.edges ? 100.0 * w.edges_visited / w.edges : 0.0, w.runs ? 100.0 * w.all_visited / w.runs : 0.0,
                w.nodes ? 100.0 * w.nodes_found / w.nodes : 0.0, w.tape_m > 0 ? 10.0 * w.false_nodes / w.tape_m : 0.0);
  std::printf("# %.1f s wall\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - wall).count());
  return 0;
}

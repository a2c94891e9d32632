#include "agents/run_comparison.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

namespace rilbed::agents {

namespace {

struct Sample {
  double x = 0, y = 0;
};
using Track = std::map<long, Sample>;  // by time in ms

// Reads trajectories.csv into per-robot tracks; an error names file and line.
std::string read_tracks(const std::filesystem::path& dir, std::map<int, Track>& out, double& last_t_s) {
  const auto path = dir / "trajectories.csv";
  std::ifstream in(path);
  if (!in) return path.string() + ": cannot open";
  std::string line;
  if (!std::getline(in, line) || line.rfind("t_s,id,x_m,y_m,theta_deg,behaviour", 0) != 0) {
    return path.string() + ":1: not a trajectories.csv header";
  }
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    std::istringstream fields(line);
    std::string t, id, x, y;
    if (!std::getline(fields, t, ',') || !std::getline(fields, id, ',') || !std::getline(fields, x, ',') ||
        !std::getline(fields, y, ',')) {
      return path.string() + ":" + std::to_string(number) + ": too few columns";
    }
    try {
      const double t_s = std::stod(t);
      out[std::stoi(id)][std::lround(t_s * 1000.0)] = {std::stod(x), std::stod(y)};
      last_t_s = std::max(last_t_s, t_s);
    } catch (const std::exception&) {
      return path.string() + ":" + std::to_string(number) + ": not a number";
    }
  }
  return "";
}

std::optional<double> formation_time(const std::filesystem::path& dir) {
  std::ifstream in(dir / "summary.json");
  if (!in) return std::nullopt;
  try {
    const auto j = nlohmann::json::parse(in);
    if (j.contains("formation_time_s") && j["formation_time_s"].is_number()) return j["formation_time_s"].get<double>();
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

}  // namespace

RunComparison compare_runs(const std::filesystem::path& a, const std::filesystem::path& b) {
  RunComparison c;
  std::map<int, Track> ta, tb;
  double end_a = 0, end_b = 0;
  if (c.error = read_tracks(a, ta, end_a); !c.error.empty()) return c;
  if (c.error = read_tracks(b, tb, end_b); !c.error.empty()) return c;
  c.common_duration_s = std::min(end_a, end_b);
  for (const auto& [id, track_a] : ta) {
    const auto it = tb.find(id);
    if (it == tb.end()) continue;
    RobotDifference d;
    double sum_sq = 0;
    for (const auto& [t_ms, pa] : track_a) {
      const auto pb = it->second.find(t_ms);
      if (pb == it->second.end()) continue;
      const double dist = std::hypot(pa.x - pb->second.x, pa.y - pb->second.y);
      sum_sq += dist * dist;
      d.max_distance_m = std::max(d.max_distance_m, dist);
      ++d.samples;
    }
    if (d.samples > 0) d.rms_distance_m = std::sqrt(sum_sq / d.samples);
    c.robots[id] = d;
  }
  c.formation_a_s = formation_time(a);
  c.formation_b_s = formation_time(b);
  return c;
}

}  // namespace rilbed::agents

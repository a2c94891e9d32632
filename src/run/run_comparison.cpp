#include "run/run_comparison.hpp"

#include "run/batch_summary.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <vector>

namespace rilbed::run {

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

// What a run's summary.json says: its formation time, and the robots that are real in it
// or stand in for real ones. A missing or unreadable summary says nothing.
struct SummaryFacts {
  std::optional<double> formation_time_s;
  std::vector<int> real_robots;
};

SummaryFacts read_summary(const std::filesystem::path& dir) {
  SummaryFacts facts;
  std::ifstream in(dir / "summary.json");
  if (!in) return facts;
  try {
    const auto j = nlohmann::json::parse(in);
    if (j.contains("formation_time_s") && j["formation_time_s"].is_number()) {
      facts.formation_time_s = j["formation_time_s"].get<double>();
    }
    for (const char* key : {"real_robots", "virtual_stand_ins"}) {
      if (!j.contains(key) || !j[key].is_array()) continue;
      for (const auto& id : j[key]) {
        if (id.is_number_integer()) facts.real_robots.push_back(id.get<int>());
      }
    }
  } catch (const std::exception&) {}
  return facts;
}

// The N of each `seed_<N>` folder in `dir`, sorted.
std::vector<std::uint64_t> seeds_in(const std::filesystem::path& dir) {
  std::vector<std::uint64_t> seeds;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_directory() || name.rfind("seed_", 0) != 0 || name.size() == 5) continue;
    if (name.find_first_not_of("0123456789", 5) != std::string::npos) continue;
    try {
      seeds.push_back(std::stoull(name.substr(5)));
    } catch (const std::exception&) {}
  }
  std::sort(seeds.begin(), seeds.end());
  return seeds;
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
  const SummaryFacts fa = read_summary(a), fb = read_summary(b);
  c.formation_a_s = fa.formation_time_s;
  c.formation_b_s = fb.formation_time_s;
  c.real_robots = fa.real_robots;
  c.real_robots.insert(c.real_robots.end(), fb.real_robots.begin(), fb.real_robots.end());
  std::sort(c.real_robots.begin(), c.real_robots.end());
  c.real_robots.erase(std::unique(c.real_robots.begin(), c.real_robots.end()), c.real_robots.end());
  return c;
}

bool is_batch_folder(const std::filesystem::path& dir) {
  return std::filesystem::exists(dir / "batch.json") || !seeds_in(dir).empty();
}

BatchComparison compare_batches(const std::filesystem::path& a, const std::filesystem::path& b) {
  BatchComparison c;
  // A batch's own summary, where it wrote one, must be readable: a damaged batch.json
  // means the folder is not what it says.
  for (const std::filesystem::path& dir : {a, b}) {
    std::string error;
    if (std::filesystem::exists(dir / "batch.json") && !read_batch_summary(dir / "batch.json", error)) {
      c.error = error;
      return c;
    }
  }
  const std::vector<std::uint64_t> sa = seeds_in(a), sb = seeds_in(b);
  if (sa.empty()) c.error = a.string() + ": no seed_<N> run folders (not a batch folder of rilbed run --seeds)";
  if (c.error.empty() && sb.empty())
    c.error = b.string() + ": no seed_<N> run folders (not a batch folder of rilbed run --seeds)";
  if (!c.error.empty()) return c;
  std::set_difference(sa.begin(), sa.end(), sb.begin(), sb.end(), std::back_inserter(c.only_a));
  std::set_difference(sb.begin(), sb.end(), sa.begin(), sa.end(), std::back_inserter(c.only_b));
  std::set<int> real, common;
  for (const std::uint64_t seed : sa) {
    if (!std::binary_search(sb.begin(), sb.end(), seed)) continue;
    const std::string folder = "seed_" + std::to_string(seed);
    RunComparison run = compare_runs(a / folder, b / folder);
    if (!run.ok()) {
      c.error = run.error;
      return c;
    }
    real.insert(run.real_robots.begin(), run.real_robots.end());
    for (const auto& [id, d] : run.robots) common.insert(id);
    c.seeds.push_back({seed, std::move(run)});
  }
  if (c.seeds.empty()) c.error = "the batches " + a.string() + " and " + b.string() + " have no seed in common";
  const std::set<int>& robots = real.empty() ? common : real;
  c.robots.assign(robots.begin(), robots.end());
  return c;
}

}  // namespace rilbed::run

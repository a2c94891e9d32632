#include "run/batch_summary.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>

#include "core/statistics.hpp"

namespace rilbed::run {

namespace {

nlohmann::json optional_number(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

// The value of `key`, checked for its type; throws std::runtime_error naming the key.
template <typename T>
T field(const nlohmann::json& j, const char* key) {
  if (!j.contains(key)) throw std::runtime_error(std::string("no '") + key + "'");
  try {
    return j.at(key).get<T>();
  } catch (const nlohmann::json::exception&) {
    throw std::runtime_error(std::string("'") + key + "' has the wrong type");
  }
}

std::optional<double> optional_field(const nlohmann::json& j, const char* key) {
  if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
  return field<double>(j, key);
}

}  // namespace

std::vector<std::uint64_t> BatchSummary::seeds() const {
  std::vector<std::uint64_t> out;
  for (const nlohmann::json& r : per_run) {
    if (r.contains("seed") && r.at("seed").is_number_unsigned()) out.push_back(r.at("seed").get<std::uint64_t>());
  }
  return out;
}

BatchSummary summarise_batch(const std::string& scenario, const std::string& mode, const std::vector<BatchRun>& runs,
                             double wall_s, int jobs) {
  BatchSummary b;
  b.scenario = scenario;
  b.mode = mode;
  b.wall_s = wall_s;
  b.jobs = jobs;
  std::vector<double> times;
  for (const BatchRun& run : runs) {
    const RunResult& r = run.result;
    if (r.ended_by.empty()) continue;  // not run (interrupted)
    ++b.runs;
    if (!run.error.empty()) ++b.failed;
    b.formed += r.formed;
    if (r.formation_time_s) times.push_back(*r.formation_time_s);
    b.collisions += r.collisions;
    b.robot_collisions += r.robot_collisions;
    b.max_overlap_m = std::max(b.max_overlap_m, r.max_overlap_m);
    nlohmann::json j = r.summary();
    if (!run.error.empty()) j["error"] = run.error;
    b.per_run.push_back(std::move(j));
  }
  if (!times.empty()) {
    b.formation_time_median_s = percentile(times, 0.5);
    b.formation_time_p95_s = percentile(times, 0.95);
  }
  return b;
}

nlohmann::json to_json(const BatchSummary& b) {
  nlohmann::json j;
  j["scenario"] = b.scenario;
  j["mode"] = b.mode;
  j["runs"] = b.runs;
  j["formed"] = b.formed;
  j["failed"] = b.failed;
  j["formation_time_median_s"] = optional_number(b.formation_time_median_s);
  j["formation_time_p95_s"] = optional_number(b.formation_time_p95_s);
  j["collisions"] = b.collisions;
  j["robot_collisions"] = b.robot_collisions;
  j["max_overlap_m"] = b.max_overlap_m;
  j["wall_s"] = b.wall_s;
  j["jobs"] = b.jobs;
  j["per_run"] = b.per_run;
  return j;
}

std::optional<BatchSummary> batch_summary_from_json(const nlohmann::json& j, std::string& error) {
  try {
    if (!j.is_object()) throw std::runtime_error("not a JSON object");
    BatchSummary b;
    b.scenario = field<std::string>(j, "scenario");
    b.mode = field<std::string>(j, "mode");
    b.runs = field<int>(j, "runs");
    b.formed = field<int>(j, "formed");
    b.failed = field<int>(j, "failed");
    b.formation_time_median_s = optional_field(j, "formation_time_median_s");
    b.formation_time_p95_s = optional_field(j, "formation_time_p95_s");
    b.collisions = field<int>(j, "collisions");
    b.robot_collisions = field<int>(j, "robot_collisions");
    b.max_overlap_m = field<double>(j, "max_overlap_m");
    b.wall_s = field<double>(j, "wall_s");
    b.jobs = field<int>(j, "jobs");
    const nlohmann::json& per_run = j.contains("per_run") ? j.at("per_run") : nlohmann::json();
    if (!per_run.is_array()) throw std::runtime_error("'per_run' is not a list");
    b.per_run.assign(per_run.begin(), per_run.end());
    return b;
  } catch (const std::runtime_error& e) {
    error = e.what();
    return std::nullopt;
  }
}

bool write_batch_summary(const std::filesystem::path& path, const BatchSummary& summary) {
  std::ofstream out(path);
  out << to_json(summary).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
  return static_cast<bool>(out);
}

std::optional<BatchSummary> read_batch_summary(const std::filesystem::path& path, std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = path.string() + ": cannot open";
    return std::nullopt;
  }
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded()) {
    error = path.string() + ": not JSON";
    return std::nullopt;
  }
  std::string why;
  auto summary = batch_summary_from_json(j, why);
  if (!summary) error = path.string() + ": " + why;
  return summary;
}

std::string batch_table(const BatchSummary& b) {
  char median[32] = "-", p95[32] = "-";
  if (b.formation_time_median_s) std::snprintf(median, sizeof median, "%.1f", *b.formation_time_median_s);
  if (b.formation_time_p95_s) std::snprintf(p95, sizeof p95, "%.1f", *b.formation_time_p95_s);
  char head[256], row[512];
  std::snprintf(head, sizeof head,
                "| scenario | mode | runs | formed | formation time median s | formation time p95 s | collisions "
                "(robot-robot) | max overlap m | wall s (%d jobs) |\n",
                b.jobs);
  std::snprintf(row, sizeof row, "| %s | %s | %d | %d | %s | %s | %d (%d) | %.2g | %.1f |\n", b.scenario.c_str(),
                b.mode.c_str(), b.runs, b.formed, median, p95, b.collisions, b.robot_collisions, b.max_overlap_m,
                b.wall_s);
  return std::string("\n") + head + "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n" + row;
}

}  // namespace rilbed::run

#include "run/run_options.hpp"

#include <algorithm>

#include "core/statistics.hpp"

namespace rilbed::run {

nlohmann::json RunResult::summary() const {
  nlohmann::json j;
  j["seed"] = seed;
  j["convoy_size"] = convoy_size;
  j["formed"] = formed;
  j["formation_time_s"] = formation_time_s ? nlohmann::json(*formation_time_s) : nlohmann::json(nullptr);
  j["collisions"] = collisions;
  j["robot_collisions"] = robot_collisions;
  j["max_overlap_m"] = max_overlap_m;
  j["simulated_s"] = simulated_s;
  j["wall_s"] = wall_s;
  j["run_wall_s"] = run_wall_s;
  j["ended_by"] = ended_by;
  j["controller_overruns"] = controller_overruns;
  j["controller_failed"] = controller_failed;
  if (!loop_latency_ms.empty()) {
    const std::vector<double> ms(loop_latency_ms.begin(), loop_latency_ms.end());
    j["loop_latency_ms"] = {{"p50", percentile(ms, 0.5)},
                            {"p99", percentile(ms, 0.99)},
                            {"max", *std::max_element(ms.begin(), ms.end())},
                            {"steps", ms.size()}};
  }
  return j;
}

}  // namespace rilbed::run

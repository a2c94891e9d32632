// Sim-to-real comparison (paper 001): the same scenario, seed and controllers run once all
// virtual and once with real robots; how far apart did the robots go, and how much
// sooner or later did the convoy form? Reads two run folders.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>

namespace rilbed::agents {

/// One robot's difference between two runs.
struct RobotDifference {
  int samples = 0;            ///< control steps present in both runs
  double rms_distance_m = 0;  ///< RMS of the distance between its positions at equal times
  double max_distance_m = 0;
};

/// Two runs compared.
struct RunComparison {
  std::map<int, RobotDifference> robots;  ///< by robot ID (robots present in both runs)
  std::optional<double> formation_a_s, formation_b_s;  ///< from each summary.json
  double common_duration_s = 0;           ///< the span of time both runs cover
  std::string error;                      ///< empty on success; names the file otherwise
  bool ok() const { return error.empty(); }
};

/// Compares the run folders `a` and `b` (trajectories.csv and summary.json of `rilbed run
/// --out`). Samples are matched by their time rounded to the millisecond.
RunComparison compare_runs(const std::filesystem::path& a, const std::filesystem::path& b);

}  // namespace rilbed::agents

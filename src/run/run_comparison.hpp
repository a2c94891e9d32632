// Sim-to-real comparison (paper 001): the same scenario, seed and controllers run once all
// virtual and once with real robots; how far apart did the robots go, and how much
// sooner or later did the convoy form? Reads two run folders, or two batch folders (one
// run folder per seed, `seed_<N>/`) seed by seed.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace rilbed::run {

/// One robot's difference between two runs.
struct RobotDifference {
  int samples = 0;            ///< control steps present in both runs
  double rms_distance_m = 0;  ///< RMS of the distance between its positions at equal times
  double max_distance_m = 0;
};

/// Two runs compared.
struct RunComparison {
  std::map<int, RobotDifference> robots;               ///< by robot ID (robots present in both runs)
  std::optional<double> formation_a_s, formation_b_s;  ///< from each summary.json
  double common_duration_s = 0;                        ///< the span of time both runs cover
  /// The robots that are real in either run, or stand in for real ones (summary.json's
  /// real_robots and virtual_stand_ins); empty when neither run had any.
  std::vector<int> real_robots;
  std::string error;  ///< empty on success; names the file otherwise
  bool ok() const { return error.empty(); }
};

/// Compares the run folders `a` and `b` (trajectories.csv and summary.json of `rilbed run
/// --out`). Samples are matched by their time rounded to the millisecond.
RunComparison compare_runs(const std::filesystem::path& a, const std::filesystem::path& b);

/// Whether `dir` is a batch folder (`rilbed run --seeds N --out DIR`): it holds
/// batch.json or `seed_<N>` run folders.
bool is_batch_folder(const std::filesystem::path& dir);

/// Two batches compared seed by seed.
struct BatchComparison {
  struct Seed {
    std::uint64_t seed = 0;
    RunComparison runs;
  };
  std::vector<Seed> seeds;            ///< the seeds both batches ran, in order
  std::vector<std::uint64_t> only_a;  ///< seeds only batch a has
  std::vector<std::uint64_t> only_b;
  /// The robots the comparison is about: every seed's real robots (or, when no run had
  /// any, every robot present in both).
  std::vector<int> robots;
  std::string error;  ///< empty on success; names the folder or file otherwise
  bool ok() const { return error.empty(); }
};

/// Compares the `seed_<N>` run folders of batches `a` and `b` that have the same N.
BatchComparison compare_batches(const std::filesystem::path& a, const std::filesystem::path& b);

}  // namespace rilbed::run

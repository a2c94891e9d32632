// A batch of runs over consecutive seeds, several at once: each in its own folder
// (seed_<N>/), then batch.json and the batch's table.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "run/batch_summary.hpp"
#include "run/run_options.hpp"

namespace rilbed::session {

/// Runs one seed (its options already hold the seed and its folder); throws for a run
/// that fails.
using SeedRunner = std::function<run::RunResult(const run::RunOptions&)>;

/// What a batch is.
struct BatchPlan {
  std::uint64_t first_seed = 1;
  int seeds = 1;
  std::filesystem::path out;  ///< seed_<N>/ and batch.json go here; empty: no folders
  int jobs = 1;               ///< runs at once (>= 1)
  /// Set to stop starting new runs (an interrupt, robots that could not be placed); may be null.
  std::vector<const std::atomic<bool>*> stop_flags;
  /// Told of each run as it ends (from the thread that ran it, one at a time).
  std::function<void(const run::BatchRun&)> on_run;
};

/// How many runs at once: `requested` if above 0, else as many as the cores hold with each
/// run's `threads`; at most `max_jobs`. Warns when that oversubscribes the cores.
int batch_jobs(int requested, int threads, int max_jobs);

/// Runs every seed of `plan` with `base` options and `run_seed`, `plan.jobs` at a time.
/// The results are in seed order; a seed not run (stopped) has an empty ended_by.
std::vector<run::BatchRun> run_batch(const BatchPlan& plan, const run::RunOptions& base, const SeedRunner& run_seed,
                                     double& wall_s);

}  // namespace rilbed::session

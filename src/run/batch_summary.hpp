// A batch of runs over seeds (`rilbed run --seeds N`) as a whole: what batch.json holds,
// made from the runs' results, written, read back, and shown as the batch's table row.
// batch.json's keys are public (other tools read them): `scenario`, `mode`, `runs`,
// `formed`, `failed`, `formation_time_median_s`, `formation_time_p95_s` (null when no run
// formed), `collisions`, `robot_collisions`, `max_overlap_m`, `wall_s`, `jobs`, `per_run`
// (each run's summary, with `error` for a run that failed).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "run/run_options.hpp"

namespace rilbed::run {

/// One run of a batch as the batch saw it.
struct BatchRun {
  RunResult result;   ///< ended_by empty: not run (the batch was interrupted or aborted)
  std::string error;  ///< why it failed; empty when it ran to its end
};

/// The batch as a whole.
struct BatchSummary {
  std::string scenario;                           ///< the scenario's name
  std::string mode;                               ///< "central" or "distributed"
  int runs = 0;                                   ///< runs that took place
  int formed = 0;                                 ///< of those, runs whose convoy formed
  int failed = 0;                                 ///< of those, runs that ended with an error
  std::optional<double> formation_time_median_s;  ///< over the runs that formed
  std::optional<double> formation_time_p95_s;
  int collisions = 0, robot_collisions = 0;  ///< summed over the runs
  double max_overlap_m = 0.0;                ///< the largest of the runs'
  double wall_s = 0.0;                       ///< the whole batch
  int jobs = 1;                              ///< runs at once
  std::vector<nlohmann::json> per_run;       ///< each run's summary.json content (+ `error`)

  /// The seeds of per_run, in its order.
  std::vector<std::uint64_t> seeds() const;
};

/// The summary of `runs` (in seed order), which took `wall_s` with `jobs` at once.
BatchSummary summarise_batch(const std::string& scenario, const std::string& mode, const std::vector<BatchRun>& runs,
                             double wall_s, int jobs);

/// batch.json's content.
nlohmann::json to_json(const BatchSummary& summary);
/// Reads batch.json's content; a missing or mistyped key is an error naming it.
std::optional<BatchSummary> batch_summary_from_json(const nlohmann::json& json, std::string& error);

/// Writes `summary` to `path` (batch.json); false if it cannot.
bool write_batch_summary(const std::filesystem::path& path, const BatchSummary& summary);
/// Reads a batch.json; nullopt with `error` naming the file (and the key) if it cannot.
std::optional<BatchSummary> read_batch_summary(const std::filesystem::path& path, std::string& error);

/// The batch's table as `rilbed run --seeds` prints it: a Markdown header and one row.
std::string batch_table(const BatchSummary& summary);

}  // namespace rilbed::run

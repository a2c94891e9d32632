#include "session/batch_runner.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <thread>

namespace rilbed::session {

namespace {

bool stopped(const BatchPlan& plan) {
  return std::any_of(plan.stop_flags.begin(), plan.stop_flags.end(),
                     [](const std::atomic<bool>* f) { return f && f->load(); });
}

}  // namespace

int batch_jobs(int requested, int threads, int max_jobs) {
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int jobs = std::clamp(requested > 0 ? requested : cores / std::max(1, threads), 1, max_jobs);
  if (jobs * threads > cores) {
    spdlog::warn(
        "{} runs at once on {} threads each is more threads than this machine's {} cores: they will wait on "
        "each other",
        jobs, threads, cores);
  }
  return jobs;
}

std::vector<run::BatchRun> run_batch(const BatchPlan& plan, const run::RunOptions& base, const SeedRunner& run_seed,
                                     double& wall_s) {
  const int n = plan.seeds;
  std::vector<run::BatchRun> runs(static_cast<std::size_t>(n));
  std::atomic<int> next{0};
  std::mutex report_mutex;
  const auto wall_start = std::chrono::steady_clock::now();
  auto worker = [&] {
    for (int i = next++; i < n && !stopped(plan); i = next++) {
      run::RunOptions o = base;
      o.seed = plan.first_seed + static_cast<std::uint64_t>(i);
      if (!plan.out.empty()) o.out_dir = plan.out / ("seed_" + std::to_string(o.seed));
      run::BatchRun& run = runs[static_cast<std::size_t>(i)];
      try {
        run.result = run_seed(o);
      } catch (const std::exception& e) {
        run.error = e.what();
        run.result.seed = o.seed;
        run.result.ended_by = "error";
      }
      std::lock_guard lock(report_mutex);
      if (plan.on_run) plan.on_run(run);
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < std::min(plan.jobs, n); ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  for (const run::BatchRun& run : runs) {
    if (!run.error.empty()) spdlog::error("seed {}: {}", run.result.seed, run.error);
  }
  return runs;
}

}  // namespace rilbed::session

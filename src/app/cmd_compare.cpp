// `rilbed compare A B`: the sim-to-real comparison of two run folders, or of two batch
// folders seed by seed (paper 001: the same scenario and seeds all virtual and with the
// real robots).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "app/commands.hpp"
#include "core/id_list.hpp"
#include "core/statistics.hpp"
#include "run/run_comparison.hpp"

namespace rilbed::app {

namespace {

std::string seconds(const std::optional<double>& t) {
  if (!t) return "not formed";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f s", *t);
  return buf;
}

std::string cell(const char* format, const std::optional<double>& value) {
  if (!value) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, format, *value);
  return buf;
}

int compare_two_runs(const std::string& a, const std::string& b) {
  const run::RunComparison c = run::compare_runs(a, b);
  if (!c.ok()) {
    spdlog::error("{}", c.error);
    return kExitFailure;
  }
  std::printf("Trajectories compared over %.1f s (samples at equal times):\n\n", c.common_duration_s);
  std::printf("| robot | samples | RMS distance m | max distance m |\n| ---: | ---: | ---: | ---: |\n");
  double sum_sq = 0;
  int n = 0;
  for (const auto& [id, d] : c.robots) {
    std::printf("| %d | %d | %.4f | %.4f |\n", id, d.samples, d.rms_distance_m, d.max_distance_m);
    sum_sq += d.rms_distance_m * d.rms_distance_m * d.samples;
    n += d.samples;
  }
  std::printf("| all | %d | %.4f | |\n\n", n, n > 0 ? std::sqrt(sum_sq / n) : 0.0);
  std::printf("formation time: %s vs %s", seconds(c.formation_a_s).c_str(), seconds(c.formation_b_s).c_str());
  if (c.formation_a_s && c.formation_b_s) std::printf(" (difference %+.1f s)", *c.formation_b_s - *c.formation_a_s);
  std::printf("\n");
  if (!c.real_robots.empty()) std::printf("real robots: %s\n", id_list_text(c.real_robots).c_str());
  return c.robots.empty() ? kExitFailure : 0;
}

// Per seed: each compared robot's trajectory RMS and the formation times; then the median
// and the 95th percentile of every column (of the difference's size for the difference).
int compare_two_batches(const std::string& a, const std::string& b) {
  const run::BatchComparison c = run::compare_batches(a, b);
  if (!c.ok()) {
    spdlog::error("{}", c.error);
    return kExitFailure;
  }
  for (const std::uint64_t seed : c.only_a) spdlog::warn("seed {} is only in {}", seed, a);
  for (const std::uint64_t seed : c.only_b) spdlog::warn("seed {} is only in {}", seed, b);
  std::printf("%zu seeds; A = %s, B = %s; RMS of each robot's distance between A and B at equal times%s:\n\n",
              c.seeds.size(), a.c_str(), b.c_str(),
              c.seeds.front().runs.real_robots.empty() ? "" : " (its real robots)");
  std::string header = "| seed |", rule = "| ---: |";
  for (const int id : c.robots) {
    header += " robot " + std::to_string(id) + " RMS m |";
    rule += " ---: |";
  }
  header += " formation A s | formation B s | difference B-A s |";
  rule += " ---: | ---: | ---: |";
  std::printf("%s\n%s\n", header.c_str(), rule.c_str());
  std::vector<std::vector<double>> rms(c.robots.size());
  std::vector<double> formed_a, formed_b, difference, size_of_difference;
  int both_formed = 0;
  for (const auto& [seed, run] : c.seeds) {
    std::string row = "| " + std::to_string(seed) + " |";
    for (std::size_t k = 0; k < c.robots.size(); ++k) {
      const auto it = run.robots.find(c.robots[k]);
      std::optional<double> value;
      if (it != run.robots.end() && it->second.samples > 0) {
        value = it->second.rms_distance_m;
        rms[k].push_back(*value);
      }
      row += " " + cell("%.4f", value) + " |";
    }
    std::optional<double> diff;
    if (run.formation_a_s) formed_a.push_back(*run.formation_a_s);
    if (run.formation_b_s) formed_b.push_back(*run.formation_b_s);
    if (run.formation_a_s && run.formation_b_s) {
      diff = *run.formation_b_s - *run.formation_a_s;
      difference.push_back(*diff);
      size_of_difference.push_back(std::abs(*diff));
      ++both_formed;
    }
    row += " " + cell("%.1f", run.formation_a_s) + " | " + cell("%.1f", run.formation_b_s) + " | " +
           cell("%+.1f", diff) + " |";
    std::printf("%s\n", row.c_str());
  }
  auto stat_row = [&](const char* name, double p, bool size_for_difference) {
    std::string row = std::string("| ") + name + " |";
    for (const auto& values : rms) {
      row += " " + cell("%.4f", values.empty() ? std::nullopt : std::optional<double>(percentile(values, p))) + " |";
    }
    auto of = [&](const std::vector<double>& v) {
      return v.empty() ? std::nullopt : std::optional<double>(percentile(v, p));
    };
    row += " " + cell("%.1f", of(formed_a)) + " | " + cell("%.1f", of(formed_b)) + " | " +
           cell(size_for_difference ? "%.1f" : "%+.1f", of(size_for_difference ? size_of_difference : difference)) +
           " |";
    std::printf("%s\n", row.c_str());
  };
  stat_row("median", 0.5, false);
  stat_row("p95", 0.95, true);
  std::printf("\nformed: A %zu of %zu, B %zu of %zu, both %d; the p95 of the difference is that of its size |B-A|\n",
              formed_a.size(), c.seeds.size(), formed_b.size(), c.seeds.size(), both_formed);
  return 0;
}

}  // namespace

void add_compare_command(CLI::App& app) {
  auto a = std::make_shared<std::string>();
  auto b = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "Compare two run folders, or two batch folders seed by seed (e.g. all virtual vs with real robots)");
  cmd->add_option("run_a", *a, "First run folder (rilbed run --out), or batch folder (rilbed run --seeds N --out)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("run_b", *b, "Second run or batch folder")->required()->check(CLI::ExistingDirectory);
  cmd->callback([a, b] {
    const bool batch_a = run::is_batch_folder(*a), batch_b = run::is_batch_folder(*b);
    if (batch_a != batch_b) {
      spdlog::error("{} is a {} folder and {} a {} folder: compare two runs or two batches", *a,
                    batch_a ? "batch" : "run", *b, batch_b ? "batch" : "run");
      exit_code() = kExitUsage;
      return;
    }
    exit_code() = batch_a ? compare_two_batches(*a, *b) : compare_two_runs(*a, *b);
  });
}

}  // namespace rilbed::app

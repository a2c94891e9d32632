// `rilbed compare RUN_A RUN_B`: the sim-to-real comparison of two run folders.
#include <spdlog/spdlog.h>

#include <cstdio>

#include "agents/run_comparison.hpp"
#include "app/commands.hpp"

namespace rilbed::app {

namespace {

std::string seconds(const std::optional<double>& t) {
  if (!t) return "not formed";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f s", *t);
  return buf;
}

}  // namespace

void add_compare_command(CLI::App& app) {
  auto a = std::make_shared<std::string>();
  auto b = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand("compare", "Compare two run folders (e.g. all virtual vs with real robots)");
  cmd->add_option("run_a", *a, "First run folder (rilbed run --out)")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("run_b", *b, "Second run folder")->required()->check(CLI::ExistingDirectory);
  cmd->callback([a, b] {
    const agents::RunComparison c = agents::compare_runs(*a, *b);
    if (!c.ok()) {
      spdlog::error("{}", c.error);
      exit_code() = kExitFailure;
      return;
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
    if (c.robots.empty()) exit_code() = kExitFailure;
  });
}

}  // namespace rilbed::app

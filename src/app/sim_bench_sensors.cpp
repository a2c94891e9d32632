#include "app/sim_bench_sensors.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "agents/library_sensor_models.hpp"
#include "run/scenario.hpp"
#include "run/sensor_parameters.hpp"
#include "run/simulation.hpp"

namespace rilbed::app {

namespace {

// The track_following scenario's element: straight down, paper 000's other numbers.
environment::TrackSensorConfig element(double mount_y_m) {
  environment::TrackSensorConfig c;
  c.mount_x_m = 0.02;
  c.mount_y_m = mount_y_m;
  c.inclination_deg = 0.0;
  return c;
}
constexpr double kMounts_m[] = {0.012, 0.0, -0.012};

// The wandering swarm on a field crossed by tape every half metre each way, each robot
// with three track elements across its front: built in, or `plugin`'s mounted.
run::Scenario track_scenario(int robots, const SensorBenchOptions& o) {
  run::Scenario s = run::wandering_scenario(robots, o.seconds, o.physics_step_ms, o.density_per_m2);
  s.name = "sim-bench-track-" + std::to_string(robots);
  s.source = "(sim-bench)";
  for (double x = 0.25; x < s.map.field.width_m; x += 0.5) {
    s.map.tracks.push_back({{{x, 0.05}, {x, s.map.field.height_m - 0.05}}, 0.025, false, ""});
  }
  for (double y = 0.25; y < s.map.field.height_m; y += 0.5) {
    s.map.tracks.push_back({{{0.05, y}, {s.map.field.width_m - 0.05, y}}, 0.025, false, ""});
  }
  return s;
}

void use_builtin(run::Scenario& s) {
  for (run::RobotSpec& r : s.robots) {
    for (const double y : kMounts_m) r.sensors.track_sensors.push_back(element(y));
  }
}

// The plug-in's three mounts, made once (shared by every robot, as a scenario entry's are).
std::optional<std::vector<environment::SensorModelMount>> plugin_mounts(const run::Scenario& s,
                                                                        const std::string& library) {
  core::Result<std::vector<agents::SensorModelEntry>> entries = agents::load_library_sensor_models(library);
  if (!entries) {
    spdlog::error("sim-bench: {}", entries.error());
    return std::nullopt;
  }
  const auto entry = std::find_if(entries->begin(), entries->end(),
                                  [](const agents::SensorModelEntry& e) { return e.name == "track_element"; });
  if (entry == entries->end()) {
    spdlog::error("sim-bench: {} holds no sensor model 'track_element'", library);
    return std::nullopt;
  }
  const environment::TrackSensorConfig c = element(0.0);
  run::ParameterFile file{"(sim-bench)",
                          {{"Height", c.height_mm, 0},
                           {"Inclination", c.inclination_deg, 0},
                           {"Cone Angle", c.cone_angle_deg, 0},
                           {"Precision", static_cast<double>(c.precision), 0},
                           {"Coverage", c.coverage_percent, 0},
                           {"Max Value", static_cast<double>(c.max_value), 0},
                           {"Error Level", c.error_level_percent, 0}}};
  core::Result<std::vector<double>> values = run::parameter_values(*entry, file);
  if (!values) {
    spdlog::error("sim-bench: {}", values.error());
    return std::nullopt;
  }
  const environment::StaticMap map(s.map);
  std::vector<environment::SensorModelMount> mounts;
  for (const double y : kMounts_m) {
    const agents::SensorMount mount{entry->name, *values, c.mount_x_m, y, 0.0, "(sim-bench)"};
    auto made = agents::mount_sensor_model(*entry, mount, map, s.control_period_us);
    if (!made) {
      spdlog::error("sim-bench: {}", made.error());
      return std::nullopt;
    }
    mounts.push_back({*made});
  }
  return mounts;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int run_sensor_bench(const SensorBenchOptions& o) {
  std::printf(
      "\n## A sensor model from a plug-in library (rilbed sim-bench --sensor-plugin %s)\n\n"
      "The swarm above at %.2f robots per m^2 on a field crossed by 25 mm tape every 0.5 m each way, each robot "
      "with three track elements across its front (paper 000's sensor: 16 cells, 15 %% coverage, 5 %% noise, "
      "looking straight down), read every control step: rilbed's own track sensor, or the same model from the "
      "plug-in library (%s, called through rilbed/sensor_model.h's C functions). One thread; wall ms per simulated "
      "second, medians of %d runs of each, the two kinds taking turns; \"same\": their trajectories are identical.\n\n"
      "| robots | built-in track sensor | plug-in track sensor | plug-in costs | same |\n"
      "| ---: | ---: | ---: | ---: | --- |\n",
      o.library.c_str(), o.density_per_m2, o.library.c_str(), o.repeat);
  bool all_same = true;
  for (const int n : o.robots) {
    run::Scenario builtin = track_scenario(n, o);
    run::Scenario plugin = builtin;
    use_builtin(builtin);
    const auto mounts = plugin_mounts(plugin, o.library);
    if (!mounts) return 1;
    for (run::RobotSpec& r : plugin.robots) r.sensors.models = *mounts;
    std::vector<double> builtin_ms, plugin_ms;
    std::uint64_t digests[2] = {0, 0};
    for (int rep = 0; rep < o.repeat; ++rep) {
      for (int kind = 0; kind < 2; ++kind) {
        run::RunOptions options;
        options.seed = o.seed;
        options.duration_s = o.seconds;
        const run::RunResult r = run::run_scenario(kind == 0 ? builtin : plugin, options);
        (kind == 0 ? builtin_ms : plugin_ms).push_back(1000.0 * r.run_wall_s / r.simulated_s);
        digests[kind] = r.trajectory_digest;
      }
    }
    const bool same = digests[0] == digests[1];
    all_same = all_same && same;
    const double b = median(builtin_ms), p = median(plugin_ms);
    std::printf("| %d | %.1f | %.1f | %+.1f %% | %s |\n", n, b, p, 100.0 * (p / b - 1.0), same ? "yes" : "NO");
    std::fflush(stdout);
  }
  if (!all_same) spdlog::error("sim-bench: the plug-in track sensor's trajectories differ from the built-in's");
  return all_same ? 0 : 1;
}

}  // namespace rilbed::app

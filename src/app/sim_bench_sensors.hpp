// `rilbed sim-bench --sensor-plugin PATH`: the cost of a sensor model from a plug-in
// library against the same model built into rilbed, on the same swarm.
#pragma once

#include <string>
#include <vector>

namespace rilbed::app {

/// How the sensor-model rows are run.
struct SensorBenchOptions {
  std::string library;      ///< a plug-in library holding `track_element` (examples/sensors/track_sensor)
  std::vector<int> robots;  ///< robot counts
  double seconds = 10.0;    ///< simulated seconds per run
  double physics_step_ms = 100.0;
  double density_per_m2 = 1.0;
  std::uint64_t seed = 1;
  int repeat = 3;  ///< runs of each kind per count, alternating; medians
};

/// Times every count with three built-in track elements per robot and with three of the
/// library's, on a field crossed by tape, and prints the table. 0, or 1 with a message on
/// stderr when the library will not serve or the two kinds' trajectories differ.
int run_sensor_bench(const SensorBenchOptions& options);

}  // namespace rilbed::app

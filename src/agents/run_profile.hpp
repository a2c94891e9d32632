// Where a simulation run's time goes (issue 19): what `rilbed sim-bench` prints.
#pragma once

namespace rilbed::agents {

/// Where a run's time goes (RunOptions::profile), seconds of wall time summed over the run.
/// Timed with steady_clock around each part (a few reads per robot and step: about 3 %
/// of a 10,000-robot step).
struct RunProfile {
  double sensing_s = 0.0;      ///< the agents' sensing (virtual sensors and their noise)
  double behaviours_s = 0.0;   ///< the controllers' steps (behaviour networks) and driving the bodies
  double integration_s = 0.0;  ///< moving the bodies (exact arcs, substeps) in the world's steps
  double collisions_s = 0.0;   ///< resolving collisions in the world's steps
  double monitor_s = 0.0;      ///< recording: trajectories, events, overlap check, observers
};

}  // namespace rilbed::agents

// Where a simulation run's time goes: what `rilbed sim-bench` prints.
#pragma once

namespace rilbed::run {

/// Where a run's time goes (RunOptions::profile), seconds of wall time summed over the run.
/// Timed with steady_clock around each part (a few reads per robot and step: about 3 %
/// of a 10,000-robot step).
struct RunProfile {
  /// The sensors: the world's sweep (its wall time times the thread count, as if every
  /// thread had swept all along) and each agent's taking of its reading. With several
  /// threads, time summed over the threads, like behaviours_s.
  double sensing_s = 0.0;
  double behaviours_s =
      0.0;  ///< the controllers' steps (behaviour networks) and driving the bodies, summed over threads
  double integration_s = 0.0;  ///< moving the bodies (exact arcs, substeps) in the world's steps
  double collisions_s = 0.0;   ///< resolving collisions in the world's steps
  double monitor_s = 0.0;      ///< recording: trajectories, events, overlap check, observers
};

}  // namespace rilbed::run

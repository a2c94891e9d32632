// Random numbers for the world's noise models. Written out instead of using the
// standard library's distributions so that one seed gives the same numbers with every
// standard library: a recorded run replays identically on another machine.
#pragma once

#include <cmath>
#include <random>
#include <utility>

namespace rilbed::environment {

/// A uniform number in [0, 1) made of 53 random bits from one draw of `rng`.
inline double uniform01(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

/// Two independent standard normal numbers (mean 0, standard deviation 1), by
/// Marsaglia's polar method. Returning the pair (rather than caching the second number
/// somewhere) keeps the draw a pure function of the generator's state.
inline std::pair<double, double> standard_normal_pair(std::mt19937_64& rng) {
  for (;;) {
    const double u = 2.0 * uniform01(rng) - 1.0;
    const double v = 2.0 * uniform01(rng) - 1.0;
    const double s = u * u + v * v;
    if (s > 0.0 && s < 1.0) {
      const double f = std::sqrt(-2.0 * std::log(s) / s);
      return {u * f, v * f};
    }
  }
}

/// One standard normal number (draws a pair and drops the second).
inline double standard_normal(std::mt19937_64& rng) { return standard_normal_pair(rng).first; }

}  // namespace rilbed::environment

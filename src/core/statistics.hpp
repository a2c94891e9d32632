// Small statistics shared by the commands that print tables.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace rilbed {

/// The p-quantile (p in [0, 1]) of `values`, linearly interpolated between the two nearest
/// ranks; 0 for no values. Takes a copy to sort.
inline double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double rank = std::clamp(p, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(rank);
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (rank - static_cast<double>(lo)) * (values[hi] - values[lo]);
}

}  // namespace rilbed

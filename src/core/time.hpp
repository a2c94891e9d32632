// Time in rilbed: integer microseconds everywhere (as LCM's utime).
#pragma once

#include <cstdint>

namespace rilbed {

/// A point in time or a duration, in microseconds.
using TimeUs = std::int64_t;

/// Seconds (double) to microseconds, rounded to the nearest microsecond.
constexpr TimeUs seconds_to_us(double s) {
  return static_cast<TimeUs>(s * 1e6 + (s >= 0 ? 0.5 : -0.5));
}
/// Microseconds to seconds.
constexpr double us_to_seconds(TimeUs t_us) { return static_cast<double>(t_us) * 1e-6; }

}  // namespace rilbed

// Time in rilbed: integer microseconds everywhere (as LCM's utime).
#pragma once

#include <cstdint>
#include <ctime>

namespace rilbed {

/// A point in time or a duration, in microseconds.
using TimeUs = std::int64_t;

/// Seconds (double) to microseconds, rounded to the nearest microsecond.
constexpr TimeUs seconds_to_us(double s) { return static_cast<TimeUs>(s * 1e6 + (s >= 0 ? 0.5 : -0.5)); }
/// Microseconds to seconds.
constexpr double us_to_seconds(TimeUs t_us) { return static_cast<double>(t_us) * 1e-6; }

/// CPU time the calling thread has used, seconds: what a piece of work costs, whatever
/// else the machine does meanwhile.
inline double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace rilbed

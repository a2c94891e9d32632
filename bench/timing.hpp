// Clocks for the benchmarks: the thread's CPU time, and what reading the clocks around a
// call costs, measured so that it can be subtracted from every sample.
#pragma once

#include <algorithm>
#include <chrono>
#include <ctime>
#include <vector>

namespace rilbed::bench {

/// The wall clock the benchmarks time with.
using Clock = std::chrono::steady_clock;

/// Milliseconds of wall time since `t0`.
inline double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// CPU time of the calling thread, milliseconds: on a shared machine it leaves out the
/// time other processes held the core. A system call (about 0.5 us on a VM).
inline double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/// What an empty interval reads on each clock, milliseconds.
struct TimerOverhead {
  double wall_ms = 0.0;
  double cpu_ms = 0.0;
};

/// The medians of `intervals` empty intervals read exactly as a timed call is (CPU clock,
/// wall clock, nothing, wall clock, CPU clock). Reading the CPU clock is a system call, a
/// few per cent of a 10 us call and nothing of a 10 ms one: subtract this from every
/// sample of every detector alike.
inline TimerOverhead measure_timer_overhead(int intervals = 20001) {
  std::vector<double> wall, cpu;
  wall.reserve(intervals);
  cpu.reserve(intervals);
  for (int i = 0; i < intervals; ++i) {
    const double c0 = thread_cpu_ms();
    const auto t0 = Clock::now();
    wall.push_back(ms_since(t0));
    cpu.push_back(thread_cpu_ms() - c0);
  }
  auto median = [](std::vector<double>& v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  return {median(wall), median(cpu)};
}

/// A timed interval less the timer's own cost (never below zero).
inline double net_ms(double measured_ms, double overhead_ms) { return std::max(0.0, measured_ms - overhead_ms); }

}  // namespace rilbed::bench

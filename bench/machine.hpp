// What the benchmarks print about the machine and the build they measured on.
#pragma once

#include <sched.h>

#include <cstdlib>
#include <fstream>
#include <string>

namespace rilbed::bench {

/// The CPU's model name (/proc/cpuinfo), or "unknown".
inline std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  }
  return "unknown";
}

/// The CPUs this process may run on: what `nproc` prints (-1 when it cannot tell).
inline int usable_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return -1;
  return CPU_COUNT(&set);
}

/// The first line of a file ("/proc/loadavg"), or "".
inline std::string first_line(const char* path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

/// An environment variable's value (tools/bench.sh sets the build type and sources), or
/// `fallback` when it is unset or empty.
inline std::string env_or(const char* name, const char* fallback) {
  const char* v = std::getenv(name);
  return v && *v ? v : fallback;
}

}  // namespace rilbed::bench

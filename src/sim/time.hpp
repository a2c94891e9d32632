// Simulated time in the DEVS kernel: integer microseconds, with one value for "never".
#pragma once

#include <limits>

#include "core/time.hpp"

namespace rilbed::sim {

/// "Never": the time advance of a passive model and the next-event time of a model
/// that waits only for input. Arithmetic on it saturates in the coordinator.
inline constexpr TimeUs kInfinity = std::numeric_limits<TimeUs>::max();

}  // namespace rilbed::sim

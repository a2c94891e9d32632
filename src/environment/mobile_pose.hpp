// A robot or moving obstacle's pose as a sensor model sees it (sensor_model.hpp): the
// SDK's own struct, so that the world's list of them goes to a plug-in as it is.
#pragma once

#include "rilbed/sensor_model.h"

namespace rilbed::environment {

/// A robot or moving obstacle, field frame: robots by ID (in the order they were added),
/// moving obstacles numbered -1, -2, ... after them.
using MobilePose = rilbed_mobile;

}  // namespace rilbed::environment

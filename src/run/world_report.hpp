// The field and the robots' sensors as the run folder's picture and viewers draw them.
#pragma once

#include <vector>

#include "run/run_observer.hpp"
#include "run/run_recorder.hpp"
#include "run/scenario.hpp"

namespace rilbed::run {

/// The field, its obstacles, tracks and beacons, and which robots are real.
FieldDrawing field_drawing(const Scenario& scenario, const std::vector<int>& real_ids);

/// What viewers need to draw the run: the field, the walls, each robot's sensors.
WorldReport world_report(const Scenario& scenario, const std::vector<int>& real_ids);

}  // namespace rilbed::run

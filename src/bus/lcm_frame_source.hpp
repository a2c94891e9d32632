// The camera frames of a recording (`rilbed run --record FILE.lcm --record-frames`) as a
// frame source for the vision pipeline, so that a run's footage can be detected again with
// other settings: `rilbed detect FILE.lcm ...`.
#pragma once

#include <memory>
#include <string>

#include "bus/lcm_bus.hpp"
#include "vision/frame_source.hpp"

namespace rilbed::bus {

/// Whether `path` names an LCM log (ends in .lcm, any case).
bool is_lcm_log_path(const std::string& path);

/// Opens the frames (rilbed::frame_t, JPEG) of the LCM log at `path`: every message on a
/// channel named RILBED_FRAMES or ending in "_RILBED_FRAMES" (a prefixed run), in log
/// order. A frame that is not a JPEG image of its stated size is an Error result naming
/// its number, and the stream goes on. Fails (naming the file) when the file cannot be
/// read or holds no frames (a recording made without --record-frames says so).
vision::OpenResult open_lcm_frames(const std::string& path);

}  // namespace rilbed::bus

// The camera's answer to "where is each real robot?": the marker tracker over a stream
// of frames, mapped to the field frame with the field calibration.
#pragma once

#include <opencv2/core.hpp>

#include <vector>

#include "core/geometry.hpp"
#include "vision/field_mapping.hpp"
#include "vision/marker_family.hpp"
#include "vision/marker_tracker.hpp"
#include "vision/vision_settings.hpp"

namespace rilbed::vision {

/// One robot seen in one frame, in the field frame.
struct FieldObservation {
  int id = 0;
  Pose2 pose;                 ///< metres; heading radians CCW from +x (the key slice's bisector)
  double score = 0.0;         ///< the marker's decoding similarity, [-1, 1]
  MarkerDetection detection;  ///< the same in the image
};

/// Tracks the listed IDs over frames of one camera and reports field poses. Not
/// thread-safe; one per camera.
class FieldTracker {
 public:
  /// Throws std::invalid_argument for a bad ID list or a calibration that
  /// validate_field_calibration() rejects.
  FieldTracker(MarkerFamily family, std::vector<int> ids, FieldCalibration calibration, TrackerConfig config = {});
  /// One frame (8-bit grey or BGR, of the calibration's image size): the robots seen, by ID.
  /// The frame is first adjusted by the settings' brightness and contrast (see
  /// seen_frame()). Throws std::invalid_argument for a frame of another size.
  std::vector<FieldObservation> process(const cv::Mat& frame);
  /// The last frame as the detector saw it: the one given to process(), after the
  /// brightness and contrast (shares its pixels when they leave it alone). Valid until
  /// the next process().
  const cv::Mat& seen_frame() const { return seen_; }
  const FrameStats& last_stats() const { return tracker_.last_stats(); }
  const FieldCalibration& calibration() const { return calibration_; }
  /// The vision settings in use (those of the config given, brightness 0, contrast 1 at first).
  const VisionSettings& settings() const { return settings_; }
  /// New settings from the next frame on (see MarkerTracker::set_config). Throws
  /// std::invalid_argument when check_vision_settings() rejects them.
  void set_settings(const VisionSettings& settings);

 private:
  MarkerTracker tracker_;
  FieldCalibration calibration_;
  VisionSettings settings_;
  cv::Mat adjusted_;  // adjust_frame()'s buffer, reused
  cv::Mat seen_;
};

}  // namespace rilbed::vision

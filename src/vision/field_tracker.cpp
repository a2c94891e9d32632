#include "vision/field_tracker.hpp"

#include <stdexcept>

namespace rilbed::vision {

FieldTracker::FieldTracker(MarkerFamily family, std::vector<int> ids, FieldCalibration calibration,
                           TrackerConfig config)
    : tracker_(std::move(family), std::move(ids), config),
      calibration_(std::move(calibration)),
      settings_(vision_settings_of(config)) {
  if (const std::string problem = validate_field_calibration(calibration_); !problem.empty()) {
    throw std::invalid_argument("field calibration: " + problem);
  }
}

std::vector<FieldObservation> FieldTracker::process(const cv::Mat& frame) {
  if (frame.size() != calibration_.image_size) {
    throw std::invalid_argument("frame of " + std::to_string(frame.cols) + "x" + std::to_string(frame.rows) +
                                " pixels, but the field calibration is for " +
                                std::to_string(calibration_.image_size.width) + "x" +
                                std::to_string(calibration_.image_size.height));
  }
  seen_ = adjust_frame(frame, settings_, adjusted_);
  std::vector<FieldObservation> out;
  for (const MarkerDetection& d : tracker_.process(seen_)) {
    FieldObservation o;
    o.id = d.id;
    o.pose.position_m = pixel_to_field(calibration_, d.u, d.v);
    o.pose.heading_rad = deg_to_rad(image_heading_to_field_deg(calibration_, d.u, d.v, d.heading_deg));
    o.score = d.score;
    o.detection = d;
    out.push_back(o);
  }
  return out;
}

void FieldTracker::set_settings(const VisionSettings& settings) {
  if (auto why = check_vision_settings(settings)) throw std::invalid_argument("vision settings: " + *why);
  settings_ = settings;
  tracker_.set_config(with_vision_settings(tracker_.config(), settings));
}

}  // namespace rilbed::vision

// An emulated overhead camera: renders markers at given field poses as a real camera
// above the field sees them (the synthetic camera: perspective, blur, noise, lighting),
// so that an emulated robot's frames go through the real detector and tracker.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

#include "vision/field_mapping.hpp"
#include "vision/synthetic_camera.hpp"

namespace rilbed::vision {

/// Knobs of the emulated camera.
struct EmulatedCameraConfig {
  cv::Size image_size{1280, 720};
  /// Height of the camera above the field's centre, metres (paper 001: about 1.5 m).
  double height_m = 1.5;
  /// Share of the image, along its tighter side, that the field fills; the field of view
  /// follows. Lower leaves more margin around the field and makes markers smaller.
  double field_fill = 0.9;
  /// Outer diameter of the printed markers, metres (a Khepera is 55 mm across).
  double marker_diameter_m = 0.05;
  /// Frames per second the camera delivers.
  double fps = 30.0;
  /// Imaging: defaults give sensor noise, a little blur and a mild lighting gradient,
  /// rendered at 2x2 samples per pixel (about 7 ms for 1280x720; 1 sample aliases edges
  /// and costs headings about 2 degrees).
  ImagingConditions conditions = [] {
    ImagingConditions c;
    c.noise_sigma = 2.0;
    c.blur_sigma_px = 0.6;
    c.light_ratio = 1.3;
    c.supersample = 2;
    return c;
  }();
  std::uint64_t seed = 1;  ///< the sensor noise's sequence
};

/// The camera. Not thread-safe.
class EmulatedOverheadCamera {
 public:
  /// A camera centred above a field of width_m x height_m. Throws std::invalid_argument for
  /// non-positive sizes.
  EmulatedOverheadCamera(double field_width_m, double field_height_m, MarkerFamily family,
                         EmulatedCameraConfig config = {});
  /// One 8-bit grey frame showing `markers` (field poses, IDs).
  cv::Mat render(const std::vector<SceneMarker>& markers);
  /// The calibration a lab would have measured for this camera (its exact homography and lens).
  const FieldCalibration& calibration() const { return calibration_; }
  const EmulatedCameraConfig& config() const { return config_; }

 private:
  EmulatedCameraConfig config_;
  SyntheticCamera camera_;
  FieldCalibration calibration_;
  cv::RNG rng_;
};

}  // namespace rilbed::vision

#include "vision/emulated_camera.hpp"

#include <cmath>
#include <stdexcept>

#include "core/geometry.hpp"

namespace rilbed::vision {

namespace {

CameraModel overhead_for(double width_m, double height_m, const EmulatedCameraConfig& c) {
  if (!(width_m > 0.0) || !(height_m > 0.0))
    throw std::invalid_argument("emulated camera: field size must be positive");
  if (!(c.height_m > 0.0) || !(c.field_fill > 0.0) || !(c.fps > 0.0)) {
    throw std::invalid_argument("emulated camera: height, field fill and fps must be positive");
  }
  // The vertical field of view that fits the field (with the fill margin) both ways.
  const double aspect = static_cast<double>(c.image_size.width) / c.image_size.height;
  const double needed_half_height_m = 0.5 * std::max(height_m, width_m / aspect) / c.field_fill;
  const double vfov_deg = rad_to_deg(2.0 * std::atan(needed_half_height_m / c.height_m));
  return CameraModel::overhead(c.image_size, vfov_deg, {width_m / 2.0, height_m / 2.0}, c.height_m, 0.0);
}

}  // namespace

EmulatedOverheadCamera::EmulatedOverheadCamera(double field_width_m, double field_height_m, MarkerFamily family,
                                               EmulatedCameraConfig config)
    : config_(config),
      camera_(overhead_for(field_width_m, field_height_m, config), std::move(family), config.conditions),
      calibration_(camera_.camera().field_calibration(field_width_m, field_height_m)),
      rng_(config.seed) {}

cv::Mat EmulatedOverheadCamera::render(const std::vector<SceneMarker>& markers) {
  return camera_.render(markers, rng_);
}

}  // namespace rilbed::vision

// Pixel <-> field mapping for the overhead camera: a plane-to-plane homography from the
// undistorted image to the field, in metres, and the OpenCV YAML file that stores it.
//
// Frames: the image has u right, v down, pixels, the centre of the top-left pixel at
// (0, 0). The field has its origin at the field's lower-left corner as seen from above,
// x right, y up, metres; a field of width W and height H spans [0, W] x [0, H].
//
// The mapping is exact only for points on the plane it was calibrated on. Markers on
// robots sit above the floor, so calibrate with markers (or the corners of a board) at
// the height of the robots' markers, not with the floor's corners.
//
// File format (OpenCV YAML, cv::FileStorage):
//   field_width_m, field_height_m   double, metres, > 0
//   homography                      3x3 double matrix, undistorted pixels -> metres
//   image_width, image_height       int, pixels
//   camera_matrix                   optional 3x3 double matrix (see calibration.hpp)
//   distortion_coefficients         optional Nx1 double matrix; present iff camera_matrix is
#pragma once

#include <opencv2/core.hpp>

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry.hpp"
#include "vision/calibration.hpp"

namespace rilbed::vision {

/// How camera pixels map to the field. A plain value; copy freely.
struct FieldCalibration {
  double width_m = 0.0;   ///< field extent along x, metres
  double height_m = 0.0;  ///< field extent along y, metres
  /// Maps homogeneous undistorted pixels (u, v, 1) to homogeneous field points in metres.
  /// "Undistorted" means after cv::undistortPoints with P = the camera matrix, i.e.
  /// still in pixels; without a lens model, raw pixels.
  cv::Matx33d homography = cv::Matx33d::eye();
  cv::Size image_size;  ///< size of the frames this calibration applies to, pixels
  /// The camera's lens; without it pixels are used as they are (no undistortion).
  std::optional<LensModel> lens;
};

/// One known point: where it is in the image and on the field.
struct PointCorrespondence {
  Vec2 image_px;  ///< raw (distorted) image position, pixels
  Vec2 field_m;   ///< field position, metres
  int label = 0;  ///< caller's name for the point (e.g. a marker ID), used in reports
};

/// Result of computing a field calibration.
struct FieldCalibrationResult {
  std::optional<FieldCalibration> calibration;
  /// RMS distance between the mapped image points and their field points over the
  /// inliers, millimetres. 0 (up to rounding) for an exact 4-point fit.
  double residual_rms_mm = 0.0;
  double residual_max_mm = 0.0;  ///< largest such distance over the inliers, millimetres
  /// Labels of the correspondences RANSAC rejected (their residual exceeded the
  /// threshold); empty for 4 points.
  std::vector<int> outlier_labels;
  /// True when the image is a mirror view of the field (the corners go clockwise on
  /// screen). A camera looking down never produces one, so this usually means the
  /// corners were given in the wrong order.
  bool mirrored = false;
  std::string error;  ///< empty on success
  bool ok() const { return error.empty(); }
};

/// Result of load_field_calibration().
struct FieldCalibrationFileResult {
  std::optional<FieldCalibration> calibration;
  std::string error;  ///< names the file and the missing or bad key; empty on success
  bool ok() const { return error.empty(); }
};

/// Computes the mapping from the image positions of the field's four corners, in this
/// order: (0, 0), (W, 0), (W, H), (0, H) - starting at the lower-left corner as seen
/// from above and going counter-clockwise (on a normal overhead image that is also
/// counter-clockwise on screen). The corners must form a convex quadrilateral.
/// `corners_px` are raw image pixels; they are undistorted with `lens` when given.
FieldCalibrationResult field_from_corners(const std::array<Vec2, 4>& corners_px, double width_m, double height_m,
                                          cv::Size image_size, const std::optional<LensModel>& lens = std::nullopt);

/// Default RANSAC threshold: a correspondence whose mapped image point lies further than
/// this from its field point is an outlier. Markers are located to a few millimetres, so
/// 2 cm tolerates noise and still rejects a marker placed at the wrong position.
inline constexpr double kDefaultRansacThresholdM = 0.02;

/// Computes the mapping from at least 4 correspondences (e.g. markers lying at known
/// field positions). Exactly 4 are fitted exactly; more are fitted with RANSAC and the
/// inliers refined, and outliers are reported. Fails when fewer than 4 points are given,
/// the size is not positive, or the points are degenerate (three or more on a line).
FieldCalibrationResult field_from_correspondences(const std::vector<PointCorrespondence>& points, double width_m,
                                                  double height_m, cv::Size image_size,
                                                  const std::optional<LensModel>& lens = std::nullopt,
                                                  double ransac_threshold_m = kDefaultRansacThresholdM);

/// Raw (distorted) image pixel (u_px, v_px) to its field position, metres. Points on the
/// image's horizon line have no field position and give NaN coordinates.
Vec2 pixel_to_field(const FieldCalibration& calibration, double u_px, double v_px);

/// Field position (x_m, y_m) to its raw (distorted) image pixel; the inverse of
/// pixel_to_field within the image.
Vec2 field_to_pixel(const FieldCalibration& calibration, double x_m, double y_m);

/// Converts an image heading at pixel (u_px, v_px) to the field frame. `heading_deg` is
/// counter-clockwise on screen from +u, i.e. atan2(-dv, du); the result is theta
/// counter-clockwise from +x, degrees in [0, 360). Found by mapping two points a few
/// pixels behind and ahead, so perspective and distortion are accounted for locally.
double image_heading_to_field_deg(const FieldCalibration& calibration, double u_px, double v_px, double heading_deg);

/// Checks a calibration's values: positive finite field size, finite invertible
/// homography, positive image size, valid lens when present. Returns what is wrong, or
/// an empty string.
std::string validate_field_calibration(const FieldCalibration& calibration);

/// Writes `calibration` to `path` as OpenCV YAML (keys in the header comment),
/// replacing the file. Returns an error naming the file, or an empty string.
[[nodiscard]] std::string save_field_calibration(const FieldCalibration& calibration, const std::string& path);

/// Reads a field calibration file. A missing file, a file that is not OpenCV YAML, a
/// missing key or a bad value gives an error naming the file and the key; never throws.
FieldCalibrationFileResult load_field_calibration(const std::string& path);

}  // namespace rilbed::vision

#include "vision/field_mapping.hpp"

#include <opencv2/calib3d.hpp>

#include <cmath>
#include <limits>

namespace rilbed::vision {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// cv::undistortPoints stops after 5 iterations by default, which leaves errors of
// several pixels near the corners of a strongly distorted (wide-angle) image; iterate
// until the reprojection is exact instead. The error is measured in pixels.
const cv::TermCriteria kUndistortCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-10);

// Half the distance between the two points mapped to turn a heading: small enough to be
// local, large enough that rounding in the homography does not matter.
constexpr double kHeadingStepPx = 2.0;

// Smallest ratio of the homography's singular values that still counts as invertible.
// A real calibration (pixels to metres) has ratios around 1e-3; a degenerate fit 1e-15.
constexpr double kMinSingularRatio = 1e-12;

std::vector<cv::Point2d> undistort_px(const std::optional<LensModel>& lens, const std::vector<cv::Point2d>& raw_px) {
  if (!lens || raw_px.empty()) return raw_px;
  std::vector<cv::Point2d> out;
  const cv::Mat k(lens->camera_matrix);
  cv::undistortPoints(raw_px, out, k, lens->distortion, cv::noArray(), k, kUndistortCriteria);
  return out;
}

Vec2 apply_homography(const cv::Matx33d& h, cv::Point2d p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1.0);
  if (q[2] == 0.0) return {kNaN, kNaN};
  return {q[0] / q[2], q[1] / q[2]};
}

// Determinant of the Jacobian of the homography at undistorted pixel p. Negative for a
// normal overhead view (v down maps to y up), positive for a mirror view.
double jacobian_det(const cv::Matx33d& h, cv::Point2d p) {
  const double w = h(2, 0) * p.x + h(2, 1) * p.y + h(2, 2);
  return cv::determinant(h) / (w * w * w);
}

std::string validate_size(double width_m, double height_m, cv::Size image_size) {
  if (!(width_m > 0.0) || !(height_m > 0.0) || !std::isfinite(width_m) || !std::isfinite(height_m)) {
    return "field size must be two positive numbers of metres";
  }
  if (image_size.width <= 0 || image_size.height <= 0) return "image size must be positive";
  return {};
}

// z of the cross product of (b - a) and (c - b): the turn at b.
double turn(cv::Point2d a, cv::Point2d b, cv::Point2d c) { return (b - a).cross(c - b); }

// Four points going round a convex quadrilateral turn the same way at every corner.
bool is_convex_in_order(const std::vector<cv::Point2d>& quad) {
  int positive = 0, negative = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    const double t = turn(quad[i], quad[(i + 1) % 4], quad[(i + 2) % 4]);
    // Turns this small mean three corners on a line (pixels squared).
    if (std::abs(t) < 1e-6) return false;
    (t > 0 ? positive : negative)++;
  }
  return positive == 4 || negative == 4;
}

// Any three of four points on a line make a homography undetermined.
bool has_three_collinear(const std::vector<cv::Point2d>& four) {
  double scale = 0.0;
  for (const auto& p : four) scale = std::max({scale, std::abs(p.x - four[0].x), std::abs(p.y - four[0].y)});
  for (std::size_t skip = 0; skip < 4; ++skip) {
    std::vector<cv::Point2d> three;
    for (std::size_t i = 0; i < 4; ++i) {
      if (i != skip) three.push_back(four[i]);
    }
    if (std::abs(turn(three[0], three[1], three[2])) <= 1e-9 * scale * scale) return true;
  }
  return false;
}

// The homography through exactly four point pairs, solved in double precision (OpenCV's
// getPerspectiveTransform takes floats, and findHomography's iterative refinement
// stops at about 1e-8 relative). h33 = 1; empty when the system is singular.
cv::Mat exact_homography(const std::vector<cv::Point2d>& from, const std::vector<cv::Point2d>& to) {
  cv::Matx<double, 8, 8> a;
  cv::Vec<double, 8> b;
  for (int i = 0; i < 4; ++i) {
    const double u = from[i].x, v = from[i].y, x = to[i].x, y = to[i].y;
    const double row_x[8] = {u, v, 1, 0, 0, 0, -u * x, -v * x};
    const double row_y[8] = {0, 0, 0, u, v, 1, -u * y, -v * y};
    for (int j = 0; j < 8; ++j) {
      a(2 * i, j) = row_x[j];
      a(2 * i + 1, j) = row_y[j];
    }
    b[2 * i] = x;
    b[2 * i + 1] = y;
  }
  cv::Vec<double, 8> h;
  if (!cv::solve(a, b, h, cv::DECOMP_LU)) return {};
  return cv::Mat(cv::Matx33d(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], 1.0), true);
}

std::string labels_text(const std::vector<int>& labels) {
  std::string s;
  for (int l : labels) s += (s.empty() ? "" : ", ") + std::to_string(l);
  return s;
}

// Fills the residuals and outliers of a fitted calibration.
void measure_residuals(const cv::Matx33d& h, const std::vector<cv::Point2d>& undistorted_px,
                       const std::vector<PointCorrespondence>& points, const std::vector<uchar>& inlier,
                       FieldCalibrationResult& result) {
  double sum_sq_m2 = 0.0;
  int count = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!inlier[i]) {
      result.outlier_labels.push_back(points[i].label);
      continue;
    }
    const Vec2 mapped_m = apply_homography(h, undistorted_px[i]);
    const double err_m = (mapped_m - points[i].field_m).norm();
    sum_sq_m2 += err_m * err_m;
    result.residual_max_mm = std::max(result.residual_max_mm, err_m * 1000.0);
    ++count;
  }
  result.residual_rms_mm = count > 0 ? std::sqrt(sum_sq_m2 / count) * 1000.0 : 0.0;
}

std::string check_fit_inputs(std::size_t point_count, double width_m, double height_m, cv::Size image_size,
                             const std::optional<LensModel>& lens) {
  if (auto error = validate_size(width_m, height_m, image_size); !error.empty()) return error;
  if (lens) {
    if (auto error = validate_lens(*lens); !error.empty()) return "intrinsics: " + error;
  }
  if (point_count < 4) return "a homography needs at least 4 points, got " + std::to_string(point_count);
  return {};
}

// Exactly 4 points: the exact solution. More: RANSAC, so that one misplaced marker
// cannot bend the whole mapping; OpenCV then refines on the inliers. `inlier` must hold
// one entry per point. Empty result and `error` set on failure.
cv::Mat estimate_homography(const std::vector<cv::Point2d>& undistorted_px, const std::vector<cv::Point2d>& field_m,
                            double ransac_threshold_m, std::vector<uchar>& inlier, std::string& error) {
  if (undistorted_px.size() == 4 && (has_three_collinear(undistorted_px) || has_three_collinear(field_m))) {
    error = "three of the 4 points lie on a line (in the image or on the field)";
    return {};
  }
  cv::Mat h;
  try {
    h = undistorted_px.size() == 4
            ? exact_homography(undistorted_px, field_m)
            : cv::findHomography(undistorted_px, field_m, cv::RANSAC, ransac_threshold_m, inlier, 2000, 0.999);
  } catch (const cv::Exception& e) {
    error = std::string("homography fit failed: ") + e.err;
    return {};
  }
  if (h.empty()) error = "no homography fits the points (are three or more of them on a line?)";
  return h;
}

FieldCalibrationResult fit(const std::vector<PointCorrespondence>& points, double width_m, double height_m,
                           cv::Size image_size, const std::optional<LensModel>& lens, double ransac_threshold_m) {
  FieldCalibrationResult result;
  result.error = check_fit_inputs(points.size(), width_m, height_m, image_size, lens);
  if (!result.error.empty()) return result;
  std::vector<cv::Point2d> raw_px, field_m;
  for (const auto& p : points) {
    raw_px.emplace_back(p.image_px.x, p.image_px.y);
    field_m.emplace_back(p.field_m.x, p.field_m.y);
  }
  const auto undistorted_px = undistort_px(lens, raw_px);
  std::vector<uchar> inlier(points.size(), 1);
  const cv::Mat h = estimate_homography(undistorted_px, field_m, ransac_threshold_m, inlier, result.error);
  if (!result.error.empty()) return result;
  FieldCalibration calibration{width_m, height_m, cv::Matx33d(h), image_size, lens};
  if (auto error = validate_field_calibration(calibration); !error.empty()) {
    result.error = "the fitted homography is unusable: " + error;
    return result;
  }
  measure_residuals(calibration.homography, undistorted_px, points, inlier, result);
  if (points.size() - result.outlier_labels.size() < 4) {
    result.error = "fewer than 4 points agree with each other (outliers: " + labels_text(result.outlier_labels) + ")";
    return result;
  }
  result.mirrored = jacobian_det(calibration.homography, undistorted_px[0]) > 0.0;
  result.calibration = std::move(calibration);
  return result;
}

// Reads a number that must be positive, naming the key when it is not.
std::string read_positive(const cv::FileStorage& fs, const std::string& path, const std::string& key, double& out) {
  if (auto error = cvyaml::read_real(fs, path, key, out); !error.empty()) return error;
  return out > 0.0 ? std::string() : path + ": key '" + key + "' must be positive";
}

std::string read_positive(const cv::FileStorage& fs, const std::string& path, const std::string& key, int& out) {
  if (auto error = cvyaml::read_int(fs, path, key, out); !error.empty()) return error;
  return out > 0 ? std::string() : path + ": key '" + key + "' must be positive";
}

}  // namespace

FieldCalibrationResult field_from_corners(const std::array<Vec2, 4>& corners_px, double width_m, double height_m,
                                          cv::Size image_size, const std::optional<LensModel>& lens) {
  const std::array<Vec2, 4> field_corners_m = {Vec2{0.0, 0.0}, Vec2{width_m, 0.0}, Vec2{width_m, height_m},
                                               Vec2{0.0, height_m}};
  std::vector<PointCorrespondence> points;
  for (int i = 0; i < 4; ++i) points.push_back({corners_px[i], field_corners_m[i], i + 1});
  if (!lens || validate_lens(*lens).empty()) {
    std::vector<cv::Point2d> raw_px;
    for (const auto& c : corners_px) raw_px.emplace_back(c.x, c.y);
    if (!is_convex_in_order(undistort_px(lens, raw_px))) {
      FieldCalibrationResult result;
      result.error =
          "the 4 corners do not form a convex quadrilateral in the order given; expected the "
          "image positions of field corners (0,0), (W,0), (W,H), (0,H), i.e. going round the field";
      return result;
    }
  }
  return fit(points, width_m, height_m, image_size, lens, kDefaultRansacThresholdM);
}

FieldCalibrationResult field_from_correspondences(const std::vector<PointCorrespondence>& points, double width_m,
                                                  double height_m, cv::Size image_size,
                                                  const std::optional<LensModel>& lens, double ransac_threshold_m) {
  return fit(points, width_m, height_m, image_size, lens, ransac_threshold_m);
}

Vec2 pixel_to_field(const FieldCalibration& calibration, double u_px, double v_px) {
  const auto undistorted = undistort_px(calibration.lens, {cv::Point2d(u_px, v_px)});
  return apply_homography(calibration.homography, undistorted[0]);
}

Vec2 field_to_pixel(const FieldCalibration& calibration, double x_m, double y_m) {
  const Vec2 undistorted_px = apply_homography(calibration.homography.inv(), cv::Point2d(x_m, y_m));
  if (!calibration.lens) return undistorted_px;
  // Back to normalised camera coordinates, then through the lens model: a point
  // (xn, yn, 1) seen with the identity pose projects to distort(xn, yn) in pixels.
  const auto& k = calibration.lens->camera_matrix;
  const cv::Vec3d normalised = k.inv() * cv::Vec3d(undistorted_px.x, undistorted_px.y, 1.0);
  const std::vector<cv::Point3d> object{{normalised[0] / normalised[2], normalised[1] / normalised[2], 1.0}};
  std::vector<cv::Point2d> image;
  cv::projectPoints(object, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(k), calibration.lens->distortion, image);
  return {image[0].x, image[0].y};
}

double image_heading_to_field_deg(const FieldCalibration& calibration, double u_px, double v_px, double heading_deg) {
  const double h_rad = deg_to_rad(heading_deg);
  // Screen heading counter-clockwise from +u with v down: the step is (cos, -sin).
  const double du = kHeadingStepPx * std::cos(h_rad);
  const double dv = -kHeadingStepPx * std::sin(h_rad);
  const Vec2 behind_m = pixel_to_field(calibration, u_px - du, v_px - dv);
  const Vec2 ahead_m = pixel_to_field(calibration, u_px + du, v_px + dv);
  const Vec2 d = ahead_m - behind_m;
  return wrap_deg_360(rad_to_deg(std::atan2(d.y, d.x)));
}

std::string validate_field_calibration(const FieldCalibration& calibration) {
  if (auto error = validate_size(calibration.width_m, calibration.height_m, calibration.image_size); !error.empty()) {
    return error;
  }
  const auto& h = calibration.homography;
  for (double v : h.val) {
    if (!std::isfinite(v)) return "homography has a non-finite entry";
  }
  cv::Vec3d singular;
  cv::SVD::compute(h, singular, cv::SVD::NO_UV);
  if (!(singular[2] > kMinSingularRatio * singular[0])) return "homography is singular";
  if (calibration.lens) {
    if (auto error = validate_lens(*calibration.lens); !error.empty()) return error;
  }
  return {};
}

std::string save_field_calibration(const FieldCalibration& calibration, const std::string& path) {
  if (auto error = validate_field_calibration(calibration); !error.empty()) {
    return path + ": not written, the calibration is invalid: " + error;
  }
  cv::FileStorage fs;
  if (auto error = cvyaml::open_for_writing(path, fs); !error.empty()) return error;
  fs << "field_width_m" << calibration.width_m;
  fs << "field_height_m" << calibration.height_m;
  fs << "homography" << cv::Mat(calibration.homography);
  fs << "image_width" << calibration.image_size.width;
  fs << "image_height" << calibration.image_size.height;
  if (calibration.lens) cvyaml::write_lens(fs, *calibration.lens);
  fs.release();
  return {};
}

FieldCalibrationFileResult load_field_calibration(const std::string& path) {
  FieldCalibrationFileResult result;
  cv::FileStorage fs;
  if (result.error = cvyaml::open_for_reading(path, fs); !result.error.empty()) return result;
  FieldCalibration c;
  cv::Mat h;
  std::string& error = result.error;
  error = read_positive(fs, path, "field_width_m", c.width_m);
  if (error.empty()) error = read_positive(fs, path, "field_height_m", c.height_m);
  if (error.empty()) error = cvyaml::read_matrix(fs, path, "homography", 3, 3, h);
  if (error.empty()) error = read_positive(fs, path, "image_width", c.image_size.width);
  if (error.empty()) error = read_positive(fs, path, "image_height", c.image_size.height);
  // The lens keys come as a pair; read_lens names whichever of the two is missing.
  if (error.empty() && (!fs["camera_matrix"].empty() || !fs["distortion_coefficients"].empty())) {
    LensModel lens;
    error = cvyaml::read_lens(fs, path, lens);
    c.lens = std::move(lens);
  }
  if (!error.empty()) return result;
  c.homography = cv::Matx33d(h);
  // Size and lens were checked above, so what is left to fail is the homography.
  if (auto bad = validate_field_calibration(c); !bad.empty()) {
    error = path + ": key 'homography': " + bad;
    return result;
  }
  result.calibration = std::move(c);
  return result;
}

}  // namespace rilbed::vision

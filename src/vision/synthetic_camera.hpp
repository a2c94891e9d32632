// A synthetic overhead camera: renders robots carrying markers on a field as a real
// camera sees them (perspective, tilt, lens distortion, blur, sensor noise, uneven
// lighting, floor clutter, MJPG compression) and reports the ground truth. It feeds
// the recorded datasets, the tests, the benchmarks and the emulated camera.
#pragma once

#include <opencv2/core.hpp>

#include <string>
#include <vector>

#include "vision/field_mapping.hpp"
#include "vision/marker_family.hpp"

namespace rilbed::vision {

/// A pinhole camera with radial/tangential distortion (OpenCV's model) looking at the
/// field plane z = 0. Field frame: x right, y up, metres, origin at a field corner.
struct CameraModel {
  cv::Size image_size{1280, 720};
  cv::Matx33d camera_matrix = cv::Matx33d::eye();
  /// k1, k2, p1, p2, k3.
  cv::Vec<double, 5> distortion{0, 0, 0, 0, 0};
  /// World-to-camera rotation (Rodrigues vector) and translation, as cv::projectPoints takes.
  cv::Vec3d rvec{0, 0, 0};
  cv::Vec3d tvec{0, 0, 0};

  /// A camera above the point `target_m` of the field at `height_m`, tilted by
  /// `tilt_deg` about its own x axis (the image's top edge moves away), image u along
  /// field +x, v along field -y when not tilted; `vfov_deg` is the vertical field of view.
  static CameraModel overhead(cv::Size image_size, double vfov_deg, cv::Point2d target_m, double height_m,
                              double tilt_deg, double k1 = 0.0, double k2 = 0.0);

  /// Projects field points at height z_m into distorted pixel coordinates.
  std::vector<cv::Point2d> project(const std::vector<cv::Point3d>& points_m) const;
  /// Homography from undistorted pixels to the field plane z = z_m (metres).
  cv::Matx33d pixel_to_plane_homography(double z_m = 0.0) const;
  /// The field calibration a lab would measure for this camera over a width_m x height_m
  /// field (its exact floor homography and lens).
  FieldCalibration field_calibration(double width_m, double height_m) const;
};

/// Every pixel of the camera's image undistorted to normalised coordinates (as
/// cv::undistortPoints without R and P gives them), row by row: exact on a grid every 4
/// pixels and interpolated cubically between (within 1e-4 pixels).
std::vector<cv::Point2d> undistorted_pixels(const CameraModel& camera);

/// One marked robot in the scene.
struct SceneMarker {
  /// A marker alone on the floor (what most scenes hold); a body is set after.
  SceneMarker(int id_ = 1, double x = 0.0, double y = 0.0, double theta = 0.0, double diameter = 0.05)
      : id(id_), x_m(x), y_m(y), theta_rad(theta), diameter_m(diameter) {}
  int id = 1;
  double x_m = 0.0, y_m = 0.0;
  double theta_rad = 0.0;  ///< heading, CCW from field +x
  double diameter_m = 0.05;
  /// The robot's body beneath the marker, as the camera sees its top: a convex outline in
  /// the robot frame (x forward, y left, metres, around the marker's centre), or (outline
  /// empty) a disc of body_radius_m; neither (the default): the marker alone on the floor.
  std::vector<cv::Point2d> body_outline_m;
  double body_radius_m = 0.0;
  double body_grey = 150.0;  ///< reflectance of the body's top, 0..255 (a mid-grey plastic)
};

/// Things on the floor that are not markers and must never get an ID (and, drawn after
/// the markers, things that cover part of a marker: see SyntheticCamera::render).
struct Clutter {
  /// Pattern: a printed square of cells (another tag family: AprilTag, ArUco), `pattern`'s
  /// pixels as cells. Cable: a round cable of width size_m along `path_m`, grey `grey`.
  enum class Kind { kDarkDisc, kRing, kTape, kChessboard, kText, kMat, kPattern, kCable };
  Kind kind = Kind::kDarkDisc;
  double x_m = 0.0, y_m = 0.0;  ///< centre (tape: start point; text: lower-left; mat: a corner)
  /// disc/ring outer diameter, tape and cable width, chessboard square, text height, the
  /// pattern's side
  double size_m = 0.05;
  double x2_m = 0.0, y2_m = 0.0;  ///< tape end point; mat: the opposite corner
  double grey = 60.0;             ///< mat and cable reflectance, 0..255
  int cols = 5, rows = 4;         ///< chessboard squares
  double angle_rad = 0.0;         ///< chessboard and pattern rotation
  std::string text;               ///< for Text
  /// For Pattern: CV_8U cells, 0 printed black, 255 printed white (nearest cell, no
  /// interpolation: printed cells have sharp edges), row 0 at the pattern's top (+y).
  cv::Mat pattern;
  /// For Cable: the centre line, field metres (a polyline).
  std::vector<cv::Point2d> path_m;
};

/// Imaging conditions.
struct ImagingConditions {
  double floor_grey = 185.0;         ///< floor level before lighting, 0..255
  double white_grey = 240.0;         ///< printed white
  double black_grey = 28.0;          ///< printed black
  double light_ratio = 1.0;          ///< brightest to darkest lighting across the field (3 for 3:1)
  double light_direction_rad = 0.3;  ///< direction in the field of increasing light
  double blur_sigma_px = 0.0;        ///< Gaussian defocus/motion blur
  double noise_sigma = 0.0;          ///< Gaussian sensor noise, grey levels
  int jpeg_quality = 0;              ///< 1..100 to pass frames through JPEG (MJPG), 0 for none
  int supersample = 4;               ///< subpixels per pixel side for anti-aliasing
  /// Subpixels per pixel side for clutter (0: as `supersample`). Clutter's edges need no
  /// sub-pixel truth; 2 draws it four times faster than 4.
  int clutter_supersample = 0;
  /// A texture on the floor (a photograph of wood, carpet, concrete, paper...): CV_32F
  /// grey levels, added to floor_grey about their own mean; empty for none. It repeats,
  /// mirrored, every floor_texture_tile_m metres along field x (its rows scaled alike), and is
  /// averaged down to about a pixel per texel first, as a lens integrates it.
  cv::Mat floor_texture;
  double floor_texture_tile_m = 0.5;  ///< the texture's width on the floor, metres
  /// The light falls by this fraction at the image's corners (0 for none), with the
  /// square of the distance from the image centre (lens vignetting).
  double vignetting = 0.0;
  /// Motion blur: the length of the smear in pixels (0 for none) and its direction in the
  /// image, radians counter-clockwise from +u. Applied after blur_sigma_px.
  double motion_blur_px = 0.0;
  double motion_blur_angle_rad = 0.0;
};

/// Ground truth of one marker in one frame.
struct MarkerTruth {
  int id = 0;
  double u = 0.0, v = 0.0;   ///< projected centre, distorted pixels
  double heading_deg = 0.0;  ///< on screen, CCW from +u, atan2(-dv, du), [0, 360)
  double x_m = 0.0, y_m = 0.0;
  double theta_deg = 0.0;  ///< field heading, CCW from +x, [0, 360)
  bool visible = false;    ///< whole marker inside the image
};

/// Renders frames of one camera. The static floor (with its clutter and lighting) is
/// rendered once at construction.
class SyntheticCamera {
 public:
  SyntheticCamera(CameraModel camera, MarkerFamily family, ImagingConditions conditions,
                  std::vector<Clutter> clutter = {});

  /// Renders the markers into an 8-bit BGR frame; `rng` drives the noise. `over` is drawn
  /// after the markers (a cable lying across a robot).
  cv::Mat render(const std::vector<SceneMarker>& markers, cv::RNG& rng, const std::vector<Clutter>& over = {}) const;
  /// The floor point (z = 0) that pixel (u, v) sees, field metres (distorted pixels).
  cv::Point2d field_point(cv::Point2d pixel) const { return field_at(pixel.x, pixel.y); }
  /// Ground truth of the markers as this camera sees them.
  std::vector<MarkerTruth> truth(const std::vector<SceneMarker>& markers) const;

  const CameraModel& camera() const { return camera_; }
  const MarkerFamily& family() const { return family_; }

 private:
  cv::Point2d field_at(double u, double v) const;  // bilinear in the per-pixel maps
  void draw_marker(cv::Mat& reflectance, const SceneMarker& m) const;
  void draw_body(cv::Mat& reflectance, const SceneMarker& m) const;
  void draw_clutter(cv::Mat& reflectance, const Clutter& c) const;
  void add_floor_texture();  // conditions_.floor_texture onto floor_

  CameraModel camera_;
  MarkerFamily family_;
  ImagingConditions conditions_;
  cv::Mat field_x_, field_y_;  // CV_64F, field coordinates of every pixel centre
  cv::Mat floor_;              // CV_32F reflectance of the static floor, 0..255
  cv::Mat light_;              // CV_32F lighting gain per pixel
};

/// Renders a single marker top-down, as `size_px` square grey image on `background`
/// grey, heading to +u (for tests and the benchmark's equal-size marker grids).
cv::Mat render_marker_topdown(const MarkerFamily& family, int id, int size_px, double heading_deg,
                              double background_grey = 185.0, int supersample = 4);

}  // namespace rilbed::vision

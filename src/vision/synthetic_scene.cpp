#include "vision/synthetic_scene.hpp"

#include <cmath>
#include <random>
#include <stdexcept>

#include "core/geometry.hpp"

namespace rilbed::vision {

namespace {

// The widest vertical field of view (degrees) at which the whole field, with a margin of
// `margin` of the image on each side, stays inside the image: the camera then frames the
// field as a lab sets it up.
double fitting_vfov(cv::Size image_size, const ScenePreset& p, double height_m, double tilt_deg, double k1, double k2,
                    double margin) {
  const cv::Point2d centre(p.field_width_m / 2, p.field_height_m / 2);
  double lo = 10.0, hi = 120.0;
  for (int it = 0; it < 40; ++it) {
    const double mid = 0.5 * (lo + hi);
    const auto cam = CameraModel::overhead(image_size, mid, centre, height_m, tilt_deg, k1, k2);
    std::vector<cv::Point3d> corners;
    for (int i = 0; i <= 10; ++i) {  // along the edges: distortion bends them
      const double t = i / 10.0;
      corners.emplace_back(t * p.field_width_m, 0, 0);
      corners.emplace_back(t * p.field_width_m, p.field_height_m, 0);
      corners.emplace_back(0, t * p.field_height_m, 0);
      corners.emplace_back(p.field_width_m, t * p.field_height_m, 0);
    }
    bool inside = true;
    for (const auto& px : cam.project(corners)) {
      inside = inside && px.x > margin * image_size.width && px.x < (1 - margin) * image_size.width &&
               px.y > margin * image_size.height && px.y < (1 - margin) * image_size.height;
    }
    (inside ? hi : lo) = mid;
  }
  return hi;
}

Clutter make_clutter(Clutter::Kind kind, double x_m, double y_m, double size_m) {
  Clutter c;
  c.kind = kind;
  c.x_m = x_m;
  c.y_m = y_m;
  c.size_m = size_m;
  return c;
}

Clutter tape(double x0, double y0, double x1, double y1, double width_m) {
  Clutter c = make_clutter(Clutter::Kind::kTape, x0, y0, width_m);
  c.x2_m = x1;
  c.y2_m = y1;
  return c;
}

void add_field_border(ScenePreset& p) {
  const double w = p.field_width_m, h = p.field_height_m;
  for (const Clutter& c :
       {tape(0, 0, w, 0, 0.02), tape(0, h, w, h, 0.02), tape(0, 0, 0, h, 0.02), tape(w, 0, w, h, 0.02)}) {
    p.clutter.push_back(c);
  }
}

}  // namespace

ScenePreset scene_preset(const std::string& name, cv::Size image_size) {
  ScenePreset p;
  p.name = name;
  const cv::Point2d centre(p.field_width_m / 2, p.field_height_m / 2);
  if (name == "nominal") {
    p.camera = CameraModel::overhead(image_size, fitting_vfov(image_size, p, 1.5, 0.0, -0.05, 0.0, 0.03), centre, 1.5,
                                     0.0, -0.05, 0.0);
    p.conditions.floor_grey = 185;
    p.conditions.blur_sigma_px = 0.6;
    p.conditions.noise_sigma = 2.0;
    p.conditions.light_ratio = 1.3;
    p.conditions.jpeg_quality = 85;
    add_field_border(p);
    return p;
  }
  if (name == "hard") {
    p.camera = CameraModel::overhead(image_size, fitting_vfov(image_size, p, 1.5, 20.0, -0.22, 0.05, 0.02), centre, 1.5,
                                     20.0, -0.22, 0.05);
    p.conditions.floor_grey = 150;
    p.conditions.blur_sigma_px = 1.0;
    p.conditions.noise_sigma = 5.0;
    p.conditions.light_ratio = 3.0;
    p.conditions.light_direction_rad = 0.4;
    p.conditions.jpeg_quality = 60;
    using K = Clutter::Kind;
    add_field_border(p);
    Clutter mat = make_clutter(K::kMat, 0.02, 0.02, 0.0);  // a dark mat: markers on a dark floor
    mat.x2_m = 0.55;
    mat.y2_m = 0.50;
    mat.grey = 55.0;
    p.clutter.push_back(mat);
    p.clutter.push_back(tape(0.30, 0.55, 0.70, 0.62, 0.015));           // a stray strip of tape
    p.clutter.push_back(make_clutter(K::kDarkDisc, 0.12, 0.12, 0.05));  // a disc the size of a marker
    p.clutter.push_back(make_clutter(K::kDarkDisc, 1.40, 1.05, 0.04));
    p.clutter.push_back(make_clutter(K::kRing, 1.38, 0.12, 0.05));  // a ring the size of a marker
    p.clutter.push_back(make_clutter(K::kRing, 0.10, 1.08, 0.06));
    Clutter board = make_clutter(K::kChessboard, 0.75, 0.08, 0.012);  // a calibration board left lying
    board.cols = 9;
    board.rows = 4;
    p.clutter.push_back(board);
    Clutter text = make_clutter(K::kText, 0.95, 1.10, 0.04);
    text.text = "RIL 6 lab";
    p.clutter.push_back(text);
    return p;
  }
  throw std::invalid_argument("unknown scene preset '" + name + "' (expected nominal or hard)");
}

std::vector<SceneMarker> robots_at(double t_s, int robot_count, const ScenePreset& preset, unsigned seed) {
  std::vector<SceneMarker> out;
  const int cols = robot_count <= 4 ? robot_count : (robot_count + 1) / 2;
  const int rows = robot_count <= 4 ? 1 : 2;
  const double cell_w = preset.field_width_m / cols, cell_h = preset.field_height_m / rows;
  for (int i = 0; i < robot_count; ++i) {
    std::mt19937 rng(seed * 1000u + static_cast<unsigned>(i));
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    const double cx = (i % cols + 0.5) * cell_w, cy = (i / cols + 0.5) * cell_h;
    // A Lissajous path that stays inside the robot's cell with room for the marker.
    const double ax = (0.5 * cell_w - 0.06) * (0.6 + 0.4 * uni(rng));
    const double ay = (0.5 * cell_h - 0.06) * (0.6 + 0.4 * uni(rng));
    const double w = (0.25 + 0.25 * uni(rng)) * (uni(rng) < 0.5 ? -1 : 1);  // rad/s
    const double phase = 2 * kPi * uni(rng);
    const double ratio = uni(rng) < 0.5 ? 1.0 : 2.0;
    const double a = w * t_s + phase;
    const double x = cx + ax * std::sin(a), y = cy + ay * std::sin(ratio * a + 0.5);
    const double dx = ax * w * std::cos(a), dy = ay * w * ratio * std::cos(ratio * a + 0.5);
    double theta = std::atan2(dy, dx);
    // Every so often a robot spins on the spot for a moment (a heading change with no motion).
    const double spin = std::fmod(t_s + 3.0 * i, 9.0);
    if (spin < 1.0) theta += 2 * kPi * spin;
    out.push_back({i + 1, x, y, theta, preset.marker_diameter_m});
  }
  return out;
}

}  // namespace rilbed::vision

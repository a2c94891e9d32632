#include "vision/synthetic_camera.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>

#include "core/geometry.hpp"

namespace rilbed::vision {

CameraModel CameraModel::overhead(cv::Size image_size, double vfov_deg, cv::Point2d target_m, double height_m,
                                  double tilt_deg, double k1, double k2) {
  CameraModel cam;
  cam.image_size = image_size;
  const double f = 0.5 * image_size.height / std::tan(deg_to_rad(vfov_deg) / 2.0);
  cam.camera_matrix = cv::Matx33d(f, 0, (image_size.width - 1) / 2.0, 0, f, (image_size.height - 1) / 2.0, 0, 0, 1);
  cam.distortion = {k1, k2, 0, 0, 0};
  // Looking straight down: camera x = field x, camera y = field -y, camera z = field -z.
  const cv::Matx33d down(1, 0, 0, 0, -1, 0, 0, 0, -1);
  const double t = deg_to_rad(tilt_deg);
  const cv::Matx33d tilt(1, 0, 0, 0, std::cos(t), -std::sin(t), 0, std::sin(t), std::cos(t));
  const cv::Matx33d r = tilt * down;
  // Place the camera on its optical axis through the target, at the given height.
  const cv::Vec3d axis_world = r.t() * cv::Vec3d(0, 0, 1);
  const double distance = height_m / -axis_world[2];
  const cv::Vec3d centre = cv::Vec3d(target_m.x, target_m.y, 0.0) - distance * axis_world;
  cv::Rodrigues(r, cam.rvec);
  cam.tvec = -(r * centre);
  return cam;
}

std::vector<cv::Point2d> CameraModel::project(const std::vector<cv::Point3d>& points_m) const {
  std::vector<cv::Point2d> out;
  if (points_m.empty()) return out;
  cv::projectPoints(points_m, rvec, tvec, camera_matrix, distortion, out);
  return out;
}

FieldCalibration CameraModel::field_calibration(double width_m, double height_m) const {
  FieldCalibration calibration;
  calibration.width_m = width_m;
  calibration.height_m = height_m;
  calibration.homography = pixel_to_plane_homography(0.0);
  calibration.image_size = image_size;
  LensModel lens;
  lens.camera_matrix = camera_matrix;
  lens.distortion.assign(distortion.val, distortion.val + 5);
  calibration.lens = lens;
  return calibration;
}

cv::Matx33d CameraModel::pixel_to_plane_homography(double z_m) const {
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  // Plane point (x, y, z_m) -> camera: R (x, y, z_m) + t = x r1 + y r2 + (z_m r3 + t).
  const cv::Vec3d r1(r(0, 0), r(1, 0), r(2, 0)), r2(r(0, 1), r(1, 1), r(2, 1)), r3(r(0, 2), r(1, 2), r(2, 2));
  const cv::Vec3d c3 = z_m * r3 + tvec;
  const cv::Matx33d plane_to_cam(r1[0], r2[0], c3[0], r1[1], r2[1], c3[1], r1[2], r2[2], c3[2]);
  cv::Matx33d h = (camera_matrix * plane_to_cam).inv();
  return h * (1.0 / h(2, 2));
}

namespace {

// Reflectance of clutter at a field point, or -1 where it does not cover the floor.
double clutter_at(const Clutter& c, double x, double y, double black, double white) {
  switch (c.kind) {
    case Clutter::Kind::kDarkDisc: return std::hypot(x - c.x_m, y - c.y_m) <= c.size_m / 2 ? black : -1.0;
    case Clutter::Kind::kRing: {
      const double r = std::hypot(x - c.x_m, y - c.y_m);
      return (r <= c.size_m / 2 && r >= 0.3 * c.size_m) ? black : -1.0;
    }
    case Clutter::Kind::kTape: {
      const Vec2 a{c.x_m, c.y_m}, b{c.x2_m, c.y2_m}, p{x, y};
      const Vec2 ab = b - a;
      const double t = std::clamp((p - a).dot(ab) / std::max(1e-12, ab.dot(ab)), 0.0, 1.0);
      return (p - (a + ab * t)).norm() <= c.size_m / 2 ? black + 10.0 : -1.0;
    }
    case Clutter::Kind::kChessboard: {
      const double dx = x - c.x_m, dy = y - c.y_m;
      const double lx = std::cos(c.angle_rad) * dx + std::sin(c.angle_rad) * dy;
      const double ly = -std::sin(c.angle_rad) * dx + std::cos(c.angle_rad) * dy;
      const double gx = lx / c.size_m + c.cols / 2.0, gy = ly / c.size_m + c.rows / 2.0;
      if (gx < -0.5 || gy < -0.5 || gx > c.cols + 0.5 || gy > c.rows + 0.5) return -1.0;
      if (gx < 0 || gy < 0 || gx >= c.cols || gy >= c.rows) return white;  // margin
      return ((static_cast<int>(gx) + static_cast<int>(gy)) % 2) ? white : black;
    }
    case Clutter::Kind::kMat:
      return (x >= std::min(c.x_m, c.x2_m) && x <= std::max(c.x_m, c.x2_m) && y >= std::min(c.y_m, c.y2_m) &&
              y <= std::max(c.y_m, c.y2_m))
                 ? c.grey
                 : -1.0;
    case Clutter::Kind::kPattern: {
      const double dx = x - c.x_m, dy = y - c.y_m;
      const double lx = std::cos(c.angle_rad) * dx + std::sin(c.angle_rad) * dy;
      const double ly = -std::sin(c.angle_rad) * dx + std::cos(c.angle_rad) * dy;
      const double gx = (lx / c.size_m + 0.5) * c.pattern.cols, gy = (0.5 - ly / c.size_m) * c.pattern.rows;
      if (c.pattern.empty() || gx < 0 || gy < 0 || gx >= c.pattern.cols || gy >= c.pattern.rows) return -1.0;
      const double cell = c.pattern.at<std::uint8_t>(static_cast<int>(gy), static_cast<int>(gx)) / 255.0;
      return black + cell * (white - black);
    }
    case Clutter::Kind::kCable: {
      const Vec2 p{x, y};
      for (std::size_t i = 0; i + 1 < c.path_m.size(); ++i) {
        const Vec2 a{c.path_m[i].x, c.path_m[i].y}, b{c.path_m[i + 1].x, c.path_m[i + 1].y};
        const Vec2 ab = b - a;
        const double t = std::clamp((p - a).dot(ab) / std::max(1e-12, ab.dot(ab)), 0.0, 1.0);
        const double d = (p - (a + ab * t)).norm();
        if (d <= c.size_m / 2) {
          // A round cable: lit along its middle, darker towards its sides.
          const double across = d / (c.size_m / 2);
          return c.grey * (1.0 - 0.35 * across * across);
        }
      }
      return -1.0;
    }
    case Clutter::Kind::kText: return -1.0;  // drawn with putText
  }
  return -1.0;
}

double lighting_gain(double ratio, double direction_rad, double x, double y, double lo, double hi) {
  const double along = std::cos(direction_rad) * x + std::sin(direction_rad) * y;
  const double t = std::clamp((along - lo) / std::max(1e-9, hi - lo), 0.0, 1.0);
  return std::exp(std::log(ratio) * (t - 0.5));
}

}  // namespace

namespace {

// Catmull-Rom weights of the four nodes around t in [0, 1) (cubic, exact for quadratics).
std::array<double, 4> catmull_rom(double t) {
  const double t2 = t * t, t3 = t2 * t;
  return {0.5 * (-t3 + 2 * t2 - t), 0.5 * (3 * t3 - 5 * t2 + 2), 0.5 * (-3 * t3 + 4 * t2 + t), 0.5 * (t3 - t2)};
}

}  // namespace

std::vector<cv::Point2d> undistorted_pixels(const CameraModel& camera) {
  // Undistorting every pixel (40 iterations each) was most of a camera's set-up: the
  // lens's inverse is smooth, so it is undistorted exactly on a grid every kStep pixels
  // (one node beyond the image on every side) and interpolated cubically between (within
  // 1e-4 px of the exact values for k1 = -0.3: SyntheticCamera's test checks it).
  constexpr int kStep = 4;
  const cv::Size size = camera.image_size;
  const int nx = (size.width - 1) / kStep + 4, ny = (size.height - 1) / kStep + 4;  // nodes at -kStep, 0, ...
  std::vector<cv::Point2d> nodes;
  nodes.reserve(static_cast<std::size_t>(nx) * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) nodes.emplace_back((i - 1) * kStep, (j - 1) * kStep);
  std::vector<cv::Point2d> exact;
  cv::undistortPoints(nodes, exact, camera.camera_matrix, camera.distortion, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 40, 1e-10));
  // Along u first, every node row: each pixel column between its four nodes.
  std::vector<cv::Point2d> rows(static_cast<std::size_t>(ny) * size.width);
  for (int u = 0; u < size.width; ++u) {
    const int i = u / kStep;  // node i + 1 is at u = i * kStep
    const auto w = catmull_rom(static_cast<double>(u - i * kStep) / kStep);
    for (int j = 0; j < ny; ++j) {
      cv::Point2d p(0, 0);
      for (int k = 0; k < 4; ++k) p += w[static_cast<std::size_t>(k)] * exact[static_cast<std::size_t>(j) * nx + i + k];
      rows[static_cast<std::size_t>(j) * size.width + u] = p;
    }
  }
  std::vector<cv::Point2d> out(static_cast<std::size_t>(size.area()));
  for (int v = 0; v < size.height; ++v) {
    const int j = v / kStep;
    const auto w = catmull_rom(static_cast<double>(v - j * kStep) / kStep);
    for (int u = 0; u < size.width; ++u) {
      cv::Point2d p(0, 0);
      for (int k = 0; k < 4; ++k)
        p += w[static_cast<std::size_t>(k)] * rows[static_cast<std::size_t>(j + k) * size.width + u];
      out[static_cast<std::size_t>(v) * size.width + u] = p;
    }
  }
  return out;
}

SyntheticCamera::SyntheticCamera(CameraModel camera, MarkerFamily family, ImagingConditions conditions,
                                 std::vector<Clutter> clutter)
    : camera_(std::move(camera)), family_(std::move(family)), conditions_(conditions) {
  const cv::Size size = camera_.image_size;
  const std::vector<cv::Point2d> normalised = undistorted_pixels(camera_);
  cv::Matx33d r;
  cv::Rodrigues(camera_.rvec, r);
  const cv::Vec3d centre = -(r.t() * camera_.tvec);
  field_x_.create(size, CV_64F);
  field_y_.create(size, CV_64F);
  for (int v = 0; v < size.height; ++v) {
    for (int u = 0; u < size.width; ++u) {
      const cv::Point2d& n = normalised[static_cast<std::size_t>(v) * size.width + u];
      const cv::Vec3d d = r.t() * cv::Vec3d(n.x, n.y, 1.0);
      const double s = d[2] < -1e-9 ? -centre[2] / d[2] : 1e6;  // rays above the horizon go far
      field_x_.at<double>(v, u) = centre[0] + s * d[0];
      field_y_.at<double>(v, u) = centre[1] + s * d[1];
    }
  }

  // Static floor: a slightly uneven grey (low-frequency, fixed pattern), then clutter.
  cv::Mat blotches(std::max(2, size.height / 64), std::max(2, size.width / 64), CV_32F);
  cv::RNG floor_rng(7);
  floor_rng.fill(blotches, cv::RNG::NORMAL, 0.0, 4.0);
  cv::resize(blotches, floor_, size, 0, 0, cv::INTER_CUBIC);
  floor_ += conditions_.floor_grey;
  if (!conditions_.floor_texture.empty()) add_floor_texture();
  for (const Clutter& c : clutter) draw_clutter(floor_, c);

  // Lighting varies across the field's extent as seen by this camera.
  double lo = 1e300, hi = -1e300;
  for (const auto& corner : {cv::Point(0, 0), cv::Point(size.width - 1, 0), cv::Point(0, size.height - 1),
                             cv::Point(size.width - 1, size.height - 1)}) {
    const double along = std::cos(conditions_.light_direction_rad) * field_x_.at<double>(corner) +
                         std::sin(conditions_.light_direction_rad) * field_y_.at<double>(corner);
    lo = std::min(lo, along);
    hi = std::max(hi, along);
  }
  light_.create(size, CV_32F);
  for (int v = 0; v < size.height; ++v) {
    for (int u = 0; u < size.width; ++u) {
      light_.at<float>(v, u) =
          static_cast<float>(lighting_gain(std::max(1.0, conditions_.light_ratio), conditions_.light_direction_rad,
                                           field_x_.at<double>(v, u), field_y_.at<double>(v, u), lo, hi));
    }
  }
  if (conditions_.vignetting > 0.0) {
    const double cu = (size.width - 1) / 2.0, cv_ = (size.height - 1) / 2.0, corner2 = cu * cu + cv_ * cv_;
    for (int v = 0; v < size.height; ++v) {
      float* row = light_.ptr<float>(v);
      for (int u = 0; u < size.width; ++u) {
        const double r2 = ((u - cu) * (u - cu) + (v - cv_) * (v - cv_)) / corner2;
        row[u] = static_cast<float>(row[u] * (1.0 - conditions_.vignetting * r2));
      }
    }
  }
}

void SyntheticCamera::add_floor_texture() {
  // Average the texture down to about one texel per pixel where the floor is nearest the
  // camera (the most pixels per metre), as the lens would: finer texels would alias.
  const cv::Size size = camera_.image_size;
  double px_per_m = 0.0;
  for (int v = 0; v + 1 < size.height; v += std::max(1, size.height / 16)) {
    for (int u = 0; u + 1 < size.width; u += std::max(1, size.width / 16)) {
      const double du = std::hypot(field_x_.at<double>(v, u + 1) - field_x_.at<double>(v, u),
                                   field_y_.at<double>(v, u + 1) - field_y_.at<double>(v, u));
      if (du > 1e-12) px_per_m = std::max(px_per_m, 1.0 / du);
    }
  }
  const double tile_m = std::max(1e-3, conditions_.floor_texture_tile_m);
  cv::Mat texture = conditions_.floor_texture;
  const double texels_per_px = texture.cols / std::max(1.0, tile_m * px_per_m);
  if (texels_per_px > 1.0) {
    cv::resize(texture, texture,
               cv::Size(std::max(2, static_cast<int>(texture.cols / texels_per_px)),
                        std::max(2, static_cast<int>(texture.rows / texels_per_px))),
               0, 0, cv::INTER_AREA);
  }
  texture = texture - cv::mean(texture)[0];
  const double texel_m = tile_m / texture.cols;
  for (int v = 0; v < size.height; ++v) {
    float* row = floor_.ptr<float>(v);
    for (int u = 0; u < size.width; ++u) {
      // Bilinear, the texture repeating mirrored in both directions (a photograph's edges
      // do not meet: mirrored, its copies join without a seam).
      const double tx = field_x_.at<double>(v, u) / texel_m - 0.5, ty = -field_y_.at<double>(v, u) / texel_m - 0.5;
      const double fx = std::floor(tx), fy = std::floor(ty);
      const double ax = tx - fx, ay = ty - fy;
      const auto mirror = [](double i, int n) {
        const int k = static_cast<int>(i - 2.0 * n * std::floor(i / (2.0 * n)));  // [0, 2n)
        return k < n ? k : 2 * n - 1 - k;
      };
      const int x0 = mirror(fx, texture.cols), x1 = mirror(fx + 1, texture.cols);
      const int y0 = mirror(fy, texture.rows), y1 = mirror(fy + 1, texture.rows);
      const float* r0 = texture.ptr<float>(y0);
      const float* r1 = texture.ptr<float>(y1);
      row[u] +=
          static_cast<float>((r0[x0] * (1 - ax) + r0[x1] * ax) * (1 - ay) + (r1[x0] * (1 - ax) + r1[x1] * ax) * ay);
    }
  }
}

cv::Point2d SyntheticCamera::field_at(double u, double v) const {
  u = std::clamp(u, 0.0, field_x_.cols - 1.0001);
  v = std::clamp(v, 0.0, field_x_.rows - 1.0001);
  const int x = static_cast<int>(u), y = static_cast<int>(v);
  const double fx = u - x, fy = v - y;
  auto lerp = [&](const cv::Mat& m) {
    return (m.at<double>(y, x) * (1 - fx) + m.at<double>(y, x + 1) * fx) * (1 - fy) +
           (m.at<double>(y + 1, x) * (1 - fx) + m.at<double>(y + 1, x + 1) * fx) * fy;
  };
  return {lerp(field_x_), lerp(field_y_)};
}

namespace {

// Pixel rectangle covering the projection of a field-aligned square (centre, half side).
cv::Rect projected_box(const CameraModel& cam, double x, double y, double half, cv::Size size) {
  std::vector<cv::Point3d> corners;
  for (int i = 0; i < 16; ++i) {  // points around the square's outline bound a distorted image well
    const double a = 2 * kPi * i / 16;
    corners.emplace_back(x + 1.42 * half * std::cos(a), y + 1.42 * half * std::sin(a), 0.0);
  }
  const auto px = cam.project(corners);
  double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
  for (const auto& p : px) {
    u0 = std::min(u0, p.x);
    v0 = std::min(v0, p.y);
    u1 = std::max(u1, p.x);
    v1 = std::max(v1, p.y);
  }
  const cv::Rect box(static_cast<int>(std::floor(u0)) - 2, static_cast<int>(std::floor(v0)) - 2,
                     static_cast<int>(std::ceil(u1 - u0)) + 5, static_cast<int>(std::ceil(v1 - v0)) + 5);
  return box & cv::Rect(0, 0, size.width, size.height);
}

}  // namespace

void SyntheticCamera::draw_body(cv::Mat& reflectance, const SceneMarker& m) const {
  double reach = m.body_radius_m;
  for (const cv::Point2d& v : m.body_outline_m) reach = std::max(reach, std::hypot(v.x, v.y));
  if (reach <= 0.0) return;
  const cv::Rect box = projected_box(camera_, m.x_m, m.y_m, reach, reflectance.size());
  const int s = std::max(1, conditions_.supersample);
  const double c = std::cos(m.theta_rad), sn = std::sin(m.theta_rad);
  const std::vector<cv::Point2d>& poly = m.body_outline_m;
  // Inside a convex counter-clockwise outline: left of every edge (either orientation is
  // accepted: the sign of the first edge's turn decides).
  double orientation = 0.0;
  for (std::size_t k = 0; k < poly.size(); ++k) {
    const cv::Point2d a = poly[k], b = poly[(k + 1) % poly.size()];
    orientation += a.x * b.y - b.x * a.y;
  }
  auto inside = [&](double lx, double ly) {
    if (poly.empty()) return std::hypot(lx, ly) <= m.body_radius_m;
    for (std::size_t k = 0; k < poly.size(); ++k) {
      const cv::Point2d a = poly[k], b = poly[(k + 1) % poly.size()];
      const double cross = (b.x - a.x) * (ly - a.y) - (b.y - a.y) * (lx - a.x);
      if (cross * orientation < 0.0) return false;
    }
    return true;
  };
  for (int v = box.y; v < box.y + box.height; ++v) {
    float* row = reflectance.ptr<float>(v);
    for (int u = box.x; u < box.x + box.width; ++u) {
      int covered = 0;
      for (int j = 0; j < s; ++j) {
        for (int i = 0; i < s; ++i) {
          const cv::Point2d f = field_at(u + (i + 0.5) / s - 0.5, v + (j + 0.5) / s - 0.5);
          const double dx = f.x - m.x_m, dy = f.y - m.y_m;
          covered += inside(c * dx + sn * dy, -sn * dx + c * dy) ? 1 : 0;
        }
      }
      if (covered == 0) continue;
      row[u] = static_cast<float>((covered * m.body_grey + (s * s - covered) * row[u]) / (s * s));
    }
  }
}

void SyntheticCamera::draw_marker(cv::Mat& reflectance, const SceneMarker& m) const {
  const double radius = m.diameter_m / 2.0;
  const cv::Rect box = projected_box(camera_, m.x_m, m.y_m, radius, reflectance.size());
  const int s = std::max(1, conditions_.supersample);
  const double c = std::cos(m.theta_rad), sn = std::sin(m.theta_rad);
  for (int v = box.y; v < box.y + box.height; ++v) {
    float* row = reflectance.ptr<float>(v);
    for (int u = box.x; u < box.x + box.width; ++u) {
      double acc = 0.0;
      int covered = 0;
      for (int j = 0; j < s; ++j) {
        for (int i = 0; i < s; ++i) {
          const cv::Point2d f = field_at(u + (i + 0.5) / s - 0.5, v + (j + 0.5) / s - 0.5);
          const double dx = f.x - m.x_m, dy = f.y - m.y_m;
          const double lx = c * dx + sn * dy, ly = -sn * dx + c * dy;
          const double colour = family_.colour_at(m.id, std::hypot(lx, ly) / radius, rad_to_deg(std::atan2(ly, lx)));
          if (colour < 0.0) continue;
          acc += conditions_.black_grey + colour * (conditions_.white_grey - conditions_.black_grey);
          ++covered;
        }
      }
      if (covered == 0) continue;
      row[u] = static_cast<float>((acc + (s * s - covered) * row[u]) / (s * s));
    }
  }
}

void SyntheticCamera::draw_clutter(cv::Mat& reflectance, const Clutter& c) const {
  if (c.kind == Clutter::Kind::kText) {
    const auto px = camera_.project({cv::Point3d(c.x_m, c.y_m, 0), cv::Point3d(c.x_m, c.y_m + c.size_m, 0)});
    const double height_px = std::abs(px[1].y - px[0].y);
    cv::putText(reflectance, c.text, px[0], cv::FONT_HERSHEY_SIMPLEX, std::max(0.2, height_px / 22.0),
                cv::Scalar(conditions_.black_grey), std::max(1, static_cast<int>(height_px / 8)), cv::LINE_AA);
    return;
  }
  double cx = c.x_m, cy = c.y_m, half = c.size_m;
  if (c.kind == Clutter::Kind::kCable) {
    if (c.path_m.empty()) return;
    double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
    for (const auto& p : c.path_m) {
      x0 = std::min(x0, p.x);
      y0 = std::min(y0, p.y);
      x1 = std::max(x1, p.x);
      y1 = std::max(y1, p.y);
    }
    cx = (x0 + x1) / 2;
    cy = (y0 + y1) / 2;
    half = std::max(x1 - x0, y1 - y0) / 2 + c.size_m;
  } else if (c.kind == Clutter::Kind::kPattern) {
    half = c.size_m * 0.75;
  } else if (c.kind == Clutter::Kind::kTape || c.kind == Clutter::Kind::kMat) {
    cx = (c.x_m + c.x2_m) / 2;
    cy = (c.y_m + c.y2_m) / 2;
    half = std::hypot(c.x2_m - c.x_m, c.y2_m - c.y_m) / 2 + c.size_m;
  } else if (c.kind == Clutter::Kind::kChessboard) {
    half = c.size_m * (std::max(c.cols, c.rows) / 2.0 + 1.0);
  }
  const cv::Rect box = projected_box(camera_, cx, cy, half, reflectance.size());
  const int s =
      std::max(1, conditions_.clutter_supersample > 0 ? conditions_.clutter_supersample : conditions_.supersample);
  for (int v = box.y; v < box.y + box.height; ++v) {
    float* row = reflectance.ptr<float>(v);
    for (int u = box.x; u < box.x + box.width; ++u) {
      double acc = 0.0;
      for (int j = 0; j < s; ++j) {
        for (int i = 0; i < s; ++i) {
          const cv::Point2d f = field_at(u + (i + 0.5) / s - 0.5, v + (j + 0.5) / s - 0.5);
          const double g = clutter_at(c, f.x, f.y, conditions_.black_grey, conditions_.white_grey);
          acc += g < 0.0 ? row[u] : g;
        }
      }
      row[u] = static_cast<float>(acc / (s * s));
    }
  }
}

namespace {

// A motion-blur kernel: a smear of `length_px` pixels in direction `angle_rad` (counter-
// clockwise from +u on screen), its weight spread evenly along it, bilinear between pixels.
cv::Mat motion_blur_kernel(double length_px, double angle_rad) {
  const int half = static_cast<int>(std::ceil(length_px / 2)) + 1;
  cv::Mat k = cv::Mat::zeros(2 * half + 1, 2 * half + 1, CV_32F);
  const int steps = std::max(2, static_cast<int>(std::ceil(length_px * 8)));
  for (int i = 0; i <= steps; ++i) {
    const double t = length_px * (static_cast<double>(i) / steps - 0.5);
    const double x = half + t * std::cos(angle_rad), y = half - t * std::sin(angle_rad);
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const double ax = x - x0, ay = y - y0;
    k.at<float>(y0, x0) += static_cast<float>((1 - ax) * (1 - ay));
    k.at<float>(y0, x0 + 1) += static_cast<float>(ax * (1 - ay));
    k.at<float>(y0 + 1, x0) += static_cast<float>((1 - ax) * ay);
    k.at<float>(y0 + 1, x0 + 1) += static_cast<float>(ax * ay);
  }
  return k / cv::sum(k)[0];
}

}  // namespace

cv::Mat SyntheticCamera::render(const std::vector<SceneMarker>& markers, cv::RNG& rng,
                                const std::vector<Clutter>& over) const {
  cv::Mat reflectance = floor_.clone();
  for (const SceneMarker& m : markers) draw_body(reflectance, m);  // bodies first: a marker sits on its robot
  for (const SceneMarker& m : markers) draw_marker(reflectance, m);
  for (const Clutter& c : over) draw_clutter(reflectance, c);
  cv::Mat radiance = reflectance.mul(light_);
  if (conditions_.blur_sigma_px > 0.0) {
    cv::GaussianBlur(radiance, radiance, cv::Size(), conditions_.blur_sigma_px);
  }
  if (conditions_.motion_blur_px > 0.0) {
    cv::filter2D(radiance, radiance, -1,
                 motion_blur_kernel(conditions_.motion_blur_px, conditions_.motion_blur_angle_rad), cv::Point(-1, -1),
                 0.0, cv::BORDER_REFLECT);
  }
  if (conditions_.noise_sigma > 0.0) {
    cv::Mat noise(radiance.size(), CV_32F);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, conditions_.noise_sigma);
    radiance += noise;
  }
  cv::Mat grey, bgr;
  radiance.convertTo(grey, CV_8U);  // saturates at 0 and 255
  cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
  if (conditions_.jpeg_quality > 0) {
    std::vector<std::uint8_t> jpeg;
    cv::imencode(".jpg", bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, std::clamp(conditions_.jpeg_quality, 1, 100)});
    bgr = cv::imdecode(jpeg, cv::IMREAD_COLOR);
  }
  return bgr;
}

std::vector<MarkerTruth> SyntheticCamera::truth(const std::vector<SceneMarker>& markers) const {
  std::vector<MarkerTruth> out;
  constexpr double kAhead_m = 0.001;
  for (const SceneMarker& m : markers) {
    const auto px =
        camera_.project({cv::Point3d(m.x_m, m.y_m, 0), cv::Point3d(m.x_m + kAhead_m * std::cos(m.theta_rad),
                                                                   m.y_m + kAhead_m * std::sin(m.theta_rad), 0)});
    MarkerTruth t;
    t.id = m.id;
    t.u = px[0].x;
    t.v = px[0].y;
    t.heading_deg = wrap_deg_360(rad_to_deg(std::atan2(-(px[1].y - px[0].y), px[1].x - px[0].x)));
    t.x_m = m.x_m;
    t.y_m = m.y_m;
    t.theta_deg = wrap_deg_360(rad_to_deg(m.theta_rad));
    const cv::Rect box = projected_box(camera_, m.x_m, m.y_m, m.diameter_m / 2, cv::Size(1 << 30, 1 << 30));
    t.visible = box.x > 0 && box.y > 0 && box.x + box.width < camera_.image_size.width &&
                box.y + box.height < camera_.image_size.height;
    out.push_back(t);
  }
  return out;
}

cv::Mat render_marker_topdown(const MarkerFamily& family, int id, int size_px, double heading_deg,
                              double background_grey, int supersample) {
  cv::Mat out(size_px, size_px, CV_8UC1);
  const double radius = size_px / 2.0, centre = (size_px - 1) / 2.0;
  const int s = std::max(1, supersample);
  for (int v = 0; v < size_px; ++v) {
    for (int u = 0; u < size_px; ++u) {
      double acc = 0.0;
      for (int j = 0; j < s; ++j) {
        for (int i = 0; i < s; ++i) {
          const double dx = u + (i + 0.5) / s - 0.5 - centre, dy = -(v + (j + 0.5) / s - 0.5 - centre);
          const double colour =
              family.colour_at(id, std::hypot(dx, dy) / radius, rad_to_deg(std::atan2(dy, dx)) - heading_deg);
          acc += colour < 0.0 ? background_grey : 28.0 + colour * (240.0 - 28.0);
        }
      }
      out.at<std::uint8_t>(v, u) = cv::saturate_cast<std::uint8_t>(acc / (s * s));
    }
  }
  return out;
}

}  // namespace rilbed::vision

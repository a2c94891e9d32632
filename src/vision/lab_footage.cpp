#include "vision/lab_footage.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "core/geometry.hpp"
#include "vision/marker_family.hpp"

namespace rilbed::vision {

const char* difficulty_name(LabDifficulty difficulty) {
  switch (difficulty) {
    case LabDifficulty::kPlain: return "plain";
    case LabDifficulty::kHard: return "hard";
    case LabDifficulty::kHarsh: return "harsh";
  }
  return "?";
}

namespace {

using Rgb = cv::Vec3d;  // linear reflectance or radiance, red-green-blue

// ------------------------------------------------------------------ random numbers
// Hash-based, so that every pixel's noise is a pure function of (scene, frame, pixel,
// sample) and a parallel render gives the same frame on any machine and thread count.
constexpr std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
double unit_of(std::uint64_t h) { return static_cast<double>(h >> 11) * 0x1.0p-53; }
std::uint64_t hash3(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  return splitmix(splitmix(splitmix(a) ^ b) ^ c);
}

// A scene's draws. Never two in one call's arguments (or one constructor's): their order is
// unspecified, and GCC evaluates them right to left on x86-64 but left to right on arm64,
// which gives another scene. Such draws are made one per statement, in the order x86 has
// always made them. This file is compiled with -ffp-contract=off (CMakeLists.txt): a * b + c
// fused into one rounding on arm64 (and not on x86-64) would move values by an ulp.
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : state_(seed) {}
  double unit() { return unit_of(state_ = splitmix(state_)); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  int integer(int lo, int hi) { return std::min(hi, lo + static_cast<int>(unit() * (hi - lo + 1))); }
  bool chance(double p) { return unit() < p; }
  double normal() {
    const double a = std::max(1e-300, unit()), b = unit();
    return std::sqrt(-2.0 * std::log(a)) * std::cos(2 * kPi * b);
  }

 private:
  std::uint64_t state_;
};

// Normal and Poisson deviates from one pixel's hash. The normal is the sum of four
// uniforms (its tails end at 3.5 sigma): a frame needs millions, and sensor noise has no
// use for the far tails.
double normal_of(std::uint64_t h) {
  double sum = 0;
  for (int k = 0; k < 4; ++k) sum += static_cast<double>((h >> (16 * k)) & 0xFFFF) * (1.0 / 65536.0);
  return (sum - 2.0 + 2.0 / 65536.0) * 1.7320508075688772;
}
double poisson_of(double mean, std::uint64_t h) {
  if (mean <= 0) return 0;
  if (mean > 40) return std::max(0.0, std::round(mean + std::sqrt(mean) * normal_of(h)));
  const double limit = std::exp(-mean);  // Knuth's product of uniforms
  double p = 1;
  int k = -1;
  do {
    ++k;
    h = splitmix(h);
    p *= unit_of(h);
  } while (p > limit && k < 200);
  return k;
}

// ------------------------------------------------------------------ value noise
// One round of mixing: the floor and the paper ask for millions of these a frame.
double lattice(std::int64_t x, std::int64_t y, std::uint64_t seed) {
  std::uint64_t h = (static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ull) ^
                    (static_cast<std::uint64_t>(y) * 0xC2B2AE3D27D4EB4Full) ^ (seed * 0x165667B19E3779F9ull);
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 32;
  return unit_of(h);
}
// Smooth noise in [0, 1] with features about one unit across.
double value_noise(double x, double y, std::uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const double tx = x - fx, ty = y - fy;
  const double sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  const double a = lattice(ix, iy, seed), b = lattice(ix + 1, iy, seed);
  const double c = lattice(ix, iy + 1, seed), d = lattice(ix + 1, iy + 1, seed);
  return (a + (b - a) * sx) * (1 - sy) + (c + (d - c) * sx) * sy;
}
// Three octaves, in [0, 1], mean 0.5.
double fbm(double x, double y, std::uint64_t seed) {
  return (4 * value_noise(x, y, seed) + 2 * value_noise(2.03 * x, 2.03 * y, seed + 1) +
          value_noise(4.1 * x, 4.1 * y, seed + 2)) /
         7.0;
}

// ------------------------------------------------------------------ the lens
// A pinhole with the angle from the axis distorted (r = f (t + k1 t^3 + k2 t^5)), square
// pixels. Camera frame: x right, y down, z along the view.
struct Lens {
  double f_px = 1000, cx = 640, cy = 480, k1 = 0, k2 = 0;
  cv::Matx33d world_to_camera = cv::Matx33d::eye();
  cv::Vec3d centre_m{0, 0, 2};

  // Distorted angle of an undistorted one, and back (Newton).
  double distort(double t) const { return t * (1 + k1 * t * t + k2 * t * t * t * t); }
  double undistort(double td) const {
    double t = td;
    for (int i = 0; i < 6; ++i) {
      const double g = distort(t) - td, dg = 1 + 3 * k1 * t * t + 5 * k2 * t * t * t * t;
      t -= g / dg;
    }
    return t;
  }
  cv::Point2d project(const cv::Vec3d& p_m) const {
    const cv::Vec3d c = world_to_camera * (p_m - centre_m);
    const double a = c[0] / c[2], b = c[1] / c[2], r = std::hypot(a, b);
    const double s = r > 1e-12 ? distort(std::atan(r)) / r : 1.0;
    return {cx + f_px * a * s, cy + f_px * b * s};
  }
  // Unit direction, world frame, of the ray through pixel (u, v).
  cv::Vec3d ray(double u, double v) const {
    const double mx = (u - cx) / f_px, my = (v - cy) / f_px, td = std::hypot(mx, my);
    const double s = td > 1e-12 ? std::tan(undistort(td)) / td : 1.0;
    const cv::Vec3d d = world_to_camera.t() * cv::Vec3d(mx * s, my * s, 1.0);
    return d / cv::norm(d);
  }
};

// ------------------------------------------------------------------ the scene
struct Robot {
  int id = 1;
  double x_m = 0, y_m = 0, theta_rad = 0;  // at t = 0
  double speed_mps = 0, turn_radps = 0;
  double body_radius_m = 0.0275, marker_radius_m = 0.0225, height_m = 0.04;
  Rgb top{0.08, 0.08, 0.08}, side{0.06, 0.06, 0.06};
  cv::Vec3d at(double t_s) const {  // x, y, heading
    const double mid = theta_rad + 0.5 * turn_radps * t_s;
    return {x_m + speed_mps * t_s * std::cos(mid), y_m + speed_mps * t_s * std::sin(mid), theta_rad + turn_radps * t_s};
  }
};

// A round cable across one (still) robot: over its top, down its side, on the floor beyond.
struct Cable {
  cv::Point2d through_m;  // a point of its centre line over the robot
  cv::Point2d along{1, 0};
  double radius_m = 0.002;
  double top_m = 0.045;  // its centre line's height over the robot
  double over_m = 0.03;  // half the length lying flat on the robot
  double drop_m = 0.04;  // the length over which it falls to the floor
  Rgb colour{0.05, 0.05, 0.05};
  double height_at(double a) const {
    const double d = std::abs(a);
    if (d <= over_m) return top_m;
    if (d >= over_m + drop_m) return radius_m;
    return top_m + (radius_m - top_m) * (d - over_m) / drop_m;
  }
};

// Something on the floor that is not a marker.
struct Decal {
  enum class Kind { kDisc, kWasher, kTape, kText, kScrew };
  Kind kind = Kind::kDisc;
  cv::Point2d centre_m;
  double size_m = 0.03;  // disc and washer diameter, tape width, text height, screw length
  double angle_rad = 0;
  double cos_a = 1, sin_a = 0;  // of angle_rad
  double length_m = 0;          // tape
  Rgb colour{0.1, 0.1, 0.1};
  cv::Mat text_mask;  // kText: CV_8U, 255 where printed, rows along -y
  double text_m_per_px = 0.0005;
};

enum class FloorKind { kLinoleum, kTiles, kWood, kMat, kCarpet };

struct Floor {
  FloorKind kind = FloorKind::kLinoleum;
  Rgb base{0.6, 0.6, 0.58};
  double tile_m = 0.3, grout_m = 0.004, plank_m = 0.12, plank_angle = 0;
  std::uint64_t seed = 1;

  Rgb at(double x, double y) const {
    switch (kind) {
      case FloorKind::kLinoleum: {
        double a =
            1 + 0.16 * (fbm(x / 0.006, y / 0.006, seed) - 0.5) + 0.08 * (fbm(x / 0.05, y / 0.05, seed + 7) - 0.5);
        const double fleck = lattice(static_cast<std::int64_t>(std::floor(x / 0.0025)),
                                     static_cast<std::int64_t>(std::floor(y / 0.0025)), seed + 9);
        if (fleck > 0.97) a *= 0.55;
        if (fleck < 0.02) a *= 1.25;
        return base * a;
      }
      case FloorKind::kTiles: {
        const double tx = x / tile_m, ty = y / tile_m;
        const double gx = (tx - std::floor(tx)) * tile_m, gy = (ty - std::floor(ty)) * tile_m;
        if (gx < grout_m || gy < grout_m) return base * 0.55;
        const double tone = 0.9 + 0.2 * lattice(static_cast<std::int64_t>(std::floor(tx)),
                                                static_cast<std::int64_t>(std::floor(ty)), seed);
        const double vein = std::abs(std::sin(12 * (x + y) + 9 * fbm(x / 0.08, y / 0.08, seed + 3)));
        return base * tone * (0.93 + 0.07 * vein);
      }
      case FloorKind::kWood: {
        const double c = std::cos(plank_angle), s = std::sin(plank_angle);
        const double along = c * x + s * y, across = -s * x + c * y;
        const double plank = std::floor(across / plank_m);
        if (across - plank * plank_m < 0.0015) return base * 0.45;  // the joint
        const double tone = 0.85 + 0.3 * lattice(static_cast<std::int64_t>(plank), 0, seed);
        const double grain =
            0.5 + 0.5 * std::sin(2 * kPi * (across / 0.004 + 4 * fbm(along / 0.3, across / 0.03, seed + 5)));
        return base * tone * (0.82 + 0.18 * grain);
      }
      case FloorKind::kMat: return base * (1 + 0.2 * (fbm(x / 0.003, y / 0.003, seed) - 0.5));
      case FloorKind::kCarpet: {
        const double pile = fbm(x / 0.0015, y / 0.0015, seed);
        const double tuft = value_noise(x / 0.0009, y / 0.0009, seed + 4);
        return base * (0.7 + 0.45 * pile + 0.2 * (tuft - 0.5));
      }
    }
    return base;
  }
};

// Paper, toner and its sheen.
struct Print {
  double white = 0.85, ink = 0.05;
  double dot_gain = 0.01;  // toner spread, a fraction of the marker's radius
  double gloss = 0.05;     // the sheen's peak, as a fraction of the lamp's light on white
  double sheen_width_m = 0.2;
  Rgb paper_tint{0.98, 1.0, 1.04};  // optical brighteners
};

struct Lamp {
  cv::Vec3d position_m{0, 0, 3};
  double ambient = 0.15;     // light from everywhere else, as a fraction of the lamp's at its foot
  double size_m = 0.2;       // its diameter (the shadows' softness)
  Rgb colour{1, 0.92, 0.8};  // a warm lamp
  // Direct irradiance on a horizontal surface at p (1 at the lamp's foot, at the floor).
  double direct(const cv::Vec3d& p) const {
    const cv::Vec3d d = position_m - p;
    const double r2 = d.dot(d);
    return position_m[2] * position_m[2] * d[2] / (r2 * std::sqrt(r2));
  }
};

struct Sensor {
  bool bayer = true;
  bool edge_aware = true;  // demosaicing: OpenCV's edge-aware, else bilinear
  double full_well_e = 10000, read_noise_e = 3, prnu = 0.01;
  double exposure_level = 0.85;  // white paper at the brightest place, as a fraction of full scale
  double digital_gain = 1.0;
  Rgb white_balance{1, 1, 1};
};

struct LabSetup {
  LabDifficulty difficulty = LabDifficulty::kPlain;
  cv::Size size{1280, 960};
  Lens lens;
  Floor floor;
  Print print;
  Lamp lamp;
  Sensor sensor;
  double defocus_centre_px = 0.4, defocus_corner_px = 0.6, diffraction_px = 0.35;
  double vignetting = 0.1;  // the lens's own fall at the corners, on top of cos^4
  double fill_factor = 0.85;
  double exposure_s = 0.004, readout_s = 0.02;
  int jpeg_quality = 90;
  double light_ratio = 1.2;
  std::vector<Robot> robots;
  std::vector<Cable> cables;
  std::vector<Decal> decals;
  std::array<std::vector<std::pair<double, double>>, 9> white_runs;  // per ID, runs of white slices (radians)
};

// ------------------------------------------------------------------ shading
struct Ray {
  cv::Vec3d origin, dir;
  cv::Vec3d at_height(double z) const { return origin + dir * ((z - origin[2]) / dir[2]); }
};

class Shader {
 public:
  Shader(const LabSetup& s, double t_frame_s) : s_(s) {
    // Each robot's reach over the frame (rows are exposed over readout_s): rays further
    // from its start than this skip it.
    for (const Robot& r : s.robots) {
      const cv::Vec3d mid = r.at(t_frame_s + 0.5 * s.readout_s);
      const double travel = r.speed_mps * (s.readout_s + s.exposure_s) + 0.002;
      reach_.push_back({mid[0], mid[1], r.body_radius_m + travel + 0.8 * r.height_m});
      // Its shadow, where it is mid-frame (it moves a millimetre or two in the exposure).
      const cv::Vec3d& lamp = s.lamp.position_m;
      const double k = r.height_m / (lamp[2] - r.height_m);
      Shadow sh;
      sh.x = mid[0] + (mid[0] - lamp[0]) * k * 0.5;
      sh.y = mid[1] + (mid[1] - lamp[1]) * k * 0.5;
      sh.radius = r.body_radius_m * (1 + 0.5 * k);
      sh.penumbra = s.lamp.size_m * k + 0.002;
      shadows_.push_back(sh);
    }
  }

  // What a ray meets, for finding the pixels whose rays meet more than one thing.
  static constexpr int kFloor = 0, kDecal = 1, kTop = 1000, kMarker = 2000, kSide = 3000, kCable = 4000;
  static bool is_marker(int surface) { return surface >= kMarker && surface < kSide; }

  // Radiance along a ray at time t; `surface` gets what it met (k* + its index).
  Rgb shade(const Ray& ray, double t_s, int* surface = nullptr) const {
    int ignored = 0;
    int& met = surface ? *surface : ignored;
    // The nearest cable. A cable lies on the floor beyond its own robot, so it may pass
    // under another robot: there the robot hides it (as the truth's cable_covers has it).
    std::optional<Rgb> cable;
    double cable_m = std::numeric_limits<double>::infinity();
    int cable_index = -1;
    for (std::size_t k = 0; k < s_.cables.size(); ++k) {
      double distance_m = 0;
      if (const auto c = cable_hit(s_.cables[k], ray, &distance_m); c && distance_m < cable_m) {
        cable = c;
        cable_m = distance_m;
        cable_index = static_cast<int>(k);
      }
    }
    const auto cable_in_front = [&](const cv::Vec3d& p) { return cable && cable_m < cv::norm(p - ray.origin); };
    // The robots' tops, then their sides, then the floor.
    const cv::Vec3d floor_p = ray.at_height(0.0);
    double best_lambda = 2;
    int side_robot = -1;
    cv::Vec3d side_p;
    for (std::size_t i = 0; i < s_.robots.size(); ++i) {
      const Robot& r = s_.robots[i];
      const cv::Vec3d top_p = ray.at_height(r.height_m);
      const cv::Vec3d& reach = reach_[i];
      const double rx = top_p[0] - reach[0], ry = top_p[1] - reach[1];
      if (rx * rx + ry * ry > reach[2] * reach[2]) continue;
      const cv::Vec3d pose = r.at(t_s);
      const double dx = top_p[0] - pose[0], dy = top_p[1] - pose[1];
      if (dx * dx + dy * dy < r.body_radius_m * r.body_radius_m) {
        if (cable_in_front(top_p)) break;
        const bool on_marker = dx * dx + dy * dy < r.marker_radius_m * r.marker_radius_m;
        met = (on_marker ? kMarker : kTop) + static_cast<int>(i);
        return top_of(r, pose, top_p);
      }
      // The side: where the ray, going down from the top's plane to the floor, enters
      // the robot's cylinder.
      const double ex = floor_p[0] - top_p[0], ey = floor_p[1] - top_p[1];
      const double a = ex * ex + ey * ey, b = 2 * (dx * ex + dy * ey);
      const double c = dx * dx + dy * dy - r.body_radius_m * r.body_radius_m;
      const double disc = b * b - 4 * a * c;
      if (a < 1e-18 || disc < 0) continue;
      const double lambda = (-b - std::sqrt(disc)) / (2 * a);
      if (lambda >= 0 && lambda <= 1 && lambda < best_lambda) {
        best_lambda = lambda;
        side_robot = static_cast<int>(i);
        side_p = top_p + (floor_p - top_p) * lambda;
      }
    }
    if (cable && (side_robot < 0 || cable_in_front(side_p))) {
      met = kCable + cable_index;
      return *cable;
    }
    if (side_robot >= 0) {
      met = kSide + side_robot;
      return side_of(s_.robots[static_cast<std::size_t>(side_robot)], t_s, side_p);
    }
    return floor_at(floor_p, met);
  }

  // Whether a ray is covered by a cable before it reaches distance `limit` (metres).
  bool cable_covers(const Ray& ray, double limit_m) const {
    for (const Cable& c : s_.cables) {
      double s_m = 0;
      if (cable_point(c, ray, &s_m) && s_m < limit_m) return true;
    }
    return false;
  }

 private:
  // Where the ray meets a cable's surface (its centre line's height, found by fixed
  // point), or nothing. `across` gets the position across it, -1..1.
  static std::optional<double> cable_point(const Cable& c, const Ray& ray, double* distance_m) {
    double z = c.top_m;
    cv::Vec3d p;
    double a = 0;
    for (int k = 0; k < 4; ++k) {
      p = ray.at_height(z);
      a = (p[0] - c.through_m.x) * c.along.x + (p[1] - c.through_m.y) * c.along.y;
      z = c.height_at(a);
    }
    p = ray.at_height(z);
    const double across = (-(p[0] - c.through_m.x) * c.along.y + (p[1] - c.through_m.y) * c.along.x) / c.radius_m;
    if (std::abs(across) >= 1) return std::nullopt;
    if (distance_m) *distance_m = cv::norm(p - ray.origin);
    return across;
  }

  // The cable's radiance where the ray meets it (`distance_m` gets how far), or nothing.
  std::optional<Rgb> cable_hit(const Cable& c, const Ray& ray, double* distance_m) const {
    {
      const auto across = cable_point(c, ray, distance_m);
      if (!across) return std::nullopt;
      // A cylinder lit from above: brighter along its crest, a narrow highlight.
      const double crest = std::sqrt(1 - *across * *across);
      const double highlight = 0.25 * std::exp(-std::pow((*across - 0.3) / 0.15, 2));
      const Rgb lit = s_.lamp.colour * (s_.lamp.ambient + 0.9 * crest);
      return mul(c.colour, lit) + s_.lamp.colour * highlight * 0.6;
    }
  }

  static Rgb mul(const Rgb& a, const Rgb& b) { return {a[0] * b[0], a[1] * b[1], a[2] * b[2]}; }

  Rgb light_at(const cv::Vec3d& p, double shadow = 1.0) const {
    return s_.lamp.colour * (s_.lamp.ambient + shadow * s_.lamp.direct(p));
  }

  // The lamp's mirror image in a horizontal plane at height z, as the camera sees it: the
  // sheen's centre on glossy paper.
  cv::Point2d sheen_centre(double z) const {
    const cv::Vec3d cam = s_.lens.centre_m, lamp = s_.lamp.position_m;
    const double k = (lamp[2] - z) / ((lamp[2] - z) + (cam[2] - z));
    return {lamp[0] + (cam[0] - lamp[0]) * k, lamp[1] + (cam[1] - lamp[1]) * k};
  }

  Rgb top_of(const Robot& r, const cv::Vec3d& pose, const cv::Vec3d& p) const {
    const double dx = p[0] - pose[0], dy = p[1] - pose[1];
    const double c = std::cos(pose[2]), s = std::sin(pose[2]);
    const double fx = c * dx + s * dy, fy = -s * dx + c * dy;  // robot frame: x forward, y left
    const double rho = std::hypot(fx, fy);
    const Rgb light = light_at(p);
    if (rho >= r.marker_radius_m) {
      const double grain = 1 + 0.1 * (value_noise(fx / 0.002, fy / 0.002, 77) - 0.5);
      return mul(r.top, light) * grain;
    }
    const double white = marker_white(r.id, rho / r.marker_radius_m, std::atan2(fy, fx));
    const Print& pr = s_.print;
    const double fibre = 1 + 0.05 * (fbm(fx / 0.0004, fy / 0.0004, 31 + r.id) - 0.5);
    const double toner = 1 + 0.35 * (value_noise(fx / 0.00025, fy / 0.00025, 57 + r.id) - 0.5);
    const double albedo = white > 0.5 ? pr.white * fibre : pr.ink * toner;
    const cv::Point2d sc = sheen_centre(r.height_m);
    const double d2 = (p[0] - sc.x) * (p[0] - sc.x) + (p[1] - sc.y) * (p[1] - sc.y);
    const double sheen =
        pr.gloss * (white > 0.5 ? 1.0 : 1.3) * std::exp(-d2 / (2 * pr.sheen_width_m * pr.sheen_width_m));
    const Rgb tint = white > 0.5 ? pr.paper_tint : Rgb(1, 1, 1);
    return mul(tint, light) * albedo + s_.lamp.colour * (sheen * s_.lamp.direct(p));
  }

  // 1 where marker `id` is white at (rho, angle), rho a fraction of its radius, angle
  // counter-clockwise from forward; toner spreads dot_gain into the white.
  double marker_white(int id, double rho, double angle) const {
    const double g = s_.print.dot_gain;
    if (rho < MarkerFamily::hole_radius + g) return 0;
    if (rho >= MarkerFamily::black_ring_outer_radius + g) return 1;
    if (rho > MarkerFamily::code_outer_radius - g) return 0;
    for (const auto& [start, end] : s_.white_runs[static_cast<std::size_t>(id)]) {
      double a = angle - start;
      a -= 2 * kPi * std::floor(a / (2 * kPi));
      const double width = end - start;
      if (a < width) return (a * rho > g && (width - a) * rho > g) ? 1 : 0;
    }
    return 0;
  }

  Rgb side_of(const Robot& r, double t_s, const cv::Vec3d& p) const {
    const cv::Vec3d pose = r.at(t_s);
    const cv::Vec3d normal(p[0] - pose[0], p[1] - pose[1], 0);
    const cv::Vec3d to_lamp = s_.lamp.position_m - p;
    const double lit = std::max(0.0, normal.dot(to_lamp) / (cv::norm(normal) * cv::norm(to_lamp)));
    return mul(r.side, s_.lamp.colour * (s_.lamp.ambient + 0.8 * lit * s_.lamp.direct(p)));
  }

  double shadow_at(const cv::Vec3d& p) const {
    double light = 1;
    for (const Shadow& sh : shadows_) {
      const double reach = sh.radius + sh.penumbra;
      if (std::abs(p[0] - sh.x) > reach || std::abs(p[1] - sh.y) > reach) continue;
      const double d = std::sqrt((p[0] - sh.x) * (p[0] - sh.x) + (p[1] - sh.y) * (p[1] - sh.y)) - sh.radius;
      if (d > sh.penumbra) continue;
      const double x = std::clamp(0.5 - d / sh.penumbra, 0.0, 1.0);
      light = std::min(light, 1 - x * x * (3 - 2 * x));
    }
    return light;
  }

  Rgb floor_at(const cv::Vec3d& p, int& met) const {
    Rgb albedo = s_.floor.at(p[0], p[1]);
    met = kFloor;
    for (std::size_t k = 0; k < s_.decals.size(); ++k) {
      if (const auto c = decal_at(s_.decals[k], p[0], p[1])) {
        albedo = *c;
        met = kDecal + static_cast<int>(k);
      }
    }
    return mul(albedo, light_at(p, shadow_at(p)));
  }

  static std::optional<Rgb> decal_at(const Decal& d, double x, double y) {
    const double dx = x - d.centre_m.x, dy = y - d.centre_m.y;
    const double reach = d.kind == Decal::Kind::kTape   ? d.length_m / 2 + d.size_m
                         : d.kind == Decal::Kind::kText ? 0.3
                                                        : d.size_m;
    if (std::abs(dx) > reach || std::abs(dy) > reach) return std::nullopt;
    const double lx = d.cos_a * dx + d.sin_a * dy, ly = -d.sin_a * dx + d.cos_a * dy;
    switch (d.kind) {
      case Decal::Kind::kDisc:
        if (std::hypot(lx, ly) < d.size_m / 2) return d.colour;
        return std::nullopt;
      case Decal::Kind::kWasher: {
        const double r = std::hypot(lx, ly);
        if (r < d.size_m / 2 && r > d.size_m * 0.22) return d.colour * (0.8 + 0.4 * (r / d.size_m));
        return std::nullopt;
      }
      case Decal::Kind::kTape:
        if (std::abs(lx) < d.length_m / 2 && std::abs(ly) < d.size_m / 2) return d.colour;
        return std::nullopt;
      case Decal::Kind::kScrew:
        if ((lx * lx) / (d.size_m * d.size_m / 4) + (ly * ly) / (d.size_m * d.size_m / 36) < 1) return d.colour;
        return std::nullopt;
      case Decal::Kind::kText: {
        const int col = static_cast<int>(std::floor(lx / d.text_m_per_px));
        const int row = static_cast<int>(std::floor(-ly / d.text_m_per_px));
        if (col < 0 || row < 0 || col >= d.text_mask.cols || row >= d.text_mask.rows) return std::nullopt;
        if (d.text_mask.at<std::uint8_t>(row, col) > 127) return d.colour;
        return std::nullopt;
      }
    }
    return std::nullopt;
  }

  struct Shadow {
    double x = 0, y = 0, radius = 0, penumbra = 0;
  };
  const LabSetup& s_;
  std::vector<cv::Vec3d> reach_;  // per robot: x, y, radius
  std::vector<Shadow> shadows_;   // per robot
};

// ------------------------------------------------------------------ drawing a scene
Lens draw_lens(const LabSetup& s, Draw& draw, double marker_px, double marker_m, double height_m, double tilt_deg,
               cv::Point2d target) {
  Lens lens;
  lens.cx = s.size.width / 2.0 + draw.uniform(-12, 12);
  lens.cy = s.size.height / 2.0 + draw.uniform(-10, 10);
  const double tilt = deg_to_rad(tilt_deg), yaw = deg_to_rad(draw.uniform(-8, 8));
  const double distance = (height_m - 0.04) / std::cos(tilt);
  lens.f_px = marker_px * distance / marker_m;
  // The view's axis leans towards +y by the tilt, its image axes turned by the yaw.
  const cv::Vec3d axis(0, std::sin(tilt), -std::cos(tilt));
  cv::Vec3d right(std::cos(yaw), std::sin(yaw), 0);
  right -= axis * right.dot(axis);
  right /= cv::norm(right);
  const cv::Vec3d down = axis.cross(right);
  lens.world_to_camera =
      cv::Matx33d(right[0], right[1], right[2], down[0], down[1], down[2], axis[0], axis[1], axis[2]);
  lens.centre_m = cv::Vec3d(target.x, target.y, 0.04) - axis * distance;
  return lens;
}

// Puts the lamp so that the light across the view spans `ratio` from brightest to darkest.
Lamp draw_lamp(const LabSetup& s, Draw& draw, double ratio) {
  Lamp lamp;
  lamp.ambient = draw.uniform(0.05, 0.2);
  lamp.size_m = draw.uniform(0.05, 0.4);
  const double warm = draw.uniform(0, 1);
  lamp.colour = Rgb(1.0, 0.95 - 0.1 * warm, 0.9 - 0.25 * warm);
  std::vector<cv::Vec3d> seen;
  for (double fu : {0.0, 0.5, 1.0})
    for (double fv : {0.0, 0.5, 1.0}) {
      const cv::Vec3d d = s.lens.ray(fu * (s.size.width - 1), fv * (s.size.height - 1));
      seen.push_back(Ray{s.lens.centre_m, d}.at_height(0));
    }
  const cv::Vec3d centre = seen[4];
  const double angle = draw.uniform(0, 2 * kPi), reach = cv::norm(seen[0] - seen[8]);
  const cv::Point2d foot(centre[0] + 0.7 * reach * std::cos(angle), centre[1] + 0.7 * reach * std::sin(angle));
  auto ratio_at = [&](double height) {
    Lamp l = lamp;
    l.position_m = cv::Vec3d(foot.x, foot.y, height);
    double lo = 1e300, hi = 0;
    for (const auto& p : seen) {
      const double e = l.ambient + l.direct(p);
      lo = std::min(lo, e);
      hi = std::max(hi, e);
    }
    return hi / lo;
  };
  double lo = 0.3, hi = 40;  // the ratio falls as the lamp rises
  for (int i = 0; i < 50; ++i) {
    const double mid = std::sqrt(lo * hi);
    (ratio_at(mid) > ratio ? lo : hi) = mid;
  }
  lamp.position_m = cv::Vec3d(foot.x, foot.y, hi);
  return lamp;
}

Floor draw_floor(Draw& draw, LabDifficulty difficulty) {
  Floor f;
  f.seed = static_cast<std::uint64_t>(draw.unit() * 1e15);
  const int kind = draw.integer(0, 4);
  f.kind = static_cast<FloorKind>(kind);
  const bool dark = difficulty != LabDifficulty::kPlain && draw.chance(0.3);
  const double level = dark ? draw.uniform(0.06, 0.16) : draw.uniform(0.35, 0.7);
  // Blue, green, then red: one draw per statement (see Draw).
  const double blue = draw.uniform(0.75, 1.05);
  const double green = draw.uniform(0.9, 1.05);
  const double red = draw.uniform(0.85, 1.1);
  const Rgb hue(red, green, blue);
  f.base = hue * level;
  if (f.kind == FloorKind::kMat) f.base = Rgb(1, 1, 1) * draw.uniform(0.05, 0.14);
  if (f.kind == FloorKind::kWood) f.base = Rgb(0.62, 0.45, 0.3) * draw.uniform(0.8, 1.3);
  f.tile_m = draw.uniform(0.2, 0.33);
  f.grout_m = draw.uniform(0.002, 0.005);
  f.plank_m = draw.uniform(0.08, 0.15);
  f.plank_angle = draw.uniform(0, kPi);
  return f;
}

std::array<std::vector<std::pair<double, double>>, 9> white_runs() {
  const MarkerFamily family = MarkerFamily::six_ucp();
  std::array<std::vector<std::pair<double, double>>, 9> runs;
  for (int id = 1; id <= 8; ++id) {
    const auto slices = family.slices(id);
    std::vector<std::pair<double, double>> mine;
    for (const MarkerSlice& sl : slices) {
      if (!sl.white) continue;
      const double a = deg_to_rad(sl.start_deg), b = deg_to_rad(sl.end_deg);
      if (!mine.empty() && std::abs(mine.back().second - a) < 1e-9) {
        mine.back().second = b;
      } else {
        mine.emplace_back(a, b);
      }
    }
    // The last run may continue into the first (across the key's start).
    if (mine.size() > 1 && std::abs(mine.back().second - 2 * kPi - mine.front().first) < 1e-9) {
      mine.front().first = mine.back().first - 2 * kPi;
      mine.pop_back();
    }
    runs[static_cast<std::size_t>(id)] = mine;
  }
  return runs;
}

// A point of the robots' plane seen at pixel (u, v).
cv::Point2d seen_at(const Lens& lens, double u, double v, double z) {
  const cv::Vec3d p = Ray{lens.centre_m, lens.ray(u, v)}.at_height(z);
  return {p[0], p[1]};
}

void place_robots(LabSetup& s, Draw& draw, double marker_m, int frames, double fps) {
  const double speed_max = s.difficulty == LabDifficulty::kPlain ? 0.15 : 0.35;
  const double height = draw.uniform(0.03, 0.06);
  const double least_body = draw.uniform(0.0275, 0.035);  // before the margin: see Draw
  const double body = std::max(marker_m / 2 + draw.uniform(0.002, 0.008), least_body);
  const std::array<Rgb, 5> tops = {Rgb(0.07, 0.07, 0.07), Rgb(0.08, 0.2, 0.1), Rgb(0.3, 0.3, 0.32),
                                   Rgb(0.55, 0.55, 0.55), Rgb(0.12, 0.14, 0.3)};
  const Rgb top = tops[static_cast<std::size_t>(draw.integer(0, 4))];
  const double margin = 70;
  for (int id = 1; id <= 8; ++id) {
    for (int attempt = 0; attempt < 200; ++attempt) {
      const double v = draw.uniform(margin, s.size.height - 1 - margin);  // v, then u: see Draw
      const double u = draw.uniform(margin, s.size.width - 1 - margin);
      const cv::Point2d p = seen_at(s.lens, u, v, height);
      const bool clear = std::all_of(s.robots.begin(), s.robots.end(), [&](const Robot& o) {
        return std::hypot(o.x_m - p.x, o.y_m - p.y) > 2 * body + 0.03 + speed_max * frames / fps;
      });
      if (!clear) continue;
      Robot r;
      r.id = id;
      r.x_m = p.x;
      r.y_m = p.y;
      r.theta_rad = draw.uniform(0, 2 * kPi);
      if (draw.chance(0.75)) {
        r.speed_mps = draw.uniform(0.02, speed_max);
        r.turn_radps = draw.uniform(-1.5, 1.5);
      } else if (draw.chance(0.4)) {
        r.turn_radps = draw.uniform(-2.5, 2.5);  // turning on the spot
      }
      r.body_radius_m = body;
      r.marker_radius_m = marker_m / 2;
      r.height_m = height;
      r.top = top;
      r.side = top * 0.8;
      s.robots.push_back(r);
      break;
    }
  }
}

void add_cables(LabSetup& s, Draw& draw) {
  if (s.difficulty == LabDifficulty::kPlain || s.robots.empty() || !draw.chance(0.6)) return;
  const int count = draw.integer(1, 2);
  const std::array<Rgb, 4> colours = {Rgb(0.04, 0.04, 0.04), Rgb(0.25, 0.25, 0.25), Rgb(0.75, 0.75, 0.72),
                                      Rgb(0.1, 0.15, 0.5)};
  for (int k = 0; k < count; ++k) {
    Robot& r = s.robots[static_cast<std::size_t>(draw.integer(0, static_cast<int>(s.robots.size()) - 1))];
    r.speed_mps = 0;  // a cable holds it
    r.turn_radps = 0;
    Cable c;
    const double a = draw.uniform(0, kPi);
    c.along = {std::cos(a), std::sin(a)};
    const double offset = draw.uniform(-0.9, 0.9) * r.marker_radius_m;
    c.through_m = {r.x_m - offset * c.along.y, r.y_m + offset * c.along.x};
    c.radius_m = draw.uniform(0.0015, 0.003);
    c.top_m = r.height_m + c.radius_m;
    c.over_m = std::sqrt(std::max(0.0, r.body_radius_m * r.body_radius_m - offset * offset));
    c.drop_m = draw.uniform(0.5, 1.5) * r.height_m;
    c.colour = colours[static_cast<std::size_t>(draw.integer(0, 3))];
    s.cables.push_back(c);
  }
}

void add_decals(LabSetup& s, Draw& draw, double marker_m) {
  const int count = s.difficulty == LabDifficulty::kPlain ? draw.integer(3, 6) : draw.integer(5, 10);
  const char* words[] = {"ROBOT 3", "KHEPERA", "LAB 2", "No 5", "GATE B", "1 2 3 4", "STOP", "ID 7"};
  for (int k = 0; k < count; ++k) {
    Decal d;
    d.kind = static_cast<Decal::Kind>(draw.integer(0, 4));
    const double v = draw.uniform(20, s.size.height - 21);  // v, then u: see Draw
    const double u = draw.uniform(20, s.size.width - 21);
    d.centre_m = seen_at(s.lens, u, v, 0);
    d.angle_rad = draw.uniform(0, 2 * kPi);
    d.cos_a = std::cos(d.angle_rad);
    d.sin_a = std::sin(d.angle_rad);
    const double grey = draw.uniform(0.03, 0.3);
    d.colour = Rgb(grey, grey, grey * draw.uniform(0.8, 1.2));
    switch (d.kind) {
      case Decal::Kind::kDisc:
      case Decal::Kind::kWasher: d.size_m = marker_m * draw.uniform(0.5, 1.1); break;
      case Decal::Kind::kTape:
        d.size_m = draw.uniform(0.012, 0.025);
        d.length_m = draw.uniform(0.1, 0.6);
        break;
      case Decal::Kind::kScrew: d.size_m = draw.uniform(0.006, 0.015); break;
      case Decal::Kind::kText: {
        d.size_m = draw.uniform(0.015, 0.04);
        const std::string word = words[draw.integer(0, 7)];
        int base = 0;
        const double scale = 2.0;
        const cv::Size sz = cv::getTextSize(word, cv::FONT_HERSHEY_SIMPLEX, scale, 5, &base);
        d.text_mask = cv::Mat::zeros(sz.height + base + 8, sz.width + 8, CV_8U);
        cv::putText(d.text_mask, word, {4, sz.height + 4}, cv::FONT_HERSHEY_SIMPLEX, scale, 255, 5, cv::LINE_AA);
        d.text_m_per_px = d.size_m / sz.height;
        break;
      }
    }
    // Nothing lies under a robot (where it would hide, or stick out as another outline).
    const bool clear = std::all_of(s.robots.begin(), s.robots.end(), [&](const Robot& r) {
      return std::hypot(r.x_m - d.centre_m.x, r.y_m - d.centre_m.y) > r.body_radius_m + marker_m;
    });
    if (clear) s.decals.push_back(d);
  }
}

LabSetup draw_setup(std::uint64_t seed, int index, const LabFootageOptions& o) {
  Draw draw(hash3(seed, static_cast<std::uint64_t>(index), 0x1ab));
  LabSetup s;
  s.size = o.image_size;
  s.difficulty = o.fixed_difficulty ? o.difficulty : static_cast<LabDifficulty>(index % 3);
  s.white_runs = white_runs();
  const double marker_m = o.marker_diameter_m > 0                 ? o.marker_diameter_m
                          : s.difficulty == LabDifficulty::kHarsh ? (draw.chance(0.5) ? 0.042 : 0.048)
                                                                  : draw.uniform(0.042, 0.048);
  double px_lo = 30, px_hi = 40, tilt_hi = 4, k1_lo = -0.05;
  switch (s.difficulty) {
    case LabDifficulty::kPlain: break;
    case LabDifficulty::kHard: px_lo = 24, px_hi = 32, tilt_hi = 10, k1_lo = -0.15; break;
    case LabDifficulty::kHarsh: px_lo = 28, px_hi = 40, tilt_hi = 20, k1_lo = -0.35; break;
  }
  if (o.min_marker_px > 0) px_lo = o.min_marker_px;
  if (o.max_marker_px > 0) px_hi = o.max_marker_px;
  const double tilt = s.difficulty == LabDifficulty::kHarsh ? draw.uniform(12, tilt_hi) : draw.uniform(0, tilt_hi);
  const double height_m = draw.uniform(1.6, 2.8);  // the height, then the size: see Draw
  const double marker_px = draw.uniform(px_lo, px_hi);
  s.lens = draw_lens(s, draw, marker_px, marker_m, height_m, tilt, {2.0, 1.5});
  s.lens.k1 = draw.uniform(k1_lo, 0);
  s.lens.k2 = -0.1 * s.lens.k1 * draw.uniform(0, 1);
  s.floor = draw_floor(draw, s.difficulty);
  const bool plain = s.difficulty == LabDifficulty::kPlain, harsh = s.difficulty == LabDifficulty::kHarsh;
  s.light_ratio = plain ? draw.uniform(1.1, 1.5) : harsh ? draw.uniform(3.5, 4.5) : draw.uniform(2.5, 3.5);
  s.lamp = draw_lamp(s, draw, s.light_ratio);
  s.print.white = draw.uniform(0.78, 0.9);
  s.print.ink = draw.uniform(0.03, 0.09);
  s.print.dot_gain = draw.uniform(0, 0.025);
  // Matte to silk paper: a sheen of a tenth of the lamp's light at most. (A glossy
  // laminate mirrors the lamp itself and washes a marker out, its black brighter than the
  // floor: no dark disc is left to find, and a lab places its lamps to avoid it.)
  s.print.gloss = plain ? draw.uniform(0, 0.04) : draw.uniform(0, 0.1);
  s.print.sheen_width_m = draw.uniform(0.1, 0.3);
  s.defocus_centre_px = plain ? draw.uniform(0.2, 0.5) : draw.uniform(0.7, 1.4);
  s.defocus_corner_px = s.defocus_centre_px + (plain ? draw.uniform(0, 0.3) : draw.uniform(0.2, 0.8));
  s.diffraction_px = draw.uniform(0.25, 0.45);
  s.vignetting = plain ? draw.uniform(0, 0.15) : draw.uniform(0.1, 0.35);
  s.fill_factor = draw.uniform(0.7, 0.95);
  s.exposure_s = plain ? draw.uniform(0.001, 0.006) : draw.uniform(0.005, 0.02);
  s.readout_s = draw.uniform(0.01, 0.033);
  s.sensor.bayer = draw.chance(0.7);
  s.sensor.edge_aware = draw.chance(0.5);
  s.sensor.full_well_e = plain ? draw.uniform(8000, 15000) : draw.uniform(4000, 9000);
  s.sensor.read_noise_e = plain ? draw.uniform(2, 4) : draw.uniform(3, 7);
  s.sensor.prnu = draw.uniform(0.005, 0.015);
  s.sensor.exposure_level = plain ? draw.uniform(0.75, 0.92) : draw.uniform(0.45, 0.8);
  s.sensor.digital_gain = std::min(1.5, 0.85 / s.sensor.exposure_level);
  s.sensor.white_balance =
      Rgb(1 / s.lamp.colour[0], 1 / s.lamp.colour[1], 1 / s.lamp.colour[2]) * draw.uniform(0.97, 1.03);
  s.jpeg_quality = plain ? draw.integer(85, 95) : harsh ? draw.integer(50, 60) : draw.integer(60, 70);
  place_robots(s, draw, marker_m, o.frames_per_scene, o.fps);
  add_cables(s, draw);
  add_decals(s, draw, marker_m);
  return s;
}

// ------------------------------------------------------------------ rendering
// A pillbox of `radius` pixels (its edge anti-aliased) convolved with a Gaussian.
cv::Mat defocus_kernel(double radius, double sigma) {
  const int half = static_cast<int>(std::ceil(radius + 3 * sigma)) + 1;
  cv::Mat k(2 * half + 1, 2 * half + 1, CV_32F);
  for (int y = -half; y <= half; ++y)
    for (int x = -half; x <= half; ++x) {
      double inside = 0;
      for (int sy = 0; sy < 4; ++sy)
        for (int sx = 0; sx < 4; ++sx) {
          const double px = x + (sx + 0.5) / 4 - 0.5, py = y + (sy + 0.5) / 4 - 0.5;
          inside += px * px + py * py <= std::max(radius, 0.3) * std::max(radius, 0.3) ? 1 : 0;
        }
      k.at<float>(y + half, x + half) = static_cast<float>(inside);
    }
  k /= cv::sum(k)[0];
  cv::GaussianBlur(k, k, {0, 0}, sigma);
  k /= cv::sum(k)[0];
  return k;
}

class Renderer {
 public:
  Renderer(const LabSetup& s, std::uint64_t seed) : s_(s), seed_(seed) {
    sharp_ = defocus_kernel(s.defocus_centre_px, s.diffraction_px);
    soft_ = defocus_kernel(s.defocus_corner_px, s.diffraction_px);
    // Exposure: white paper under the brightest light seen reaches exposure_level.
    double brightest = 0;
    for (int v = 0; v < s.size.height; v += 32)
      for (int u = 0; u < s.size.width; u += 32) {
        const cv::Vec3d p = Ray{s.lens.centre_m, s.lens.ray(u, v)}.at_height(0.04);
        brightest = std::max(brightest, s.lamp.ambient + s.lamp.direct(p));
      }
    exposure_ = s.sensor.exposure_level / (s.print.white * brightest);
    centre_rays_.resize(static_cast<std::size_t>(s.size.area()));
    cv::parallel_for_(cv::Range(0, s.size.height), [&](const cv::Range& rows) {
      for (int v = rows.start; v < rows.end; ++v)
        for (int u = 0; u < s.size.width; ++u)
          centre_rays_[static_cast<std::size_t>(v) * static_cast<std::size_t>(s.size.width) +
                       static_cast<std::size_t>(u)] = s.lens.ray(u, v);
    });
    // Natural vignetting (cos^4 of the ray's angle) and the lens's own; how far each pixel
    // lies towards the soft corners.
    vignette_.create(s.size, CV_32F);
    corner_weight_.create(s.size, CV_32F);
    const double half_diagonal = std::hypot(s.size.width / 2.0, s.size.height / 2.0);
    for (int v = 0; v < s.size.height; ++v)
      for (int u = 0; u < s.size.width; ++u) {
        const double mx = (u - s.lens.cx) / s.lens.f_px, my = (v - s.lens.cy) / s.lens.f_px;
        const double c = std::cos(s.lens.undistort(std::hypot(mx, my)));
        const double rho = std::hypot(u - s.size.width / 2.0, v - s.size.height / 2.0) / half_diagonal;
        vignette_.at<float>(v, u) = static_cast<float>(c * c * c * c * (1 - s.vignetting * rho * rho));
        corner_weight_.at<float>(v, u) = static_cast<float>(rho * rho);
      }
    // Each photosite's own gain, the same in every frame.
    prnu_.create(s.size, CV_32F);
    for (int v = 0; v < s.size.height; ++v)
      for (int u = 0; u < s.size.width; ++u)
        prnu_.at<float>(v, u) = static_cast<float>(
            1 +
            s.sensor.prnu *
                normal_of(hash3(seed, static_cast<std::uint64_t>(v) * 4096 + static_cast<std::uint64_t>(u), 0x9a1)));
  }

  cv::Mat frame(int index, double t_s) const { return sensor(optics(trace(index, t_s)), index); }

 private:
  // Radiance per pixel: one ray at its centre first; where that image changes within a
  // pixel's neighbours (an edge, a small thing), 16 jittered rays over the photosite at
  // their own moments of the exposure.
  cv::Mat trace(int index, double t_s) const {
    const int w = s_.size.width, h = s_.size.height;
    const Shader shader(s_, t_s);
    cv::Mat first(h, w, CV_32FC3);
    cv::Mat surface(h, w, CV_32S);
    auto row_time = [&](double v) { return t_s + s_.readout_s * v / h; };
    cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& rows) {
      for (int v = rows.start; v < rows.end; ++v)
        for (int u = 0; u < w; ++u) {
          const cv::Vec3d& dir =
              centre_rays_[static_cast<std::size_t>(v) * static_cast<std::size_t>(w) + static_cast<std::size_t>(u)];
          const Rgb c = shader.shade(Ray{s_.lens.centre_m, dir}, row_time(v), &surface.at<int>(v, u));
          first.at<cv::Vec3f>(v, u) =
              cv::Vec3f(static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2]));
        }
    });
    // Pixels whose neighbours' rays met something else (an outline), and every pixel of a
    // marker (its pattern is all edges) or a moving robot (its rays need their moments).
    cv::Mat hi, lo, surface_f;
    surface.convertTo(surface_f, CV_32F);
    cv::dilate(surface_f, hi, cv::Mat());
    cv::erode(surface_f, lo, cv::Mat());
    cv::Mat edges = hi != lo;
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u)
        if (Shader::is_marker(surface.at<int>(v, u))) edges.at<std::uint8_t>(v, u) = 255;
    const cv::Mat moving = moving_mask(t_s);
    cv::Mat out = first.clone();
    cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& rows) {
      for (int v = rows.start; v < rows.end; ++v)
        for (int u = 0; u < w; ++u) {
          if (!edges.at<std::uint8_t>(v, u) && !moving.at<std::uint8_t>(v, u)) continue;
          Rgb sum(0, 0, 0);
          const std::uint64_t base = hash3(seed_, static_cast<std::uint64_t>(index),
                                           static_cast<std::uint64_t>(v) * 4096 + static_cast<std::uint64_t>(u));
          for (int k = 0; k < 16; ++k) {
            const std::uint64_t hk = hash3(base, static_cast<std::uint64_t>(k), 1);
            const double ju = (k % 4 + unit_of(hk)) / 4 - 0.5, jv = (k / 4 + unit_of(splitmix(hk))) / 4 - 0.5;
            const double su = u + ju * s_.fill_factor, sv = v + jv * s_.fill_factor;
            // Times stratified apart from positions (a shuffled stratum).
            const double jt = ((k * 7) % 16 + unit_of(splitmix(hk + 1))) / 16 - 0.5;
            sum += shader.shade(Ray{s_.lens.centre_m, s_.lens.ray(su, sv)}, row_time(sv) + jt * s_.exposure_s);
          }
          sum *= 1.0 / 16;
          out.at<cv::Vec3f>(v, u) =
              cv::Vec3f(static_cast<float>(sum[0]), static_cast<float>(sum[1]), static_cast<float>(sum[2]));
        }
    });
    return out;
  }

  // Pixels a moving robot crosses during the frame: their rays need their own moments.
  cv::Mat moving_mask(double t_s) const {
    cv::Mat mask = cv::Mat::zeros(s_.size, CV_8U);
    for (const Robot& r : s_.robots) {
      if (r.speed_mps == 0 && r.turn_radps == 0) continue;
      std::vector<cv::Point> outline;
      for (double dt : {-s_.exposure_s, s_.readout_s + s_.exposure_s}) {
        const cv::Vec3d pose = r.at(t_s + dt);
        for (int k = 0; k < 16; ++k) {
          const double a = 2 * kPi * k / 16, rr = r.body_radius_m + 0.003;
          for (double z : {0.0, r.height_m}) {
            const cv::Point2d px =
                s_.lens.project(cv::Vec3d(pose[0] + rr * std::cos(a), pose[1] + rr * std::sin(a), z));
            outline.emplace_back(static_cast<int>(px.x), static_cast<int>(px.y));
          }
        }
      }
      std::vector<cv::Point> hull;
      cv::convexHull(outline, hull);
      cv::fillConvexPoly(mask, hull, 255);
    }
    cv::dilate(mask, mask, cv::Mat());
    return mask;
  }

  // Vignetting, then the defocus disc growing from the centre to the corners.
  cv::Mat optics(const cv::Mat& radiance) const {
    const int w = s_.size.width, h = s_.size.height;
    cv::Mat lit = radiance.clone();
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) lit.at<cv::Vec3f>(v, u) *= vignette_.at<float>(v, u);
    cv::Mat sharp, soft;
    cv::filter2D(lit, sharp, -1, sharp_, {-1, -1}, 0, cv::BORDER_REFLECT);
    cv::filter2D(lit, soft, -1, soft_, {-1, -1}, 0, cv::BORDER_REFLECT);
    cv::Mat out(h, w, CV_32FC3);
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) {
        const float k = corner_weight_.at<float>(v, u);
        out.at<cv::Vec3f>(v, u) = sharp.at<cv::Vec3f>(v, u) * (1 - k) + soft.at<cv::Vec3f>(v, u) * k;
      }
    return out;
  }

  // Photo-electrons, their noise, the ADC, the mosaic and its demosaicing, white
  // balance, the tone curve, JPEG.
  cv::Mat sensor(const cv::Mat& irradiance, int index) const {
    const int w = s_.size.width, h = s_.size.height;
    const Sensor& sn = s_.sensor;
    const double full_scale = 1023.0;
    cv::Mat raw(h, w, CV_16UC1);
    cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& rows) {
      for (int v = rows.start; v < rows.end; ++v)
        for (int u = 0; u < w; ++u) {
          const cv::Vec3f e = irradiance.at<cv::Vec3f>(v, u);
          double signal = 0;
          if (sn.bayer) {  // RGGB
            const int channel = (v % 2 == 0) ? (u % 2 == 0 ? 0 : 1) : (u % 2 == 0 ? 1 : 2);
            signal = e[channel];
          } else {
            signal = 0.3 * e[0] + 0.59 * e[1] + 0.11 * e[2];
          }
          const std::uint64_t px = static_cast<std::uint64_t>(v) * 4096 + static_cast<std::uint64_t>(u);
          const double gain = prnu_.at<float>(v, u);
          const double electrons = std::max(0.0, signal * exposure_ * sn.full_well_e * gain);
          const std::uint64_t hn = hash3(seed_, px, 0x100 + static_cast<std::uint64_t>(index));
          double counted = poisson_of(electrons, hn) + sn.read_noise_e * normal_of(splitmix(hn ^ 0x55));
          const double dn =
              std::clamp(std::round(counted / sn.full_well_e * full_scale * sn.digital_gain), 0.0, full_scale);
          raw.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(dn * 64);
        }
    });
    cv::Mat rgb;  // 16-bit R, G, B
    if (sn.bayer) {
      // An RGGB mosaic starting at (0, 0) is OpenCV's "BayerBG" pattern named from its
      // second row; converting to RGB gives channels R, G, B.
      cv::demosaicing(raw, rgb, sn.edge_aware ? cv::COLOR_BayerBG2RGB_EA : cv::COLOR_BayerBG2RGB);
    } else {
      cv::cvtColor(raw, rgb, cv::COLOR_GRAY2RGB);
    }
    std::array<std::uint8_t, 4096> curve{};
    for (int i = 0; i < 4096; ++i) {
      const double x = i / 4095.0;
      const double y = x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1 / 2.4) - 0.055;
      curve[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(std::clamp(std::round(255 * y), 0.0, 255.0));
    }
    const Rgb wb = sn.bayer ? sn.white_balance : Rgb(1, 1, 1);
    cv::Mat bgr(h, w, CV_8UC3);
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) {
        const cv::Vec3w p = rgb.at<cv::Vec3w>(v, u);
        cv::Vec3b& out = bgr.at<cv::Vec3b>(v, u);
        for (int c = 0; c < 3; ++c) {
          const double x = std::min(1.0, p[c] / (64.0 * full_scale) * wb[c]);
          out[2 - c] = curve[static_cast<std::size_t>(x * 4095)];
        }
      }
    std::vector<std::uint8_t> jpeg;
    cv::imencode(".jpg", bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, s_.jpeg_quality});
    return cv::imdecode(jpeg, cv::IMREAD_COLOR);
  }

  const LabSetup& s_;
  std::uint64_t seed_;
  cv::Mat sharp_, soft_;
  cv::Mat vignette_, corner_weight_, prnu_;  // CV_32F per pixel
  std::vector<cv::Vec3d> centre_rays_;       // per pixel, row by row: the ray through its centre
  double exposure_ = 1;
};

// Ground truth of one robot's marker in frame starting at t_s: where its centre projects
// at the moment its row was exposed.
StressTruth truth_of(const LabSetup& s, const Shader& shader, const Robot& r, double t_s) {
  double t = t_s;
  cv::Point2d c;
  for (int k = 0; k < 3; ++k) {
    const cv::Vec3d pose = r.at(t);
    c = s.lens.project(cv::Vec3d(pose[0], pose[1], r.height_m));
    t = t_s + s.readout_s * c.y / s.size.height;
  }
  const cv::Vec3d pose = r.at(t);
  StressTruth truth;
  truth.id = r.id;
  truth.u = c.x;
  truth.v = c.y;
  const cv::Point2d ahead =
      s.lens.project(cv::Vec3d(pose[0] + 1e-4 * std::cos(pose[2]), pose[1] + 1e-4 * std::sin(pose[2]), r.height_m));
  truth.heading_deg = wrap_deg_360(rad_to_deg(std::atan2(-(ahead.y - c.y), ahead.x - c.x)));
  std::vector<cv::Point2f> outline;
  bool inside = true;
  for (int k = 0; k < 48; ++k) {
    const double a = 2 * kPi * k / 48;
    const cv::Point2d p = s.lens.project(
        cv::Vec3d(pose[0] + r.marker_radius_m * std::cos(a), pose[1] + r.marker_radius_m * std::sin(a), r.height_m));
    outline.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
    inside = inside && p.x >= 2 && p.y >= 2 && p.x <= s.size.width - 3 && p.y <= s.size.height - 3;
  }
  truth.diameter_px = 2 * std::sqrt(std::abs(cv::contourArea(outline)) / kPi);
  truth.visible = inside;
  // The share of the marker's disc a cable hides from the camera.
  int covered = 0, points = 0;
  for (int iy = -10; iy <= 10; ++iy)
    for (int ix = -10; ix <= 10; ++ix) {
      const double fx = ix / 10.0, fy = iy / 10.0;
      if (fx * fx + fy * fy > 1) continue;
      ++points;
      const cv::Vec3d q(pose[0] + fx * r.marker_radius_m, pose[1] + fy * r.marker_radius_m, r.height_m);
      const cv::Vec3d d = q - s.lens.centre_m;
      if (shader.cable_covers(Ray{s.lens.centre_m, d / cv::norm(d)}, cv::norm(d))) ++covered;
    }
  truth.occluded = static_cast<double>(covered) / points;
  return truth;
}

StressFloor stress_floor_of(FloorKind kind) {
  switch (kind) {
    case FloorKind::kLinoleum: return StressFloor::kConcrete;
    case FloorKind::kTiles: return StressFloor::kPhoto;
    case FloorKind::kWood: return StressFloor::kWood;
    case FloorKind::kMat: return StressFloor::kPlain;
    case FloorKind::kCarpet: return StressFloor::kCarpet;
  }
  return StressFloor::kPlain;
}

const char* floor_kind_name(FloorKind kind) {
  switch (kind) {
    case FloorKind::kLinoleum: return "linoleum";
    case FloorKind::kTiles: return "tiles";
    case FloorKind::kWood: return "wood";
    case FloorKind::kMat: return "rubber mat";
    case FloorKind::kCarpet: return "carpet";
  }
  return "?";
}

}  // namespace

StressScene make_lab_scene(std::uint64_t seed, int index, const LabFootageOptions& options) {
  const LabSetup s = draw_setup(seed, index, options);
  StressScene scene;
  scene.seed = seed;
  scene.index = index;
  StressConditions& c = scene.conditions;
  c.image_size = s.size;
  c.marker_diameter_px =
      s.robots.empty() ? 0
                       : s.lens.f_px * 2 * s.robots[0].marker_radius_m / (s.lens.centre_m[2] - s.robots[0].height_m);
  c.blur_sigma_px = std::hypot(0.5 * 0.5 * (s.defocus_centre_px + s.defocus_corner_px), s.diffraction_px);
  double fastest = 0;
  for (const Robot& r : s.robots) fastest = std::max(fastest, r.speed_mps);
  c.motion_blur_px =
      fastest * s.exposure_s * c.marker_diameter_px / (2 * (s.robots.empty() ? 1 : s.robots[0].marker_radius_m));
  c.noise_sigma = 0;  // shot noise: no one sigma
  c.jpeg_quality = s.jpeg_quality;
  c.light_ratio = s.light_ratio;
  c.vignetting = s.vignetting;
  c.tilt_deg = rad_to_deg(std::acos(-s.lens.world_to_camera(2, 2)));
  c.k1 = s.lens.k1;
  c.floor = s.floor.kind == FloorKind::kMat ? StressFloor::kPlain : stress_floor_of(s.floor.kind);
  c.floor_source = std::string(difficulty_name(s.difficulty)) + " " + floor_kind_name(s.floor.kind);
  c.floor_grey = 255 * (s.floor.base[0] + s.floor.base[1] + s.floor.base[2]) / 3;
  c.clutter_items = static_cast<int>(s.decals.size() + s.cables.size());
  c.robots = static_cast<int>(s.robots.size());
  // A homography at the markers' height from the view's corners (the lens's distortion
  // is not in it: the calibration is approximate, and the scoring does not use it).
  std::vector<cv::Point2f> image_pts, field_pts;
  const double zm = s.robots.empty() ? 0.04 : s.robots[0].height_m;
  for (double fu : {0.1, 0.9})
    for (double fv : {0.1, 0.9}) {
      const double u = fu * (s.size.width - 1), v = fv * (s.size.height - 1);
      const cv::Point2d p = seen_at(s.lens, u, v, zm);
      image_pts.emplace_back(static_cast<float>(u), static_cast<float>(v));
      field_pts.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
    }
  scene.calibration.width_m = 4.0;
  scene.calibration.height_m = 3.0;
  scene.calibration.image_size = s.size;
  scene.calibration.homography = cv::Matx33d(cv::getPerspectiveTransform(image_pts, field_pts));
  const Renderer renderer(s, hash3(seed, static_cast<std::uint64_t>(index), 0x5e5));
  for (int f = 0; f < options.frames_per_scene; ++f) {
    const double t = f / options.fps;
    scene.frames.push_back(renderer.frame(f, t));
    const Shader shader(s, t);
    std::vector<StressTruth> truth;
    for (const Robot& r : s.robots) truth.push_back(truth_of(s, shader, r, t));
    scene.truth.push_back(std::move(truth));
  }
  return scene;
}

}  // namespace rilbed::vision

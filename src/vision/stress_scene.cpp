#include "vision/stress_scene.hpp"

#include <apriltag/apriltag.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagStandard41h12.h>
#include <opencv2/aruco.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>

#include "core/geometry.hpp"

namespace rilbed::vision {

const char* floor_name(StressFloor floor) {
  switch (floor) {
    case StressFloor::kPlain: return "plain";
    case StressFloor::kPhoto: return "photo";
    case StressFloor::kWood: return "wood";
    case StressFloor::kFabric: return "fabric";
    case StressFloor::kCarpet: return "carpet";
    case StressFloor::kConcrete: return "concrete";
  }
  return "?";
}

namespace {

// opencv-doc's sample photographs that make plausible floors once tiled, greyed and
// toned down: fur, foliage, brick, paper with print, clutter on a desk, paintings.
constexpr std::array kFloorPhotos = {
    "baboon.jpg",       "board.jpg",     "building.jpg", "fruits.jpg",     "home.jpg",
    "starry_night.jpg", "graf1.png",     "stuff.jpg",    "smarties.png",   "sudoku.png",
    "text_defocus.jpg", "notes.png",     "aero1.jpg",    "leuvenA.jpg",    "orange.jpg",
    "butterfly.jpg",    "HappyFish.jpg", "pic1.png",     "imageTextN.png", "lena.jpg",
};

// Draws from one scene's own random stream: scene (seed, index) is the same on every machine
// (std::mt19937_64's sequence is fixed by the standard; the distributions are written here
// rather than taken from <random>, whose results differ between standard libraries). Never
// two draws in one call's arguments (or one constructor's): their order is unspecified, and
// GCC evaluates them right to left on x86-64 but left to right on arm64, which gives another
// scene. Such draws are made one per statement, in the order x86 has always made them.
// This file is compiled with -ffp-contract=off (CMakeLists.txt): a * b + c fused into one
// rounding on arm64 (and not on x86-64) would move the draws by an ulp.
class SceneRandom {
 public:
  SceneRandom(std::uint64_t seed, int index)
      : engine_(mix(seed * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(index))) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  int integer(int lo, int hi) { return lo + static_cast<int>(unit() * (hi - lo + 1)) % (hi - lo + 1); }  // [lo, hi]
  bool chance(double p) { return unit() < p; }
  double normal() {  // Box-Muller
    const double a = std::max(1e-300, unit()), b = unit();
    return std::sqrt(-2.0 * std::log(a)) * std::cos(2 * kPi * b);
  }
  std::uint64_t bits() { return engine_(); }

 private:
  static std::uint64_t mix(std::uint64_t z) {  // splitmix64's finaliser: nearby seeds, unrelated streams
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double unit() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  std::mt19937_64 engine_;
};

// Smooth noise: white noise of `cells` x `cells` blown up (cubic) to `size` x `size`, unit
// standard deviation.
cv::Mat smooth_noise(SceneRandom& rnd, int size, int cells_x, int cells_y) {
  cv::Mat coarse(std::max(2, cells_y), std::max(2, cells_x), CV_32F);
  for (int y = 0; y < coarse.rows; ++y)
    for (int x = 0; x < coarse.cols; ++x) coarse.at<float>(y, x) = static_cast<float>(rnd.normal());
  cv::Mat out;
  cv::resize(coarse, out, cv::Size(size, size), 0, 0, cv::INTER_CUBIC);
  return out;
}

cv::Mat unit_contrast(const cv::Mat& texture) {
  cv::Scalar mean, stddev;
  cv::meanStdDev(texture, mean, stddev);
  return (texture - mean[0]) / std::max(1e-6, stddev[0]);
}

// Drawn floors, 512 x 512 texels, zero mean and unit standard deviation.
cv::Mat drawn_floor(StressFloor kind, SceneRandom& rnd) {
  constexpr int n = 512;
  cv::Mat t(n, n, CV_32F);
  switch (kind) {
    case StressFloor::kWood: {  // long grain along x, bent by slow noise, with fine fibres
      const cv::Mat bend = smooth_noise(rnd, n, 3, 8), fibre = smooth_noise(rnd, n, 256, 6);
      const double lines = rnd.uniform(10, 40);
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
          t.at<float>(y, x) = static_cast<float>(std::sin(2 * kPi * (lines * y / n + 1.5 * bend.at<float>(y, x))) +
                                                 0.35 * fibre.at<float>(y, x));
      break;
    }
    case StressFloor::kFabric: {  // a weave: threads over and under, with slubs
      const double period = rnd.uniform(4, 12);
      const cv::Mat slub = smooth_noise(rnd, n, 64, 64);
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const double a = std::sin(2 * kPi * x / period), b = std::sin(2 * kPi * y / period);
          const bool over = (static_cast<int>(x / period) + static_cast<int>(y / period)) % 2;
          t.at<float>(y, x) = static_cast<float>((over ? a * a : b * b) + 0.3 * slub.at<float>(y, x));
        }
      break;
    }
    case StressFloor::kCarpet: {  // fine pile and slow patches
      cv::Mat pile(n, n, CV_32F);
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) pile.at<float>(y, x) = static_cast<float>(rnd.normal());
      cv::GaussianBlur(pile, pile, cv::Size(), rnd.uniform(0.6, 1.8));
      t = unit_contrast(pile) + 0.6 * smooth_noise(rnd, n, 6, 6);
      break;
    }
    case StressFloor::kConcrete: {  // octaves of blotches, and dark pores
      t = cv::Mat::zeros(n, n, CV_32F);
      for (int cells = 4, k = 0; k < 5; ++k, cells *= 2) t += smooth_noise(rnd, n, cells, cells) * (1.0 / (1 + k));
      const int pores = rnd.integer(50, 400);
      for (int i = 0; i < pores; ++i) {
        // Radius, then y, then x: one draw per statement (see SceneRandom).
        const int radius = rnd.integer(1, 4);
        const int y = rnd.integer(0, n - 1);
        const int x = rnd.integer(0, n - 1);
        cv::circle(t, cv::Point(x, y), radius, cv::Scalar(-3.0), -1, cv::LINE_AA);
      }
      break;
    }
    case StressFloor::kPlain:
    case StressFloor::kPhoto: t = cv::Mat::zeros(n, n, CV_32F); break;
  }
  return unit_contrast(t);
}

cv::Mat photo_floor(const std::string& path) {
  const cv::Mat grey = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (grey.empty()) return {};
  cv::Mat t;
  grey.convertTo(t, CV_32F);
  return unit_contrast(t);
}

// Another tag family's pattern as cells (0 black, 255 white) with a one-cell white quiet
// zone: AprilTag (tag36h11, tag25h9, tagStandard41h12) or ArUco (4x4, 5x5, 6x6).
cv::Mat other_tag(SceneRandom& rnd) {
  cv::Mat cells;
  if (rnd.chance(0.5)) {
    const int which = rnd.integer(0, 2);
    apriltag_family_t* family = which == 0   ? tag36h11_create()
                                : which == 1 ? tag25h9_create()
                                             : tagStandard41h12_create();
    image_u8_t* image = apriltag_to_image(family, rnd.integer(0, static_cast<int>(family->ncodes) - 1));
    cells = cv::Mat(image->height, image->width, CV_8U);
    for (int y = 0; y < image->height; ++y)
      for (int x = 0; x < image->width; ++x) cells.at<std::uint8_t>(y, x) = image->buf[y * image->stride + x];
    // image_u8_destroy is not exported by Debian's libapriltag; it frees these two.
    std::free(image->buf);
    std::free(image);
    if (which == 0)
      tag36h11_destroy(family);
    else if (which == 1)
      tag25h9_destroy(family);
    else
      tagStandard41h12_destroy(family);
  } else {
    const int bits = rnd.integer(4, 6);
    const auto dictionary = cv::aruco::getPredefinedDictionary(bits == 4   ? cv::aruco::DICT_4X4_50
                                                               : bits == 5 ? cv::aruco::DICT_5X5_100
                                                                           : cv::aruco::DICT_6X6_250);
    cv::Mat marker;
    cv::aruco::drawMarker(dictionary, rnd.integer(0, dictionary->bytesList.rows - 1), bits + 2, marker, 1);
    cv::copyMakeBorder(marker, cells, 1, 1, 1, 1, cv::BORDER_CONSTANT, cv::Scalar(255));
  }
  return cells;
}

struct Pose {
  double x = 0, y = 0, theta = 0;
};

// A robot of the scene: its pose in every frame of the clip and its occluding cable (in its
// own frame), if any.
struct Robot {
  int id = 0;
  std::vector<Pose> poses;
  bool touching = false;
  double occluded = 0;
  std::vector<cv::Point2d> cable_local;  // centre line in the robot's frame, metres
  double cable_width_m = 0, cable_grey = 0;
};

double point_polyline_distance(cv::Point2d p, const std::vector<cv::Point2d>& path) {
  double best = 1e300;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Vec2 a{path[i].x, path[i].y}, b{path[i + 1].x, path[i + 1].y}, q{p.x, p.y};
    const Vec2 ab = b - a;
    const double t = std::clamp((q - a).dot(ab) / std::max(1e-18, ab.dot(ab)), 0.0, 1.0);
    best = std::min(best, (q - (a + ab * t)).norm());
  }
  return best;
}

// The fraction of a disc of radius r (at the origin) a cable covers, on a 96 x 96 grid.
double covered_fraction(const std::vector<cv::Point2d>& cable, double width_m, double r) {
  int inside = 0, covered = 0;
  constexpr int n = 96;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const cv::Point2d p(r * (2.0 * (i + 0.5) / n - 1.0), r * (2.0 * (j + 0.5) / n - 1.0));
      if (p.x * p.x + p.y * p.y > r * r) continue;
      ++inside;
      if (point_polyline_distance(p, cable) <= width_m / 2) ++covered;
    }
  }
  return inside ? static_cast<double>(covered) / inside : 0.0;
}

// A cable across a robot's marker (radius r) covering `fraction` of it: straight across the
// disc, bent beyond it, at the offset from the centre that covers that much (bisection).
void lay_cable(Robot& robot, SceneRandom& rnd, double r, double fraction) {
  robot.cable_width_m = 2 * r * rnd.uniform(0.08, 0.2);
  robot.cable_grey = rnd.uniform(10, 230);
  const double phi = rnd.uniform(0, 2 * kPi);
  const cv::Point2d along(std::cos(phi), std::sin(phi)), across(-std::sin(phi), std::cos(phi));
  const double reach = r * rnd.uniform(2.5, 5.0), bend = r * rnd.uniform(-1.0, 1.0);
  auto cable_at = [&](double offset) {
    const cv::Point2d c = across * offset;
    return std::vector<cv::Point2d>{c - along * reach + across * bend, c - along * (1.2 * r), c + along * (1.2 * r),
                                    c + along * reach - across * bend};
  };
  double lo = 0, hi = r + robot.cable_width_m;  // covered fraction falls from lo to hi
  for (int i = 0; i < 30; ++i) {
    const double mid = (lo + hi) / 2;
    if (covered_fraction(cable_at(mid), robot.cable_width_m, r) > fraction)
      lo = mid;
    else
      hi = mid;
  }
  robot.cable_local = cable_at(hi);
  robot.occluded = covered_fraction(robot.cable_local, robot.cable_width_m, r);
}

Clutter cable_in_field(const Robot& robot, const Pose& pose) {
  Clutter c;
  c.kind = Clutter::Kind::kCable;
  c.size_m = robot.cable_width_m;
  c.grey = robot.cable_grey;
  const double cs = std::cos(pose.theta), sn = std::sin(pose.theta);
  for (const auto& p : robot.cable_local)
    c.path_m.emplace_back(pose.x + cs * p.x - sn * p.y, pose.y + sn * p.x + cs * p.y);
  return c;
}

StressConditions draw_conditions(SceneRandom& rnd, const StressOptions& options,
                                 const std::vector<std::string>& photos) {
  StressConditions c;
  c.image_size = options.image_size;
  c.marker_diameter_px = rnd.uniform(20, 64);
  c.blur_sigma_px = rnd.uniform(0, 2);
  c.motion_blur_px = rnd.uniform(0, 4);
  c.motion_blur_angle_deg = rnd.uniform(0, 360);
  c.noise_sigma = rnd.uniform(0, 10);
  c.jpeg_quality = rnd.integer(50, 95);
  c.light_ratio = rnd.uniform(1, 4);
  c.vignetting = rnd.uniform(0, 0.5);
  c.tilt_deg = rnd.uniform(0, 20);
  c.k1 = rnd.uniform(-0.3, 0);
  const double f = rnd.uniform(0, 1);
  if (f < 0.2) {
    c.floor = StressFloor::kPlain;
    c.floor_source = "light";
    c.floor_grey = rnd.uniform(150, 215);
  } else if (f < 0.3) {
    c.floor = StressFloor::kPlain;
    c.floor_source = "dark";
    c.floor_grey = rnd.uniform(40, 100);
  } else if (f < 0.6 && !photos.empty()) {
    c.floor = StressFloor::kPhoto;
    c.floor_source = photos[static_cast<std::size_t>(rnd.integer(0, static_cast<int>(photos.size()) - 1))];
    c.floor_grey = rnd.uniform(70, 200);
  } else {
    c.floor = static_cast<StressFloor>(rnd.integer(2, 5));
    c.floor_source = floor_name(c.floor);
    c.floor_grey = rnd.uniform(70, 200);
  }
  c.clutter_items = rnd.integer(4, 14);
  c.robots = rnd.integer(4, 8);
  return c;
}

// Clutter of one scene: kind, size (in marker diameters d_m) and place drawn at random.
Clutter draw_clutter_item(SceneRandom& rnd, double d_m, cv::Point2d at) {
  static const std::array<const char*, 8> kWords = {"rilbed",  "KHEPERA", "lab 3", "0123",
                                                    "CAUTION", "x=1.5",   "ID 4",  "robot"};
  Clutter c;
  c.x_m = at.x;
  c.y_m = at.y;
  c.angle_rad = rnd.uniform(0, 2 * kPi);
  switch (rnd.integer(0, 8)) {
    case 0:
      c.kind = Clutter::Kind::kDarkDisc;
      c.size_m = d_m * rnd.uniform(0.5, 1.3);
      break;
    case 1:
      c.kind = Clutter::Kind::kRing;
      c.size_m = d_m * rnd.uniform(0.7, 1.3);
      break;
    case 2: {
      c.kind = Clutter::Kind::kTape;
      c.size_m = d_m * rnd.uniform(0.1, 0.5);
      const double length = d_m * rnd.uniform(2, 8);
      c.x2_m = at.x + length * std::cos(c.angle_rad);
      c.y2_m = at.y + length * std::sin(c.angle_rad);
      break;
    }
    case 3:
      c.kind = Clutter::Kind::kChessboard;
      c.size_m = d_m * rnd.uniform(0.15, 0.4);
      c.cols = rnd.integer(3, 7);
      c.rows = rnd.integer(3, 7);
      break;
    case 4:
      c.kind = Clutter::Kind::kText;
      c.size_m = d_m * rnd.uniform(0.3, 0.8);
      c.text = kWords[static_cast<std::size_t>(rnd.integer(0, static_cast<int>(kWords.size()) - 1))];
      break;
    case 5:
    case 6:
      c.kind = Clutter::Kind::kPattern;
      c.size_m = d_m * rnd.uniform(0.8, 2.0);
      c.pattern = other_tag(rnd);
      break;
    default: {  // a cable wandering over the floor
      c.kind = Clutter::Kind::kCable;
      c.size_m = d_m * rnd.uniform(0.05, 0.2);
      c.grey = rnd.uniform(10, 230);
      double heading = c.angle_rad;
      cv::Point2d p = at;
      const int points = rnd.integer(4, 8);
      for (int i = 0; i < points; ++i) {
        c.path_m.push_back(p);
        heading += rnd.uniform(-0.6, 0.6);
        p += cv::Point2d(std::cos(heading), std::sin(heading)) * (d_m * rnd.uniform(0.6, 1.4));
      }
      break;
    }
  }
  return c;
}

// How far clutter reaches from its anchor point (for keeping it off the robots' paths).
double clutter_reach(const Clutter& c) {
  switch (c.kind) {
    case Clutter::Kind::kTape: return std::hypot(c.x2_m - c.x_m, c.y2_m - c.y_m) + c.size_m;
    case Clutter::Kind::kChessboard: return c.size_m * (std::max(c.cols, c.rows) / 2.0 + 1.0) * 1.42;
    case Clutter::Kind::kText: return c.size_m * c.text.size() * 0.9 + c.size_m;
    case Clutter::Kind::kPattern: return c.size_m * 0.75;
    case Clutter::Kind::kCable: {
      double reach = 0;
      for (const auto& p : c.path_m) reach = std::max(reach, std::hypot(p.x - c.x_m, p.y - c.y_m));
      return reach + c.size_m;
    }
    default: return c.size_m / 2;
  }
}

// The widest vertical field of view (degrees, at most `cap`) a lens of radial distortion
// k1 < 0 can have on this image and still be one to one: barrel distortion r (1 + k1 r^2)
// peaks at r = 1 / sqrt(-3 k1), and beyond it no real point maps to the image (a lab's
// calibration of such a lens carries k2, k3 terms that keep it monotonic). The image's
// corner is kept within 90 % of that peak.
double widest_vfov_deg(cv::Size image, double k1, double cap) {
  if (k1 >= -1e-6) return cap;
  const double peak = (2.0 / 3.0) / std::sqrt(-3.0 * k1);  // the largest distorted radius
  const double f_min = 0.5 * std::hypot(image.width, image.height) / (0.9 * peak);
  return std::min(cap, 2.0 * rad_to_deg(std::atan(0.5 * image.height / f_min)));
}

// The projected outer disc's equivalent diameter, pixels.
double projected_diameter_px(const CameraModel& camera, const Pose& pose, double r_m) {
  std::vector<cv::Point3d> rim;
  for (int i = 0; i < 48; ++i) {
    const double a = 2 * kPi * i / 48;
    rim.emplace_back(pose.x + r_m * std::cos(a), pose.y + r_m * std::sin(a), 0.0);
  }
  const auto px = camera.project(rim);
  double area = 0;
  for (std::size_t i = 0; i < px.size(); ++i) {
    const auto& a = px[i];
    const auto& b = px[(i + 1) % px.size()];
    area += a.x * b.y - b.x * a.y;
  }
  return 2 * std::sqrt(std::abs(area) / 2 / kPi);
}

}  // namespace

std::vector<std::string> stress_floor_photos(const StressOptions& options) {
  std::vector<std::string> found;
  if (options.photo_dir.empty()) return found;
  for (const char* name : kFloorPhotos) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(std::filesystem::path(options.photo_dir) / name, ec)) found.emplace_back(name);
  }
  return found;
}

StressScene make_stress_scene(std::uint64_t seed, int index, const StressOptions& options) {
  SceneRandom rnd(seed, index);
  StressScene scene;
  scene.seed = seed;
  scene.index = index;
  const auto photos = stress_floor_photos(options);
  StressConditions& c = scene.conditions;
  c = draw_conditions(rnd, options, photos);

  // The camera: over the middle of a 4 x 3 m floor, 2.5 m up, tilted and distorting.
  const cv::Point2d target(2.0, 1.5);
  const double vfov_max = widest_vfov_deg(c.image_size, c.k1, 65.0);
  const CameraModel camera = CameraModel::overhead(c.image_size, rnd.uniform(std::min(45.0, 0.85 * vfov_max), vfov_max),
                                                   target, 2.5, c.tilt_deg, c.k1);
  scene.calibration = camera.field_calibration(4.0, 3.0);
  // Metres per pixel at the image centre set the markers' size.
  const auto probe =
      camera.project({cv::Point3d(target.x - 0.01, target.y, 0), cv::Point3d(target.x + 0.01, target.y, 0)});
  const double px_per_m = std::hypot(probe[1].x - probe[0].x, probe[1].y - probe[0].y) / 0.02;
  const double d_m = c.marker_diameter_px / px_per_m, r_m = d_m / 2;

  ImagingConditions imaging;
  imaging.floor_grey = c.floor_grey;
  imaging.white_grey = rnd.uniform(205, 245);
  imaging.black_grey = rnd.uniform(12, 45);
  imaging.light_ratio = c.light_ratio;
  imaging.light_direction_rad = rnd.uniform(0, 2 * kPi);
  imaging.blur_sigma_px = c.blur_sigma_px;
  imaging.noise_sigma = c.noise_sigma;
  imaging.jpeg_quality = c.jpeg_quality;
  imaging.vignetting = c.vignetting;
  imaging.motion_blur_px = c.motion_blur_px;
  imaging.motion_blur_angle_rad = deg_to_rad(c.motion_blur_angle_deg);
  imaging.clutter_supersample = 2;
  if (c.floor != StressFloor::kPlain) {
    cv::Mat texture = c.floor == StressFloor::kPhoto
                          ? photo_floor((std::filesystem::path(options.photo_dir) / c.floor_source).string())
                          : drawn_floor(c.floor, rnd);
    const double contrast = rnd.uniform(6, 35);  // the texture's standard deviation, grey levels
    imaging.floor_texture = texture * contrast;
    imaging.floor_texture_tile_m = d_m * rnd.uniform(3, 30);
  }

  // Places inside the image, through the camera's own calibration.
  const double margin_px = 1.5 * c.marker_diameter_px + 8;
  auto random_floor_point = [&] {
    // v, then u: one draw per statement (see SceneRandom).
    const double v = rnd.uniform(margin_px, c.image_size.height - 1 - margin_px);
    const double u = rnd.uniform(margin_px, c.image_size.width - 1 - margin_px);
    const Vec2 p = pixel_to_field(scene.calibration, u, v);
    return cv::Point2d(p.x, p.y);
  };
  // Whether a marker at `pose` lies wholly inside the image, `margin` pixels from its edges.
  auto inside_image = [&](const Pose& pose, double margin) {
    std::vector<cv::Point3d> rim;
    for (int i = 0; i < 24; ++i)
      rim.emplace_back(pose.x + r_m * std::cos(2 * kPi * i / 24), pose.y + r_m * std::sin(2 * kPi * i / 24), 0.0);
    for (const auto& p : camera.project(rim))
      if (p.x < margin || p.y < margin || p.x > c.image_size.width - 1 - margin ||
          p.y > c.image_size.height - 1 - margin)
        return false;
    return true;
  };

  // Robots: IDs drawn from 1-8, some touching another, driving (or turning) through the clip.
  std::vector<int> ids = {1, 2, 3, 4, 5, 6, 7, 8};
  for (int i = 7; i > 0; --i)
    std::swap(ids[static_cast<std::size_t>(i)], ids[static_cast<std::size_t>(rnd.integer(0, i))]);
  const int frames = std::max(1, options.frames_per_scene);
  const double dt = 1.0 / options.fps;
  std::vector<Robot> robots;
  for (int k = 0; k < c.robots; ++k) {
    for (int attempt = 0; attempt < 200; ++attempt) {
      Robot robot;
      robot.id = ids[static_cast<std::size_t>(k)];
      Pose start;
      double speed = d_m * rnd.uniform(0, 4), turn = deg_to_rad(rnd.uniform(-120, 120));
      if (!robots.empty() && rnd.chance(0.35)) {  // against another robot, both standing
        const Robot& other = robots[static_cast<std::size_t>(rnd.integer(0, static_cast<int>(robots.size()) - 1))];
        const double a = rnd.uniform(0, 2 * kPi), gap = d_m * rnd.uniform(1.0, 1.06);
        start = {other.poses[0].x + gap * std::cos(a), other.poses[0].y + gap * std::sin(a), 0};
        speed = 0;
        robot.touching = true;
        if (other.poses.front().x != other.poses.back().x) continue;  // only against one standing
      } else {
        const cv::Point2d p = random_floor_point();
        start = {p.x, p.y, 0};
      }
      start.theta = rnd.uniform(0, 2 * kPi);
      robot.poses.push_back(start);
      for (int f = 1; f < frames; ++f) {
        Pose p = robot.poses.back();
        p.theta += turn * dt;
        p.x += speed * dt * std::cos(p.theta);
        p.y += speed * dt * std::sin(p.theta);
        robot.poses.push_back(p);
      }
      bool fits = true;
      for (const Pose& p : robot.poses) fits = fits && inside_image(p, 4.0);
      for (const Robot& other : robots) {
        const double least = robot.touching ? 0.999 * d_m : 1.4 * d_m;
        for (int f = 0; f < frames && fits; ++f) {
          const Pose& a = robot.poses[static_cast<std::size_t>(f)];
          const Pose& b = other.poses[static_cast<std::size_t>(f)];
          fits = std::hypot(a.x - b.x, a.y - b.y) >= least;
        }
      }
      if (!fits) continue;
      if (rnd.chance(0.25)) lay_cable(robot, rnd, r_m, rnd.uniform(0.02, 0.15));
      robots.push_back(std::move(robot));
      break;
    }
  }
  // A robot is "touching" when any other marker comes within 6 % of a diameter of its own.
  for (Robot& a : robots) {
    for (const Robot& b : robots) {
      if (&a == &b) continue;
      for (int f = 0; f < frames; ++f) {
        const Pose& p = a.poses[static_cast<std::size_t>(f)];
        const Pose& q = b.poses[static_cast<std::size_t>(f)];
        if (std::hypot(p.x - q.x, p.y - q.y) < 1.06 * d_m) a.touching = true;
      }
    }
  }

  // Clutter on the floor, clear of every robot through the clip.
  std::vector<Clutter> clutter;
  for (int i = 0; i < c.clutter_items; ++i) {
    for (int attempt = 0; attempt < 100; ++attempt) {
      const Clutter item = draw_clutter_item(rnd, d_m, random_floor_point());
      const double reach = clutter_reach(item);
      bool clear = true;
      for (const Robot& robot : robots)
        for (const Pose& p : robot.poses)
          clear = clear && std::hypot(p.x - item.x_m, p.y - item.y_m) > reach + r_m + 0.1 * d_m;
      if (!clear) continue;
      clutter.push_back(item);
      break;
    }
  }
  c.clutter_items = static_cast<int>(clutter.size());
  c.robots = static_cast<int>(robots.size());

  const SyntheticCamera renderer(camera, MarkerFamily::six_ucp(), imaging, clutter);
  cv::RNG noise(static_cast<std::uint64_t>(rnd.bits()));
  for (int f = 0; f < frames; ++f) {
    std::vector<SceneMarker> markers;
    std::vector<Clutter> over;
    for (const Robot& robot : robots) {
      const Pose& p = robot.poses[static_cast<std::size_t>(f)];
      markers.push_back({robot.id, p.x, p.y, p.theta, d_m});
      if (!robot.cable_local.empty()) over.push_back(cable_in_field(robot, p));
    }
    scene.frames.push_back(renderer.render(markers, noise, over));
    std::vector<StressTruth> truth;
    const auto seen = renderer.truth(markers);
    for (std::size_t i = 0; i < robots.size(); ++i) {
      StressTruth t;
      t.id = seen[i].id;
      t.u = seen[i].u;
      t.v = seen[i].v;
      t.heading_deg = seen[i].heading_deg;
      t.visible = seen[i].visible;
      t.diameter_px = projected_diameter_px(camera, robots[i].poses[static_cast<std::size_t>(f)], r_m);
      t.occluded = robots[i].occluded;
      t.touching = robots[i].touching;
      truth.push_back(t);
    }
    scene.truth.push_back(std::move(truth));
  }
  return scene;
}

}  // namespace rilbed::vision

// The vision stress set: scenes whose every imaging condition is drawn at random
// from a range wider than any one lab's, so that the detector is measured on footage
// nobody tuned it to. One scene is one camera, floor, light and clutter, and a short clip
// of its robots driving; its ground truth says, per marker, where its centre projects, which
// way its forward axis points in the image, how large it appears and how much of it is
// covered. `rilbed synth --preset stress`, bench/bench_stress and the stress CTest draw
// from it.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "vision/field_mapping.hpp"
#include "vision/synthetic_camera.hpp"

namespace rilbed::vision {

/// What a stress scene's floor is.
enum class StressFloor {
  kPlain,     ///< an even grey, light or dark
  kPhoto,     ///< a photograph (opencv-doc's sample images), tiled and rescaled
  kWood,      ///< a drawn wood grain
  kFabric,    ///< a drawn woven fabric
  kCarpet,    ///< a drawn carpet (fine random pile)
  kConcrete,  ///< a drawn concrete (blotches and pores)
};

/// The name of a floor kind ("plain", "photo", "wood", ...).
const char* floor_name(StressFloor floor);

/// The imaging conditions of one stress scene, each drawn from the range in its comment.
struct StressConditions {
  cv::Size image_size{1280, 960};
  double marker_diameter_px = 32;  ///< 20-64: the printed outer diameter (white ring included) at the image centre
  double blur_sigma_px = 0;        ///< 0-2: Gaussian defocus
  double motion_blur_px = 0;       ///< 0-4: a smear in any direction
  double motion_blur_angle_deg = 0;
  double noise_sigma = 0;  ///< 0-10 grey levels
  int jpeg_quality = 95;   ///< 50-95
  double light_ratio = 1;  ///< 1-4: brightest to darkest across the field
  double vignetting = 0;   ///< 0-0.5: the light's fall at the corners
  double tilt_deg = 0;     ///< 0-20
  double k1 = 0;           ///< 0 to -0.3: radial (barrel) distortion, with the matching calibration
  StressFloor floor = StressFloor::kPlain;
  std::string floor_source;  ///< the photograph's file name, or the drawn texture's name
  double floor_grey = 185;   ///< the floor's mean level: light (150-215) or dark (40-100)
  int clutter_items = 0;     ///< 4-14
  int robots = 8;            ///< 4-8 robots, IDs drawn from 1-8
};

/// Ground truth of one marker in one frame of a stress scene.
struct StressTruth {
  int id = 0;
  double u = 0, v = 0;     ///< projection of the marker's centre, distorted pixels
  double heading_deg = 0;  ///< direction of the projected forward axis at the centre, CCW from +u, [0, 360)
  double diameter_px = 0;  ///< the projected outer disc's equivalent diameter (2 sqrt(area / pi)), pixels
  double occluded = 0;     ///< fraction of the outer disc covered (0-0.15)
  bool touching = false;   ///< another robot's marker touches (or nearly touches) it
  bool visible = false;    ///< the whole marker is inside the image
};

/// One stress scene: its conditions, calibration and clip.
struct StressScene {
  std::uint64_t seed = 0;
  int index = 0;  ///< the scene's number within its set (with seed, all it is drawn from)
  StressConditions conditions;
  FieldCalibration calibration;                 ///< the field calibration a lab would measure for its camera
  std::vector<cv::Mat> frames;                  ///< 8-bit BGR, JPEG-compressed at conditions.jpeg_quality
  std::vector<std::vector<StressTruth>> truth;  ///< per frame, every robot's marker
};

/// Knobs of the generator.
struct StressOptions {
  int frames_per_scene = 4;  ///< the clip's length (tracked mode follows it; full-frame takes each frame)
  double fps = 15;           ///< the clip's frame rate (how far the robots drive between frames)
  /// Folder of photographs for the Photo floors; empty or missing: the drawn floors only.
  std::string photo_dir = "/usr/share/doc/opencv-doc/examples/data";
  cv::Size image_size{1280, 960};
};

/// Draws and renders scene `index` of the set `seed` (the same pair gives the same scene).
StressScene make_stress_scene(std::uint64_t seed, int index, const StressOptions& options = {});

/// The photographs used for Photo floors (file names within options.photo_dir that exist).
std::vector<std::string> stress_floor_photos(const StressOptions& options);

}  // namespace rilbed::vision

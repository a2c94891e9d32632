// A second footage generator, independent of the stress set's (stress_scene.hpp), so that
// the detector is reported on images made by a model nobody tuned it to. Where the stress
// set paints reflectance into pixels and then blurs and adds grey-level noise, this one
// follows light from the floor to the file, as a lab's camera makes it:
//
//   - geometry: rays cast from a pinhole through a fisheye-style lens (the angle, not the
//     radius, is distorted: r = f (theta + k1 theta^3 + k2 theta^5)) onto robots of a
//     given height (their tops, their sides) and the floor below; each pixel integrates
//     4x4 jittered rays over its photosite (fill factor below one), not a box of
//     subpixels;
//   - the print: markers are paper stickers with a fibre grain, toner that spreads (dot
//     gain), a glossy sheen where the lamp's reflection falls, on a robot's dark top;
//   - light: one lamp (inverse-square, cosine) with ambient light, the robots' soft
//     shadows, natural vignetting (cos^4) and the lens's own;
//   - optics: a defocus disc (pillbox) that grows towards the corners, then diffraction;
//   - time: each row is exposed later than the one above (rolling shutter) and each ray
//     at its own moment of the exposure (motion blur), the robots driving arcs;
//   - the sensor: photo-electrons with shot noise (Poisson: grows with brightness), read
//     noise, pixel gain spread, a 10-bit ADC, a Bayer mosaic demosaiced by OpenCV or a
//     mono sensor, white balance, an sRGB tone curve, then JPEG;
//   - occluders: cables lying over a robot's marker and on the floor beyond, and things
//     on the floor that must never get an ID (dark discs, washers, tape, printed text).
//
// Its ground truth has the stress set's form (StressScene, StressTruth), so StressTally
// scores both. bench_stress --generator lab and the lab-footage CTest draw from it.
#pragma once

#include <cstdint>
#include <string>

#include "vision/stress_scene.hpp"

namespace rilbed::vision {

/// How hard a lab-footage scene is, after the three kinds of footage.
enum class LabDifficulty {
  kPlain,  ///< a good lamp, a sharp lens, markers about 30-40 px, a little noise, JPEG 85-95
  kHard,   ///< blur, 3:1 light, JPEG 60-70, markers about 24-32 px, motion
  kHarsh,  ///< tilt 12-20 degrees, strong lens distortion, 4:1 light, blur, JPEG 50-60
};

/// The name of a difficulty ("plain", "hard", "harsh").
const char* difficulty_name(LabDifficulty difficulty);

/// Knobs of the generator.
struct LabFootageOptions {
  int frames_per_scene = 6;  ///< the clip's length (tracked mode follows it)
  double fps = 15;
  cv::Size image_size{1280, 960};
  /// Scene k's difficulty is kinds[k % 3] in this order (plain, hard, harsh) unless one
  /// is fixed here.
  bool fixed_difficulty = false;
  LabDifficulty difficulty = LabDifficulty::kPlain;
  /// The printed markers' outer diameter, metres; 0 draws 42-48 mm per scene.
  double marker_diameter_m = 0;
  /// Smallest and largest marker diameter at the image centre, pixels; 0 takes the
  /// difficulty's range.
  double min_marker_px = 0, max_marker_px = 0;
};

/// Draws and renders scene `index` of the set `seed` (the same pair gives the same
/// scene). `conditions` summarises the scene in the stress set's terms (blur as one
/// Gaussian's sigma, the light's ratio, JPEG quality, tilt, the floor), and
/// `floor_source` names the drawn floor and the difficulty.
StressScene make_lab_scene(std::uint64_t seed, int index, const LabFootageOptions& options = {});

}  // namespace rilbed::vision

// Ready-made scenes for the synthetic overhead camera: the lab's 1.5 x 1.2 m field seen
// from about 1.5 m, eight marked robots driving smooth paths, and two sets of imaging
// conditions (nominal and hard). Used to make datasets/, by tests and by benchmarks.
#pragma once

#include <string>
#include <vector>

#include "vision/synthetic_camera.hpp"

namespace rilbed::vision {

/// A named set of camera, conditions and clutter.
struct ScenePreset {
  std::string name;
  CameraModel camera;
  ImagingConditions conditions;
  std::vector<Clutter> clutter;
  double field_width_m = 1.5;
  double field_height_m = 1.2;
  double marker_diameter_m = 0.05;
};

/// "nominal": straight overhead 1280x720 camera, mild blur and noise, light floor, MJPG.
/// "hard": tilted 20 degrees, strong barrel distortion, blur, noise, 3:1 lighting,
/// mid-grey floor with a dark mat, clutter (discs, rings, tape, a chessboard, text),
/// stronger MJPG compression. Throws std::invalid_argument for another name.
ScenePreset scene_preset(const std::string& name, cv::Size image_size = {1280, 720});

/// Poses of `robot_count` robots (IDs 1..robot_count) at time t_s: each drives a smooth
/// closed path (a rounded figure of its own, seeded by `seed`) inside its own part of
/// the field, facing where it goes; some turn on the spot now and then.
std::vector<SceneMarker> robots_at(double t_s, int robot_count, const ScenePreset& preset, unsigned seed);

}  // namespace rilbed::vision

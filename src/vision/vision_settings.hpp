// The vision knobs a person turns while watching the camera (the web panel's vision
// settings, `rilbed console vision NAME VALUE`, a scenario's `camera: {vision: ...}`):
// the image's brightness and contrast before detection, the marker search's threshold,
// the marker size limits and the least score for an ID. Each maps onto the pipeline's
// own knobs (BlobDetectorConfig, TrackerConfig); the rest of TrackerConfig stays as it is.
#pragma once

#include <opencv2/core.hpp>

#include <array>
#include <optional>
#include <string>
#include <string_view>

#include "vision/marker_tracker.hpp"

namespace rilbed::vision {

/// The settings, with their defaults (those of a default TrackerConfig, the image as
/// the camera gives it).
struct VisionSettings {
  /// Grey levels added to every pixel after the contrast gain, [-128, 128]. Raises or
  /// lowers a whole under- or over-exposed image; costs one pass over the frame when not 0
  /// (together with contrast).
  double brightness = 0.0;
  /// Gain about mid-grey (128), [0.2, 5]: above 1 spreads the grey levels (a washed-out
  /// image), below 1 squeezes them (noise that makes specks).
  double contrast = 1.0;
  /// Least local contrast, grey levels [1, 255], for pixels to count as dark or bright in
  /// the marker search (BlobDetectorConfig::min_local_contrast). Lower finds fainter
  /// markers and fills more noise.
  int threshold = 24;
  /// Smallest and largest marker diameter looked for, pixels [6, 4000], min < max.
  double min_diameter_px = 18.0;
  double max_diameter_px = 480.0;
  /// Least decoding similarity for a marker to take an ID, [0, 1]
  /// (TrackerConfig::min_assign_score). Lower finds markers in worse images and lets
  /// clutter take IDs more often.
  double min_score = 0.75;

  bool operator==(const VisionSettings&) const = default;
};

/// The settings' names, as the console, the web panel ("vision." + name) and scenarios
/// spell them.
inline constexpr std::array<std::string_view, 6> kVisionSettingNames = {
    "brightness", "contrast", "threshold", "min_diameter_px", "max_diameter_px", "min_score"};

/// One setting by name; nullopt for an unknown name.
std::optional<double> vision_setting(const VisionSettings& settings, std::string_view name);

/// Sets one setting by name, checking its range (a whole number for the threshold).
/// Returns nullopt, or why not ("unknown vision setting 'x' (brightness, ...)",
/// "contrast 9 is outside 0.2..5"). Leaves `settings` as it was when refused.
std::optional<std::string> set_vision_setting(VisionSettings& settings, std::string_view name, double value);

/// Why the settings as a whole cannot be used ("min_diameter_px 500 is not below
/// max_diameter_px 480"), or nullopt.
std::optional<std::string> check_vision_settings(const VisionSettings& settings);

/// The settings a tracker configuration has (brightness 0, contrast 1).
VisionSettings vision_settings_of(const TrackerConfig& config);

/// `config` with the settings' detection knobs.
TrackerConfig with_vision_settings(TrackerConfig config, const VisionSettings& settings);

/// Whether the image passes through unchanged (brightness 0, contrast 1).
bool leaves_image_alone(const VisionSettings& settings);

/// The frame with the settings' contrast and brightness: out = clamp(contrast * (in -
/// 128) + 128 + brightness), per channel, saturated to 8 bits. `frame` itself (shared,
/// not copied) when leaves_image_alone(); otherwise written into `buffer` (reused
/// between frames) and returned. 8-bit frames only (others are returned as they are).
cv::Mat adjust_frame(const cv::Mat& frame, const VisionSettings& settings, cv::Mat& buffer);

/// The settings as one flow-style YAML mapping, "{brightness: 0, contrast: 1, ...}", what a
/// scenario's `camera: {vision: ...}` takes.
std::string vision_settings_yaml(const VisionSettings& settings);

}  // namespace rilbed::vision

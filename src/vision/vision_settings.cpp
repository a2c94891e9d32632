#include "vision/vision_settings.hpp"

#include <cmath>
#include <sstream>

namespace rilbed::vision {

namespace {

// Where each setting lives in the struct, and its range.
struct SettingSpec {
  std::string_view name;
  double low, high;
  bool whole;
};

constexpr std::array<SettingSpec, 6> kSpecs = {{
    {"brightness", -128.0, 128.0, false},
    {"contrast", 0.2, 5.0, false},
    {"threshold", 1.0, 255.0, true},
    {"min_diameter_px", 6.0, 4000.0, false},
    {"max_diameter_px", 6.0, 4000.0, false},
    {"min_score", 0.0, 1.0, false},
}};

std::string number_text(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

std::string names_text() {
  std::string names;
  for (const std::string_view n : kVisionSettingNames) names += (names.empty() ? "" : ", ") + std::string(n);
  return names;
}

}  // namespace

std::optional<double> vision_setting(const VisionSettings& s, std::string_view name) {
  if (name == "brightness") return s.brightness;
  if (name == "contrast") return s.contrast;
  if (name == "threshold") return s.threshold;
  if (name == "min_diameter_px") return s.min_diameter_px;
  if (name == "max_diameter_px") return s.max_diameter_px;
  if (name == "min_score") return s.min_score;
  return std::nullopt;
}

std::optional<std::string> set_vision_setting(VisionSettings& s, std::string_view name, double value) {
  const SettingSpec* spec = nullptr;
  for (const SettingSpec& candidate : kSpecs) {
    if (candidate.name == name) spec = &candidate;
  }
  if (!spec) return "unknown vision setting '" + std::string(name.substr(0, 64)) + "' (" + names_text() + ")";
  const std::string shown = std::string(name) + " " + number_text(value);
  if (!std::isfinite(value) || value < spec->low || value > spec->high) {
    return shown + " is outside " + number_text(spec->low) + ".." + number_text(spec->high);
  }
  if (spec->whole && value != std::floor(value)) return shown + " is not a whole number";
  if (name == "brightness") s.brightness = value;
  if (name == "contrast") s.contrast = value;
  if (name == "threshold") s.threshold = static_cast<int>(value);
  if (name == "min_diameter_px") s.min_diameter_px = value;
  if (name == "max_diameter_px") s.max_diameter_px = value;
  if (name == "min_score") s.min_score = value;
  return std::nullopt;
}

std::optional<std::string> check_vision_settings(const VisionSettings& s) {
  for (const std::string_view name : kVisionSettingNames) {
    VisionSettings copy;
    if (auto why = set_vision_setting(copy, name, *vision_setting(s, name))) return why;
  }
  if (!(s.min_diameter_px < s.max_diameter_px)) {
    return "min_diameter_px " + number_text(s.min_diameter_px) + " is not below max_diameter_px " +
           number_text(s.max_diameter_px);
  }
  return std::nullopt;
}

VisionSettings vision_settings_of(const TrackerConfig& config) {
  VisionSettings s;
  s.threshold = config.blobs.min_local_contrast;
  s.min_diameter_px = config.blobs.min_diameter_px;
  s.max_diameter_px = config.blobs.max_diameter_px;
  s.min_score = config.min_assign_score;
  return s;
}

TrackerConfig with_vision_settings(TrackerConfig config, const VisionSettings& s) {
  config.blobs.min_local_contrast = s.threshold;
  config.blobs.min_diameter_px = s.min_diameter_px;
  config.blobs.max_diameter_px = s.max_diameter_px;
  config.min_assign_score = s.min_score;
  return config;
}

bool leaves_image_alone(const VisionSettings& s) { return s.brightness == 0.0 && s.contrast == 1.0; }

cv::Mat adjust_frame(const cv::Mat& frame, const VisionSettings& s, cv::Mat& buffer) {
  if (leaves_image_alone(s) || frame.depth() != CV_8U) return frame;
  // convertTo saturates and is vectorised by OpenCV (universal intrinsics) on every CPU.
  frame.convertTo(buffer, -1, s.contrast, 128.0 * (1.0 - s.contrast) + s.brightness);
  return buffer;
}

std::string vision_settings_yaml(const VisionSettings& s) {
  std::string out = "{";
  for (const std::string_view name : kVisionSettingNames) {
    if (out.size() > 1) out += ", ";
    out += std::string(name) + ": " + number_text(*vision_setting(s, name));
  }
  return out + "}";
}

}  // namespace rilbed::vision

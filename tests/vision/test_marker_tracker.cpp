#include <gtest/gtest.h>

#include <map>

#include "core/geometry.hpp"
#include "vision/marker_tracker.hpp"
#include "vision/synthetic_scene.hpp"

using namespace rilbed;
using namespace rilbed::vision;

namespace {

struct Errors {
  int expected = 0, found = 0, wrong_id = 0;
  double max_centre_px = 0, max_heading_deg = 0, sum_centre2 = 0, sum_heading2 = 0;
};

// Runs `frames` frames of a preset through a tracker and compares with the truth.
Errors run_scene(const std::string& preset_name, int frames, bool tracked, unsigned seed) {
  const auto preset = scene_preset(preset_name);
  SyntheticCamera camera(preset.camera, MarkerFamily::six_ucp(), preset.conditions, preset.clutter);
  MarkerTracker tracker(MarkerFamily::six_ucp(), {1, 2, 3, 4, 5, 6, 7, 8});
  cv::RNG rng(seed);
  Errors e;
  for (int f = 0; f < frames; ++f) {
    const auto robots = robots_at(f / 15.0, 8, preset, seed);
    const cv::Mat img = camera.render(robots, rng);
    const auto found = tracked ? tracker.process(img) : tracker.detect_full_frame(img);
    std::map<int, MarkerTruth> truth;
    for (const auto& t : camera.truth(robots)) if (t.visible) truth[t.id] = t;
    e.expected += static_cast<int>(truth.size());
    for (const auto& d : found) {
      auto it = truth.find(d.id);
      // A detection far from its ID's true place is a wrong ID.
      if (it == truth.end() || std::hypot(d.u - it->second.u, d.v - it->second.v) > 5.0) {
        ++e.wrong_id;
        continue;
      }
      ++e.found;
      const double dc = std::hypot(d.u - it->second.u, d.v - it->second.v);
      const double dh = std::abs(wrap_deg_180(d.heading_deg - it->second.heading_deg));
      e.max_centre_px = std::max(e.max_centre_px, dc);
      e.max_heading_deg = std::max(e.max_heading_deg, dh);
      e.sum_centre2 += dc * dc;
      e.sum_heading2 += dh * dh;
    }
  }
  return e;
}

}  // namespace

TEST(MarkerTracker, NominalSceneAllFoundPrecisely) {
  const Errors e = run_scene("nominal", 20, true, 1);
  EXPECT_EQ(e.wrong_id, 0);
  EXPECT_EQ(e.found, e.expected);
  EXPECT_LT(std::sqrt(e.sum_centre2 / e.found), 0.3);
  EXPECT_LT(std::sqrt(e.sum_heading2 / e.found), 1.5);
  EXPECT_LT(e.max_heading_deg, 5.0);
}

TEST(MarkerTracker, HardSceneNoFalseIds) {
  const Errors e = run_scene("hard", 20, true, 2);
  EXPECT_EQ(e.wrong_id, 0);
  EXPECT_GE(e.found, 0.97 * e.expected);
  EXPECT_LT(std::sqrt(e.sum_centre2 / e.found), 0.5);
  EXPECT_LT(std::sqrt(e.sum_heading2 / e.found), 2.5);
}

TEST(MarkerTracker, FullFrameMatchesTracked) {
  const Errors full = run_scene("nominal", 5, false, 3);
  EXPECT_EQ(full.wrong_id, 0);
  EXPECT_EQ(full.found, full.expected);
}

TEST(MarkerTracker, RejectsBadIds) {
  EXPECT_THROW(MarkerTracker(MarkerFamily::six_ucp(), {}), std::invalid_argument);
  EXPECT_THROW(MarkerTracker(MarkerFamily::six_ucp(), {1, 9}), std::invalid_argument);
}

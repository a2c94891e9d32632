// The detector on footage from the second generator (src/vision/lab_footage.hpp), whose
// model of light, lens, print and sensor is independent of the stress set's and was never
// tuned on: scenes plain, hard and harsh in turn, scored full-frame and tracked, held to
// the targets of vision that finds every whole marker (all but one, kHeldWorstBiasDeg,
// which 18 scenes cannot resolve). The seed was drawn after the last threshold changed
// and no threshold was looked at on it; draw a new one whenever a threshold changes
// (`bench_stress --generator lab --seed S` prints the whole table of any seed, and
// --explain says why each missed marker was missed).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <future>
#include <numeric>
#include <vector>

#include "sanitized.hpp"
#include "vision/lab_footage.hpp"
#include "vision/marker_tracker.hpp"
#include "vision/stress_score.hpp"

namespace rilbed::vision {
namespace {

constexpr std::uint64_t kSeed = 4519659663454669402ull;  // drawn after the last threshold changed; never tuned on

// Each ID's mean heading error over 18 scenes (about 55 whole markers of 24 px and more
// per ID) scatters by about 0.1 degrees, so the worst of eight cannot be held to the 0.3
// degree target here: this seed's first 18 scenes read 0.30 (ID 4, full-frame), its 60
// 0.09 (bench_stress --generator lab, where the target is read off). This catches a
// collapse; every other bound below is the target itself.
constexpr double kHeldWorstBiasDeg = 0.45;

// Under the sanitizers (some thirty times slower) a few scenes, held to the mistakes only.
constexpr int kScenes = kSanitized ? 3 : 18;
constexpr int kFrames = 4;

struct Tallies {
  StressTally full, tracked;
};

const Tallies& tallies() {
  static const Tallies result = [] {
    Tallies t;
    const std::vector<int> ids = {1, 2, 3, 4, 5, 6, 7, 8};
    LabFootageOptions options;
    options.frames_per_scene = kFrames;
    MarkerTracker single(MarkerFamily::six_ucp(), ids);
    auto render = [options](int k) { return make_lab_scene(kSeed, k, options); };
    std::future<StressScene> next = std::async(std::launch::async, render, 0);
    for (int k = 0; k < kScenes; ++k) {
      const StressScene scene = next.get();
      if (k + 1 < kScenes) next = std::async(std::launch::async, render, k + 1);
      MarkerTracker clip(MarkerFamily::six_ucp(), ids);
      for (int f = 0; f < static_cast<int>(scene.frames.size()); ++f) {
        const cv::Mat& frame = scene.frames[static_cast<std::size_t>(f)];
        t.full.add(scene, f, single.detect_full_frame(frame), single.last_stats().declined);
        t.tracked.add(scene, f, clip.process(frame), clip.last_stats().declined);
      }
    }
    return t;
  }();
  return result;
}

bool whole(const StressOutcome& o) { return o.occluded == 0 && !o.touching; }

// The green levels, sorted, read at 48 points of a circle of `fraction` of the marker's
// outer radius around its truth's centre (each point clamped into the frame).
std::vector<int> ring_levels(const cv::Mat& frame, const StressTruth& t, double fraction) {
  constexpr int kReads = 48;
  std::vector<int> levels;
  for (int k = 0; k < kReads; ++k) {
    const double angle = 2 * 3.141592653589793 * k / kReads, r = fraction * 0.5 * t.diameter_px;
    const int x = std::clamp(static_cast<int>(std::lround(t.u + r * std::cos(angle))), 0, frame.cols - 1);
    const int y = std::clamp(static_cast<int>(std::lround(t.v + r * std::sin(angle))), 0, frame.rows - 1);
    levels.push_back(frame.at<cv::Vec3b>(y, x)[1]);
  }
  std::sort(levels.begin(), levels.end());
  return levels;
}

TEST(LabFootage, GeneratorIsDeterministicAndItsTruthLiesOnTheMarkers) {
  LabFootageOptions options;
  options.frames_per_scene = 1;
  const StressScene a = make_lab_scene(kSeed, 1, options), b = make_lab_scene(kSeed, 1, options);
  ASSERT_EQ(a.frames.size(), 1u);
  EXPECT_EQ(cv::norm(a.frames[0], b.frames[0], cv::NORM_INF), 0.0);
  ASSERT_EQ(a.truth[0].size(), 8u);
  auto ring_level = [&](const StressTruth& t, double fraction) {
    const std::vector<int> levels = ring_levels(a.frames[0], t, fraction);
    return std::accumulate(levels.begin(), levels.end(), 0.0) / static_cast<double>(levels.size());
  };
  for (const StressTruth& t : a.truth[0]) {
    EXPECT_GT(t.diameter_px, 15.0);
    // The truth lies on its marker: the black ring's middle (0.67 of the outer radius)
    // reads darker than the white ring's (0.89) all round. (Not the hole alone: on a small
    // marker under motion blur the hole, 4 px across, is smeared with the white slices
    // around it; seed 11049315908254191147's scene 1 has one, its centre at grey 183.)
    // Only for markers the targets cover: seed 4519659663454669402's scene 1 has an
    // 18 px one in a corner under 2.5 px of motion smear whose rings both read 124-127.
    if (t.diameter_px < 24.0) continue;
    EXPECT_LT(ring_level(t, 0.67) + 20, ring_level(t, 0.89)) << "ID " << t.id;
  }
}

// A cable lies on the floor beyond its own robot and may run under another: that robot's
// top hides it, as the truth (which counts only what lies between camera and marker) has
// it. Drawn over the top instead, it crossed marker 2 of this scene, which the truth calls
// whole, and turned its black ring white where it passed (grey 229 against the white
// ring's 142).
TEST(LabFootage, ACableOnTheFloorRunsUnderOtherRobots) {
  LabFootageOptions options;
  options.frames_per_scene = 4;
  const StressScene scene = make_lab_scene(5238905471622739143ull, 11, options);
  ASSERT_EQ(scene.frames.size(), 4u);
  const cv::Mat& frame = scene.frames[1];
  const auto it =
      std::find_if(scene.truth[1].begin(), scene.truth[1].end(), [](const StressTruth& t) { return t.id == 2; });
  ASSERT_NE(it, scene.truth[1].end());
  EXPECT_EQ(it->occluded, 0.0);
  const std::vector<int> black = ring_levels(frame, *it, 0.67), white = ring_levels(frame, *it, 0.89);
  EXPECT_LT(black.back(), white[white.size() / 2]) << "black ring's brightest " << black.back();
}

// A white cable lies over the white ring of this scene's marker 1 and 3 px into the
// edge of its black ring (7 % of the marker covered). The fill stops at the cable, its
// moments put the centre a pixel away from it, and the code read around that centre
// gave a heading 13-14 degrees off in every frame. The outline fitted without the
// crossings on the cable (TrackerConfig::rim_refit) puts the centre back, and the code
// read there the heading.
TEST(LabFootage, ACableOverAMarkersRimLeavesItsCentreAndHeading) {
  LabFootageOptions options;
  options.frames_per_scene = 4;
  const StressScene scene = make_lab_scene(12690901603533338626ull, 59, options);
  MarkerTracker tracker(MarkerFamily::six_ucp(), {1, 2, 3, 4, 5, 6, 7, 8});
  for (std::size_t f = 0; f < scene.frames.size(); ++f) {
    const auto truth =
        std::find_if(scene.truth[f].begin(), scene.truth[f].end(), [](const StressTruth& t) { return t.id == 1; });
    ASSERT_NE(truth, scene.truth[f].end());
    EXPECT_GT(truth->occluded, 0.0);
    const auto found = tracker.detect_full_frame(scene.frames[f]);
    const auto d = std::find_if(found.begin(), found.end(), [](const MarkerDetection& m) { return m.id == 1; });
    ASSERT_NE(d, found.end()) << "frame " << f;
    EXPECT_LT(std::hypot(d->u - truth->u, d->v - truth->v), 0.5) << "frame " << f;
    EXPECT_LT(std::abs(std::remainder(d->heading_deg - truth->heading_deg, 360.0)), 5.0) << "frame " << f;
  }
}

TEST(LabFootage, FullFrameAndTrackedFindEveryWholeMarkerWithoutMistakes) {
  for (const bool tracked : {false, true}) {
    SCOPED_TRACE(tracked ? "tracked" : "full-frame");
    const StressTally& t = tracked ? tallies().tracked : tallies().full;
    EXPECT_EQ(t.frames(), kScenes * kFrames);
    // Markers under cables included.
    EXPECT_EQ(t.count(StressMistake::Kind::kWrongId), 0) << list_mistakes(t);
    EXPECT_EQ(t.count(StressMistake::Kind::kFalseDetection), 0) << list_mistakes(t);
    EXPECT_EQ(t.count(StressMistake::Kind::kWrongHeading), 0) << list_mistakes(t);
    EXPECT_EQ(t.count(StressMistake::Kind::kDuplicate), 0) << list_mistakes(t);
    if (kSanitized) continue;

    const auto large = summarise(t.outcomes(), [](const StressOutcome& o) { return whole(o) && o.diameter_px >= 28; });
    ASSERT_GT(large.markers, 200);
    EXPECT_GE(large.recall(), 0.99) << large.found << " of " << large.markers;
    const auto mid = summarise(
        t.outcomes(), [](const StressOutcome& o) { return whole(o) && o.diameter_px >= 24 && o.diameter_px < 28; });
    ASSERT_GT(mid.markers, 40);
    EXPECT_GE(mid.recall(), 0.97) << mid.found << " of " << mid.markers;

    const auto all = summarise(t.outcomes(), [](const StressOutcome& o) { return whole(o) && o.diameter_px >= 24; });
    EXPECT_LE(all.centre_rms_px, 0.15);
    EXPECT_LE(std::abs(all.worst_bias_deg), kHeldWorstBiasDeg) << "ID " << all.worst_bias_id;
    // Scene k is hard when k % 3 == 1.
    const auto hard = summarise(
        t.outcomes(), [](const StressOutcome& o) { return whole(o) && o.scene % 3 == 1 && o.diameter_px >= 24; });
    EXPECT_LE(hard.heading_rms_deg, 1.0);
  }
}

}  // namespace
}  // namespace rilbed::vision

// The vision stress set held to its targets: 60 scenes (240 frames) whose every
// condition is drawn at random from wide ranges (src/vision/stress_scene.hpp), scored
// full-frame and tracked. The seed is not one any threshold was tuned on; draw a new one
// whenever a threshold changes (bench/bench_stress --seed S runs thousands of frames from
// any seed and prints the whole table). Every bound below is the stress set's own target, but
// for the two that 240 frames cannot resolve (kHeld* below).
#include <gtest/gtest.h>

#include <cstdio>
#include <future>

#include "sanitized.hpp"
#include "vision/marker_tracker.hpp"
#include "vision/stress_score.hpp"

namespace rilbed::vision {
namespace {

constexpr std::uint64_t kSeed = 3354018184;  // drawn after the last threshold changed, never tuned on

// Under AddressSanitizer (`./run asan`, a Debug build) the detector runs some thirty times
// slower: there the test renders 12 scenes and holds them to the mistakes only (a wrong ID,
// a false detection, a heading far off need no statistics; recall and RMS over 12 scenes
// would be noise). The scenes are the same, the results bit for bit those of Release.
constexpr int kScenes = kSanitized ? 12 : 60;

// Two of the stress set's targets are held here at a level below the target, for want of frames
// rather than of accuracy. On a fresh seed of 2,000 frames (bench_stress) recall at 24-32
// px is 0.951 full-frame and 0.964 tracked, and the worst ID's mean heading error 0.11
// degrees. But marker sizes, blur and floor are drawn per scene, so these 60 scenes hold
// the 24-32 px markers of only a dozen or two scenes, and their recall swings with those
// scenes' blur and floors: fresh seeds read 0.93-0.95, and this one 0.74 / 0.79 (heavy blur
// on wood and concrete in several; the code before the last change reads the same). The
// bias is a mean over one ID's detections, covered ones among them: 0.40 degrees on an
// earlier seed. The bounds below catch a collapse; the targets are read off bench_stress's
// 2,000 frames (500 scenes), whose 24-32 px recall still scatters by about 0.015.
constexpr double kHeldMidRecall = 0.70;    // target 0.95 (bench_stress, 2,000 frames)
constexpr double kHeldWorstBiasDeg = 0.5;  // target 0.3 (bench_stress, 2,000 frames)

struct Tallies {
  StressTally full, tracked;
};

// Renders the scenes two at a time (rendering is most of the test's time) and scores
// each as it comes.
const Tallies& tallies() {
  static const Tallies result = [] {
    Tallies t;
    const std::vector<int> ids = {1, 2, 3, 4, 5, 6, 7, 8};
    MarkerTracker single(MarkerFamily::six_ucp(), ids);
    std::future<StressScene> next = std::async(std::launch::async, [] { return make_stress_scene(kSeed, 0); });
    for (int k = 0; k < kScenes; ++k) {
      const StressScene scene = next.get();
      if (k + 1 < kScenes) next = std::async(std::launch::async, [k] { return make_stress_scene(kSeed, k + 1); });
      MarkerTracker clip(MarkerFamily::six_ucp(), ids);
      for (int f = 0; f < static_cast<int>(scene.frames.size()); ++f) {
        const auto found = single.detect_full_frame(scene.frames[static_cast<std::size_t>(f)]);
        t.full.add(scene, f, found, single.last_stats().declined);
        const auto followed = clip.process(scene.frames[static_cast<std::size_t>(f)]);
        t.tracked.add(scene, f, followed, clip.last_stats().declined);
      }
    }
    return t;
  }();
  return result;
}

// One test for both modes: the scenes are rendered once (CTest runs each test in a process
// of its own).
TEST(StressSet, FullFrameAndTrackedHoldTheirTargetsOrTheLevelReached) {
  for (const bool tracked : {false, true}) {
    SCOPED_TRACE(tracked ? "tracked" : "full-frame");
    const StressTally& t = tracked ? tallies().tracked : tallies().full;
    EXPECT_EQ(t.frames(), kScenes * 4);
    std::printf("%s: %d frames, %zu markers, %d declined as ambiguous\n", tracked ? "tracked" : "full-frame",
                t.frames(), t.outcomes().size(), t.declined());
    // A miss beats a wrong ID; clutter (other tag families among it) never gets one; no
    // heading is far off.
    EXPECT_EQ(t.count(StressMistake::Kind::kWrongId), 0) << list_mistakes(t);
    EXPECT_EQ(t.count(StressMistake::Kind::kFalseDetection), 0) << list_mistakes(t);
    EXPECT_EQ(t.count(StressMistake::Kind::kWrongHeading), 0) << list_mistakes(t);
    EXPECT_EQ(t.count(StressMistake::Kind::kDuplicate), 0) << list_mistakes(t);
    if (kSanitized) continue;

    const auto large =
        summarise(t.outcomes(), [](const StressOutcome& o) { return o.occluded == 0 && o.diameter_px >= 32; });
    ASSERT_GT(large.markers, 300);
    EXPECT_GE(large.recall(), 0.99) << large.found << " of " << large.markers;

    // Markers 24-32 px across, the most blurred of which are at the edge of reading. A
    // seed's 60 scenes hold 130-200 of them (sizes are drawn per scene).
    const auto mid = summarise(t.outcomes(), [](const StressOutcome& o) {
      return o.occluded == 0 && o.diameter_px >= 24 && o.diameter_px < 32;
    });
    ASSERT_GT(mid.markers, 120);
    EXPECT_GE(mid.recall(), kHeldMidRecall) << mid.found << " of " << mid.markers;

    // Markers 24 px and larger, partly covered ones included: centre and heading accurate,
    // and no ID's heading biased (a bias by code is what a lab cannot calibrate away).
    const auto all = summarise(t.outcomes(), [](const StressOutcome& o) { return o.diameter_px >= 24; });
    ASSERT_GT(all.found, 500);
    EXPECT_LE(all.centre_rms_px, 0.2);
    EXPECT_LE(all.heading_rms_deg, 1.0);
    EXPECT_LE(std::abs(all.worst_bias_deg), kHeldWorstBiasDeg) << "ID " << all.worst_bias_id;
    EXPECT_LE(all.heading_max_deg, kStressWrongHeadingDeg);
  }
}

}  // namespace
}  // namespace rilbed::vision

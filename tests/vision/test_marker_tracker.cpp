#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include <opencv2/imgproc.hpp>

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
    for (const auto& t : camera.truth(robots))
      if (t.visible) truth[t.id] = t;
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

// A marker hidden for a few frames (a hand over the robot) comes back with its own ID,
// and no other marker takes its ID meanwhile.
TEST(MarkerTracker, OcclusionDoesNotSwapIds) {
  const auto preset = scene_preset("nominal");
  SyntheticCamera camera(preset.camera, MarkerFamily::six_ucp(), preset.conditions, preset.clutter);
  MarkerTracker tracker(MarkerFamily::six_ucp(), {1, 2, 3, 4, 5, 6, 7, 8});
  cv::RNG rng(4);
  for (int f = 0; f < 20; ++f) {
    auto robots = robots_at(f / 15.0, 8, preset, 4);
    const bool hidden = f >= 5 && f < 9;
    if (hidden) robots.erase(robots.begin() + 2);  // robot 3 vanishes
    const auto truth = camera.truth(robots);
    const auto found = tracker.process(camera.render(robots, rng));
    EXPECT_EQ(found.size(), hidden ? 7u : 8u) << "frame " << f;
    for (const auto& d : found) {
      const auto it = std::find_if(truth.begin(), truth.end(), [&](const auto& t) { return t.id == d.id; });
      ASSERT_NE(it, truth.end()) << "frame " << f << " reported absent ID " << d.id;
      EXPECT_LT(std::hypot(d.u - it->u, d.v - it->v), 1.0) << "frame " << f << " ID " << d.id;
    }
  }
}

// Tracked frames search only near the markers: no full-frame search once all are found.
TEST(MarkerTracker, TrackedFramesSkipTheFullSearch) {
  const auto preset = scene_preset("nominal");
  SyntheticCamera camera(preset.camera, MarkerFamily::six_ucp(), preset.conditions, preset.clutter);
  MarkerTracker tracker(MarkerFamily::six_ucp(), {1, 2, 3, 4, 5, 6, 7, 8});
  cv::RNG rng(5);
  for (int f = 0; f < 6; ++f) {
    const auto found = tracker.process(camera.render(robots_at(f / 15.0, 8, preset, 5), rng));
    ASSERT_EQ(found.size(), 8u);
    EXPECT_EQ(tracker.last_stats().full_search, f == 0) << "frame " << f;
    if (f > 0) {
      EXPECT_TRUE(std::all_of(found.begin(), found.end(), [](const auto& d) { return d.tracked; }));
    }
  }
}

// Once tracked, markers are re-found from their outlines (no fill of their discs), and
// the result matches what the fill-based path gives.
TEST(MarkerTracker, TrackedFramesUseTheEdgeFit) {
  const auto preset = scene_preset("nominal");
  SyntheticCamera camera(preset.camera, MarkerFamily::six_ucp(), preset.conditions, preset.clutter);
  TrackerConfig without;
  without.use_edge_fit = false;
  MarkerTracker by_edges(MarkerFamily::six_ucp(), {1, 2, 3, 4, 5, 6, 7, 8});
  MarkerTracker by_fill(MarkerFamily::six_ucp(), {1, 2, 3, 4, 5, 6, 7, 8}, without);
  cv::RNG rng(9);
  int edge_fits = 0;
  for (int f = 0; f < 8; ++f) {
    const cv::Mat img = camera.render(robots_at(f / 15.0, 8, preset, 9), rng);
    const auto a = by_edges.process(img);
    const auto b = by_fill.process(img);
    ASSERT_EQ(a.size(), 8u);
    ASSERT_EQ(b.size(), 8u);
    if (f > 0) {
      edge_fits += by_edges.last_stats().edge_fits;
      EXPECT_EQ(by_fill.last_stats().edge_fits, 0);
    }
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].id, b[i].id);
      EXPECT_NEAR(a[i].u, b[i].u, 0.1);
      EXPECT_NEAR(a[i].v, b[i].v, 0.1);
      EXPECT_NEAR(wrap_deg_180(a[i].heading_deg - b[i].heading_deg), 0.0, 2.5);
    }
  }
  EXPECT_GE(edge_fits, 7 * 7);  // nearly every tracked marker of frames 1..7
}

// A marker that jumps further than the edge fit reaches (a dropped frame, a bump) is
// found again by the fill around its prediction, with its ID, in the same frame.
TEST(MarkerTracker, AJumpBeyondTheEdgeFitFallsBackToTheFill) {
  const auto f = MarkerFamily::six_ucp();
  MarkerTracker tracker(f, {3, 6});
  auto frame_with = [&](int x3, int y3) {
    cv::Mat img(240, 320, CV_8UC1, cv::Scalar(185));
    render_marker_topdown(f, 3, 32, 30.0).copyTo(img(cv::Rect(x3, y3, 32, 32)));
    render_marker_topdown(f, 6, 32, 200.0).copyTo(img(cv::Rect(220, 150, 32, 32)));
    return img;
  };
  ASSERT_EQ(tracker.process(frame_with(100, 80)).size(), 2u);
  ASSERT_EQ(tracker.process(frame_with(100, 80)).size(), 2u);
  EXPECT_EQ(tracker.last_stats().edge_fits, 2);
  EXPECT_EQ(tracker.last_stats().fills, 0);
  const auto found = tracker.process(frame_with(109, 86));  // 11 px away from where it was
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].id, 3);
  EXPECT_NEAR(found[0].u, 109 + 15.5, 0.2);
  EXPECT_NEAR(found[0].v, 86 + 15.5, 0.2);
  EXPECT_TRUE(found[0].tracked);
  EXPECT_EQ(tracker.last_stats().edge_fits, 1);  // marker 6 only
  EXPECT_GE(tracker.last_stats().fills, 1);
  EXPECT_FALSE(tracker.last_stats().full_search);
}

// Markers about 24 px across under blur and noise still decode with the right heading.
TEST(MarkerTracker, SmallMarkersUnderBlurAndNoise) {
  const auto f = MarkerFamily::six_ucp();
  cv::RNG rng(6);
  int found = 0;
  double heading_err2 = 0.0;
  for (int id = 1; id <= 8; ++id) {
    for (int k = 0; k < 4; ++k) {
      const double heading = rng.uniform(0.0, 360.0);
      constexpr int kScale = 8;
      cv::Mat big(64 * kScale, 64 * kScale, CV_8UC1, cv::Scalar(185));
      render_marker_topdown(f, id, 24 * kScale, heading, 185.0, 1)
          .copyTo(big(cv::Rect(150, 170, 24 * kScale, 24 * kScale)));
      cv::Mat img, noise(64, 64, CV_16SC1);
      cv::resize(big, img, {64, 64}, 0, 0, cv::INTER_AREA);
      cv::GaussianBlur(img, img, {}, 0.7);
      rng.fill(noise, cv::RNG::NORMAL, 0, 3);
      img.convertTo(img, CV_16S);
      img += noise;
      img.convertTo(img, CV_8U);
      const auto d = detect_markers(img, f, {1, 2, 3, 4, 5, 6, 7, 8});
      if (d.size() == 1 && d[0].id == id) {
        ++found;
        const double err = wrap_deg_180(d[0].heading_deg - heading);
        heading_err2 += err * err;
      }
    }
  }
  EXPECT_GE(found, 31);
  EXPECT_LT(std::sqrt(heading_err2 / std::max(found, 1)), 2.0);
}

// A camera close to the field sees markers hundreds of pixels across.
TEST(MarkerTracker, LargeMarkers) {
  const auto f = MarkerFamily::six_ucp();
  for (int size : {100, 250, 400}) {
    for (int id : {1, 6, 8}) {
      cv::Mat img(size * 3, size * 3, CV_8UC1, cv::Scalar(185));
      render_marker_topdown(f, id, size, 40.0).copyTo(img(cv::Rect(size, size, size, size)));
      cv::GaussianBlur(img, img, {}, 1.0);
      const auto d = detect_markers(img, f, {1, 2, 3, 4, 5, 6, 7, 8});
      ASSERT_EQ(d.size(), 1u) << "size " << size << " id " << id;
      EXPECT_EQ(d[0].id, id);
      EXPECT_NEAR(d[0].u, 1.5 * size - 0.5, 0.2);
      EXPECT_NEAR(wrap_deg_180(d[0].heading_deg - 40.0), 0.0, 0.5);
    }
  }
}

// A noisy sensor must not turn the floor into contrast: the search stays with the
// markers (few candidate blobs) and finds them all.
TEST(MarkerTracker, NoisyFloorDoesNotFloodTheSearch) {
  auto preset = scene_preset("nominal");
  preset.conditions.noise_sigma = 7.0;
  preset.conditions.jpeg_quality = 90;
  SyntheticCamera camera(preset.camera, MarkerFamily::six_ucp(), preset.conditions, preset.clutter);
  MarkerTracker tracker(MarkerFamily::six_ucp(), {1, 2, 3, 4, 5, 6, 7, 8});
  cv::RNG rng(8);
  const auto found = tracker.detect_full_frame(camera.render(robots_at(0.0, 8, preset, 8), rng));
  EXPECT_EQ(found.size(), 8u);
  EXPECT_LE(tracker.last_stats().blobs, 16);
  // Markers, the border tape and a few noise specks; without the noise floor it is
  // thousands of specks.
  EXPECT_LT(tracker.last_stats().fills, 400);
}

// Doubtful blobs are fitted again from their outline: a square fits no ellipse and
// never reaches the decoder.
TEST(MarkerTracker, DoubtfulSquaresAreRefittedAndDropped) {
  cv::Mat img(200, 200, CV_8UC1, cv::Scalar(185));
  cv::rectangle(img, {20, 20, 30, 30}, cv::Scalar(28), cv::FILLED);
  cv::rectangle(img, {120, 120, 24, 24}, cv::Scalar(28), cv::FILLED);
  MarkerTracker tracker(MarkerFamily::six_ucp(), {1, 2, 3, 4, 5, 6, 7, 8});
  EXPECT_TRUE(tracker.detect_full_frame(img).empty());
  EXPECT_GE(tracker.last_stats().refits, 1);
  EXPECT_EQ(tracker.last_stats().refits_kept, 0);
  EXPECT_EQ(tracker.last_stats().blobs, 0);
}

// A marker right at the frame's edge: the edge tiles get thresholds too.
TEST(MarkerTracker, MarkerAtTheFrameEdge) {
  const auto f = MarkerFamily::six_ucp();
  cv::Mat img(120, 160, CV_8UC1, cv::Scalar(185));
  render_marker_topdown(f, 5, 32, 10.0).copyTo(img(cv::Rect(1, 1, 32, 32)));
  render_marker_topdown(f, 2, 32, 200.0).copyTo(img(cv::Rect(160 - 33, 120 - 33, 32, 32)));
  const auto d = detect_markers(img, f, {1, 2, 3, 4, 5, 6, 7, 8});
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].id, 2);
  EXPECT_EQ(d[1].id, 5);
  EXPECT_NEAR(d[1].u, 16.5, 0.2);
}

// Between correlations a tracked marker is spot-checked: its heading follows from the
// key's edges, its score is its last correlation's, and it is correlated again at least
// every full_confirm_interval_frames frames. The heading stays as precise as the
// correlation's.
TEST(MarkerTracker, SpotChecksBetweenCorrelations) {
  const auto preset = scene_preset("nominal");
  SyntheticCamera camera(preset.camera, MarkerFamily::six_ucp(), preset.conditions, preset.clutter);
  TrackerConfig config;
  config.full_confirm_interval_frames = 4;
  MarkerTracker tracker(MarkerFamily::six_ucp(), {1, 2, 3, 4, 5, 6, 7, 8}, config);
  cv::RNG rng(5);
  std::map<int, int> since_correlated;
  std::map<int, double> last_score;
  int spot_checked = 0, correlated = 0;
  for (int f = 0; f < 24; ++f) {
    const auto robots = robots_at(f / 15.0, 8, preset, 5);
    const auto found = tracker.process(camera.render(robots, rng));
    ASSERT_EQ(found.size(), 8u) << "frame " << f;
    std::map<int, MarkerTruth> truth;
    for (const auto& t : camera.truth(robots)) truth[t.id] = t;
    for (const auto& d : found) {
      EXPECT_NEAR(wrap_deg_180(d.heading_deg - truth[d.id].heading_deg), 0.0, 2.5) << "frame " << f << " id " << d.id;
      if (d.spot_checked) {
        ++spot_checked;
        EXPECT_TRUE(d.tracked);
        EXPECT_DOUBLE_EQ(d.score, last_score[d.id]) << "frame " << f << " id " << d.id;
        EXPECT_LT(++since_correlated[d.id], 4) << "frame " << f << " id " << d.id;
      } else {
        ++correlated;
        since_correlated[d.id] = 0;
        last_score[d.id] = d.score;  // what the track keeps (a fresh decode or a confirmation above the old bar)
      }
    }
  }
  EXPECT_GE(spot_checked, 8 * 23 * 3 / 4 - 8);  // most tracked markers, about 3 frames in 4
  EXPECT_GE(correlated, 8 + 8 * 23 / 4 - 8);
}

// A spot check does not keep an ID on a marker that was swapped for another one.
TEST(MarkerTracker, ASwappedMarkerIsDecodedAgain) {
  const auto f = MarkerFamily::six_ucp();
  MarkerTracker tracker(f, {3, 4, 6});
  auto frame_with = [&](int id_there) {
    cv::Mat img(240, 320, CV_8UC1, cv::Scalar(185));
    render_marker_topdown(f, id_there, 32, 30.0).copyTo(img(cv::Rect(100, 80, 32, 32)));
    render_marker_topdown(f, 6, 32, 200.0).copyTo(img(cv::Rect(220, 150, 32, 32)));
    return img;
  };
  for (int i = 0; i < 3; ++i) {
    const auto found = tracker.process(frame_with(3));
    ASSERT_EQ(found.size(), 2u);
    EXPECT_EQ(found[0].id, 3);
  }
  EXPECT_TRUE(tracker.process(frame_with(3))[0].spot_checked);
  const auto found = tracker.process(frame_with(4));
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].id, 4);
  EXPECT_FALSE(found[0].spot_checked);
  EXPECT_EQ(found[1].id, 6);
}

// A marker whose outline stretches from frame to frame (it moves to where the lens or the
// perspective draws it otherwise) keeps being found, and the disc's shape follows it:
// the quick fit keeps the shape only while it still fits, and the whole outline is
// refitted when it does not, or when the code is correlated.
TEST(MarkerTracker, TheShapeFollowsAStretchingMarker) {
  const auto f = MarkerFamily::six_ucp();
  MarkerTracker tracker(f, {3, 6});
  constexpr int kScale = 4;
  auto frame_with = [&](double stretch) {
    cv::Mat big(240 * kScale, 320 * kScale, CV_8UC1, cv::Scalar(185));
    render_marker_topdown(f, 3, 32 * kScale, 30.0, 185.0, 1)
        .copyTo(big(cv::Rect(100 * kScale, 80 * kScale, 32 * kScale, 32 * kScale)));
    render_marker_topdown(f, 6, 32 * kScale, 200.0, 185.0, 1)
        .copyTo(big(cv::Rect(220 * kScale, 150 * kScale, 32 * kScale, 32 * kScale)));
    // Stretched along u about marker 3's centre.
    const double cx = (116.0) * kScale;
    const cv::Matx23d warp(stretch, 0, cx * (1.0 - stretch), 0, 1, 0);
    cv::Mat warped, img;
    cv::warpAffine(big, warped, warp, big.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    cv::resize(warped, img, cv::Size(320, 240), 0, 0, cv::INTER_AREA);
    return img;
  };
  const double disc_radius = 0.78 * 16.0;
  for (int i = 0; i <= 30; ++i) {
    const double stretch = 1.0 + 0.01 * i;  // up to 1.3 wide
    const auto found = tracker.process(frame_with(stretch));
    ASSERT_EQ(found.size(), 2u) << "frame " << i;
    ASSERT_EQ(found[0].id, 3);
    // The outline's axes: stretch * r along u, r along v.
    const cv::Matx22d& s = found[0].disc_shape;
    const double along_u = std::hypot(s(0, 0), s(1, 0)), along_v = std::hypot(s(0, 1), s(1, 1));
    EXPECT_NEAR(along_u / disc_radius, stretch, 0.04) << "frame " << i;
    EXPECT_NEAR(along_v / disc_radius, 1.0, 0.04) << "frame " << i;
    // The heading seen on screen: the forward direction (cos 30, -sin 30) stretched.
    const double expected = std::atan2(std::sin(kPi / 6), stretch * std::cos(kPi / 6)) * 180.0 / kPi;
    EXPECT_NEAR(wrap_deg_180(found[0].heading_deg - expected), 0.0, 1.5) << "frame " << i;
  }
}

// A marker on a robot's dark top 1.6 times as wide as the marker (twice its dark disc's
// width) is found with its ID, at every ID, centred on the top and a quarter of the top's
// radius off its centre, in a full search and when tracked. Centred, the sweep takes the
// top whole and only the search inside it (seeded in its middle) finds the marker.
TEST(MarkerTracker, MarkersOnDarkTopsAreFoundInside) {
  const auto f = MarkerFamily::six_ucp();
  constexpr int kSize = 34;
  for (const double off_centre : {0.0, 0.25}) {
    for (int id = 1; id <= 8; ++id) {
      cv::Mat grey(240, 320, CV_8UC1, cv::Scalar(185));
      const double top_radius = 0.8 * kSize;
      const cv::Point2d top_centre(150.3, 110.6);
      const double angle = 0.7 * id;
      const cv::Point2d marker_centre =
          top_centre + off_centre * top_radius * cv::Point2d(std::cos(angle), std::sin(angle));
      cv::circle(grey, cv::Point(static_cast<int>(top_centre.x * 16), static_cast<int>(top_centre.y * 16)),
                 static_cast<int>(top_radius * 16), cv::Scalar(40), cv::FILLED, cv::LINE_AA, 4);
      const int x0 = static_cast<int>(std::lround(marker_centre.x - kSize / 2.0));
      const int y0 = static_cast<int>(std::lround(marker_centre.y - kSize / 2.0));
      const cv::Rect where(x0, y0, kSize, kSize);
      // The marker's corners outside its white ring take the top's grey.
      render_marker_topdown(f, id, kSize, 30.0 * id, 40.0).copyTo(grey(where));
      cv::GaussianBlur(grey, grey, cv::Size(), 0.8);
      const double u = x0 + kSize / 2.0 - 0.5, v = y0 + kSize / 2.0 - 0.5;
      const std::string what = "id " + std::to_string(id) + " off centre " + std::to_string(off_centre);
      MarkerTracker tracker(f, {id});  // only its ID: the inside search runs only if it is missed
      const auto full = tracker.detect_full_frame(grey);
      ASSERT_EQ(full.size(), 1u) << what;
      EXPECT_EQ(full[0].id, id) << what;
      EXPECT_NEAR(full[0].u, u, 0.3) << what;
      EXPECT_NEAR(full[0].v, v, 0.3) << what;
      // Centred, the marker's hole is the top's centre, and the sweep takes the top whole:
      // only the search inside finds the marker. (A quarter off, the top's centre may lie
      // on a white slice, and the exact fill that follows finds the marker at once.)
      if (off_centre == 0.0) {
        EXPECT_GT(tracker.last_stats().nested_searches, 0) << what << ": the sweep no longer takes the top whole";
      }
      for (int frame = 0; frame < 3; ++frame) {
        const auto tracked = tracker.process(grey);
        ASSERT_EQ(tracked.size(), 1u) << what << " frame " << frame;
        EXPECT_EQ(tracked[0].id, id) << what << " frame " << frame;
      }
    }
  }
}

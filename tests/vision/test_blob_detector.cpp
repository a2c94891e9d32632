#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "vision/blob_detector.hpp"
#include "vision/synthetic_camera.hpp"

using namespace rilbed::vision;

// The centroid is sub-pixel: a marker placed at fractional positions (by rendering it
// larger and resizing with area averaging) is found within 0.1 px.
TEST(BlobDetector, SubPixelCentroid) {
  const auto f = MarkerFamily::six_ucp();
  BlobDetector detector;
  for (double offset : {0.0, 0.25, 0.5, 0.75}) {
    constexpr int kScale = 8;
    const int size_px = 32;
    cv::Mat big(100 * kScale, 100 * kScale, CV_8UC1, cv::Scalar(185));
    const cv::Mat marker = render_marker_topdown(f, 3, size_px * kScale, 30.0, 185.0, 1);
    const int shift = static_cast<int>(offset * kScale);
    marker.copyTo(big(cv::Rect(30 * kScale + shift, 40 * kScale + shift, marker.cols, marker.rows)));
    cv::Mat img;
    cv::resize(big, img, cv::Size(100, 100), 0, 0, cv::INTER_AREA);
    const auto blobs = detector.detect(img);
    ASSERT_EQ(blobs.size(), 1u);
    // The marker covers big pixels [30k+shift, 30k+shift+32k); its centre in small pixel
    // coordinates (centres at integers) is 30 + offset + 16 - 0.5.
    EXPECT_NEAR(blobs[0].u, 30 + offset + size_px / 2.0 - 0.5, 0.1);
    EXPECT_NEAR(blobs[0].v, 40 + offset + size_px / 2.0 - 0.5, 0.1);
    EXPECT_NEAR(blobs[0].disc_diameter_px(), 0.8 * size_px, 0.8);
  }
}

TEST(BlobDetector, RejectsSquaresAndLines) {
  cv::Mat img(200, 200, CV_8UC1, cv::Scalar(185));
  cv::rectangle(img, {20, 20, 30, 30}, cv::Scalar(28), cv::FILLED);   // square
  cv::line(img, {100, 20}, {180, 60}, cv::Scalar(28), 4);             // tape
  cv::rectangle(img, {20, 120, 60, 20}, cv::Scalar(28), cv::FILLED);  // bar
  // The square's outline strays from an ellipse by a chord error of about 0.2: doubtful
  // at most, for the tracker's edge fit to turn down (MarkerTracker test below).
  BlobDetector detector;
  for (const Blob& b : detector.detect(img)) EXPECT_TRUE(b.doubtful) << b.u << ", " << b.v;
  BlobDetectorConfig strict;
  strict.max_doubtful_chord_error = 0.0;
  EXPECT_TRUE(BlobDetector(strict).detect(img).empty());
}

// A disc with a notch in its outline (as heavy blur bleeds a marker's white key slice
// into its black ring) is reported, flagged doubtful, near its true centre.
TEST(BlobDetector, NotchedDiscIsDoubtful) {
  cv::Mat img(100, 100, CV_8UC1, cv::Scalar(185));
  cv::circle(img, {50, 50}, 15, cv::Scalar(28), cv::FILLED, cv::LINE_AA);
  const std::vector<cv::Point> notch = {{50, 50}, {62, 33}, {70, 42}};
  cv::fillPoly(img, std::vector<std::vector<cv::Point>>{notch}, cv::Scalar(185), cv::LINE_AA);
  cv::circle(img, {50, 50}, 4, cv::Scalar(28), cv::FILLED);  // the hole stays dark
  const auto blobs = BlobDetector().detect(img);
  ASSERT_EQ(blobs.size(), 1u);
  EXPECT_TRUE(blobs[0].doubtful);
  EXPECT_NEAR(blobs[0].u, 49.5, 3.0);
  EXPECT_NEAR(blobs[0].v, 49.5, 3.0);
}

TEST(BlobDetector, FindsTiltedEllipses) {
  cv::Mat img(200, 200, CV_8UC1, cv::Scalar(185));
  cv::ellipse(img, {{100.3f, 90.7f}, {40.f, 28.f}, 30.f}, cv::Scalar(28), cv::FILLED, cv::LINE_AA);
  BlobDetector detector;
  const auto blobs = detector.detect(img);
  ASSERT_EQ(blobs.size(), 1u);
  EXPECT_NEAR(blobs[0].u, 100.3, 0.15);
  EXPECT_NEAR(blobs[0].v, 90.7, 0.15);
}

TEST(BlobDetector, RoiSearchFindsOnlyInside) {
  cv::Mat img(200, 300, CV_8UC1, cv::Scalar(185));
  cv::circle(img, {50, 50}, 15, cv::Scalar(28), cv::FILLED, cv::LINE_AA);
  cv::circle(img, {200, 120}, 15, cv::Scalar(28), cv::FILLED, cv::LINE_AA);
  BlobDetector detector;
  EXPECT_EQ(detector.detect(img).size(), 2u);
  const auto inside = detector.detect(img, cv::Rect(150, 70, 100, 100));
  ASSERT_EQ(inside.size(), 1u);
  EXPECT_NEAR(inside[0].u, 200, 0.2);
  // A blob cut by the ROI's border is not reported.
  EXPECT_TRUE(detector.detect(img, cv::Rect(190, 70, 100, 100)).empty());
}

// On a light floor (lighter than 0.7 of the markers' white), the floor beside a
// marker's white ring is darker than the ring but holds no black: it is not searched (no
// fill starts there). On a darker floor it is searched again, and the markers are still
// found.
TEST(BlobDetector, FloorBesideTheWhiteRingIsNotFilled) {
  const auto f = MarkerFamily::six_ucp();
  for (double floor_grey : {120.0, 160.0, 185.0, 200.0}) {
    cv::Mat img(200, 200, CV_8UC1, cv::Scalar(floor_grey));
    render_marker_topdown(f, 2, 32, 10.0, floor_grey).copyTo(img(cv::Rect(50, 60, 32, 32)));
    render_marker_topdown(f, 5, 48, 100.0, floor_grey).copyTo(img(cv::Rect(110, 100, 48, 48)));
    BlobDetector detector;
    detector.take_fill_count();
    EXPECT_EQ(detector.detect(img).size(), 2u) << "floor " << floor_grey;
    const int fills = detector.take_fill_count();
    // Each marker's disc is one fill; a few specks of the rings' anti-aliasing may add
    // more, but not the floor tiles around the rings (there are dozens).
    if (floor_grey > 0.7 * 240) {
      EXPECT_LE(fills, 2) << "floor " << floor_grey;
    }
  }
}

// A marker under heavy glare (its black lighter than 0.7 of its white) is found only
// with the ratio raised.
TEST(BlobDetector, GlareNeedsTheBlackRatioRaised) {
  const auto f = MarkerFamily::six_ucp();
  cv::Mat marker = render_marker_topdown(f, 2, 48, 10.0, 185.0);
  // Compress 28..240 into 170..240: black at about 0.71 of white.
  marker.convertTo(marker, CV_8U, 70.0 / 212.0, 170.0 - 28.0 * 70.0 / 212.0);
  cv::Mat img(120, 120, CV_8UC1, cv::Scalar(185));
  marker.copyTo(img(cv::Rect(30, 30, 48, 48)));
  BlobDetector strict;
  EXPECT_TRUE(strict.detect(img).empty());
  BlobDetectorConfig glare;
  glare.max_black_to_white = 0.9;
  BlobDetector lenient(glare);
  EXPECT_EQ(lenient.detect(img).size(), 1u);
}

// A thin circular floor track around robots is an ellipse-shaped dark region whose row
// extents hold the markers inside it: the markers must still be found on their own
// (the extent sweep does not stand for a region that is mostly light inside).
TEST(BlobDetector, CircularTrackAroundMarkersDoesNotHideThem) {
  const auto f = MarkerFamily::six_ucp();
  cv::Mat img(360, 360, CV_8UC1, cv::Scalar(190));
  cv::circle(img, {180, 180}, 140, cv::Scalar(30), 6, cv::LINE_AA);
  render_marker_topdown(f, 2, 32, 10.0, 190.0).copyTo(img(cv::Rect(120, 150, 32, 32)));
  render_marker_topdown(f, 6, 40, 70.0, 190.0).copyTo(img(cv::Rect(200, 190, 40, 40)));
  BlobDetector detector;
  const auto blobs = detector.detect(img);
  auto found_at = [&](double u, double v) {
    return std::any_of(blobs.begin(), blobs.end(), [&](const Blob& b) { return std::hypot(b.u - u, b.v - v) < 0.5; });
  };
  EXPECT_TRUE(found_at(120 + 15.5, 150 + 15.5));
  EXPECT_TRUE(found_at(200 + 19.5, 190 + 19.5));
}

// A thick dark ring (more than half dark, like a marker's disc) around a marker off its
// centre: the ring's row extents hold the marker too, and only its light centre tells
// the detector to fill it exactly and find the marker on its own.
TEST(BlobDetector, ThickRingAroundAMarkerDoesNotHideIt) {
  const auto f = MarkerFamily::six_ucp();
  cv::Mat img(200, 200, CV_8UC1, cv::Scalar(190));
  cv::circle(img, {100, 100}, 50, cv::Scalar(30), 20, cv::LINE_AA);  // radii 40..60: 0.56 dark
  render_marker_topdown(f, 3, 32, 40.0, 190.0).copyTo(img(cv::Rect(98, 70, 32, 32)));
  BlobDetector detector;
  const auto blobs = detector.detect(img);
  EXPECT_TRUE(
      std::any_of(blobs.begin(), blobs.end(), [](const Blob& b) { return std::hypot(b.u - 113.5, b.v - 85.5) < 0.5; }));
}

// The extent sweep and the run-by-run fill agree on a marker's disc wherever the seed
// falls on it: every seed row of a search finds the same blob.
TEST(BlobDetector, MarkerFoundTheSameFromEverySeedRow) {
  const auto f = MarkerFamily::six_ucp();
  for (int id = 1; id <= 8; ++id) {
    for (double heading : {0.0, 90.0, 200.0, 300.0}) {
      cv::Mat img(100, 100, CV_8UC1, cv::Scalar(185));
      render_marker_topdown(f, id, 48, heading, 185.0).copyTo(img(cv::Rect(26, 26, 48, 48)));
      for (int step : {1, 2, 3, 5}) {
        BlobDetectorConfig config;
        config.seed_row_step = step;
        BlobDetector detector(config);
        const auto blobs = detector.detect(img);
        ASSERT_EQ(blobs.size(), 1u) << "id " << id << " heading " << heading << " step " << step;
        EXPECT_NEAR(blobs[0].u, 49.5, 0.05);
        EXPECT_NEAR(blobs[0].v, 49.5, 0.05);
      }
    }
  }
}

// rays_crossing_bright tells a dark robot top holding a marker (the marker's white ring
// all round inside it) from a marker's own disc (two black slices from hole to rim) and a
// solid dark disc (nothing bright inside), at every heading and at two sizes and blurs.
TEST(BlobDetector, RaysCrossingBrightTellATopHoldingAMarker) {
  const auto f = MarkerFamily::six_ucp();
  for (const int size_px : {28, 40}) {
    for (const double blur_px : {0.0, 1.2}) {
      for (int id = 1; id <= 8; ++id) {
        for (double heading = 0; heading < 360; heading += 37) {
          // A marker on the floor: its own disc.
          cv::Mat floor(160, 160, CV_8UC1, cv::Scalar(185));
          render_marker_topdown(f, id, size_px, heading, 185.0).copyTo(floor(cv::Rect(60, 60, size_px, size_px)));
          // The same marker on a dark top 1.6 times its width.
          cv::Mat top(160, 160, CV_8UC1, cv::Scalar(185));
          const double centre = 60 + size_px / 2.0 - 0.5;
          cv::circle(top, cv::Point(static_cast<int>(centre * 16), static_cast<int>(centre * 16)),
                     static_cast<int>(0.8 * size_px * 16), cv::Scalar(45), cv::FILLED, cv::LINE_AA, 4);
          render_marker_topdown(f, id, size_px, heading, 45.0).copyTo(top(cv::Rect(60, 60, size_px, size_px)));
          if (blur_px > 0) {
            cv::GaussianBlur(floor, floor, cv::Size(), blur_px);
            cv::GaussianBlur(top, top, cv::Size(), blur_px);
          }
          BlobDetector detector;
          const auto own = detector.detect(floor);
          ASSERT_EQ(own.size(), 1u) << "id " << id << " heading " << heading;
          const auto on_top = detector.detect(top);
          const auto top_blob = std::max_element(on_top.begin(), on_top.end(), [](const Blob& a, const Blob& b) {
            return a.filled_area_px < b.filled_area_px;
          });
          ASSERT_NE(top_blob, on_top.end()) << "id " << id << " heading " << heading;
          ASSERT_GT(top_blob->disc_diameter_px(), 1.3 * own[0].disc_diameter_px());
          const std::string where = "size " + std::to_string(size_px) + " blur " + std::to_string(blur_px) + " id " +
                                    std::to_string(id) + " heading " + std::to_string(heading);
          EXPECT_EQ(rays_crossing_bright(top, *top_blob, 16, 0.3, 0.95), 16) << where;
          EXPECT_LE(rays_crossing_bright(floor, own[0], 16, 0.3, 0.95), 14) << where;
        }
      }
    }
  }
  // A solid dark disc: nothing bright inside.
  cv::Mat solid(120, 120, CV_8UC1, cv::Scalar(185));
  cv::circle(solid, {60, 60}, 18, cv::Scalar(40), cv::FILLED, cv::LINE_AA);
  BlobDetector detector;
  const auto blobs = detector.detect(solid);
  ASSERT_EQ(blobs.size(), 1u);
  EXPECT_EQ(rays_crossing_bright(solid, blobs[0], 16, 0.3, 0.95), 0);
}

// The tile statistics (vector kernels: sixteen tiles at a time, then two, then one) give
// the threshold the rule states, on every tile of frames whose width is no multiple of
// the kernels' steps: each 8x8 tile's darkest and brightest pixel over every other row,
// taken over its 3x3 neighbourhood (clamped at the frame's edge), and their rounded-up
// midpoint where the darkest is dark enough against the brightest to be black.
TEST(BlobDetector, LocalThresholdsFollowTheirRuleOnEveryTile) {
  BlobDetectorConfig config;
  config.min_local_contrast = 0;  // no contrast cut: the rule below alone decides
  config.max_noise_contrast = 0;
  config.max_black_to_white = 0.7;
  const int ratio_256 = static_cast<int>(0.7 * 255.0);
  std::mt19937 rng(20261207);
  for (const cv::Size size : {cv::Size(1283, 961), cv::Size(200, 100), cv::Size(131, 37)}) {
    cv::Mat grey(size, CV_8UC1);
    // Blocks of random levels with noise: every tile sees another darkest and brightest.
    std::uniform_int_distribution<int> level(0, 255), noise(-20, 20);
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        const int block = ((y / 5) * 7919 + (x / 6) * 104729) % 251;
        grey.at<std::uint8_t>(y, x) = cv::saturate_cast<std::uint8_t>(block + noise(rng) + (level(rng) < 3 ? -90 : 0));
      }
    }
    BlobDetector detector(config);
    detector.detect(grey);
    const int tiles_x = (size.width + 7) / 8, tiles_y = (size.height + 7) / 8;
    std::vector<int> tile_min(tiles_x * tiles_y, 255), tile_max(tiles_x * tiles_y, 0);
    for (int y = 0; y < size.height; y += 2) {
      for (int x = 0; x < size.width; ++x) {
        const int i = (y / 8) * tiles_x + x / 8;
        tile_min[i] = std::min<int>(tile_min[i], grey.at<std::uint8_t>(y, x));
        tile_max[i] = std::max<int>(tile_max[i], grey.at<std::uint8_t>(y, x));
      }
    }
    int wrong = 0;
    for (int ty = 0; ty < tiles_y; ++ty) {
      for (int tx = 0; tx < tiles_x; ++tx) {
        int mn = 255, mx = 0;
        for (int ny = std::max(0, ty - 1); ny <= std::min(tiles_y - 1, ty + 1); ++ny) {
          for (int nx = std::max(0, tx - 1); nx <= std::min(tiles_x - 1, tx + 1); ++nx) {
            mn = std::min(mn, tile_min[ny * tiles_x + nx]);
            mx = std::max(mx, tile_max[ny * tiles_x + nx]);
          }
        }
        const int expected = mn > ((mx * ratio_256) >> 8) ? 0 : (mn + mx + 1) / 2;
        const int got = detector.local_threshold(std::min(size.width - 1, tx * 8), std::min(size.height - 1, ty * 8));
        if (got != expected) {
          if (++wrong <= 5) ADD_FAILURE() << size << " tile " << tx << "," << ty << ": " << got << " != " << expected;
        }
      }
    }
    EXPECT_EQ(wrong, 0) << size;
  }
}

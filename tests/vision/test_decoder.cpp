#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/geometry.hpp"
#include "vision/blob_detector.hpp"
#include "vision/decoder.hpp"
#include "vision/marker_tracker.hpp"
#include "vision/synthetic_camera.hpp"

using namespace rilbed;
using namespace rilbed::vision;

namespace {
// One marker top-down in the middle of a light canvas.
cv::Mat canvas_with_marker(const MarkerFamily& f, int id, int size_px, double heading_deg) {
  cv::Mat canvas(size_px * 3, size_px * 3, CV_8UC1, cv::Scalar(185));
  render_marker_topdown(f, id, size_px, heading_deg).copyTo(canvas(cv::Rect(size_px, size_px, size_px, size_px)));
  return canvas;
}

// The best-scoring entry of a row of matches.
const CodeMatch& best_match(const std::vector<CodeMatch>& matches) {
  return *std::max_element(matches.begin(), matches.end(),
                           [](const auto& a, const auto& b) { return a.score < b.score; });
}
}  // namespace

// Every ID at many headings decodes to itself with the right heading.
TEST(Decoder, DecodesEveryIdAndHeading) {
  const auto f = MarkerFamily::six_ucp();
  std::vector<int> ids{1, 2, 3, 4, 5, 6, 7, 8};
  Decoder decoder(f, ids);
  BlobDetector detector;
  for (int id : ids) {
    for (double heading = 3.7; heading < 360; heading += 37.1) {
      const cv::Mat img = canvas_with_marker(f, id, 48, heading);
      const auto blobs = detector.detect(img);
      ASSERT_EQ(blobs.size(), 1u) << "id " << id << " heading " << heading;
      const auto signal = decoder.sample(img, blobs[0]);
      ASSERT_TRUE(signal.usable);
      const auto matches = decoder.match_all(signal, blobs[0]);
      const CodeMatch& best = best_match(matches);
      EXPECT_EQ(best.id, id) << "heading " << heading;
      EXPECT_GT(best.score, 0.9);
      EXPECT_NEAR(wrap_deg_180(best.heading_deg - heading), 0.0, 1.0) << "id " << id;
    }
  }
}

TEST(Decoder, LargeFamilyDecodes) {
  const auto f = MarkerFamily::by_name("9ucp");
  std::vector<int> ids;
  for (int id = 1; id <= 64; ++id) ids.push_back(id);
  Decoder decoder(f, ids);
  BlobDetector detector;
  for (int id : {1, 17, 42, 64}) {
    const cv::Mat img = canvas_with_marker(f, id, 64, 100.0);
    const auto blobs = detector.detect(img);
    ASSERT_EQ(blobs.size(), 1u);
    const auto matches = decoder.match_all(decoder.sample(img, blobs[0]), blobs[0]);
    const auto* best = &best_match(matches);
    EXPECT_EQ(best->id, id);
    EXPECT_NEAR(wrap_deg_180(best->heading_deg - 100.0), 0.0, 1.5);
  }
}

// A uniform dark disc with a light surround has no code and must not decode.
TEST(Decoder, RejectsUniformDisc) {
  cv::Mat img(120, 120, CV_8UC1, cv::Scalar(185));
  cv::circle(img, {60, 60}, 20, cv::Scalar(28), cv::FILLED, cv::LINE_AA);
  BlobDetector detector;
  const auto blobs = detector.detect(img);
  ASSERT_EQ(blobs.size(), 1u);  // it is a round blob...
  Decoder decoder(MarkerFamily::six_ucp(), {1, 2, 3});
  EXPECT_FALSE(decoder.sample(img, blobs[0]).usable);  // ...without a code
}

// Cross-covariance against the ideal signal is 1 for a perfect signal, per eq. 4.
TEST(Decoder, ScoreIsNormalised) {
  const auto f = MarkerFamily::six_ucp();
  Decoder decoder(f, {5});
  const cv::Mat img = canvas_with_marker(f, 5, 96, 0.0);
  BlobDetector detector;
  const auto blobs = detector.detect(img);
  ASSERT_EQ(blobs.size(), 1u);
  const auto m = decoder.match_all(decoder.sample(img, blobs[0]), blobs[0]);
  EXPECT_GT(m[0].score, 0.97);
  EXPECT_LE(m[0].score, 1.0);
}

// Hundreds of IDs: decoding by key and bits finds each ID without scoring all 512.
TEST(Decoder, TwelveSliceFamilyDecodesByKeyAndBits) {
  const auto f = MarkerFamily::by_name("12ucp");
  std::vector<int> ids;
  for (int id = 1; id <= f.max_id(); ++id) ids.push_back(id);
  Decoder decoder(f, ids);
  BlobDetector detector;
  for (int id : {1, 2, 100, 255, 256, 377, 511, 512}) {
    const cv::Mat img = canvas_with_marker(f, id, 72, 33.0 + id);
    const auto blobs = detector.detect(img);
    ASSERT_EQ(blobs.size(), 1u);
    const auto matches = decoder.match_all(decoder.sample(img, blobs[0]), blobs[0]);
    const auto* best = &best_match(matches);
    EXPECT_EQ(best->id, id);
    EXPECT_GT(best->score, 0.9);
    EXPECT_NEAR(wrap_deg_180(best->heading_deg - (33.0 + id)), 0.0, 1.5) << "id " << id;
    // Only the code read and its one-bit neighbours are scored.
    const auto scored = std::count_if(matches.begin(), matches.end(), [](const auto& m) { return m.score > -1.0; });
    EXPECT_LE(scored, 10);
  }
}

// A tracked confirmation (match_one with the heading last seen) finds the same peak as a
// search over every lag when the marker turned a little (the lags next to the expected
// one) or further within the window (the climb towards its edge). Turned well beyond
// the window, it finds the true peak or a poor one that no caller accepts (below
// TrackerConfig::min_assign_score; the tracker then decodes the marker afresh), never
// a confident wrong heading.
TEST(Decoder, MatchOneFindsThePeakFromTheHeadingLastSeen) {
  const double min_assign_score = TrackerConfig{}.min_assign_score;
  for (const char* family : {"6ucp", "9ucp"}) {
    const auto f = MarkerFamily::by_name(family);
    const int id = f.max_id() > 8 ? 42 : 6;
    for (int samples : {60, 120}) {
      DecoderConfig config;
      config.samples = samples;
      Decoder decoder(f, {id}, config);
      BlobDetector detector;
      for (double heading : {12.0, 137.5, 301.0}) {
        const cv::Mat img = canvas_with_marker(f, id, 64, heading);
        const auto blobs = detector.detect(img);
        ASSERT_EQ(blobs.size(), 1u);
        const auto signal = decoder.sample(img, blobs[0]);
        ASSERT_TRUE(signal.usable);
        const CodeMatch everywhere = decoder.match_one(signal, blobs[0], id);
        EXPECT_GT(everywhere.score, 0.9) << family << " " << samples << " " << heading;
        EXPECT_NEAR(wrap_deg_180(everywhere.heading_deg - heading), 0.0, 1.5) << family << " " << samples;
        for (double turned : {0.0, 4.0, -4.0, 9.0, -9.0, 13.0, -13.0, 40.0, -90.0, 180.0}) {
          const CodeMatch near = decoder.match_one(signal, blobs[0], id, wrap_deg_360(heading - turned));
          const std::string where =
              std::string(family) + " samples " + std::to_string(samples) + " turned " + std::to_string(turned);
          if (std::abs(turned) < 15.0 || near.score >= min_assign_score) {
            EXPECT_NEAR(near.score, everywhere.score, 1e-9) << where;
            EXPECT_NEAR(wrap_deg_180(near.heading_deg - everywhere.heading_deg), 0.0, 1e-6) << where;
          }
        }
      }
    }
  }
}

// The spot check finds the heading from the key's edges, from a heading last seen a few
// degrees off, as precisely as the correlation does, for every 6UCP ID and a spread of
// 9UCP IDs, from 24 to 64 px across.
TEST(Decoder, SpotCheckFindsTheHeadingFromTheKeyEdges) {
  for (const char* family : {"6ucp", "9ucp"}) {
    const auto f = MarkerFamily::by_name(family);
    std::vector<int> ids;
    if (f.max_id() > 8) {
      ids = {1, 17, 42, 64};
    } else {
      for (int id = 1; id <= 8; ++id) ids.push_back(id);
    }
    Decoder decoder(f, ids);
    BlobDetector detector;
    for (int size : {24, 32, 64}) {
      for (int id : ids) {
        for (double heading : {7.0, 131.3, 250.9}) {
          const cv::Mat img = canvas_with_marker(f, id, size, heading);
          const auto blobs = detector.detect(img);
          ASSERT_EQ(blobs.size(), 1u);
          const auto signal = decoder.sample(img, blobs[0]);
          ASSERT_TRUE(signal.usable);
          // A correlation's key angle is its heading's in the blob's frame too.
          const CodeMatch correlated = decoder.match_one(signal, blobs[0], id);
          EXPECT_NEAR(
              wrap_rad_pi(correlated.key_angle_rad - decoder.key_angle_of_heading(blobs[0], correlated.heading_deg)),
              0.0, 1e-9);
          for (double turned : {0.0, 4.0, -4.0, 8.0, -8.0}) {
            const std::string where = std::string(family) + " size " + std::to_string(size) + " id " +
                                      std::to_string(id) + " heading " + std::to_string(heading) + " turned " +
                                      std::to_string(turned);
            const auto found =
                decoder.spot_check(img, blobs[0], id, decoder.key_angle_of_heading(blobs[0], heading - turned),
                                   signal.black_level, signal.white_level);
            ASSERT_TRUE(found.has_value()) << where;
            EXPECT_NEAR(wrap_deg_180(found->heading_deg - heading), 0.0, size < 32 ? 1.5 : 1.0) << where;
            // The angle it gives is the heading's in the blob's frame.
            EXPECT_NEAR(wrap_rad_pi(found->key_angle_rad - decoder.key_angle_of_heading(blobs[0], found->heading_deg)),
                        0.0, 1e-9)
                << where;
          }
        }
      }
    }
  }
}

// The spot check never passes a marker as another ID, nor a disc without a code; from a
// heading beyond its reach it finds the true one or nothing (the caller correlates).
TEST(Decoder, SpotCheckRefusesOtherIdsAndNonMarkers) {
  const auto f = MarkerFamily::six_ucp();
  const std::vector<int> ids{1, 2, 3, 4, 5, 6, 7, 8};
  Decoder decoder(f, ids);
  BlobDetector detector;
  for (int id : ids) {
    for (double heading : {0.0, 97.0, 222.0}) {
      const cv::Mat img = canvas_with_marker(f, id, 32, heading);
      const auto blobs = detector.detect(img);
      ASSERT_EQ(blobs.size(), 1u);
      const auto signal = decoder.sample(img, blobs[0]);
      for (int other : ids) {
        if (other == id) continue;
        for (double turned : {0.0, 5.0, -5.0}) {
          EXPECT_FALSE(decoder
                           .spot_check(img, blobs[0], other, decoder.key_angle_of_heading(blobs[0], heading - turned),
                                       signal.black_level, signal.white_level)
                           .has_value())
              << "marker " << id << " checked as " << other << " heading " << heading << " turned " << turned;
        }
      }
      for (double turned : {30.0, -45.0, 90.0, 180.0}) {
        const auto found =
            decoder.spot_check(img, blobs[0], id, decoder.key_angle_of_heading(blobs[0], heading - turned),
                               signal.black_level, signal.white_level);
        if (found) {
          EXPECT_NEAR(wrap_deg_180(found->heading_deg - heading), 0.0, 1.0) << "id " << id << " turned " << turned;
        }
      }
    }
  }
  cv::Mat disc(120, 120, CV_8UC1, cv::Scalar(185));
  cv::circle(disc, {60, 60}, 12, cv::Scalar(28), cv::FILLED, cv::LINE_AA);
  const auto blobs = detector.detect(disc);
  ASSERT_EQ(blobs.size(), 1u);
  for (int id : ids) {
    for (double heading : {0.0, 120.0, 240.0}) {
      EXPECT_FALSE(decoder.spot_check(disc, blobs[0], id, decoder.key_angle_of_heading(blobs[0], heading), 28.0, 185.0)
                       .has_value())
          << id;
    }
  }
  EXPECT_THROW(decoder.spot_check(disc, blobs[0], 9, 0.0, 28.0, 185.0), std::invalid_argument);
}

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <cmath>

#include "vision/disc_edge_fit.hpp"
#include "vision/marker_tracker.hpp"
#include "vision/ring_search.hpp"
#include "vision/synthetic_camera.hpp"

using namespace rilbed::vision;

namespace {

const std::vector<int> kIds = {1, 2, 3, 4, 5, 6, 7, 8};
constexpr int kLeft = 37, kTop = 41;  // where one_marker puts the marker's image

// One marker of `size_px` on a light floor, blurred by `blur_px`.
cv::Mat one_marker(int id, int size_px, double heading_deg, double blur_px) {
  cv::Mat img(120, 120, CV_8UC1, cv::Scalar(185));
  render_marker_topdown(MarkerFamily::six_ucp(), id, size_px, heading_deg)
      .copyTo(img(cv::Rect(kLeft, kTop, size_px, size_px)));
  cv::GaussianBlur(img, img, cv::Size(), blur_px);
  return img;
}

cv::Point2d centre_of(int size_px) { return {kLeft + 0.5 * (size_px - 1), kTop + 0.5 * (size_px - 1)}; }
double disc_radius_of(int size_px) { return 0.5 * size_px * MarkerFamily::black_ring_outer_radius; }

// A lobe of the disc: `fraction` of its radius, its centre `offset` of the radius away
// from the disc's centre in direction `angle_rad`; a fill's threshold.
Blob lobe(int size_px, double fraction, double offset, double angle_rad) {
  const cv::Point2d c = centre_of(size_px);
  const double r = disc_radius_of(size_px);
  Blob b;
  b.u = c.x + offset * r * std::cos(angle_rad);
  b.v = c.y + offset * r * std::sin(angle_rad);
  b.shape = cv::Matx22d(fraction * r, 0.0, 0.0, fraction * r);
  b.filled_area_px = CV_PI * fraction * r * fraction * r;
  b.threshold = 110.0;
  b.doubtful = true;
  return b;
}

}  // namespace

TEST(RingSearch, FindsTheWholeDiscFromALobeOfIt) {
  for (int id : kIds) {
    for (int size : {24, 30, 40}) {
      SCOPED_TRACE("ID " + std::to_string(id) + ", " + std::to_string(size) + " px");
      const cv::Mat img = one_marker(id, size, 25.0 * id, 1.6);
      const double r = disc_radius_of(size);
      for (double angle = 0.3; angle < 6.2; angle += 1.4) {
        const Blob fragment = lobe(size, 0.6, 0.35, angle);
        const auto disc = search_ring(img, fragment);
        ASSERT_TRUE(disc.has_value());
        const cv::Point2d c = centre_of(size);
        EXPECT_LT(std::hypot(disc->u - c.x, disc->v - c.y), 0.2 * r);
        EXPECT_NEAR(std::sqrt(cv::determinant(disc->shape)), r, 0.15 * r);
        EXPECT_EQ(disc->threshold, fragment.threshold);
        // Close enough for the strict edge fit, which finds the outline to a fraction of
        // a pixel.
        // At the threshold a fill would use: midway between the marker's darkest and
        // lightest grey.
        double darkest = 0.0, lightest = 0.0;
        cv::minMaxLoc(img(cv::Rect(kLeft, kTop, size, size)), &darkest, &lightest);
        const auto fit = fit_disc_edges(img, *disc, 0.5 * (darkest + lightest));
        ASSERT_TRUE(fit.has_value()) << "lobe towards " << angle << " rad: disc at (" << disc->u - c.x << ", "
                                     << disc->v - c.y << ") from the centre, radius "
                                     << std::sqrt(cv::determinant(disc->shape)) << " of " << r;
        EXPECT_LT(std::hypot(fit->blob.u - c.x, fit->blob.v - c.y), 0.3);
      }
    }
  }
}

TEST(RingSearch, FindsNothingOnAPlainFloorOrBeyondItsSize) {
  cv::Mat floor(120, 120, CV_8UC1, cv::Scalar(150));
  cv::Mat noise(floor.size(), CV_8UC1);
  cv::randn(noise, 0, 4);
  floor += noise;
  EXPECT_FALSE(search_ring(floor, lobe(28, 0.6, 0.3, 1.0)).has_value());

  // A fragment larger than max_fragment_diameter_px is not searched.
  const cv::Mat img = one_marker(3, 60, 10.0, 1.0);
  RingSearchConfig config;
  config.max_fragment_diameter_px = 20.0;
  EXPECT_FALSE(search_ring(img, lobe(60, 0.6, 0.3, 1.0), config).has_value());
  config.max_fragment_diameter_px = 40.0;
  EXPECT_TRUE(search_ring(img, lobe(60, 0.6, 0.3, 1.0), config).has_value());

  // Near the image's edge only circles wholly inside are tried; none is, here.
  EXPECT_FALSE(search_ring(img(cv::Rect(0, 0, 12, 12)).clone(), lobe(28, 0.6, 0.3, 1.0)).has_value());
}

// Markers of 24 px blurred by 1.8-2 px: for some headings the white slices bleed into the
// thin black ring and the fill finds only a lobe of the disc, which no re-fit of its
// outline can grow into the whole. The ring search finds those, and names none wrongly.
TEST(RingSearch, LetsTheTrackerReadSmallBlurredMarkersWhoseDiscBreaksIntoLobes) {
  TrackerConfig without;
  without.use_ring_search = false;
  MarkerTracker plain(MarkerFamily::six_ucp(), kIds, without), searching(MarkerFamily::six_ucp(), kIds);
  int found_with = 0, found_without = 0, searches = 0;
  for (int id : kIds) {
    for (double blur : {1.8, 2.0}) {
      for (double heading : {0.0, 37.0, 75.0, 130.0, 200.0, 290.0}) {
        const cv::Mat img = one_marker(id, 24, heading, blur);
        const cv::Point2d c = centre_of(24);
        for (const bool with : {true, false}) {
          MarkerTracker& tracker = with ? searching : plain;
          const auto found = tracker.detect_full_frame(img);
          ASSERT_LE(found.size(), 1u);
          if (found.empty()) continue;
          EXPECT_EQ(found[0].id, id) << "heading " << heading << ", blur " << blur;
          EXPECT_LT(std::hypot(found[0].u - c.x, found[0].v - c.y), 1.0);
          (with ? found_with : found_without) += found[0].id == id;
          if (with) searches += tracker.last_stats().ring_searches;
        }
      }
    }
  }
  EXPECT_GE(found_with, found_without + 3) << "with " << found_with << ", without " << found_without;
  EXPECT_GT(searches, 0);
}

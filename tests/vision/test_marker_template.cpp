#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <string>

#include "vision/marker_template.hpp"
#include "vision/marker_tracker.hpp"
#include "vision/synthetic_camera.hpp"

using namespace rilbed::vision;

namespace {

const std::vector<int> kIds = {1, 2, 3, 4, 5, 6, 7, 8};

// One marker of `size_px` on a light floor, blurred by `blur_px` (0: sharp).
cv::Mat one_marker(int id, int size_px, double heading_deg, double blur_px) {
  cv::Mat img(120, 120, CV_8UC1, cv::Scalar(185));
  render_marker_topdown(MarkerFamily::six_ucp(), id, size_px, heading_deg)
      .copyTo(img(cv::Rect(37, 41, size_px, size_px)));
  if (blur_px > 0) cv::GaussianBlur(img, img, cv::Size(), blur_px);
  return img;
}

Blob disc_of(const MarkerDetection& d) {
  Blob b;
  b.u = d.u;
  b.v = d.v;
  b.shape = d.disc_shape;
  return b;
}

}  // namespace

TEST(MarkerTemplates, TheMarkerItsCodeSaysMatchesAndNoOtherReading) {
  MarkerTemplates templates(MarkerFamily::six_ucp(), kIds);
  for (int id : kIds) {
    const cv::Mat img = one_marker(id, 40, 30.0 * id, 0.7);
    const auto found = detect_markers(img, MarkerFamily::six_ucp(), kIds);
    ASSERT_EQ(found.size(), 1u) << "ID " << id;
    const Blob disc = disc_of(found[0]);
    const double own = templates.correlation(img, disc, id, found[0].key_angle_rad);
    EXPECT_GE(own, 0.97) << "ID " << id;
    for (int other : kIds) {
      if (other == id) continue;
      EXPECT_LT(templates.correlation(img, disc, other, found[0].key_angle_rad), own) << id << " as " << other;
    }
    // Turned half a turn, ID 1's white key lies where its code is black.
    if (id == 1) {
      EXPECT_LT(templates.correlation(img, disc, id, found[0].key_angle_rad + 3.14159), 0.8);
    }
  }
}

TEST(MarkerTemplates, SmallBlurredMarkersStillMatch) {
  MarkerTemplates templates(MarkerFamily::six_ucp(), kIds);
  for (int id : {1, 5, 8}) {
    const cv::Mat img = one_marker(id, 26, 200.0, 1.5);
    const auto found = detect_markers(img, MarkerFamily::six_ucp(), kIds);
    ASSERT_EQ(found.size(), 1u) << "ID " << id;
    EXPECT_GE(templates.correlation(img, disc_of(found[0]), id, found[0].key_angle_rad),
              templates.config().min_correlation)
        << "ID " << id;
  }
}

// Letters and digits are the floor's commonest lookalikes (an "e" reads as ID 8): at
// no place, size and heading near the glyph does any ID's template reach the bar.
TEST(MarkerTemplates, PrintedLettersAndDigitsDoNotMatchAnywhere) {
  MarkerTemplates templates(MarkerFamily::six_ucp(), kIds);
  for (const std::string glyph : {"e", "o", "a", "3", "7", "8", "6"}) {
    cv::Mat img(80, 80, CV_8UC1, cv::Scalar(200));
    cv::putText(img, glyph, {24, 54}, cv::FONT_HERSHEY_SIMPLEX, 1.1, cv::Scalar(30), 3, cv::LINE_AA);
    cv::GaussianBlur(img, img, cv::Size(), 0.8);
    cv::Mat dark;
    cv::threshold(img, dark, 115, 255, cv::THRESH_BINARY_INV);
    const cv::Rect box = cv::boundingRect(dark);
    double best = -1.0;
    for (double du = -2; du <= 2; du += 1) {
      for (double dv = -2; dv <= 2; dv += 1) {
        for (double scale = 0.8; scale <= 1.25; scale += 0.09) {
          Blob disc;
          disc.u = box.x + box.width / 2.0 - 0.5 + du;
          disc.v = box.y + box.height / 2.0 - 0.5 + dv;
          disc.shape = cv::Matx22d::eye() * (scale * std::max(box.width, box.height) / 2.0);
          for (int id : kIds) {
            for (int k = 0; k < 48; ++k)
              best = std::max(best, templates.correlation(img, disc, id, k * 3.14159265 / 24));
          }
        }
      }
    }
    EXPECT_LT(best, templates.config().min_correlation) << "glyph " << glyph;
    RecordProperty("best_" + glyph, std::to_string(best));
  }
}

TEST(MarkerTemplates, AMarkerCutByTheFrameEdgeIsComparedOnWhatIsInside) {
  MarkerTemplates templates(MarkerFamily::six_ucp(), kIds);
  cv::Mat img(80, 80, CV_8UC1, cv::Scalar(185));
  // Two columns of its white ring fall beyond the frame: centre (13.5, 35.5), R = 16 px,
  // heading 45 degrees.
  render_marker_topdown(MarkerFamily::six_ucp(), 3, 32, 45.0)(cv::Rect(2, 0, 30, 32))
      .copyTo(img(cv::Rect(0, 20, 30, 32)));
  Blob disc;
  disc.u = 13.5;
  disc.v = 35.5;
  disc.shape = cv::Matx22d::eye() * (16.0 * MarkerFamily::black_ring_outer_radius);
  const double key = 45.0 * 3.14159265358979 / 180.0;
  EXPECT_GE(templates.correlation(img, disc, 3, key), 0.95);
  EXPECT_EQ(templates.correlation(img, disc, 9, key), -1.0);  // not one of the IDs
  // Cut into its black ring: too little left to judge.
  disc.u = 8.5;
  EXPECT_EQ(templates.correlation(img, disc, 3, key), -1.0);
}

// A gap in the black ring (a printed "e"'s opening, a light cable across a marker) is a
// local flaw the whole marker's correlation averages away; the ring's sector check is
// what sees it.
TEST(MarkerTemplates, AGapInTheBlackRingFailsTheRingCheck) {
  MarkerTemplates templates(MarkerFamily::six_ucp(), kIds);
  for (int id : {2, 6, 8}) {
    const double heading_deg = 40.0 * id;
    cv::Mat img = one_marker(id, 40, heading_deg, 0.7);
    const auto found = detect_markers(img, MarkerFamily::six_ucp(), kIds);
    ASSERT_EQ(found.size(), 1u) << "ID " << id;
    const Blob disc = disc_of(found[0]);
    const TemplateFit whole = templates.fit(img, disc, id, found[0].key_angle_rad);
    EXPECT_LT(whole.black_ring_misfit, 0.5) << "ID " << id;
    EXPECT_TRUE(templates.matches(img, disc, id, found[0].key_angle_rad)) << "ID " << id;
    // Floor grey over 30 degrees of the ring (radius 0.55-0.78 R of the 20 px radius),
    // opposite the key slice; OpenCV's arcs turn clockwise on screen.
    const cv::Point centre(37 + 20, 41 + 20);
    const double away_deg = -(heading_deg + 180.0);
    cv::ellipse(img, centre, cv::Size(13, 13), 0.0, away_deg - 15.0, away_deg + 15.0, cv::Scalar(185), 5);
    const TemplateFit gapped = templates.fit(img, disc, id, found[0].key_angle_rad);
    // The whole marker still correlates well enough: the correlation alone would pass it.
    EXPECT_GE(gapped.correlation, templates.config().min_correlation) << "ID " << id;
    EXPECT_GT(gapped.black_ring_misfit, templates.config().max_black_ring_misfit) << "ID " << id;
    EXPECT_FALSE(templates.matches(img, disc, id, found[0].key_angle_rad)) << "ID " << id;
  }
}

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

#include "vision/blob_detector.hpp"
#include "vision/disc_edge_fit.hpp"
#include "vision/synthetic_camera.hpp"

using namespace rilbed::vision;

namespace {

constexpr int kScale = 8;

// A 32 px marker at sub-pixel position (u0 + offset, v0 + offset) on a light floor,
// area-sampled (rendered 8x larger and averaged down). Returns the image and sets the
// true centre of the marker.
cv::Mat marker_image(double offset, double heading_deg, cv::Point2d& centre) {
  const auto f = MarkerFamily::six_ucp();
  const int size_px = 32;
  cv::Mat big(120 * kScale, 120 * kScale, CV_8UC1, cv::Scalar(185));
  const cv::Mat marker = render_marker_topdown(f, 3, size_px * kScale, heading_deg, 185.0, 1);
  const int shift = static_cast<int>(std::lround(offset * kScale));
  marker.copyTo(big(cv::Rect(40 * kScale + shift, 44 * kScale + shift, marker.cols, marker.rows)));
  cv::Mat img;
  cv::resize(big, img, cv::Size(120, 120), 0, 0, cv::INTER_AREA);
  centre = {40 + shift / double(kScale) + size_px / 2.0 - 0.5, 44 + shift / double(kScale) + size_px / 2.0 - 0.5};
  return img;
}

// A dark ellipse of axes 15 and 10 px, tilted by 30 degrees, centred at `c` on a light
// floor, area-sampled (a disc seen by a tilted camera).
cv::Mat tilted_ellipse_image(cv::Point2d c) {
  cv::Mat big(200 * kScale, 200 * kScale, CV_8UC1, cv::Scalar(200));
  cv::ellipse(big, {{float(c.x * kScale + 3.5), float(c.y * kScale + 3.5)}, {30.f * kScale, 20.f * kScale}, 30.f},
              cv::Scalar(30), cv::FILLED);
  cv::Mat img;
  cv::resize(big, img, cv::Size(200, 200), 0, 0, cv::INTER_AREA);
  return img;
}

Blob disc_at(cv::Point2d p, double radius_px) {
  Blob b;
  b.u = p.x;
  b.v = p.y;
  b.shape = cv::Matx22d(radius_px, 0, 0, radius_px);
  return b;
}

}  // namespace

// From a prediction off by up to two pixels the fit lands on the true centre, within a
// tenth of a pixel from its 16 crossings (a third of the accuracy goal; the benchmark's
// tracked centres are within 0.03 px RMS), and measures the disc's size and the rings'
// levels.
TEST(DiscEdgeFit, RecoversTheCentreFromAnOffPrediction) {
  for (double offset : {0.0, 0.375, 0.75}) {
    cv::Point2d truth;
    const cv::Mat img = marker_image(offset, 70.0, truth);
    for (cv::Point2d error : {cv::Point2d(0, 0), cv::Point2d(1.5, -1.0), cv::Point2d(-2.0, 1.2)}) {
      const auto fit = fit_disc_edges(img, disc_at(truth + error, 12.0), 110.0);
      ASSERT_TRUE(fit.has_value()) << "offset " << offset << " error " << error;
      EXPECT_NEAR(fit->blob.u, truth.x, 0.1);
      EXPECT_NEAR(fit->blob.v, truth.y, 0.1);
      // The dark disc is 0.78 of the marker's 16 px radius.
      EXPECT_NEAR(std::sqrt(cv::determinant(fit->blob.shape)), 0.78 * 16, 0.4);
      EXPECT_LT(fit->black_level, 60.0);
      EXPECT_GT(fit->white_level, 200.0);
      EXPECT_GT(fit->white_fraction, 0.95);
    }
  }
}

// A marker that moved a little further than the crossings' reach (4 px here; a robot
// speeding up or turning between frames) shows its crossings on one side only; the fit
// estimates the shift from them, fits again from there and lands on the true centre
// without a fill. (Each of these shifts fails without the second fit. Much larger ones
// put the walks inside the code, and the caller's fill takes over.)
TEST(DiscEdgeFit, FollowsADiscBeyondItsReach) {
  cv::Point2d truth;
  const cv::Mat img = marker_image(0.375, 200.0, truth);
  for (cv::Point2d error : {cv::Point2d(4.0, 1.0), cv::Point2d(4.5, 0.5), cv::Point2d(3.0, 3.0), cv::Point2d(0.5, -5.0),
                            cv::Point2d(-5.0, -1.0)}) {
    const auto fit = fit_disc_edges(img, disc_at(truth + error, 12.0), 110.0);
    EXPECT_TRUE(fit.has_value()) << "error " << error;
    if (!fit) continue;
    EXPECT_NEAR(fit->blob.u, truth.x, 0.1) << "error " << error;
    EXPECT_NEAR(fit->blob.v, truth.y, 0.1) << "error " << error;
  }
}

// The fit follows an ellipse (a tilted view) as well as a circle.
TEST(DiscEdgeFit, FitsATiltedEllipse) {
  const cv::Point2d c(100.3, 90.7);
  const cv::Mat img = tilted_ellipse_image(c);
  const auto fit = fit_disc_edges(img, disc_at(c + cv::Point2d(1, 1), 12.5), 115.0);
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(fit->blob.u, c.x, 0.05);
  EXPECT_NEAR(fit->blob.v, c.y, 0.05);
  // Axes 15 and 10 px: the shape's determinant is their product.
  EXPECT_NEAR(cv::determinant(fit->blob.shape), 150.0, 5.0);
}

// A prediction too far off, an empty floor, a square and a marker cut by the image's
// border all give no fit (the caller then falls back to the fill).
TEST(DiscEdgeFit, RefusesWhatIsNotTheDisc) {
  cv::Point2d truth;
  const cv::Mat img = marker_image(0.0, 0.0, truth);
  EXPECT_FALSE(fit_disc_edges(img, disc_at(truth + cv::Point2d(7, 0), 12.0), 110.0).has_value());
  const cv::Mat floor(120, 120, CV_8UC1, cv::Scalar(185));
  EXPECT_FALSE(fit_disc_edges(floor, disc_at({60, 60}, 12.0), 110.0).has_value());
  cv::Mat square(120, 120, CV_8UC1, cv::Scalar(185));
  cv::rectangle(square, {48, 48, 24, 24}, cv::Scalar(28), cv::FILLED);
  EXPECT_FALSE(fit_disc_edges(square, disc_at({59.5, 59.5}, 12.0), 110.0).has_value());
  EXPECT_FALSE(fit_disc_edges(img, disc_at({10, 60}, 12.0), 110.0).has_value());
  // The size may not jump: a disc half the predicted size is not this track's.
  EXPECT_FALSE(fit_disc_edges(img, disc_at(truth, 18.0), 110.0).has_value());
}

// load_disc_area reads the marker's area (at least a byte of every cache line of it)
// and nothing outside the image, whatever the prediction.
TEST(DiscEdgeFit, LoadDiscAreaReadsTheAreaOnly) {
  cv::Mat img(120, 200, CV_8UC1, cv::Scalar(0));
  EXPECT_EQ(load_disc_area(img, disc_at({100, 60}, 12.0)), 0);
  img(cv::Rect(50, 47, 41, 27)).setTo(0x40);  // the rows of the disc at (70, 60), as wide as the fit reads
  img.at<std::uint8_t>(60, 150) = 0x01;       // a pixel far from it
  EXPECT_EQ(load_disc_area(img, disc_at({70, 60}, 12.0)), 0x40);
  EXPECT_EQ(load_disc_area(img, disc_at({100, 100}, 12.0)), 0);  // beside both
  // A marker wider than a cache line reads every line of its rows.
  cv::Mat wide(300, 400, CV_8UC1, cv::Scalar(0));
  wide.at<std::uint8_t>(150, 192) = 0x08;  // inside, on neither end of its row
  EXPECT_EQ(load_disc_area(wide, disc_at({192.5, 150}, 40.0)), 0x08);
  // Predictions at and beyond the image's corners are clipped to it.
  for (cv::Point2d p : {cv::Point2d(0, 0), cv::Point2d(199, 119), cv::Point2d(-50, 30), cv::Point2d(260, 200)}) {
    load_disc_area(img, disc_at(p, 12.0));
    prefetch_disc_area(img, disc_at(p, 12.0));
  }
}

// Keeping the shape, 2 rows and 2 columns find the centre and the size of a disc from a
// prediction off by up to two pixels and by 5 % in size, about as well as the whole
// ellipse's fit; the residual it reports stays small for a disc of the kept shape and
// grows for one whose shape changed (the tracker then fits the whole ellipse).
TEST(DiscEdgeFit, KeepingTheShapeFitsCentreAndSize) {
  DiscEdgeFitConfig quick;
  quick.lines = 2;
  quick.keep_shape = true;
  for (double offset : {0.0, 0.375, 0.75}) {
    cv::Point2d truth;
    const cv::Mat img = marker_image(offset, 40.0, truth);
    // The dark disc of a 32 px marker: radius 0.78 * 16 px.
    const double radius = 0.78 * 16.0;
    for (const cv::Point2d error : {cv::Point2d(0, 0), cv::Point2d(1.5, -1.0), cv::Point2d(-2.0, 0.5)}) {
      for (double size_error : {0.95, 1.0, 1.05}) {
        const auto fit = fit_disc_edges(img, disc_at(truth + error, radius * size_error), 110.0, quick);
        ASSERT_TRUE(fit.has_value()) << offset << " " << error << " " << size_error;
        EXPECT_NEAR(fit->blob.u, truth.x, 0.1) << offset << " " << error << " " << size_error;
        EXPECT_NEAR(fit->blob.v, truth.y, 0.1) << offset << " " << error << " " << size_error;
        EXPECT_NEAR(std::sqrt(cv::determinant(fit->blob.shape)), radius, 0.3);
        // The shape is the prediction's, scaled: still a circle.
        EXPECT_NEAR(fit->blob.shape(0, 1), 0.0, 1e-12);
        EXPECT_NEAR(fit->blob.shape(0, 0), fit->blob.shape(1, 1), 1e-12);
        EXPECT_LT(fit->residual, 0.02);
        EXPECT_GT(fit->black_level, 0.0);
        EXPECT_GT(fit->white_level, fit->black_level + 50.0);
      }
    }
  }
  // An ellipse of axes 15 and 10 px predicted as a circle: the kept shape does not fit
  // it (refused, or a residual the tracker refits on), while the whole fit does.
  const cv::Point2d c(100.3, 90.7);
  const cv::Mat img = tilted_ellipse_image(c);
  const auto kept = fit_disc_edges(img, disc_at(c, 12.2), 115.0, quick);
  EXPECT_TRUE(!kept.has_value() || kept->residual > 0.02);
  const auto whole = fit_disc_edges(img, disc_at(c, 12.2), 115.0);
  ASSERT_TRUE(whole.has_value());
  EXPECT_LT(whole->residual, 0.02);
}

// A light band (a cable) lying diagonally over the lower left of the black ring's edge
// moves the crossings under it inwards: an ellipse through all of them is refused or its
// centre is pulled more than 0.3 px away from the band. Dropping the crossings that lie
// deep inside the ellipse (max_outliers) fits the rest and finds the centre within
// 0.2 px; a clean disc drops none and fits as before. (A band straight along a row or
// column of crossings would cut off a cap that an ellipse squeezed to that side fits as
// well as the disc: no crossing then lies far from it, and none is dropped.)
TEST(DiscEdgeFit, DropsTheCrossingsALightBandCovers) {
  DiscEdgeFitConfig all;
  all.lines = 8;
  DiscEdgeFitConfig trimmed = all;
  trimmed.max_outliers = 8;
  const double radius = 0.78 * 16.0;
  for (double offset : {0.0, 0.375}) {
    cv::Point2d truth;
    cv::Mat img = marker_image(offset, 70.0, truth);
    const auto clean_all = fit_disc_edges(img, disc_at(truth + cv::Point2d(0.5, 0), radius), 110.0, all);
    const auto clean_trimmed = fit_disc_edges(img, disc_at(truth + cv::Point2d(0.5, 0), radius), 110.0, trimmed);
    ASSERT_TRUE(clean_all && clean_trimmed);
    EXPECT_EQ(clean_trimmed->outliers, 0);
    EXPECT_EQ(clean_trimmed->blob.u, clean_all->blob.u);
    EXPECT_EQ(clean_trimmed->blob.v, clean_all->blob.v);

    // The band: 5 px wide, at 45 degrees, its inner edge 3 px inside the disc's
    // outline towards the lower left, across the white ring and the floor beyond.
    const cv::Point2d normal(-std::sqrt(0.5), std::sqrt(0.5)), along(std::sqrt(0.5), std::sqrt(0.5));
    auto at = [&](double out, double length) { return truth + normal * out + along * length; };
    std::vector<cv::Point> band;
    for (const cv::Point2d& p :
         {at(radius - 3.0, -60), at(radius - 3.0, 60), at(radius + 2.0, 60), at(radius + 2.0, -60)})
      band.emplace_back(static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y)));
    cv::fillConvexPoly(img, band, cv::Scalar(235), cv::LINE_AA);
    // Predicted where a fill of what is left would put it: away from the band.
    const Blob bitten = disc_at(truth - normal * 0.8, radius - 0.8);
    const auto through_all = fit_disc_edges(img, bitten, 110.0, all);
    if (through_all) EXPECT_GT(std::hypot(through_all->blob.u - truth.x, through_all->blob.v - truth.y), 0.3);
    const auto fit = fit_disc_edges(img, bitten, 110.0, trimmed);
    ASSERT_TRUE(fit.has_value()) << "offset " << offset;
    EXPECT_GT(fit->outliers, 0);
    EXPECT_NEAR(fit->blob.u, truth.x, 0.2) << "offset " << offset;
    EXPECT_NEAR(fit->blob.v, truth.y, 0.2) << "offset " << offset;
    EXPECT_NEAR(std::sqrt(cv::determinant(fit->blob.shape)), radius, 0.4);
  }
}

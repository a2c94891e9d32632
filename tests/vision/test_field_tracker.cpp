#include <gtest/gtest.h>

#include <cmath>

#include "vision/emulated_camera.hpp"
#include "vision/field_tracker.hpp"

namespace rilbed::vision {
namespace {

TEST(EmulatedCamera, RobotsAreFoundWhereTheyAre) {
  EmulatedOverheadCamera camera(1.5, 1.2, MarkerFamily::six_ucp());
  FieldTracker tracker(MarkerFamily::six_ucp(), {1, 2, 3, 4, 5, 6, 7, 8}, camera.calibration());
  std::vector<SceneMarker> markers;
  for (int i = 0; i < 8; ++i) {
    markers.push_back({i + 1, 0.15 + 0.17 * i, 0.2 + 0.1 * i + 0.03 * (i % 3), deg_to_rad(45.0 * i + 7.0), 0.05});
  }
  // Robots drive 1 cm and turn 3 degrees per frame; every frame finds all of them.
  double heading_sq = 0.0;
  int count = 0;
  for (int frame = 0; frame < 10; ++frame) {
    const cv::Mat image = camera.render(markers);
    ASSERT_EQ(image.size(), camera.calibration().image_size);
    const auto seen = tracker.process(image);
    ASSERT_EQ(seen.size(), 8u) << "frame " << frame;
    for (const FieldObservation& o : seen) {
      const SceneMarker& m = markers[o.id - 1];
      EXPECT_NEAR(o.pose.position_m.x, m.x_m, 0.002) << o.id;
      EXPECT_NEAR(o.pose.position_m.y, m.y_m, 0.002) << o.id;
      const double heading_error_deg = wrap_deg_180(rad_to_deg(o.pose.heading_rad - m.theta_rad));
      EXPECT_NEAR(heading_error_deg, 0.0, 3.0) << o.id;
      heading_sq += heading_error_deg * heading_error_deg;
      ++count;
    }
    for (SceneMarker& m : markers) {
      m.x_m += 0.01 * std::cos(m.theta_rad);
      m.y_m += 0.01 * std::sin(m.theta_rad);
      m.theta_rad += deg_to_rad(3.0);
    }
  }
  EXPECT_LT(std::sqrt(heading_sq / count), 1.0);  // RMS, degrees
}

TEST(EmulatedCamera, FramesOfAnotherSizeAreRefused) {
  EmulatedOverheadCamera camera(1.5, 1.2, MarkerFamily::six_ucp());
  FieldTracker tracker(MarkerFamily::six_ucp(), {1}, camera.calibration());
  EXPECT_THROW(tracker.process(cv::Mat(480, 640, CV_8UC1, cv::Scalar(180))), std::invalid_argument);
  EXPECT_THROW(EmulatedOverheadCamera(0.0, 1.0, MarkerFamily::six_ucp()), std::invalid_argument);
}

TEST(EmulatedCamera, AnEmptyFieldShowsNoRobot) {
  EmulatedOverheadCamera camera(1.5, 1.2, MarkerFamily::six_ucp());
  FieldTracker tracker(MarkerFamily::six_ucp(), {1, 2}, camera.calibration());
  EXPECT_TRUE(tracker.process(camera.render({})).empty());
}

}  // namespace
}  // namespace rilbed::vision

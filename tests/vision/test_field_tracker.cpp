#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

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

// Robots' bodies are rendered beneath their markers (a disc, or an outline that turns with
// the robot), and the markers on them are found as well as on the bare floor.
TEST(EmulatedCamera, RobotsAreRenderedWithTheirBodiesAndStillFound) {
  EmulatedCameraConfig quiet;
  quiet.conditions.noise_sigma = 0.0;
  EmulatedOverheadCamera camera(1.5, 1.2, MarkerFamily::six_ucp(), quiet);
  FieldTracker tracker(MarkerFamily::six_ucp(), {1, 2, 3, 4}, camera.calibration());
  const std::vector<cv::Point2d> square = {{0.035, 0.035}, {-0.035, 0.035}, {-0.035, -0.035}, {0.035, -0.035}};
  const std::vector<cv::Point2d> wedge = {{0.065, 0.0}, {-0.025, 0.035}, {-0.025, -0.035}};
  std::vector<SceneMarker> bare;
  for (int i = 0; i < 4; ++i) bare.push_back({i + 1, 0.3 + 0.3 * i, 0.4 + 0.15 * i, deg_to_rad(50.0 * i + 10.0), 0.05});
  std::vector<SceneMarker> bodies = bare;
  bodies[0].body_radius_m = 0.0275;  // a Khepera
  bodies[1].body_radius_m = 0.035;   // an e-puck
  bodies[2].body_outline_m = square;
  bodies[3].body_outline_m = wedge;
  const cv::Mat without = camera.render(bare), with = camera.render(bodies);
  const auto seen = tracker.process(with);
  ASSERT_EQ(seen.size(), 4u);
  for (const FieldObservation& o : seen) {
    const SceneMarker& m = bodies[static_cast<std::size_t>(o.id - 1)];
    EXPECT_NEAR(o.pose.position_m.x, m.x_m, 0.002) << o.id;
    EXPECT_NEAR(o.pose.position_m.y, m.y_m, 0.002) << o.id;
    EXPECT_NEAR(wrap_deg_180(rad_to_deg(o.pose.heading_rad - m.theta_rad)), 0.0, 3.0) << o.id;
  }
  // The pixels the bodies changed: more for the e-puck than the Khepera, and fewer for the
  // square than for the disc around it (its bounding disc, 49.5 mm).
  cv::Mat changed;
  cv::absdiff(with, without, changed);
  cv::cvtColor(changed, changed, cv::COLOR_BGR2GRAY);
  auto changed_near = [&](const SceneMarker& m) {
    const cv::Mat one = camera.render({m});
    SceneMarker alone = m;
    alone.body_outline_m.clear();
    alone.body_radius_m = 0.0;
    cv::Mat d;
    cv::absdiff(one, camera.render({alone}), d);
    cv::cvtColor(d, d, cv::COLOR_BGR2GRAY);
    return cv::countNonZero(d > 2);
  };
  const int khepera = changed_near(bodies[0]), epuck = changed_near(bodies[1]), sq = changed_near(bodies[2]);
  SceneMarker round = bodies[2];
  round.body_outline_m.clear();
  round.body_radius_m = 0.035 * std::sqrt(2.0);
  EXPECT_GT(khepera, 0);
  EXPECT_GT(epuck, 2 * khepera);
  EXPECT_LT(sq, changed_near(round));
  EXPECT_GT(changed_near(bodies[3]), 0);
  EXPECT_GT(cv::countNonZero(changed > 2), khepera + epuck + sq);
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

#include <gtest/gtest.h>

#include <cmath>

#include "vision/emulated_camera.hpp"
#include "vision/field_tracker.hpp"
#include "vision/vision_settings.hpp"

namespace rilbed::vision {
namespace {

TEST(VisionSettings, EachIsSetByNameWithinItsRange) {
  VisionSettings s;
  EXPECT_EQ(s, vision_settings_of(TrackerConfig{}));
  EXPECT_FALSE(set_vision_setting(s, "contrast", 2.5));
  EXPECT_FALSE(set_vision_setting(s, "threshold", 40));
  EXPECT_FALSE(set_vision_setting(s, "brightness", -20));
  EXPECT_EQ(*vision_setting(s, "contrast"), 2.5);
  EXPECT_EQ(s.threshold, 40);
  EXPECT_EQ(*vision_setting(s, "brightness"), -20);
  const VisionSettings before = s;
  EXPECT_EQ(*set_vision_setting(s, "contrast", 9), "contrast 9 is outside 0.2..5");
  EXPECT_EQ(*set_vision_setting(s, "threshold", 30.5), "threshold 30.5 is not a whole number");
  EXPECT_EQ(*set_vision_setting(s, "min_score", std::nan("")), "min_score nan is outside 0..1");
  const auto unknown = set_vision_setting(s, "gamma", 1);
  ASSERT_TRUE(unknown);
  EXPECT_NE(unknown->find("unknown vision setting 'gamma' (brightness, contrast"), std::string::npos) << *unknown;
  EXPECT_EQ(s, before);
  EXPECT_FALSE(vision_setting(s, "gamma"));
}

TEST(VisionSettings, TheSizeLimitsMustLeaveRoom) {
  VisionSettings s;
  EXPECT_FALSE(check_vision_settings(s));
  s.min_diameter_px = 500;
  EXPECT_EQ(*check_vision_settings(s), "min_diameter_px 500 is not below max_diameter_px 480");
  s.min_diameter_px = 2;
  EXPECT_EQ(*check_vision_settings(s), "min_diameter_px 2 is outside 6..4000");
}

TEST(VisionSettings, TheyMapOntoThePipelinesKnobsAndBack) {
  VisionSettings s;
  s.threshold = 31;
  s.min_diameter_px = 12;
  s.max_diameter_px = 90;
  s.min_score = 0.6;
  const TrackerConfig c = with_vision_settings(TrackerConfig{}, s);
  EXPECT_EQ(c.blobs.min_local_contrast, 31);
  EXPECT_EQ(c.blobs.min_diameter_px, 12);
  EXPECT_EQ(c.blobs.max_diameter_px, 90);
  EXPECT_EQ(c.min_assign_score, 0.6);
  EXPECT_EQ(vision_settings_of(c), s);
  EXPECT_EQ(vision_settings_yaml(s),
            "{brightness: 0, contrast: 1, threshold: 31, min_diameter_px: 12, max_diameter_px: 90, min_score: 0.6}");
}

TEST(VisionSettings, ContrastIsAGainAboutMidGreyAndBrightnessAnOffset) {
  cv::Mat frame(1, 4, CV_8UC1);
  frame.at<std::uint8_t>(0, 0) = 0;
  frame.at<std::uint8_t>(0, 1) = 100;
  frame.at<std::uint8_t>(0, 2) = 128;
  frame.at<std::uint8_t>(0, 3) = 250;
  cv::Mat buffer;
  VisionSettings s;
  EXPECT_EQ(adjust_frame(frame, s, buffer).data, frame.data);  // untouched, not copied
  s.contrast = 2.0;
  s.brightness = 10.0;
  const cv::Mat out = adjust_frame(frame, s, buffer);
  EXPECT_EQ(out.at<std::uint8_t>(0, 0), 0);   // saturated
  EXPECT_EQ(out.at<std::uint8_t>(0, 1), 82);  // 2 * (100 - 128) + 128 + 10
  EXPECT_EQ(out.at<std::uint8_t>(0, 2), 138);
  EXPECT_EQ(out.at<std::uint8_t>(0, 3), 255);  // saturated
  const cv::Mat bgr(2, 2, CV_8UC3, cv::Scalar(100, 128, 0));
  const cv::Mat bgr_out = adjust_frame(bgr, s, buffer);
  EXPECT_EQ(bgr_out.type(), CV_8UC3);
  EXPECT_EQ(bgr_out.at<cv::Vec3b>(1, 1), cv::Vec3b(82, 138, 0));
}

class TunedTracker : public ::testing::Test {
 protected:
  EmulatedOverheadCamera camera{1.5, 1.2, MarkerFamily::six_ucp()};
  FieldTracker tracker{MarkerFamily::six_ucp(), {1, 2, 3}, camera.calibration()};
  std::vector<SceneMarker> markers{{1, 0.3, 0.3, 0.2, 0.05}, {2, 0.8, 0.6, 2.0, 0.05}, {3, 1.2, 0.9, -1.0, 0.05}};
};

TEST_F(TunedTracker, AWashedOutImageIsFoundAgainWithMoreContrast) {
  // Every grey level squeezed to a tenth of its distance from mid-grey: the markers' black
  // and white differ by less than the search's threshold.
  cv::Mat washed;
  camera.render(markers).convertTo(washed, -1, 0.1, 128.0 * 0.9);
  EXPECT_TRUE(tracker.process(washed).empty());
  VisionSettings s = tracker.settings();
  s.contrast = 5.0;
  tracker.set_settings(s);
  EXPECT_EQ(tracker.process(washed).size(), 3u);
  // The detector saw the frame with the contrast applied.
  double lo = 0, hi = 0;
  cv::minMaxLoc(tracker.seen_frame(), &lo, &hi);
  EXPECT_GT(hi - lo, 100.0);
}

TEST_F(TunedTracker, SearchAndScoreLimitsTakeEffectOnTheNextFrame) {
  const cv::Mat image = camera.render(markers);
  ASSERT_EQ(tracker.process(image).size(), 3u);
  const VisionSettings defaults = tracker.settings();
  VisionSettings strict = defaults;
  strict.min_score = 1.0;  // no printed marker decodes perfectly
  tracker.set_settings(strict);
  EXPECT_TRUE(tracker.process(camera.render(markers)).empty());
  VisionSettings small = defaults;
  small.max_diameter_px = 10;  // the markers are ~30 px across
  small.min_diameter_px = 6;
  tracker.set_settings(small);
  EXPECT_TRUE(tracker.process(camera.render(markers)).empty());
  tracker.set_settings(defaults);
  EXPECT_EQ(tracker.process(camera.render(markers)).size(), 3u);
  VisionSettings bad = defaults;
  bad.min_diameter_px = 600;
  EXPECT_THROW(tracker.set_settings(bad), std::invalid_argument);
  EXPECT_EQ(tracker.settings(), defaults);
}

}  // namespace
}  // namespace rilbed::vision

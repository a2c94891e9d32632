#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include "core/geometry.hpp"
#include "vision/synthetic_scene.hpp"

using namespace rilbed;
using namespace rilbed::vision;

// The projected ground truth and the pixel-to-field homography agree (no distortion).
TEST(SyntheticCamera, HomographyInvertsProjection) {
  const auto cam = CameraModel::overhead({1280, 720}, 46.0, {0.75, 0.6}, 1.5, 15.0);
  const cv::Matx33d h = cam.pixel_to_plane_homography();
  for (double x : {0.1, 0.7, 1.4}) {
    for (double y : {0.1, 0.6, 1.1}) {
      const auto px = cam.project({cv::Point3d(x, y, 0)});
      const cv::Vec3d f = h * cv::Vec3d(px[0].x, px[0].y, 1.0);
      EXPECT_NEAR(f[0] / f[2], x, 1e-9);
      EXPECT_NEAR(f[1] / f[2], y, 1e-9);
    }
  }
}

// Looking straight down, field +x is image +u and field +y is image -v, so field and
// screen headings agree.
TEST(SyntheticCamera, OverheadOrientation) {
  const auto cam = CameraModel::overhead({640, 480}, 46.0, {0.75, 0.6}, 1.5, 0.0);
  const auto px = cam.project({cv::Point3d(0.75, 0.6, 0), cv::Point3d(0.85, 0.6, 0), cv::Point3d(0.75, 0.7, 0)});
  EXPECT_NEAR(px[0].x, 319.5, 1e-6);
  EXPECT_NEAR(px[0].y, 239.5, 1e-6);
  EXPECT_GT(px[1].x, px[0].x);
  EXPECT_LT(px[2].y, px[0].y);
  SyntheticCamera camera(cam, MarkerFamily::six_ucp(), {});
  const auto t = camera.truth({{3, 0.75, 0.6, deg_to_rad(30.0), 0.05}});
  EXPECT_NEAR(t[0].heading_deg, 30.0, 1e-3);
  EXPECT_TRUE(t[0].visible);
}

// The rendered marker is where the truth says: its dark disc is centred on (u, v).
TEST(SyntheticCamera, RendersMarkerAtTruth) {
  const auto preset = scene_preset("nominal", {640, 480});
  ImagingConditions clean;
  SyntheticCamera camera(preset.camera, MarkerFamily::six_ucp(), clean);
  cv::RNG rng(1);
  const std::vector<SceneMarker> m{{1, 0.5, 0.5, 0.0, 0.08}};
  const cv::Mat img = camera.render(m, rng);
  const auto t = camera.truth(m);
  // The hole at the centre is black, the key slice (forward = +u) white.
  const cv::Vec3b centre = img.at<cv::Vec3b>(cvRound(t[0].v), cvRound(t[0].u));
  EXPECT_LT(centre[0], 60);
  const cv::Vec3b key = img.at<cv::Vec3b>(cvRound(t[0].v), cvRound(t[0].u + 5));
  EXPECT_GT(key[0], 180);
}

TEST(SyntheticScene, RobotsStayInsideTheField) {
  const auto preset = scene_preset("hard");
  for (double t = 0; t < 60; t += 0.5) {
    for (const auto& r : robots_at(t, 8, preset, 1)) {
      EXPECT_GT(r.x_m, 0.03);
      EXPECT_LT(r.x_m, preset.field_width_m - 0.03);
      EXPECT_GT(r.y_m, 0.03);
      EXPECT_LT(r.y_m, preset.field_height_m - 0.03);
    }
  }
  EXPECT_THROW(scene_preset("foggy"), std::invalid_argument);
}

// The camera's pixels undistorted on a grid and interpolated agree with undistorting each
// pixel exactly, for the strongest lens the stress set draws (k1 = -0.3, tilted 20
// degrees, 40 degrees of view: a wider view would take the corners beyond where that lens
// is one to one): within 1e-4 px everywhere, the corners included.
TEST(SyntheticCamera, InterpolatedUndistortionMatchesTheExactOne) {
  const auto cam = CameraModel::overhead({1280, 960}, 40.0, {2.0, 1.5}, 2.5, 20.0, -0.3);
  const std::vector<cv::Point2d> fast = undistorted_pixels(cam);
  ASSERT_EQ(fast.size(), 1280u * 960u);
  std::vector<cv::Point2d> pixels, exact;
  cv::RNG rng(3);
  for (int i = 0; i < 4000; ++i) pixels.emplace_back(rng.uniform(0, 1280), rng.uniform(0, 960));
  for (const cv::Point2d corner :
       {cv::Point2d(0, 0), cv::Point2d(1279, 0), cv::Point2d(0, 959), cv::Point2d(1279, 959)})
    pixels.push_back(corner);
  cv::undistortPoints(pixels, exact, cam.camera_matrix, cam.distortion, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 40, 1e-10));
  const double f = cam.camera_matrix(0, 0);
  double worst_px = 0.0;
  cv::Point2d worst_at;
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const cv::Point2d& a = fast[static_cast<std::size_t>(pixels[i].y) * 1280 + static_cast<std::size_t>(pixels[i].x)];
    const double e = f * std::hypot(a.x - exact[i].x, a.y - exact[i].y);
    if (e > worst_px) {
      worst_px = e;
      worst_at = pixels[i];
    }
  }
  EXPECT_LT(worst_px, 1e-4) << "at pixel " << worst_at;
}

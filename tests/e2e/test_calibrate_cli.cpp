// End-to-end tests of `rilbed calibrate intrinsics|field`: run the real binary, read
// back what it wrote.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "run_command.hpp"
#include "vision/calibration.hpp"
#include "vision/field_mapping.hpp"
#include "vision/marker_family.hpp"
#include "vision/synthetic_camera.hpp"
#include "vision/synthetic_scene.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

// What OpenCV 4.6's calibration sample prints for left01..left14 with a 9x6 board
// ("RMS error reported by calibrateCamera: 0.409026"); see
// tests/vision/test_calibration.cpp for the command.
constexpr double kOpenCvSampleRmsPx = 0.409026;

const std::string kData = RILBED_OPENCV_DATA_DIR;

// Built by appending: GCC 12 gives a false -Wrestrict for "literal" + std::string.
std::string quoted(const fs::path& p) {
  std::string s(1, '\'');
  s += p.string();
  s += '\'';
  return s;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// ------------------------------------------------------------------ intrinsics

TEST(CalibrateIntrinsicsCli, LeftImagesMatchOpenCvSample) {
  const auto dir = scratch_dir("calib_intrinsics");
  const auto out = dir / "camera.yml";
  const auto r = run_rilbed("calibrate intrinsics --images '" + kData +
                            "/left*.jpg' --board 9x6 --square-mm 25 --out " + quoted(out));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_TRUE(contains(r.out, "RMS reprojection error: 0.409")) << r.out;
  EXPECT_TRUE(contains(r.out, "used: " + kData + "/left01.jpg")) << r.out;
  // left.jpg matches the glob but shows no 9x6 board: skipped with a warning naming it.
  if (fs::exists(kData + "/left.jpg")) {
    EXPECT_TRUE(contains(r.err, kData + "/left.jpg")) << r.err;
  }

  cv::FileStorage f(out.string(), cv::FileStorage::READ);
  ASSERT_TRUE(f.isOpened());
  for (const char* key : {"image_width", "image_height", "camera_matrix", "distortion_coefficients", "rms_px",
                          "board_cols", "board_rows", "square_mm", "images_used"}) {
    EXPECT_FALSE(f[key].empty()) << key;
  }
  EXPECT_NEAR(static_cast<double>(f["rms_px"]), kOpenCvSampleRmsPx, 1e-3);
  EXPECT_EQ(static_cast<int>(f["image_width"]), 640);
  EXPECT_EQ(static_cast<int>(f["image_height"]), 480);
  EXPECT_EQ(static_cast<int>(f["board_cols"]), 9);
  EXPECT_EQ(static_cast<int>(f["board_rows"]), 6);
  EXPECT_EQ(static_cast<double>(f["square_mm"]), 25.0);
  EXPECT_EQ(f["images_used"].size(), 13u);
  cv::Mat k;
  f["camera_matrix"] >> k;
  EXPECT_EQ(k.size(), cv::Size(3, 3));
  fs::remove_all(dir);
}

TEST(CalibrateIntrinsicsCli, FewerThanThreeUsableImagesFail) {
  const auto dir = scratch_dir("calib_few");
  const auto out = dir / "camera.yml";
  const auto r = run_rilbed("calibrate intrinsics --images '" + kData +
                            "/left0[12].jpg' --board 9x6 --square-mm 25 --out " + quoted(out));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(contains(r.err, "only 2 of 2 images are usable")) << r.err;
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(dir);
}

TEST(CalibrateIntrinsicsCli, BadOptionsNameTheInput) {
  const auto dir = scratch_dir("calib_badopt");
  const auto out = quoted(dir / "camera.yml");
  auto r =
      run_rilbed("calibrate intrinsics --images '" + kData + "/left*.jpg' --board 9by6 --square-mm 25 --out " + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(contains(r.err, "--board '9by6'")) << r.err;
  r = run_rilbed("calibrate intrinsics --images '" + kData + "/left*.jpg' --board 9x6 --square-mm -3 --out " + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(contains(r.err, "--square-mm")) << r.err;
  r = run_rilbed("calibrate intrinsics --images '" + (dir / "none*.jpg").string() +
                 "' --board 9x6 --square-mm 25 --out " + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(contains(r.err, (dir / "none*.jpg").string())) << r.err;
  EXPECT_TRUE(contains(r.err, "matches no file")) << r.err;
  fs::remove_all(dir);
}

// ------------------------------------------------------------------ field

// The "hard" preset's camera: tilted 20 degrees with strong barrel distortion, so the
// corner test exercises undistortion.
struct FieldScene {
  vision::ScenePreset preset = vision::scene_preset("hard");
  std::vector<cv::Point2d> corners_px() const {
    const double w = preset.field_width_m, h = preset.field_height_m;
    return preset.camera.project({{0, 0, 0}, {w, 0, 0}, {w, h, 0}, {0, h, 0}});
  }
  /// Writes the camera's true intrinsics as an intrinsics file.
  void write_intrinsics(const fs::path& path) const {
    vision::CameraIntrinsics in;
    in.image_size = preset.camera.image_size;
    in.lens.camera_matrix = preset.camera.camera_matrix;
    const auto& d = preset.camera.distortion;
    in.lens.distortion.assign(d.val, d.val + 5);
    ASSERT_EQ(vision::save_intrinsics(in, path.string()), "");
  }
  /// A frame of the empty field, written as PNG.
  void write_frame(const fs::path& path, const std::vector<vision::SceneMarker>& markers = {}) const {
    const vision::SyntheticCamera camera(preset.camera, vision::MarkerFamily::six_ucp(), preset.conditions,
                                         preset.clutter);
    cv::RNG rng(1);
    ASSERT_TRUE(cv::imwrite(path.string(), camera.render(markers, rng)));
  }
};

std::string corners_arg(const std::vector<cv::Point2d>& corners_px) {
  std::string s;
  for (const auto& c : corners_px) {
    if (!s.empty()) s += ',';
    s += cv::format("%.9f,%.9f", c.x, c.y);
  }
  return s;
}

TEST(CalibrateFieldCli, CornersMapBackToFieldCorners) {
  const auto dir = scratch_dir("calib_field");
  const FieldScene scene;
  scene.write_frame(dir / "frame.png");
  scene.write_intrinsics(dir / "camera.yml");
  const double w = scene.preset.field_width_m, h = scene.preset.field_height_m;
  const auto corners = scene.corners_px();
  const std::string size = cv::format("%.3f,%.3f", w, h);
  for (bool with_intrinsics : {true, false}) {
    const auto out = dir / (with_intrinsics ? "field_lens.yml" : "field_plain.yml");
    const auto r = run_rilbed("calibrate field --image " + quoted(dir / "frame.png") + " --corners " +
                              corners_arg(corners) + " --size-m " + size + " --out " + quoted(out) +
                              (with_intrinsics ? " --intrinsics " + quoted(dir / "camera.yml") : ""));
    ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
    EXPECT_TRUE(contains(r.out, "homography residual: RMS 0.000 mm")) << r.out;
    cv::FileStorage f(out.string(), cv::FileStorage::READ);
    for (const char* key : {"field_width_m", "field_height_m", "homography", "image_width", "image_height"}) {
      EXPECT_FALSE(f[key].empty()) << key;
    }
    EXPECT_EQ(f["camera_matrix"].empty(), !with_intrinsics);
    const auto loaded = vision::load_field_calibration(out.string());
    ASSERT_TRUE(loaded.ok()) << loaded.error;
    const std::vector<Vec2> field_corners_m = {{0, 0}, {w, 0}, {w, h}, {0, h}};
    for (std::size_t i = 0; i < 4; ++i) {
      const Vec2 m = vision::pixel_to_field(*loaded.calibration, corners[i].x, corners[i].y);
      EXPECT_LT((m - field_corners_m[i]).norm(), 0.001) << "corner " << i + 1;
    }
    // With the lens model the whole field maps right, not only the corners.
    const auto centre_px = scene.preset.camera.project({{w / 2, h / 2, 0}})[0];
    const Vec2 centre_m = vision::pixel_to_field(*loaded.calibration, centre_px.x, centre_px.y);
    if (with_intrinsics) {
      EXPECT_LT((centre_m - Vec2{w / 2, h / 2}).norm(), 0.001);
    }
  }
  fs::remove_all(dir);
}

TEST(CalibrateFieldCli, MarkersAtKnownPositions) {
  const auto dir = scratch_dir("calib_markers");
  FieldScene scene;
  scene.preset = vision::scene_preset("nominal");
  std::vector<vision::SceneMarker> markers;
  // Not all on two lines: along a line a homography can absorb a misplaced point.
  const std::vector<Vec2> at_m = {{0.15, 0.15}, {0.75, 0.12}, {1.35, 0.15}, {1.35, 1.05},
                                  {0.75, 1.08}, {0.15, 1.05}, {0.60, 0.55}};
  std::string arg;
  for (std::size_t i = 0; i < at_m.size(); ++i) {
    markers.push_back(
        {static_cast<int>(i + 1), at_m[i].x, at_m[i].y, 0.3 * static_cast<double>(i), scene.preset.marker_diameter_m});
    if (!arg.empty()) arg += ';';
    arg += cv::format("%zu:%.3f,%.3f", i + 1, at_m[i].x, at_m[i].y);
  }
  scene.write_frame(dir / "frame.png", markers);
  scene.write_intrinsics(dir / "camera.yml");
  const auto out = dir / "field.yml";
  const auto r = run_rilbed("calibrate field --image " + quoted(dir / "frame.png") + " --markers '" + arg +
                            "' --size-m 1.5,1.2 --intrinsics " + quoted(dir / "camera.yml") + " --out " + quoted(out));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_TRUE(contains(r.out, "homography residual: RMS")) << r.out;
  const auto loaded = vision::load_field_calibration(out.string());
  ASSERT_TRUE(loaded.ok()) << loaded.error;
  for (const Vec2 p : std::vector<Vec2>{{0.4, 0.6}, {1.1, 0.3}, {0.75, 0.6}}) {
    const auto px = scene.preset.camera.project({{p.x, p.y, 0}})[0];
    const Vec2 m = vision::pixel_to_field(*loaded.calibration, px.x, px.y);
    EXPECT_LT((m - p).norm(), 0.005) << p.x << "," << p.y;
  }

  // Marker 5 said to lie 20 cm from where it is, and marker 8 not on the field at all:
  // RANSAC leaves 5 out, 8 is reported missing, the other six still calibrate.
  const std::string wrong = arg.replace(arg.find("5:0.750,1.080"), 13, "5:0.750,0.880") + ";8:0.5,0.5";
  const auto r2 = run_rilbed("calibrate field --image " + quoted(dir / "frame.png") + " --markers '" + wrong +
                             "' --size-m 1.5,1.2 --intrinsics " + quoted(dir / "camera.yml") + " --out " + quoted(out));
  ASSERT_EQ(r2.exit_code, 0) << r2.out << r2.err;
  EXPECT_TRUE(contains(r2.err, "marker 5 disagrees")) << r2.err;
  EXPECT_TRUE(contains(r2.err, "marker 8 not found")) << r2.err;
  EXPECT_TRUE(contains(r2.out, "over 6 points")) << r2.out;
  fs::remove_all(dir);
}

TEST(CalibrateFieldCli, BadInputIsNamed) {
  const auto dir = scratch_dir("calib_field_bad");
  const FieldScene scene;
  scene.write_frame(dir / "frame.png");
  const std::string frame = quoted(dir / "frame.png");
  const std::string corners = corners_arg(scene.corners_px());
  const std::string out = quoted(dir / "field.yml");
  struct Case {
    std::string args;
    std::string expected;  // part of the error message
  };
  const std::string missing_image = (dir / "missing.png").string();
  const std::string not_yaml = (dir / "not_yaml.yml").string();
  const std::string no_key = (dir / "no_key.yml").string();
  std::ofstream(not_yaml) << "fx = 800\n";
  std::ofstream(no_key) << "%YAML:1.0\n---\nimage_width: 1280\nimage_height: 720\n";
  const std::vector<Case> cases = {
      {"--image '" + missing_image + "' --corners " + corners + " --size-m 1.5,1.2", missing_image},
      {"--image " + frame + " --corners 1,2,3,4,5,6,7 --size-m 1.5,1.2", "--corners '1,2,3,4,5,6,7': expected 8"},
      {"--image " + frame + " --corners " + corners + " --size-m 1.5", "--size-m '1.5'"},
      {"--image " + frame + " --corners " + corners + " --size-m 1.5,-1", "--size-m '1.5,-1'"},
      {"--image " + frame + " --corners " + corners + " --size-m 1.5,1.2 --intrinsics '" + not_yaml + "'", not_yaml},
      {"--image " + frame + " --corners " + corners + " --size-m 1.5,1.2 --intrinsics '" + no_key + "'",
       "missing key 'camera_matrix'"},
      {"--image " + frame + " --corners " + corners + " --size-m 1.5,1.2 --intrinsics '" + kData +
           "/left_intrinsics.yml'",
       "640x480"},
      {"--image " + frame + " --markers '1:0,0;2:1,0;3:1,1' --size-m 1.5,1.2", "at least 4 markers"},
      {"--image " + frame + " --markers '1:0,0;2:1,0;3:1,1;4:x,1' --size-m 1.5,1.2", "'4:x,1'"},
      {"--image " + frame + " --size-m 1.5,1.2", "--corners or --markers"},
  };
  for (const auto& c : cases) {
    const auto r = run_rilbed("calibrate field " + c.args + " --out " + out);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_TRUE(contains(r.err, c.expected)) << c.args << "\nstderr: " << r.err;
    EXPECT_FALSE(fs::exists(dir / "field.yml")) << c.args;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rilbed::e2e

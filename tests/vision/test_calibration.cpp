// Tests of the camera intrinsics calibration and the pixel <-> field mapping.
#include <gtest/gtest.h>
#include <unistd.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "vision/calibration.hpp"
#include "vision/field_mapping.hpp"

namespace rilbed::vision {
namespace {

namespace fs = std::filesystem;

// RMS reprojection error of OpenCV 4.6's own calibration sample on the same images.
// Obtained with (images.xml lists left01..left14 of RILBED_OPENCV_DATA_DIR, sorted;
// there is no left10):
//   g++ -O2 -o calibration /usr/share/doc/opencv-doc/examples/cpp/calibration.cpp $(pkg-config --cflags --libs opencv4)
//   QT_QPA_PLATFORM=offscreen ./calibration -w=9 -h=6 -s=25 -o=out.yml images.xml
// which printed
//   RMS error reported by calibrateCamera: 0.409026
//   Calibration succeeded. avg reprojection error = 0.4090258
// (-s=1, the sample's default square size, prints the same.) Ours reports
// calibrateCamera's value too: 0.40902621, and the same camera matrix to 1e-10 px.
constexpr double kOpenCvSampleRmsPx = 0.409026;

std::vector<std::string> left_images() {
  std::vector<std::string> paths;
  for (int i = 1; i <= 14; ++i) {
    const fs::path p = fs::path(RILBED_OPENCV_DATA_DIR) / cv::format("left%02d.jpg", i);
    if (fs::exists(p)) paths.push_back(p.string());
  }
  return paths;
}

// A scratch directory unique to this process, emptied on creation.
fs::path scratch(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("rilbed_test_calibration_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// ------------------------------------------------------------------ intrinsics

TEST(Intrinsics, MatchesOpenCvSampleOnLeftImages) {
  const auto paths = left_images();
  ASSERT_EQ(paths.size(), 13u) << "expected left01..left14 without left10 in " << RILBED_OPENCV_DATA_DIR;
  const auto result = calibrate_intrinsics(paths, {9, 6, 25.0});
  ASSERT_TRUE(result.ok()) << result.error;
  const auto& in = *result.intrinsics;
  EXPECT_NEAR(in.rms_px, kOpenCvSampleRmsPx, 1e-3);
  EXPECT_EQ(in.image_size, cv::Size(640, 480));
  EXPECT_EQ(in.images_used.size(), 13u);
  for (const auto& report : result.images) EXPECT_TRUE(report.usable) << report.path << ": " << report.reason;
  // The sample's camera matrix, to well within the spread of repeated calibrations.
  EXPECT_NEAR(in.lens.camera_matrix(0, 0), 536.46, 0.05);
  EXPECT_NEAR(in.lens.camera_matrix(1, 1), 536.41, 0.05);
  EXPECT_NEAR(in.lens.camera_matrix(0, 2), 342.37, 0.05);
  EXPECT_NEAR(in.lens.camera_matrix(1, 2), 235.55, 0.05);
  ASSERT_GE(in.lens.distortion.size(), 5u);
  EXPECT_NEAR(in.lens.distortion[0], -0.2786, 1e-3);
  EXPECT_EQ(in.lens.distortion[4], 0.0);  // k3 is fixed, as in the sample
}

TEST(Intrinsics, ReportsUnusableImagesAndSkipsOtherSizes) {
  const auto dir = scratch("unusable");
  const auto paths = left_images();
  ASSERT_GE(paths.size(), 3u);
  write_text(dir / "text.jpg", "not an image\n");
  cv::imwrite((dir / "blank.png").string(), cv::Mat(480, 640, CV_8UC3, cv::Scalar(128, 128, 128)));
  cv::Mat small;
  cv::resize(cv::imread(paths[0]), small, cv::Size(320, 240), 0, 0, cv::INTER_AREA);
  cv::imwrite((dir / "small.png").string(), small);
  const std::vector<std::string> input = {paths[0],
                                          (dir / "text.jpg").string(),
                                          paths[1],
                                          (dir / "missing.jpg").string(),
                                          (dir / "blank.png").string(),
                                          (dir / "small.png").string(),
                                          paths[2]};
  const auto result = calibrate_intrinsics(input, {9, 6, 25.0});
  ASSERT_TRUE(result.ok()) << result.error;
  ASSERT_EQ(result.images.size(), input.size());
  EXPECT_TRUE(result.images[0].usable);
  EXPECT_NE(result.images[1].reason.find("cannot be read"), std::string::npos) << result.images[1].reason;
  EXPECT_TRUE(result.images[2].usable);
  EXPECT_NE(result.images[3].reason.find("does not exist"), std::string::npos) << result.images[3].reason;
  EXPECT_NE(result.images[4].reason.find("no 9x6 chessboard"), std::string::npos) << result.images[4].reason;
  EXPECT_NE(result.images[5].reason.find("320x240"), std::string::npos) << result.images[5].reason;
  EXPECT_NE(result.images[5].reason.find("640x480"), std::string::npos) << result.images[5].reason;
  EXPECT_TRUE(result.images[6].usable);
  EXPECT_EQ(result.intrinsics->images_used, (std::vector<std::string>{paths[0], paths[1], paths[2]}));
  fs::remove_all(dir);
}

TEST(Intrinsics, FailsWithTooFewUsableImages) {
  const auto paths = left_images();
  ASSERT_GE(paths.size(), 2u);
  const auto result = calibrate_intrinsics({paths[0], paths[1], "/nonexistent/x.jpg"}, {9, 6, 25.0});
  EXPECT_FALSE(result.ok());
  EXPECT_FALSE(result.intrinsics);
  EXPECT_NE(result.error.find("only 2 of 3"), std::string::npos) << result.error;
  EXPECT_EQ(result.images.size(), 3u);
}

TEST(Intrinsics, RejectsBadBoard) {
  EXPECT_FALSE(calibrate_intrinsics(left_images(), {2, 6, 25.0}).ok());
  EXPECT_FALSE(calibrate_intrinsics(left_images(), {9, 6, 0.0}).ok());
  EXPECT_FALSE(calibrate_intrinsics(left_images(), {9, 6, -1.0}).ok());
}

CameraIntrinsics example_intrinsics() {
  CameraIntrinsics in;
  in.image_size = {1280, 720};
  in.lens.camera_matrix = cv::Matx33d(812.5, 0, 641.25, 0, 810.125, 359.5, 0, 0, 1);
  in.lens.distortion = {-0.31, 0.12, 0.0011, -0.0007, 0.0};
  in.rms_px = 0.4090258;
  in.board = {9, 6, 24.5};
  in.images_used = {"/a/left01.jpg", "/a/left02.jpg"};
  return in;
}

TEST(Intrinsics, SaveLoadRoundTrip) {
  const auto dir = scratch("intrinsics_yaml");
  const auto path = (dir / "camera.yml").string();
  const auto in = example_intrinsics();
  ASSERT_EQ(save_intrinsics(in, path), "");
  const auto loaded = load_intrinsics(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error;
  const auto& out = *loaded.intrinsics;
  EXPECT_EQ(out.image_size, in.image_size);
  for (int i = 0; i < 9; ++i) EXPECT_EQ(out.lens.camera_matrix.val[i], in.lens.camera_matrix.val[i]);
  EXPECT_EQ(out.lens.distortion, in.lens.distortion);
  EXPECT_EQ(out.rms_px, in.rms_px);
  EXPECT_EQ(out.board.cols, 9);
  EXPECT_EQ(out.board.rows, 6);
  EXPECT_EQ(out.board.square_mm, 24.5);
  EXPECT_EQ(out.images_used, in.images_used);
  // The file carries exactly the documented keys.
  cv::FileStorage f(path, cv::FileStorage::READ);
  for (const char* key : {"image_width", "image_height", "camera_matrix", "distortion_coefficients", "rms_px",
                          "board_cols", "board_rows", "square_mm", "images_used"}) {
    EXPECT_FALSE(f[key].empty()) << key;
  }
  fs::remove_all(dir);
}

TEST(Intrinsics, LoadsTheOpenCvSampleOutputFormat) {
  // OpenCV's left_intrinsics.yml (written by its calibration sample) shares the
  // required keys with ours; the informative keys are simply absent.
  const auto loaded = load_intrinsics(std::string(RILBED_OPENCV_DATA_DIR) + "/left_intrinsics.yml");
  ASSERT_TRUE(loaded.ok()) << loaded.error;
  EXPECT_EQ(loaded.intrinsics->image_size, cv::Size(640, 480));
  EXPECT_NEAR(loaded.intrinsics->lens.camera_matrix(0, 0), 535.9157, 1e-3);
  EXPECT_EQ(loaded.intrinsics->lens.distortion.size(), 5u);
  EXPECT_EQ(loaded.intrinsics->rms_px, 0.0);
}

TEST(Intrinsics, LoadErrorsNameTheFileAndKey) {
  const auto dir = scratch("intrinsics_bad");
  const auto missing = (dir / "missing.yml").string();
  auto r = load_intrinsics(missing);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.error.find(missing), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("does not exist"), std::string::npos) << r.error;

  const auto text = (dir / "text.yml").string();
  write_text(text, "this is not yaml: [ at all\n");
  r = load_intrinsics(text);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.error.find(text), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("not an OpenCV YAML"), std::string::npos) << r.error;

  const auto empty = (dir / "empty.yml").string();
  write_text(empty, "");
  r = load_intrinsics(empty);
  EXPECT_NE(r.error.find("empty"), std::string::npos) << r.error;

  r = load_intrinsics(dir.string());
  EXPECT_NE(r.error.find("directory"), std::string::npos) << r.error;

  const auto no_matrix = (dir / "no_matrix.yml").string();
  write_text(no_matrix, "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n");
  r = load_intrinsics(no_matrix);
  EXPECT_NE(r.error.find(no_matrix), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("missing key 'camera_matrix'"), std::string::npos) << r.error;

  const auto bad_matrix = (dir / "bad_matrix.yml").string();
  write_text(bad_matrix,
             "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n"
             "camera_matrix: !!opencv-matrix\n  rows: 2\n  cols: 2\n  dt: d\n  data: [1, 0, 0, 1]\n"
             "distortion_coefficients: !!opencv-matrix\n  rows: 5\n  cols: 1\n  dt: d\n  data: [0, 0, 0, 0, 0]\n");
  r = load_intrinsics(bad_matrix);
  EXPECT_NE(r.error.find("'camera_matrix' must be a 3x3"), std::string::npos) << r.error;

  const auto bad_width = (dir / "bad_width.yml").string();
  write_text(bad_width, "%YAML:1.0\n---\nimage_width: wide\nimage_height: 480\n");
  r = load_intrinsics(bad_width);
  EXPECT_NE(r.error.find("'image_width' must be an integer"), std::string::npos) << r.error;
  fs::remove_all(dir);
}

// ------------------------------------------------------------------ field mapping

// A simulated overhead camera above a 2 m x 1.5 m field, tilted so that perspective
// matters, with strong barrel distortion.
struct SimulatedCamera {
  cv::Matx33d k{800, 0, 640, 0, 805, 360, 0, 0, 1};
  std::vector<double> distortion{-0.30, 0.10, 0.001, -0.0005, 0.0};
  cv::Vec3d rvec;
  cv::Vec3d tvec;
  cv::Size image_size{1280, 720};
  double width_m = 2.0;
  double height_m = 1.5;

  SimulatedCamera() {
    // Looking straight down: field x -> camera x (image right), field y -> camera -y
    // (image up), field z -> camera -z. Then tilt a little about two axes.
    const cv::Matx33d down(1, 0, 0, 0, -1, 0, 0, 0, -1);
    cv::Matx33d tilt;
    cv::Rodrigues(cv::Vec3d(0.12, -0.08, 0.25), tilt);
    const cv::Matx33d r = tilt * down;
    cv::Rodrigues(r, rvec);
    const cv::Vec3d centre_m(1.0, 0.75, 2.3);
    tvec = -(r * centre_m);
  }

  Vec2 project(Vec2 field_m) const {
    std::vector<cv::Point2d> px;
    cv::projectPoints(std::vector<cv::Point3d>{{field_m.x, field_m.y, 0.0}}, rvec, tvec, cv::Mat(k), distortion, px);
    return {px[0].x, px[0].y};
  }
  LensModel lens() const { return {k, distortion}; }
  std::array<Vec2, 4> corners_px() const {
    return {project({0, 0}), project({width_m, 0}), project({width_m, height_m}), project({0, height_m})};
  }
};

std::vector<Vec2> grid_points(double width_m, double height_m) {
  std::vector<Vec2> points;
  for (double x = 0.0; x <= width_m + 1e-9; x += width_m / 7) {
    for (double y = 0.0; y <= height_m + 1e-9; y += height_m / 5) points.push_back({x, y});
  }
  return points;
}

TEST(FieldMapping, CornersRoundTripWithDistortion) {
  const SimulatedCamera cam;
  const auto result = field_from_corners(cam.corners_px(), cam.width_m, cam.height_m, cam.image_size, cam.lens());
  ASSERT_TRUE(result.ok()) << result.error;
  EXPECT_LT(result.residual_rms_mm, 1e-6);
  EXPECT_FALSE(result.mirrored);
  const auto& cal = *result.calibration;
  for (const Vec2 f : grid_points(cam.width_m, cam.height_m)) {
    const Vec2 px = cam.project(f);
    ASSERT_GT(px.x, 0);  // the simulated field stays inside the image
    ASSERT_LT(px.y, cam.image_size.height);
    const Vec2 back_m = pixel_to_field(cal, px.x, px.y);
    EXPECT_NEAR(back_m.x, f.x, 1e-6) << "at " << f.x << "," << f.y;
    EXPECT_NEAR(back_m.y, f.y, 1e-6) << "at " << f.x << "," << f.y;
    const Vec2 again_px = field_to_pixel(cal, f.x, f.y);
    EXPECT_NEAR(again_px.x, px.x, 1e-6);
    EXPECT_NEAR(again_px.y, px.y, 1e-6);
  }
}

TEST(FieldMapping, IgnoringDistortionIsMeasurablyWrong) {
  // Guards the test above: the distortion is strong enough to matter.
  const SimulatedCamera cam;
  const auto result = field_from_corners(cam.corners_px(), cam.width_m, cam.height_m, cam.image_size);
  ASSERT_TRUE(result.ok()) << result.error;
  const Vec2 px = cam.project({1.0, 0.75});
  const Vec2 m = pixel_to_field(*result.calibration, px.x, px.y);
  EXPECT_GT((m - Vec2{1.0, 0.75}).norm(), 0.01);
}

TEST(FieldMapping, CorrespondencesRejectAMisplacedMarker) {
  const SimulatedCamera cam;
  std::vector<PointCorrespondence> points;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise_px(0.0, 0.3);
  const std::vector<Vec2> field = {{0.2, 0.2}, {1.0, 0.1}, {1.8, 0.3}, {1.7, 1.3}, {1.0, 1.4}, {0.3, 1.2}, {0.9, 0.8}};
  for (std::size_t i = 0; i < field.size(); ++i) {
    const Vec2 px = cam.project(field[i]);
    points.push_back({{px.x + noise_px(rng), px.y + noise_px(rng)}, field[i], static_cast<int>(i + 1)});
  }
  points[4].field_m.x += 0.25;  // marker 5 lies 25 cm away from where the user says
  const auto result = field_from_correspondences(points, cam.width_m, cam.height_m, cam.image_size, cam.lens());
  ASSERT_TRUE(result.ok()) << result.error;
  EXPECT_EQ(result.outlier_labels, std::vector<int>{5});
  EXPECT_LT(result.residual_rms_mm, 3.0);  // 0.3 px of noise is about 1 mm here
  EXPECT_GT(result.residual_rms_mm, 0.0);
  const Vec2 px = cam.project({1.5, 1.0});
  const Vec2 m = pixel_to_field(*result.calibration, px.x, px.y);
  EXPECT_NEAR(m.x, 1.5, 0.005);
  EXPECT_NEAR(m.y, 1.0, 0.005);
}

TEST(FieldMapping, FourCorrespondencesFitExactly) {
  const SimulatedCamera cam;
  std::vector<PointCorrespondence> points;
  for (const Vec2 f : std::vector<Vec2>{{0.3, 0.2}, {1.6, 0.25}, {1.5, 1.2}, {0.4, 1.1}}) {
    points.push_back({cam.project(f), f, 0});
  }
  const auto result = field_from_correspondences(points, cam.width_m, cam.height_m, cam.image_size, cam.lens());
  ASSERT_TRUE(result.ok()) << result.error;
  EXPECT_LT(result.residual_max_mm, 1e-6);
  const Vec2 m = pixel_to_field(*result.calibration, cam.project({2.0, 1.5}).x, cam.project({2.0, 1.5}).y);
  EXPECT_NEAR(m.x, 2.0, 1e-6);
  EXPECT_NEAR(m.y, 1.5, 1e-6);
}

TEST(FieldMapping, RejectsDegenerateInput) {
  const cv::Size size(640, 480);
  // Corners 3 and 4 swapped: the quadrilateral crosses itself.
  auto r = field_from_corners({Vec2{100, 400}, Vec2{500, 400}, Vec2{100, 100}, Vec2{500, 100}}, 2, 1.5, size);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.error.find("convex"), std::string::npos) << r.error;
  // Three corners on a line.
  r = field_from_corners({Vec2{100, 400}, Vec2{300, 400}, Vec2{500, 400}, Vec2{100, 100}}, 2, 1.5, size);
  EXPECT_FALSE(r.ok());
  r = field_from_corners({Vec2{100, 400}, Vec2{500, 400}, Vec2{500, 100}, Vec2{100, 100}}, 0, 1.5, size);
  EXPECT_NE(r.error.find("field size"), std::string::npos) << r.error;
  r = field_from_corners({Vec2{100, 400}, Vec2{500, 400}, Vec2{500, 100}, Vec2{100, 100}}, 2, 1.5, {0, 0});
  EXPECT_NE(r.error.find("image size"), std::string::npos) << r.error;
  r = field_from_correspondences({{{1, 2}, {0, 0}, 1}, {{5, 2}, {1, 0}, 2}, {{5, 9}, {1, 1}, 3}}, 2, 1.5, size);
  EXPECT_NE(r.error.find("at least 4"), std::string::npos) << r.error;
  std::vector<PointCorrespondence> collinear;
  for (int i = 0; i < 6; ++i) collinear.push_back({{100.0 + 50 * i, 200.0}, {0.2 * i, 0.5}, i});
  EXPECT_FALSE(field_from_correspondences(collinear, 2, 1.5, size).ok());
  LensModel bad_lens;
  bad_lens.camera_matrix(0, 0) = -1;
  r = field_from_corners({Vec2{100, 400}, Vec2{500, 400}, Vec2{500, 100}, Vec2{100, 100}}, 2, 1.5, size, bad_lens);
  EXPECT_NE(r.error.find("intrinsics"), std::string::npos) << r.error;
}

TEST(FieldMapping, FlagsAMirroredCornerOrder) {
  // The corners given clockwise on screen: still convex, but a mirror image of the field.
  const auto r =
      field_from_corners({Vec2{100, 400}, Vec2{100, 100}, Vec2{500, 100}, Vec2{500, 400}}, 2, 1.5, cv::Size(640, 480));
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_TRUE(r.mirrored);
}

// Heading conversion on affine mappings whose answers can be worked out by hand.
TEST(FieldMapping, HeadingOnUprightImage) {
  // x = u / 100, y = (300 - v) / 100: the usual overhead view, so screen angles are
  // field angles.
  const auto r = field_from_corners({Vec2{0, 300}, Vec2{400, 300}, Vec2{400, 0}, Vec2{0, 0}}, 4, 3, {400, 300});
  ASSERT_TRUE(r.ok()) << r.error;
  for (double h : {0.0, 30.0, 90.0, 135.0, 270.0, 359.0}) {
    EXPECT_NEAR(image_heading_to_field_deg(*r.calibration, 120, 80, h), h, 1e-6) << h;
  }
}

TEST(FieldMapping, HeadingOnRotatedImage) {
  // The camera is turned by 90 degrees: x = v / 100, y = u / 100. Corner (0,0) is at
  // pixel (0,0), (4,0) at v = 400, (4,3) at (300,400), (0,3) at u = 300.
  // Screen heading 0 (towards +u) is field +y: 90 degrees. Screen heading 90 (up the
  // screen, -v) is field -x: 180. In general theta = heading + 90.
  const auto r = field_from_corners({Vec2{0, 0}, Vec2{0, 400}, Vec2{300, 400}, Vec2{300, 0}}, 4, 3, {300, 400});
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_FALSE(r.mirrored);
  const auto& cal = *r.calibration;
  EXPECT_NEAR(pixel_to_field(cal, 120, 250).x, 2.5, 1e-9);
  EXPECT_NEAR(pixel_to_field(cal, 120, 250).y, 1.2, 1e-9);
  EXPECT_NEAR(image_heading_to_field_deg(cal, 120, 250, 0.0), 90.0, 1e-6);
  EXPECT_NEAR(image_heading_to_field_deg(cal, 120, 250, 90.0), 180.0, 1e-6);
  EXPECT_NEAR(image_heading_to_field_deg(cal, 120, 250, 45.0), 135.0, 1e-6);
  EXPECT_NEAR(image_heading_to_field_deg(cal, 120, 250, 300.0), 30.0, 1e-6);
}

TEST(FieldMapping, HeadingOnMirroredImage) {
  // A mirror view: x = u / 100, y = v / 100 (v grows downwards on screen but y grows
  // upwards on the field). A screen heading h points along (cos h, -sin h) in (u, v),
  // hence along (cos h, -sin h) in (x, y): theta = 360 - h.
  const auto r = field_from_corners({Vec2{0, 0}, Vec2{400, 0}, Vec2{400, 300}, Vec2{0, 300}}, 4, 3, {400, 300});
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_TRUE(r.mirrored);
  EXPECT_NEAR(image_heading_to_field_deg(*r.calibration, 200, 100, 30.0), 330.0, 1e-6);
  EXPECT_NEAR(image_heading_to_field_deg(*r.calibration, 200, 100, 90.0), 270.0, 1e-6);
  EXPECT_NEAR(image_heading_to_field_deg(*r.calibration, 200, 100, 0.0), 0.0, 1e-6);
}

TEST(FieldMapping, HeadingFollowsPerspectiveAndDistortion) {
  // The heading of a step between two projected field points, converted, is the
  // field direction of that step.
  const SimulatedCamera cam;
  const auto r = field_from_corners(cam.corners_px(), cam.width_m, cam.height_m, cam.image_size, cam.lens());
  ASSERT_TRUE(r.ok()) << r.error;
  for (double theta : {0.0, 60.0, 135.0, 250.0}) {
    const Vec2 from_m{0.3, 1.3};
    const Vec2 to_m = from_m + Vec2{std::cos(deg_to_rad(theta)), std::sin(deg_to_rad(theta))} * 1e-4;
    const Vec2 a = cam.project(from_m), b = cam.project(to_m);
    const double heading = wrap_deg_360(rad_to_deg(std::atan2(-(b.y - a.y), b.x - a.x)));
    const double got = image_heading_to_field_deg(*r.calibration, a.x, a.y, heading);
    EXPECT_NEAR(wrap_deg_180(got - theta), 0.0, 0.01) << theta;
  }
}

FieldCalibration example_field(bool with_lens) {
  const SimulatedCamera cam;
  auto r = field_from_corners(cam.corners_px(), cam.width_m, cam.height_m, cam.image_size,
                              with_lens ? std::optional<LensModel>(cam.lens()) : std::nullopt);
  EXPECT_TRUE(r.ok()) << r.error;
  return *r.calibration;
}

void expect_same(const FieldCalibration& a, const FieldCalibration& b) {
  EXPECT_EQ(a.width_m, b.width_m);
  EXPECT_EQ(a.height_m, b.height_m);
  for (int i = 0; i < 9; ++i) EXPECT_EQ(a.homography.val[i], b.homography.val[i]);
  EXPECT_EQ(a.image_size, b.image_size);
  ASSERT_EQ(a.lens.has_value(), b.lens.has_value());
  if (a.lens) {
    for (int i = 0; i < 9; ++i) EXPECT_EQ(a.lens->camera_matrix.val[i], b.lens->camera_matrix.val[i]);
    EXPECT_EQ(a.lens->distortion, b.lens->distortion);
  }
}

TEST(FieldMapping, SaveLoadRoundTrip) {
  const auto dir = scratch("field_yaml");
  for (bool with_lens : {false, true}) {
    const auto path = (dir / (with_lens ? "lens.yml" : "plain.yml")).string();
    const auto cal = example_field(with_lens);
    ASSERT_EQ(save_field_calibration(cal, path), "");
    const auto loaded = load_field_calibration(path);
    ASSERT_TRUE(loaded.ok()) << loaded.error;
    expect_same(cal, *loaded.calibration);
    cv::FileStorage f(path, cv::FileStorage::READ);
    for (const char* key : {"field_width_m", "field_height_m", "homography", "image_width", "image_height"}) {
      EXPECT_FALSE(f[key].empty()) << key;
    }
    EXPECT_EQ(f["camera_matrix"].empty(), !with_lens);
    EXPECT_EQ(f["distortion_coefficients"].empty(), !with_lens);
  }
  fs::remove_all(dir);
}

TEST(FieldMapping, LoadErrorsNameTheFileAndKey) {
  const auto dir = scratch("field_bad");
  const auto missing = (dir / "missing.yml").string();
  auto r = load_field_calibration(missing);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.error.find(missing), std::string::npos) << r.error;

  const auto png = (dir / "image.yml").string();
  cv::imwrite((dir / "image.png").string(), cv::Mat(10, 10, CV_8UC1, cv::Scalar(0)));
  fs::rename(dir / "image.png", png);
  r = load_field_calibration(png);
  EXPECT_NE(r.error.find(png), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("not an OpenCV YAML"), std::string::npos) << r.error;

  // A good file with one key taken out or spoilt at a time.
  const auto good = (dir / "good.yml").string();
  ASSERT_EQ(save_field_calibration(example_field(true), good), "");
  const std::string text = read_text(good);
  ASSERT_FALSE(text.empty());
  auto without = [&](const std::string& key) {
    // Drops the key's line and, for a matrix, its indented body.
    std::istringstream in(text);
    std::string line, out;
    bool dropping = false;
    while (std::getline(in, line)) {
      if (line.rfind(key + ":", 0) == 0) {
        dropping = true;
        continue;
      }
      if (dropping && line.rfind(" ", 0) == 0) continue;
      dropping = false;
      out += line + "\n";
    }
    return out;
  };
  for (const char* key : {"field_width_m", "homography", "image_height", "distortion_coefficients"}) {
    const auto path = (dir / (std::string("no_") + key + ".yml")).string();
    write_text(path, without(key));
    r = load_field_calibration(path);
    EXPECT_FALSE(r.ok()) << key;
    EXPECT_NE(r.error.find(path), std::string::npos) << r.error;
    EXPECT_NE(r.error.find(std::string("missing key '") + key + "'"), std::string::npos) << r.error;
  }
  const auto negative = (dir / "negative.yml").string();
  write_text(negative, without("field_height_m") + "field_height_m: -1.5\n");
  r = load_field_calibration(negative);
  EXPECT_NE(r.error.find("'field_height_m' must be positive"), std::string::npos) << r.error;

  const auto singular = (dir / "singular.yml").string();
  write_text(singular, without("homography") +
                           "homography: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
                           "  data: [1, 2, 3, 2, 4, 6, 0, 0, 1]\n");
  r = load_field_calibration(singular);
  EXPECT_NE(r.error.find("'homography'"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("singular"), std::string::npos) << r.error;

  const auto wrong_shape = (dir / "wrong_shape.yml").string();
  write_text(wrong_shape, without("homography") +
                              "homography: !!opencv-matrix\n  rows: 2\n  cols: 3\n  dt: d\n"
                              "  data: [1, 0, 0, 0, 1, 0]\n");
  r = load_field_calibration(wrong_shape);
  EXPECT_NE(r.error.find("'homography' must be a 3x3"), std::string::npos) << r.error;

  const auto scalar = (dir / "scalar.yml").string();
  write_text(scalar, without("homography") + "homography: 7\n");
  r = load_field_calibration(scalar);
  EXPECT_NE(r.error.find("'homography' must be a 3x3"), std::string::npos) << r.error;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rilbed::vision

#include "vision/calibration.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <system_error>

namespace rilbed::vision {
namespace {

// ---- settings of OpenCV's calibration sample (samples/cpp/calibration.cpp, 4.6) -------
// Kept identical so that our RMS equals the sample's on the same images.

// findChessboardCorners flags the sample passes.
constexpr int kChessboardFlags = cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_FAST_CHECK | cv::CALIB_CB_NORMALIZE_IMAGE;
// cornerSubPix half window: the sample's -ws default of 11 (it passes Size(11, 11)).
constexpr int kSubPixHalfWindowPx = 11;
// cornerSubPix stop: 30 iterations or a move below 1e-4 px, as in the sample.
const cv::TermCriteria kSubPixCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.0001);
// calibrateCamera flags with the sample's defaults (no -zt, -a, -p): k3 fixed at 0,
// LU decomposition.
constexpr int kCalibrateFlags = cv::CALIB_FIX_K3 | cv::CALIB_USE_LU;
// The sample starts from an 8-coefficient zero vector; calibrateCamera fixes k4..k6
// without CALIB_RATIONAL_MODEL, but the vector length still selects its code path.
constexpr int kInitialDistortionCount = 8;

std::string size_text(cv::Size s) { return std::to_string(s.width) + "x" + std::to_string(s.height); }

// Corners of one image where the board was found.
struct BoardView {
  std::size_t report_index = 0;
  cv::Size image_size;
  std::vector<cv::Point2f> corners_px;
};

// Reads one image and looks for the board; fills the report's reason on failure.
std::optional<BoardView> find_board(const std::string& path, cv::Size pattern, CalibrationImageReport& report) {
  // Checked first so that OpenCV does not log its own warning for a missing file.
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    report.reason = std::filesystem::exists(path, ec) ? "is not a regular file" : "does not exist";
    return std::nullopt;
  }
  const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  if (image.empty()) {
    report.reason = "cannot be read as an image";
    return std::nullopt;
  }
  BoardView view;
  view.image_size = image.size();
  // The sample searches the colour image and refines on grey; do the same.
  if (!cv::findChessboardCorners(image, pattern, view.corners_px, kChessboardFlags)) {
    report.reason = "no " + size_text(pattern) + " chessboard found";
    return std::nullopt;
  }
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  cv::cornerSubPix(grey, view.corners_px, cv::Size(kSubPixHalfWindowPx, kSubPixHalfWindowPx), cv::Size(-1, -1),
                   kSubPixCriteria);
  return view;
}

// The size shared by most views; ties go to the size seen first, so a calibration set
// with one odd image out keeps the majority rather than the first file.
cv::Size majority_size(const std::vector<BoardView>& views) {
  std::vector<std::pair<cv::Size, int>> counts;
  for (const auto& v : views) {
    auto it = std::find_if(counts.begin(), counts.end(), [&](const auto& c) { return c.first == v.image_size; });
    if (it == counts.end()) {
      counts.emplace_back(v.image_size, 1);
    } else {
      ++it->second;
    }
  }
  auto best = counts.begin();
  for (auto it = counts.begin(); it != counts.end(); ++it) {
    if (it->second > best->second) best = it;
  }
  return best == counts.end() ? cv::Size() : best->first;
}

// Board corners in the board's plane, row by row, in square_mm units. Float, as in
// the sample, so that the solver sees the very same numbers.
std::vector<cv::Point3f> board_points(const ChessboardSpec& board) {
  std::vector<cv::Point3f> points;
  const auto square = static_cast<float>(board.square_mm);
  for (int i = 0; i < board.rows; ++i) {
    for (int j = 0; j < board.cols; ++j) points.emplace_back(float(j) * square, float(i) * square, 0.0f);
  }
  return points;
}

std::string validate_board(const ChessboardSpec& board) {
  // findChessboardCorners asserts on patterns with fewer than 3 inner corners a side.
  if (board.cols < 3 || board.rows < 3) {
    return "board must have at least 3x3 inner corners, got " + std::to_string(board.cols) + "x" +
           std::to_string(board.rows);
  }
  if (!(board.square_mm > 0.0) || !std::isfinite(board.square_mm)) {
    return "square size must be a positive number of millimetres";
  }
  return {};
}

bool all_finite(const cv::Mat& m) { return cv::checkRange(m, true, nullptr, -1e300, 1e300); }

std::vector<double> to_vector(const cv::Mat& m) {
  std::vector<double> out;
  cv::Mat flat = m.reshape(1, 1);
  flat.convertTo(flat, CV_64F);
  out.assign(flat.begin<double>(), flat.end<double>());
  return out;
}

}  // namespace

namespace {

// Keeps the views of the calibration size, marking them usable and the others skipped.
std::vector<std::vector<cv::Point2f>> select_views(std::vector<BoardView>& views, cv::Size image_size,
                                                   IntrinsicsResult& result, CameraIntrinsics& intrinsics) {
  std::vector<std::vector<cv::Point2f>> image_points;
  for (auto& view : views) {
    auto& report = result.images[view.report_index];
    if (view.image_size != image_size) {
      report.reason =
          "image is " + size_text(view.image_size) + ", the calibration images are " + size_text(image_size);
      continue;
    }
    report.usable = true;
    image_points.push_back(std::move(view.corners_px));
    intrinsics.images_used.push_back(report.path);
  }
  return image_points;
}

// Runs the solver as the sample does; fills the lens and RMS, or returns an error.
std::string solve(const std::vector<std::vector<cv::Point2f>>& image_points, const ChessboardSpec& board,
                  CameraIntrinsics& intrinsics) {
  const std::vector<std::vector<cv::Point3f>> object_points(image_points.size(), board_points(board));
  cv::Mat camera_matrix = cv::Mat::eye(3, 3, CV_64F);
  cv::Mat distortion = cv::Mat::zeros(kInitialDistortionCount, 1, CV_64F);
  std::vector<cv::Mat> rvecs, tvecs;
  try {
    intrinsics.rms_px = cv::calibrateCamera(object_points, image_points, intrinsics.image_size, camera_matrix,
                                            distortion, rvecs, tvecs, kCalibrateFlags);
  } catch (const cv::Exception& e) {
    return std::string("calibration failed: ") + e.err;
  }
  if (!all_finite(camera_matrix) || !all_finite(distortion)) {
    return "calibration diverged (non-finite camera matrix or distortion)";
  }
  intrinsics.lens.camera_matrix = cv::Matx33d(camera_matrix);
  intrinsics.lens.distortion = to_vector(distortion);
  return {};
}

}  // namespace

IntrinsicsResult calibrate_intrinsics(const std::vector<std::string>& image_paths, const ChessboardSpec& board,
                                      int min_images) {
  IntrinsicsResult result;
  if (result.error = validate_board(board); !result.error.empty()) return result;
  const cv::Size pattern(board.cols, board.rows);
  std::vector<BoardView> views;
  for (const auto& path : image_paths) {
    result.images.push_back({path, false, {}});
    if (auto view = find_board(path, pattern, result.images.back())) {
      view->report_index = result.images.size() - 1;
      views.push_back(std::move(*view));
    }
  }
  CameraIntrinsics intrinsics;
  intrinsics.image_size = majority_size(views);
  intrinsics.board = board;
  const auto image_points = select_views(views, intrinsics.image_size, result, intrinsics);
  if (static_cast<int>(image_points.size()) < min_images) {
    result.error = "only " + std::to_string(image_points.size()) + " of " + std::to_string(image_paths.size()) +
                   " images are usable, at least " + std::to_string(min_images) + " are needed";
    return result;
  }
  if (result.error = solve(image_points, board, intrinsics); !result.error.empty()) return result;
  result.intrinsics = std::move(intrinsics);
  return result;
}

std::string validate_lens(const LensModel& lens) {
  const auto& k = lens.camera_matrix;
  for (int i = 0; i < 9; ++i) {
    if (!std::isfinite(k.val[i])) return "camera_matrix has a non-finite entry";
  }
  if (!(k(0, 0) > 0.0) || !(k(1, 1) > 0.0)) return "camera_matrix focal lengths fx, fy must be positive";
  if (k(2, 0) != 0.0 || k(2, 1) != 0.0 || k(2, 2) != 1.0) return "camera_matrix last row must be 0 0 1";
  const std::size_t n = lens.distortion.size();
  if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14) {
    return "distortion_coefficients must have 4, 5, 8, 12 or 14 values, got " + std::to_string(n);
  }
  for (double d : lens.distortion) {
    if (!std::isfinite(d)) return "distortion_coefficients has a non-finite value";
  }
  return {};
}

std::string save_intrinsics(const CameraIntrinsics& intrinsics, const std::string& path) {
  cv::FileStorage fs;
  if (auto error = cvyaml::open_for_writing(path, fs); !error.empty()) return error;
  fs << "image_width" << intrinsics.image_size.width;
  fs << "image_height" << intrinsics.image_size.height;
  cvyaml::write_lens(fs, intrinsics.lens);
  fs << "rms_px" << intrinsics.rms_px;
  fs << "board_cols" << intrinsics.board.cols;
  fs << "board_rows" << intrinsics.board.rows;
  fs << "square_mm" << intrinsics.board.square_mm;
  fs << "images_used"
     << "[";
  for (const auto& p : intrinsics.images_used) fs << p;
  fs << "]";
  fs.release();
  return {};
}

IntrinsicsFileResult load_intrinsics(const std::string& path) {
  IntrinsicsFileResult result;
  cv::FileStorage fs;
  if (auto error = cvyaml::open_for_reading(path, fs); !error.empty()) {
    result.error = error;
    return result;
  }
  CameraIntrinsics in;
  std::string error = cvyaml::read_int(fs, path, "image_width", in.image_size.width);
  if (error.empty()) error = cvyaml::read_int(fs, path, "image_height", in.image_size.height);
  if (error.empty() && (in.image_size.width <= 0 || in.image_size.height <= 0)) {
    error = path + ": image_width and image_height must be positive, got " + size_text(in.image_size);
  }
  if (error.empty()) error = cvyaml::read_lens(fs, path, in.lens);
  // The remaining keys are informative: read them when present and well-formed.
  if (error.empty() && !fs["rms_px"].empty()) error = cvyaml::read_real(fs, path, "rms_px", in.rms_px);
  if (error.empty() && !fs["board_cols"].empty()) error = cvyaml::read_int(fs, path, "board_cols", in.board.cols);
  if (error.empty() && !fs["board_rows"].empty()) error = cvyaml::read_int(fs, path, "board_rows", in.board.rows);
  if (error.empty() && !fs["square_mm"].empty()) error = cvyaml::read_real(fs, path, "square_mm", in.board.square_mm);
  if (error.empty()) {
    for (const auto& node : fs["images_used"]) {
      if (node.isString()) in.images_used.push_back(node.string());
    }
    result.intrinsics = std::move(in);
  }
  result.error = error;
  return result;
}

// ---------------------------------------------------------------- OpenCV YAML helpers
namespace cvyaml {

std::string open_for_reading(const std::string& path, cv::FileStorage& fs) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  // Checked here because cv::FileStorage logs to stderr or asserts on these.
  if (!std::filesystem::exists(status)) return path + ": file does not exist";
  if (std::filesystem::is_directory(status)) return path + ": is a directory, not a calibration file";
  if (std::filesystem::file_size(path, ec) == 0) return path + ": file is empty";
  try {
    if (!fs.open(path, cv::FileStorage::READ)) return path + ": cannot be opened for reading";
  } catch (const cv::Exception& e) {
    return path + ": not an OpenCV YAML file (it must begin with \"%YAML:1.0\" and parse): " + e.err;
  }
  if (!fs.root().isMap()) return path + ": top level is not a map of keys";
  return {};
}

std::string open_for_writing(const std::string& path, cv::FileStorage& fs) {
  // Checked here because cv::FileStorage logs its own error to stderr otherwise.
  if (path.empty()) return "cannot write a file with an empty name";
  std::error_code ec;
  const auto parent = std::filesystem::absolute(path, ec).parent_path();
  if (!std::filesystem::is_directory(parent, ec)) {
    return path + ": cannot be written, directory " + parent.string() + " does not exist";
  }
  if (std::filesystem::is_directory(path, ec)) return path + ": cannot be written, it is a directory";
  try {
    if (fs.open(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML)) return {};
  } catch (const cv::Exception& e) {
    return path + ": cannot be written: " + e.err;
  }
  return path + ": cannot be opened for writing";
}

std::string read_int(const cv::FileStorage& fs, const std::string& path, const std::string& key, int& out) {
  const cv::FileNode node = fs[key];
  if (node.empty()) return path + ": missing key '" + key + "'";
  if (!node.isInt()) return path + ": key '" + key + "' must be an integer";
  out = static_cast<int>(node);
  return {};
}

std::string read_real(const cv::FileStorage& fs, const std::string& path, const std::string& key, double& out) {
  const cv::FileNode node = fs[key];
  if (node.empty()) return path + ": missing key '" + key + "'";
  if (!node.isReal() && !node.isInt()) return path + ": key '" + key + "' must be a number";
  out = static_cast<double>(node);
  if (!std::isfinite(out)) return path + ": key '" + key + "' must be finite";
  return {};
}

std::string read_matrix(const cv::FileStorage& fs, const std::string& path, const std::string& key, int rows, int cols,
                        cv::Mat& out) {
  const cv::FileNode node = fs[key];
  if (node.empty()) return path + ": missing key '" + key + "'";
  const std::string bad = path + ": key '" + key + "' must be a";
  const std::string shape = (rows > 0 ? std::to_string(rows) : "N") + "x" + (cols > 0 ? std::to_string(cols) : "N");
  if (!node.isMap()) return bad + " " + shape + " !!opencv-matrix";
  cv::Mat m;
  try {
    node >> m;
  } catch (const cv::Exception& e) {
    return bad + " " + shape + " !!opencv-matrix (" + e.err + ")";
  }
  if (m.channels() != 1 || (rows > 0 && m.rows != rows) || (cols > 0 && m.cols != cols) ||
      (m.empty() && (rows > 0 || cols > 0))) {
    return bad + " " + shape + " single-channel matrix, got " + std::to_string(m.rows) + "x" + std::to_string(m.cols) +
           "x" + std::to_string(m.channels());
  }
  if (!m.empty()) m.convertTo(m, CV_64F);
  if (!m.empty() && !all_finite(m)) return path + ": key '" + key + "' has a non-finite entry";
  out = m;
  return {};
}

std::string read_lens(const cv::FileStorage& fs, const std::string& path, LensModel& lens) {
  cv::Mat k, d;
  if (auto error = read_matrix(fs, path, "camera_matrix", 3, 3, k); !error.empty()) return error;
  if (auto error = read_matrix(fs, path, "distortion_coefficients", -1, -1, d); !error.empty()) return error;
  if (!d.empty() && d.rows != 1 && d.cols != 1) {
    return path + ": key 'distortion_coefficients' must be a row or column vector";
  }
  LensModel candidate;
  candidate.camera_matrix = cv::Matx33d(k);
  if (!d.empty()) candidate.distortion = to_vector(d);
  if (auto error = validate_lens(candidate); !error.empty()) return path + ": " + error;
  lens = std::move(candidate);
  return {};
}

void write_lens(cv::FileStorage& fs, const LensModel& lens) {
  fs << "camera_matrix" << cv::Mat(lens.camera_matrix);
  fs << "distortion_coefficients" << cv::Mat(lens.distortion, true);
}

}  // namespace cvyaml
}  // namespace rilbed::vision

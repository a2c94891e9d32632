// Camera intrinsics: chessboard calibration of the overhead camera's lens (focal
// lengths, principal point, distortion) from a set of photographs of a flat
// chessboard, and the OpenCV YAML file that stores the result.
//
// The detection and solver settings are those of OpenCV's own calibration sample
// (samples/cpp/calibration.cpp) with its default flags, so that a set of images gives
// the same RMS reprojection error here as there; tests/vision/test_calibration.cpp
// pins that equality on OpenCV's left01..left14 photographs.
//
// File format (OpenCV YAML, cv::FileStorage):
//   image_width, image_height   int, pixels
//   camera_matrix               3x3 double matrix [fx 0 cx; 0 fy cy; 0 0 1], pixels
//   distortion_coefficients     Nx1 double matrix, OpenCV order k1 k2 p1 p2 [k3 ...]
//   rms_px                      double, RMS reprojection error of the calibration
//   board_cols, board_rows      int, inner corners of the chessboard
//   square_mm                   double, side of one chessboard square
//   images_used                 sequence of strings, the image paths that took part
// The first four keys are required when loading; the others are informative, so a file
// written by OpenCV's sample (which shares the first four keys) loads too.
#pragma once

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace rilbed::vision {

/// A chessboard calibration target.
struct ChessboardSpec {
  int cols = 0;            ///< inner corners along a row (OpenCV's pattern width), >= 3
  int rows = 0;            ///< inner corners along a column (pattern height), >= 3
  double square_mm = 0.0;  ///< side of one square, millimetres, > 0
};

/// A pinhole camera with lens distortion, in OpenCV's model.
struct LensModel {
  /// [fx 0 cx; 0 fy cy; 0 0 1], pixels.
  cv::Matx33d camera_matrix = cv::Matx33d::eye();
  /// OpenCV order (k1, k2, p1, p2[, k3[, k4, k5, k6[, ...]]]); 4, 5, 8, 12 or 14 values,
  /// or empty for no distortion.
  std::vector<double> distortion;
};

/// The outcome of an intrinsics calibration, or what an intrinsics file holds.
struct CameraIntrinsics {
  cv::Size image_size;  ///< size of the images the lens model applies to, pixels
  LensModel lens;
  double rms_px = 0.0;                   ///< RMS reprojection error over all corners, pixels (0: unknown)
  ChessboardSpec board;                  ///< the target used (zeros: unknown)
  std::vector<std::string> images_used;  ///< paths of the images that took part
};

/// What calibration made of one input image.
struct CalibrationImageReport {
  std::string path;
  bool usable = false;  ///< the board was found and the image has the calibration size
  /// Why the image was not used (unreadable, no board found, different size); empty
  /// when usable.
  std::string reason;
};

/// Result of calibrate_intrinsics(): the intrinsics, or an error; the per-image reports
/// are filled either way, in input order.
struct IntrinsicsResult {
  std::optional<CameraIntrinsics> intrinsics;
  std::vector<CalibrationImageReport> images;
  std::string error;  ///< empty on success
  bool ok() const { return error.empty(); }
};

/// Result of load_intrinsics().
struct IntrinsicsFileResult {
  std::optional<CameraIntrinsics> intrinsics;
  std::string error;  ///< names the file and the missing or bad key; empty on success
  bool ok() const { return error.empty(); }
};

/// Fewest usable images calibrate_intrinsics() accepts by default. Fewer views leave the
/// principal point and distortion poorly determined.
inline constexpr int kMinCalibrationImages = 3;

/// Calibrates the camera from photographs of `board`. Each image is read (colour),
/// searched for the chessboard's inner corners, and refined to sub-pixel accuracy; the
/// calibration size is the size shared by most images whose board was found, and
/// images of another size are skipped (reported as unusable, with both sizes). Fails
/// when the board spec is invalid or fewer than `min_images` images are usable.
/// Corner coordinates are in square_mm units, so extrinsics (not kept) would be in mm.
IntrinsicsResult calibrate_intrinsics(const std::vector<std::string>& image_paths, const ChessboardSpec& board,
                                      int min_images = kMinCalibrationImages);

/// Writes `intrinsics` to `path` as OpenCV YAML (keys in the header comment), replacing
/// the file. Returns an error naming the file, or an empty string on success.
[[nodiscard]] std::string save_intrinsics(const CameraIntrinsics& intrinsics, const std::string& path);

/// Reads an intrinsics file. A missing file, a file that is not OpenCV YAML/XML/JSON, a
/// missing required key or a bad value (non-positive size, camera matrix not 3x3 with
/// positive focal lengths, distortion of an unsupported length, non-finite numbers)
/// gives an error naming the file and the key; it never throws.
IntrinsicsFileResult load_intrinsics(const std::string& path);

/// Checks a lens model: 3x3 camera matrix with finite, positive fx and fy and finite
/// entries, distortion empty or of 4, 5, 8, 12 or 14 finite values. Returns what is
/// wrong, or an empty string.
std::string validate_lens(const LensModel& lens);

/// Small helpers for reading and writing OpenCV YAML calibration files, shared by the
/// intrinsics and field calibration files. Every reader returns an error message that
/// names the file and the key (empty on success) and never throws.
namespace cvyaml {

/// Opens `path` for reading. Fails with a message naming the file when it does not
/// exist, is a directory, is empty, or is not OpenCV YAML/XML/JSON (OpenCV's YAML needs
/// the "%YAML:1.0" first line that cv::FileStorage writes).
std::string open_for_reading(const std::string& path, cv::FileStorage& fs);

/// Reads the integer at top-level `key` into `out`.
std::string read_int(const cv::FileStorage& fs, const std::string& path, const std::string& key, int& out);

/// Reads the finite number (integer or real) at top-level `key` into `out`.
std::string read_real(const cv::FileStorage& fs, const std::string& path, const std::string& key, double& out);

/// Reads the matrix at top-level `key` into `out` as CV_64F. `rows`/`cols` of -1 accept
/// any count. Non-finite entries are an error.
std::string read_matrix(const cv::FileStorage& fs, const std::string& path, const std::string& key, int rows, int cols,
                        cv::Mat& out);

/// Reads camera_matrix and distortion_coefficients and validates them (validate_lens).
std::string read_lens(const cv::FileStorage& fs, const std::string& path, LensModel& lens);

/// Writes camera_matrix and distortion_coefficients (an Nx1 matrix; 0x1 when empty).
void write_lens(cv::FileStorage& fs, const LensModel& lens);

/// Opens `path` for writing as YAML whatever its extension. Returns an error naming the
/// file, or an empty string.
std::string open_for_writing(const std::string& path, cv::FileStorage& fs);

}  // namespace cvyaml

}  // namespace rilbed::vision

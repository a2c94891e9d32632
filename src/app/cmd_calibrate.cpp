// `rilbed calibrate`: camera intrinsics from chessboard photographs, and the pixel ->
// field mapping from one overhead frame.
//
//   rilbed calibrate intrinsics --images GLOB --board COLSxROWS --square-mm S --out FILE
//   rilbed calibrate field --image FRAME --size-m W,H --out FILE [--intrinsics FILE]
//                          (--corners u1,v1,u2,v2,u3,v3,u4,v4 | --markers ID:X,Y[;ID:X,Y...] [--family NAME])
//
// File formats and the corner order are described in calibration/README.md.
// Exit codes: 0 success, 2 a bad option value (nothing written), 1 an input that cannot
// be used (missing or unreadable file, too few usable images, markers not found) or an
// output that cannot be written.
#include <glob.h>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "app/commands.hpp"
#include "vision/calibration.hpp"
#include "vision/field_mapping.hpp"
#include "vision/marker_family.hpp"
#include "vision/marker_tracker.hpp"

namespace rilbed::app {
namespace {

namespace fs = std::filesystem;
using vision::FieldCalibrationResult;
using vision::LensModel;
using vision::PointCorrespondence;

/// A value parsed from an option, or a message naming the option and what is wrong.
template <typename T>
struct Parsed {
  T value{};
  std::string error;  ///< empty on success
  bool ok() const { return error.empty(); }
};

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (std::size_t pos; (pos = s.find(sep, start)) != std::string::npos; start = pos + 1) {
    parts.push_back(s.substr(start, pos - start));
  }
  parts.push_back(s.substr(start));
  return parts;
}

/// A whole string as a finite number.
std::optional<double> to_number(const std::string& text) {
  const std::string t = trim(text);
  if (t.empty()) return std::nullopt;
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (end != t.c_str() + t.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

/// A whole string as an integer.
std::optional<int> to_int(const std::string& text) {
  const auto v = to_number(text);
  if (!v || *v != std::floor(*v) || std::abs(*v) > 1e9) return std::nullopt;
  return static_cast<int>(*v);
}

/// Exactly `count` comma-separated numbers.
Parsed<std::vector<double>> parse_numbers(const std::string& option, const std::string& text, std::size_t count,
                                          const std::string& shape) {
  Parsed<std::vector<double>> r;
  const auto parts = split(text, ',');
  if (parts.size() != count) {
    r.error = option + " '" + text + "': expected " + std::to_string(count) + " comma-separated numbers (" + shape +
              "), got " + std::to_string(parts.size());
    return r;
  }
  for (const auto& p : parts) {
    const auto v = to_number(p);
    if (!v) {
      r.error = option + " '" + text + "': '" + trim(p) + "' is not a number";
      return r;
    }
    r.value.push_back(*v);
  }
  return r;
}

// ---------------------------------------------------------------- intrinsics

/// The options of `calibrate intrinsics` as typed.
struct IntrinsicsOptions {
  std::string images_glob;
  std::string board;
  double square_mm = 0.0;
  std::string out;
};

/// "COLSxROWS", inner corners.
Parsed<vision::ChessboardSpec> parse_board(const std::string& text, double square_mm) {
  Parsed<vision::ChessboardSpec> r;
  std::string lower = text;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  const auto parts = split(lower, 'x');
  const auto cols = parts.size() == 2 ? to_int(parts[0]) : std::nullopt;
  const auto rows = parts.size() == 2 ? to_int(parts[1]) : std::nullopt;
  if (!cols || !rows || *cols < 3 || *rows < 3) {
    r.error = "--board '" + text + "': expected COLSxROWS inner corners, each at least 3 (e.g. 9x6)";
    return r;
  }
  if (!(square_mm > 0.0) || !std::isfinite(square_mm)) {
    r.error = "--square-mm: " + std::to_string(square_mm) + " is not a positive length";
    return r;
  }
  r.value = {*cols, *rows, square_mm};
  return r;
}

/// The files matching a glob(3) pattern, sorted byte-wise so the order never depends
/// on the locale.
std::vector<std::string> expand_glob(const std::string& pattern) {
  glob_t g{};
  std::vector<std::string> paths;
  if (::glob(pattern.c_str(), 0, nullptr, &g) == 0) {
    for (std::size_t i = 0; i < g.gl_pathc; ++i) paths.emplace_back(g.gl_pathv[i]);
  }
  ::globfree(&g);
  std::sort(paths.begin(), paths.end());
  return paths;
}

void print_intrinsics(const vision::CameraIntrinsics& in, std::size_t image_count) {
  const auto& k = in.lens.camera_matrix;
  std::cout << "images used: " << in.images_used.size() << " of " << image_count << "\n";
  std::cout << "image size: " << in.image_size.width << "x" << in.image_size.height << " px\n";
  std::cout << "camera matrix: fx " << k(0, 0) << " fy " << k(1, 1) << " cx " << k(0, 2) << " cy " << k(1, 2)
            << " px\n";
  std::cout << "distortion:";
  for (double d : in.lens.distortion) std::cout << " " << d;
  std::cout << "\n";
  std::cout << "RMS reprojection error: " << in.rms_px << " px\n";
}

int run_intrinsics(const IntrinsicsOptions& o) {
  const std::string who = "rilbed calibrate intrinsics: ";
  const auto board = parse_board(o.board, o.square_mm);
  if (!board.ok()) {
    std::cerr << who << board.error << "\n";
    return kExitUsage;
  }
  const auto paths = expand_glob(o.images_glob);
  if (paths.empty()) {
    std::cerr << who << "--images '" << o.images_glob << "' matches no file\n";
    return kExitFailure;
  }
  const auto result = vision::calibrate_intrinsics(paths, board.value);
  for (const auto& report : result.images) {
    if (report.usable) {
      std::cout << "used: " << report.path << "\n";
    } else {
      std::cerr << who << "warning: skipped " << report.path << ": " << report.reason << "\n";
    }
  }
  if (!result.ok()) {
    std::cerr << who << result.error << "\n";
    return kExitFailure;
  }
  print_intrinsics(*result.intrinsics, paths.size());
  if (auto error = vision::save_intrinsics(*result.intrinsics, o.out); !error.empty()) {
    std::cerr << who << error << "\n";
    return kExitFailure;
  }
  std::cout << "wrote " << o.out << "\n";
  return 0;
}

// ---------------------------------------------------------------- field

/// The options of `calibrate field` as typed.
struct FieldOptions {
  std::string image;
  std::string corners;
  std::string markers;
  std::string family = "6ucp";
  std::string size_m;
  std::string out;
  std::string intrinsics;
};

/// One marker lying at a known field position.
struct PlacedMarker {
  int id = 0;
  Vec2 field_m;
};

/// "ID:X,Y;ID:X,Y...", at least 4 distinct IDs of the family.
Parsed<std::vector<PlacedMarker>> parse_markers(const std::string& text, const vision::MarkerFamily& family) {
  Parsed<std::vector<PlacedMarker>> r;
  std::set<int> seen;
  for (const auto& item : split(text, ';')) {
    if (trim(item).empty()) continue;  // tolerate a trailing ';'
    const auto colon = item.find(':');
    const bool has_colon = colon != std::string::npos;
    const auto id = has_colon ? to_int(item.substr(0, colon)) : std::nullopt;
    const auto xy = parse_numbers("--markers", has_colon ? item.substr(colon + 1) : "", 2, "X,Y");
    if (!id || !xy.ok()) {
      r.error = "--markers: '" + trim(item) + "' is not ID:X,Y (X, Y in metres)";
      return r;
    }
    if (!family.valid_id(*id)) {
      r.error = "--markers: ID " + std::to_string(*id) + " is not in family " + family.name() + " (IDs " +
                std::to_string(family.min_id()) + ".." + std::to_string(family.max_id()) + ")";
      return r;
    }
    if (!seen.insert(*id).second) {
      r.error = "--markers: ID " + std::to_string(*id) + " is given twice";
      return r;
    }
    r.value.push_back({*id, {xy.value[0], xy.value[1]}});
  }
  if (r.value.size() < 4) {
    r.error = "--markers: at least 4 markers are needed, got " + std::to_string(r.value.size());
  }
  return r;
}

/// The options checked and turned into values.
struct FieldJob {
  double width_m = 0.0;
  double height_m = 0.0;
  std::optional<std::array<Vec2, 4>> corners_px;
  std::vector<PlacedMarker> markers;
  vision::MarkerFamily family = vision::MarkerFamily::six_ucp();
};

/// Checks every option before any file is read.
std::string make_field_job(const FieldOptions& o, FieldJob& job) {
  if (o.corners.empty() == o.markers.empty()) return "give either --corners or --markers";
  const auto size = parse_numbers("--size-m", o.size_m, 2, "W,H");
  if (!size.ok()) return size.error;
  if (!(size.value[0] > 0.0) || !(size.value[1] > 0.0)) {
    return "--size-m '" + o.size_m + "': width and height must be positive (metres)";
  }
  job.width_m = size.value[0];
  job.height_m = size.value[1];
  if (!o.corners.empty()) {
    const auto c = parse_numbers("--corners", o.corners, 8, "u1,v1,u2,v2,u3,v3,u4,v4");
    if (!c.ok()) return c.error;
    job.corners_px = std::array<Vec2, 4>{};
    for (int i = 0; i < 4; ++i) (*job.corners_px)[i] = {c.value[2 * i], c.value[2 * i + 1]};
    return {};
  }
  try {
    job.family = vision::MarkerFamily::by_name(o.family);
  } catch (const std::invalid_argument& e) {
    return std::string("--family: ") + e.what();
  }
  auto markers = parse_markers(o.markers, job.family);
  if (!markers.ok()) return markers.error;
  job.markers = std::move(markers.value);
  return {};
}

/// Reads the frame; a message naming it when that fails.
std::string read_frame(const std::string& path, cv::Mat& image) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return "--image '" + path + "': file does not exist";
  image = cv::imread(path, cv::IMREAD_COLOR);
  if (image.empty()) return "--image '" + path + "': cannot be read as an image";
  return {};
}

/// Loads --intrinsics when given and checks it is for frames of this size.
std::string read_lens(const std::string& path, cv::Size frame_size, const std::string& frame_path,
                      std::optional<LensModel>& lens) {
  if (path.empty()) return {};
  const auto loaded = vision::load_intrinsics(path);
  if (!loaded.ok()) return "--intrinsics: " + loaded.error;
  const cv::Size s = loaded.intrinsics->image_size;
  if (s != frame_size) {
    return "--intrinsics '" + path + "' is for " + std::to_string(s.width) + "x" + std::to_string(s.height) +
           " images but --image '" + frame_path + "' is " + std::to_string(frame_size.width) + "x" +
           std::to_string(frame_size.height);
  }
  lens = loaded.intrinsics->lens;
  return {};
}

/// Finds the placed markers in the frame and pairs them with their field positions;
/// markers not found are reported and left out.
std::vector<PointCorrespondence> find_markers(const cv::Mat& image, const FieldJob& job, const std::string& who) {
  std::vector<int> ids;
  for (const auto& m : job.markers) ids.push_back(m.id);
  std::map<int, vision::MarkerDetection> found;
  for (const auto& d : vision::detect_markers(image, job.family, ids)) found[d.id] = d;
  std::vector<PointCorrespondence> points;
  for (const auto& m : job.markers) {
    const auto it = found.find(m.id);
    if (it == found.end()) {
      std::cerr << who << "warning: marker " << m.id << " not found in --image\n";
      continue;
    }
    std::cout << "marker " << m.id << ": pixel " << it->second.u << "," << it->second.v << " -> field " << m.field_m.x
              << "," << m.field_m.y << " m\n";
    points.push_back({{it->second.u, it->second.v}, m.field_m, m.id});
  }
  return points;
}

void print_fit(const FieldCalibrationResult& r, std::size_t point_count, const std::string& who) {
  // Micrometres are below anything a camera resolves; fixed notation keeps 1e-13 quiet.
  std::cout << std::fixed << std::setprecision(3) << "homography residual: RMS " << r.residual_rms_mm << " mm, max "
            << r.residual_max_mm << " mm over " << point_count - r.outlier_labels.size() << " points\n"
            << std::defaultfloat << std::setprecision(6);
  for (int label : r.outlier_labels) {
    std::cerr << who << "warning: marker " << label << " disagrees with the others and was left out\n";
  }
  if (r.mirrored) {
    std::cerr << who << "warning: the image is a mirror view of the field; check the corner order "
              << "(field corners (0,0), (W,0), (W,H), (0,H), counter-clockwise seen from above)\n";
  }
}

void warn_outside(const std::array<Vec2, 4>& corners_px, cv::Size size, const std::string& who) {
  for (std::size_t i = 0; i < corners_px.size(); ++i) {
    const Vec2 c = corners_px[i];
    if (c.x < 0 || c.y < 0 || c.x > size.width - 1 || c.y > size.height - 1) {
      std::cerr << who << "warning: corner " << i + 1 << " (" << c.x << "," << c.y << ") lies outside the "
                << size.width << "x" << size.height << " image\n";
    }
  }
}

int run_field(const FieldOptions& o) {
  const std::string who = "rilbed calibrate field: ";
  FieldJob job;
  if (auto error = make_field_job(o, job); !error.empty()) {
    std::cerr << who << error << "\n";
    return kExitUsage;
  }
  cv::Mat image;
  std::optional<LensModel> lens;
  std::string error = read_frame(o.image, image);
  if (error.empty()) error = read_lens(o.intrinsics, image.size(), o.image, lens);
  if (!error.empty()) {
    std::cerr << who << error << "\n";
    return kExitFailure;
  }
  FieldCalibrationResult result;
  std::size_t point_count = 4;
  if (job.corners_px) {
    warn_outside(*job.corners_px, image.size(), who);
    result = vision::field_from_corners(*job.corners_px, job.width_m, job.height_m, image.size(), lens);
  } else {
    const auto points = find_markers(image, job, who);
    point_count = points.size();
    if (points.size() < 4) {
      std::cerr << who << "only " << points.size() << " of the " << job.markers.size()
                << " markers were found in --image '" << o.image << "'; at least 4 are needed\n";
      return kExitFailure;
    }
    result = vision::field_from_correspondences(points, job.width_m, job.height_m, image.size(), lens);
  }
  if (!result.ok()) {
    std::cerr << who << result.error << "\n";
    return kExitFailure;
  }
  print_fit(result, point_count, who);
  if (auto save_error = vision::save_field_calibration(*result.calibration, o.out); !save_error.empty()) {
    std::cerr << who << save_error << "\n";
    return kExitFailure;
  }
  std::cout << "wrote " << o.out << "\n";
  return 0;
}

}  // namespace

void add_calibrate_command(CLI::App& app) {
  CLI::App* calibrate = app.add_subcommand("calibrate", "Camera intrinsics and pixel-to-field calibration");
  calibrate->require_subcommand(1);

  // Shared with the callbacks, which run after parsing, when this function has returned.
  auto in = std::make_shared<IntrinsicsOptions>();
  CLI::App* intrinsics = calibrate->add_subcommand("intrinsics", "Calibrate the lens from chessboard photographs");
  intrinsics->add_option("--images", in->images_glob, "Glob of the chessboard images (quote it), e.g. 'shots/*.jpg'")
      ->required();
  intrinsics->add_option("--board", in->board, "Inner corners of the chessboard, COLSxROWS, e.g. 9x6")->required();
  intrinsics->add_option("--square-mm", in->square_mm, "Side of one chessboard square, mm")->required();
  intrinsics->add_option("--out", in->out, "Intrinsics file to write (OpenCV YAML)")->required();
  intrinsics->callback([in] { exit_code() = run_intrinsics(*in); });

  auto fo = std::make_shared<FieldOptions>();
  CLI::App* field = calibrate->add_subcommand("field", "Map image pixels to field metres from one overhead frame");
  field->add_option("--image", fo->image, "Overhead frame showing the field")->required();
  auto* corners = field->add_option("--corners", fo->corners,
                                    "Pixels of field corners (0,0),(W,0),(W,H),(0,H): u1,v1,u2,v2,u3,v3,u4,v4");
  auto* markers = field->add_option("--markers", fo->markers,
                                    "Markers at known field positions, metres: 'ID:X,Y;ID:X,Y;...' (at least 4)");
  corners->excludes(markers);
  field->add_option("--family", fo->family, "Marker family of --markers")->capture_default_str()->needs(markers);
  field->add_option("--size-m", fo->size_m, "Field width and height in metres: W,H")->required();
  field->add_option("--out", fo->out, "Field calibration file to write (OpenCV YAML)")->required();
  field->add_option("--intrinsics", fo->intrinsics, "Intrinsics file from 'calibrate intrinsics' (undistorts pixels)");
  field->callback([fo] { exit_code() = run_field(*fo); });
}

}  // namespace rilbed::app

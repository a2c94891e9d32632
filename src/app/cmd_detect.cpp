// `rilbed detect`: runs the overhead-camera pipeline over recorded footage or a live
// camera and writes one CSV row per identified marker per frame.
#include <spdlog/spdlog.h>
#include <unistd.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>

#include "app/commands.hpp"
#include "app/interrupt.hpp"
#include "bus/lcm_frame_source.hpp"
#include "core/geometry.hpp"
#include "core/id_list.hpp"
#include "vision/field_mapping.hpp"
#include "vision/frame_source.hpp"
#include "vision/marker_tracker.hpp"

namespace rilbed::app {
namespace {

struct DetectOptions {
  std::string input;
  int camera = -1;
  std::string family = "6ucp";
  std::string ids;
  std::string csv = "-";
  std::string calib;
  std::string annotate;
  bool no_track = false;
  bool quiet = false;
  long max_frames = -1;
  double min_diameter_px = 0.0;
  double max_diameter_px = 0.0;
  double min_score = 0.0;
};

// Draws what the pipeline found over a frame, for the annotated video.
void annotate_frame(cv::Mat& bgr, const std::vector<vision::MarkerDetection>& found, int frame_index) {
  for (const auto& d : found) {
    const cv::Point2d c(d.u, d.v);
    const double r = d.diameter_px / 2.0;
    const double h = deg_to_rad(d.heading_deg);
    const cv::Scalar colour = d.tracked ? cv::Scalar(0, 200, 0) : cv::Scalar(0, 160, 255);
    cv::circle(bgr, c, cvRound(r), colour, 2, cv::LINE_AA);
    cv::arrowedLine(bgr, c, c + cv::Point2d(std::cos(h), -std::sin(h)) * (r * 1.8), colour, 2, cv::LINE_AA, 0, 0.3);
    cv::putText(bgr, std::to_string(d.id), c + cv::Point2d(r + 3, -r), cv::FONT_HERSHEY_SIMPLEX, 0.6,
                cv::Scalar(0, 0, 255), 2, cv::LINE_AA);
  }
  cv::putText(bgr, "frame " + std::to_string(frame_index), {10, 25}, cv::FONT_HERSHEY_SIMPLEX, 0.7,
              cv::Scalar(0, 0, 255), 2, cv::LINE_AA);
}

void print_progress(int done, std::optional<int> total, double fps) {
  if (!total || *total <= 0) {
    std::fprintf(stderr, "\r%d frames  %.0f fps", done, fps);
    return;
  }
  const int width = 30;
  const int filled = std::min(width, done * width / *total);
  std::fprintf(stderr, "\r[%s%s] %d/%d  %.0f fps", std::string(filled, '#').c_str(),
               std::string(width - filled, '.').c_str(), done, *total, fps);
}

// The marker family and the IDs to look for (every ID of the family when none are given);
// false (logged) for a name or list that cannot be used.
bool family_and_ids(const DetectOptions& opt, std::optional<vision::MarkerFamily>& family, std::vector<int>& ids) {
  try {
    family = vision::MarkerFamily::by_name(opt.family);
  } catch (const std::invalid_argument& e) {
    spdlog::error("--family: {}", e.what());
    return false;
  }
  if (opt.ids.empty()) {
    for (int id = family->min_id(); id <= family->max_id(); ++id) ids.push_back(id);
    return true;
  }
  const auto parsed = parse_id_list(opt.ids, family->min_id(), family->max_id());
  if (!parsed.ok()) {
    spdlog::error("--ids: {}", parsed.error);
    return false;
  }
  ids = parsed.ids;
  return true;
}

// One frame's detections as CSV rows (`frame,id,u,v,heading_deg,score`, with the field
// pose when calibrated).
void write_rows(std::ostream& csv, int frame, const std::vector<vision::MarkerDetection>& found,
                const std::optional<vision::FieldCalibration>& calib) {
  char line[256];
  for (const auto& d : found) {
    std::snprintf(line, sizeof line, "%d,%d,%.3f,%.3f,%.2f,%.4f", frame, d.id, d.u, d.v, d.heading_deg, d.score);
    csv << line;
    if (calib) {
      const Vec2 f = vision::pixel_to_field(*calib, d.u, d.v);
      const double theta = vision::image_heading_to_field_deg(*calib, d.u, d.v, d.heading_deg);
      std::snprintf(line, sizeof line, ",%.5f,%.5f,%.2f", f.x, f.y, theta);
      csv << line;
    }
    csv << '\n';
  }
}

// The frame with what was found drawn over it, into the annotated video (opened at the
// first frame, at the source's rate).
void write_annotated(cv::VideoWriter& video, const DetectOptions& opt, const vision::FrameSource& source,
                     const vision::FrameResult& r, const std::vector<vision::MarkerDetection>& found) {
  cv::Mat bgr;
  if (r.image.channels() == 1) {
    cv::cvtColor(r.image, bgr, cv::COLOR_GRAY2BGR);
  } else {
    bgr = r.image.clone();
  }
  annotate_frame(bgr, found, r.index);
  if (!video.isOpened()) {
    const double fps = source.fps() > 0 ? source.fps() : 30.0;
    video.open(opt.annotate, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, bgr.size());
    if (!video.isOpened()) spdlog::error("--annotate: cannot write '{}'", opt.annotate);
  }
  if (video.isOpened()) video.write(bgr);
}

// What a detect run counted, for its summary.
struct DetectCounts {
  std::map<int, long> per_id;
  long frames = 0, bad_frames = 0, rows = 0, declined = 0;
  double pipeline_s = 0.0;
};

void print_summary(const DetectCounts& c, const std::vector<int>& ids, double wall, bool interrupted) {
  std::fprintf(stderr, "summary: %ld frames read, %ld bad frames skipped, %ld detections%s\n", c.frames, c.bad_frames,
               c.rows, interrupted ? " (interrupted)" : "");
  for (int id : ids) {
    const auto it = c.per_id.find(id);
    const long n = it == c.per_id.end() ? 0 : it->second;
    std::fprintf(stderr, "  id %3d: %6ld frames (%5.1f%%)\n", id, n, c.frames ? 100.0 * n / c.frames : 0.0);
  }
  // A marker two readings explain almost equally well is reported as nothing: counted here.
  std::fprintf(stderr, "  declined: %ld markers left unnamed (two IDs or headings read almost alike)\n", c.declined);
  std::fprintf(stderr, "  speed: %.1f frames/s overall, %.1f frames/s in the pipeline (%.3f ms/frame)\n",
               c.frames / std::max(wall, 1e-9), c.frames / std::max(c.pipeline_s, 1e-9),
               c.frames ? 1000.0 * c.pipeline_s / c.frames : 0.0);
}

int run_detect(const DetectOptions& opt) {
  // The family and IDs first: a typo there is a usage error before any file is opened.
  std::optional<vision::MarkerFamily> family;
  std::vector<int> ids;
  if (!family_and_ids(opt, family, ids)) return kExitUsage;

  std::optional<vision::FieldCalibration> calib;
  if (!opt.calib.empty()) {
    auto loaded = vision::load_field_calibration(opt.calib);
    if (!loaded.ok()) {
      spdlog::error("--calib: {}", loaded.error);
      return kExitUsage;
    }
    calib = loaded.calibration;
  }

  // A run's recording (--record-frames) is footage too: its frames go through the pipeline again.
  vision::OpenResult opened = opt.camera >= 0                   ? vision::open_camera(opt.camera)
                              : bus::is_lcm_log_path(opt.input) ? bus::open_lcm_frames(opt.input)
                                                                : vision::open_frame_source(opt.input);
  if (!opened.ok()) {
    spdlog::error("{}", opened.error);
    return kExitFailure;
  }
  vision::FrameSource& source = *opened.source;
  spdlog::info("reading {}", source.describe());

  std::ofstream csv_file;
  std::ostream* csv = &std::cout;
  if (opt.csv != "-") {
    csv_file.open(opt.csv);
    if (!csv_file) {
      spdlog::error("--csv: cannot write '{}'", opt.csv);
      return kExitFailure;
    }
    csv = &csv_file;
  }
  *csv << "frame,id,u,v,heading_deg,score" << (calib ? ",x_m,y_m,theta_deg" : "") << "\n";

  vision::TrackerConfig config;
  if (opt.min_diameter_px > 0) config.blobs.min_diameter_px = opt.min_diameter_px;
  if (opt.max_diameter_px > 0) config.blobs.max_diameter_px = opt.max_diameter_px;
  if (opt.min_score > 0) config.min_assign_score = opt.min_score;
  vision::MarkerTracker tracker(*family, ids, config);

  cv::VideoWriter annotated;
  const bool show_progress = !opt.quiet && ::isatty(STDERR_FILENO);
  DetectCounts counts;
  const auto start = std::chrono::steady_clock::now();
  const InterruptFlag interrupt;
  while (!interrupt.raised() && (opt.max_frames < 0 || counts.frames < opt.max_frames)) {
    vision::FrameResult r = source.next();
    if (r.is_end()) break;
    if (r.is_error()) {
      ++counts.bad_frames;
      if (show_progress) std::fputc('\n', stderr);
      spdlog::warn("{}", r.error);
      continue;
    }
    ++counts.frames;
    const auto t0 = std::chrono::steady_clock::now();
    const auto found = opt.no_track ? tracker.detect_full_frame(r.image) : tracker.process(r.image);
    counts.pipeline_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    counts.declined += tracker.last_stats().declined;
    for (const auto& d : found) ++counts.per_id[d.id];
    counts.rows += static_cast<long>(found.size());
    write_rows(*csv, r.index, found, calib);
    if (!opt.annotate.empty()) write_annotated(annotated, opt, source, r, found);
    if (show_progress && counts.frames % 5 == 0) {
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      print_progress(r.index + 1, source.frame_count(), counts.frames / std::max(wall, 1e-9));
    }
  }
  if (show_progress) std::fputc('\n', stderr);
  csv->flush();
  print_summary(counts, ids, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                interrupt.raised());
  if (counts.frames == 0) {
    spdlog::error("no frame could be read from {}",
                  opt.camera >= 0 ? "camera " + std::to_string(opt.camera) : opt.input);
    return kExitFailure;
  }
  return 0;
}

}  // namespace

void add_detect_command(CLI::App& app) {
  auto opt = std::make_shared<DetectOptions>();
  CLI::App* cmd = app.add_subcommand("detect", "Find, identify and track markers in footage or a live camera");
  cmd->add_option("input", opt->input,
                  "Video file, image, directory of images (name order), printf-style sequence (img_%04d.png), or a "
                  "run's recording FILE.lcm made with --record-frames");
  cmd->add_option("--camera", opt->camera, "Live camera index instead of INPUT")->check(CLI::NonNegativeNumber);
  cmd->add_option("--family", opt->family, "Marker family (6ucp, or kucp for k in 7..14)")->capture_default_str();
  cmd->add_option("--ids", opt->ids, "IDs that may be present, e.g. 1-8 or 1,3,6 (default: every ID of the family)");
  cmd->add_option("--csv", opt->csv, "CSV output file, - for stdout")->capture_default_str();
  cmd->add_option("--calib", opt->calib, "Field calibration (rilbed calibrate field): adds x_m,y_m,theta_deg");
  cmd->add_option("--annotate", opt->annotate, "Write an annotated MJPG video (.avi) of what was found");
  cmd->add_flag("--no-track", opt->no_track, "Search the whole frame every frame (no tracking)");
  cmd->add_option("--max-frames", opt->max_frames, "Stop after N frames");
  cmd->add_option("--min-diameter-px", opt->min_diameter_px, "Smallest marker diameter in pixels (default 18)");
  cmd->add_option("--max-diameter-px", opt->max_diameter_px, "Largest marker diameter in pixels (default 480)");
  cmd->add_option("--min-score", opt->min_score, "Least similarity for an ID (default 0.75)");
  cmd->add_flag("-q,--quiet", opt->quiet, "No progress bar");
  cmd->callback([opt, cmd] {
    if (opt->input.empty() == (opt->camera < 0)) {
      throw CLI::ValidationError("detect", "give either INPUT or --camera N");
    }
    (void)cmd;
    exit_code() = run_detect(*opt);
  });
}

}  // namespace rilbed::app

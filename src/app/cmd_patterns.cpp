// `rilbed patterns`: writes printable marker files, one per requested ID, and with PDF
// also an A4 sheet of all of them.
//
//   rilbed patterns --ids 1-8 --diameter-mm D --format svg|pdf|png --px N --out DIR --family NAME
//
// Exit codes: 0 success, 2 a bad option value (nothing written), 1 an IO failure.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "app/commands.hpp"
#include "core/id_list.hpp"
#include "vision/marker_family.hpp"
#include "vision/pattern_writer.hpp"

namespace rilbed::app {
namespace {

namespace fs = std::filesystem;
using vision::MarkerFamily;
using vision::PatternFormat;
using vision::PatternResult;

/// The options as typed on the command line.
struct PatternsOptions {
  std::string ids;  ///< empty: every ID of the family
  double diameter_mm = 50.0;
  std::string format = "pdf";
  int size_px = 512;
  std::string out_dir = ".";
  std::string family = "6ucp";
};

/// The options checked and turned into values the writer takes.
struct PatternsJob {
  MarkerFamily family = MarkerFamily::six_ucp();
  std::vector<int> ids;
  PatternFormat format = PatternFormat::kPdf;
  double diameter_mm = 50.0;
  int size_px = 512;
  fs::path out_dir;
};

/// A usage error: the message names the offending option and value.
struct UsageError {
  std::string message;
};

std::string number_text(double value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

/// Checks every option before anything is written, so a typo never leaves half a set
/// of files behind.
std::optional<UsageError> make_job(const PatternsOptions& o, PatternsJob& job) {
  try {
    job.family = MarkerFamily::by_name(o.family);
  } catch (const std::invalid_argument& e) {
    return UsageError{std::string("--family: ") + e.what()};
  }
  if (o.ids.empty()) {
    for (int id = job.family.min_id(); id <= job.family.max_id(); ++id) job.ids.push_back(id);
  } else {
    IdListResult parsed = parse_id_list(o.ids, job.family.min_id(), job.family.max_id());
    if (!parsed.ok()) {
      return UsageError{"--ids '" + o.ids + "' for family " + job.family.name() + ": " + parsed.error};
    }
    job.ids = std::move(parsed.ids);
  }
  const std::optional<PatternFormat> format = vision::parse_pattern_format(o.format);
  if (!format) return UsageError{"--format: unknown format '" + o.format + "' (expected svg, pdf or png)"};
  job.format = *format;
  if (!(o.diameter_mm > 0.0) || !std::isfinite(o.diameter_mm)) {
    return UsageError{"--diameter-mm: " + number_text(o.diameter_mm) + " is not a positive length"};
  }
  if (job.format == PatternFormat::kPdf && o.diameter_mm > vision::max_sheet_diameter_mm()) {
    return UsageError{"--diameter-mm: " + number_text(o.diameter_mm) + " mm does not fit on the A4 sheet (at most " +
                      number_text(vision::max_sheet_diameter_mm()) + " mm); use --format svg for larger markers"};
  }
  job.diameter_mm = o.diameter_mm;
  if (o.size_px < 1 || o.size_px > vision::kMaxPngSizePx) {
    return UsageError{"--px: " + std::to_string(o.size_px) + " is outside 1.." + std::to_string(vision::kMaxPngSizePx)};
  }
  job.size_px = o.size_px;
  if (o.out_dir.empty()) return UsageError{"--out: empty directory name"};
  job.out_dir = o.out_dir;
  return std::nullopt;
}

/// Creates the output directory if missing; an error message naming it otherwise.
std::optional<std::string> prepare_out_dir(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return "cannot create output directory '" + dir.string() + "': " + ec.message();
  if (!fs::is_directory(dir, ec)) return "output path '" + dir.string() + "' is not a directory";
  return std::nullopt;
}

PatternResult write_one(const PatternsJob& job, int id, const fs::path& path) {
  switch (job.format) {
    case PatternFormat::kSvg: return vision::write_marker_svg(job.family, id, job.diameter_mm, path);
    case PatternFormat::kPdf: return vision::write_marker_pdf(job.family, id, job.diameter_mm, path);
    case PatternFormat::kPng: return vision::write_marker_png(job.family, id, job.size_px, path);
  }
  return PatternResult{"unhandled pattern format"};
}

/// Writes every file of the job, printing each path once it is written; stops at the
/// first failure (usually the directory is unwritable, so the rest would fail too).
int write_all(const PatternsJob& job) {
  if (const auto error = prepare_out_dir(job.out_dir)) {
    std::cerr << "rilbed patterns: " << *error << "\n";
    return kExitFailure;
  }
  for (int id : job.ids) {
    const fs::path path = job.out_dir / vision::marker_file_name(job.family, id, job.format);
    if (const PatternResult r = write_one(job, id, path); !r.ok()) {
      std::cerr << "rilbed patterns: " << r.error << "\n";
      return kExitFailure;
    }
    std::cout << path.string() << "\n";
  }
  if (job.format == PatternFormat::kPdf) {
    const fs::path path = job.out_dir / vision::sheet_file_name(job.family);
    if (const PatternResult r = vision::write_marker_sheet_pdf(job.family, job.ids, job.diameter_mm, path); !r.ok()) {
      std::cerr << "rilbed patterns: " << r.error << "\n";
      return kExitFailure;
    }
    std::cout << path.string() << "\n";
  }
  return 0;
}

int run_patterns(const PatternsOptions& options) {
  PatternsJob job;
  if (const auto usage = make_job(options, job)) {
    std::cerr << "rilbed patterns: " << usage->message << "\n";
    return kExitUsage;
  }
  return write_all(job);
}

}  // namespace

void add_patterns_command(CLI::App& app) {
  // Shared with the callback, which runs after parsing, when this function has returned.
  auto options = std::make_shared<PatternsOptions>();
  CLI::App* cmd = app.add_subcommand("patterns", "Write printable marker files (SVG, PDF or PNG)");
  cmd->add_option("--ids", options->ids, "IDs to write, e.g. 1-8 or 1,3,5-7 (default: every ID of the family)");
  cmd->add_option("--diameter-mm", options->diameter_mm, "Marker outer diameter on paper, in mm (SVG, PDF)")
      ->capture_default_str();
  cmd->add_option("--format", options->format, "svg, pdf (one file per ID plus an A4 sheet) or png")
      ->capture_default_str();
  cmd->add_option("--px", options->size_px, "PNG width and height in pixels")->capture_default_str();
  cmd->add_option("--out", options->out_dir, "Output directory, created if missing")->capture_default_str();
  cmd->add_option("--family", options->family, "Marker family: 6ucp, or kucp for k in 7..14")->capture_default_str();
  cmd->callback([options] { exit_code() = run_patterns(*options); });
}

}  // namespace rilbed::app

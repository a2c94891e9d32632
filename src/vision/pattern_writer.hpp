// Printable and displayable marker files: one marker as SVG, PDF or PNG, and A4 PDF
// sheets of several markers with a scale bar. Every shape is drawn from MarkerFamily
// (slice angles and colours, ring radii), so a printed marker is exactly the marker the
// decoder and the synthetic camera model.
//
// Orientation: slice angles grow counter-clockwise as seen on the printed page or on
// screen, and the key slice's bisector (the robot's forward direction) points to the
// right (+u in an image, +x on the page).
//
// Vector output (SVG, PDF) is at true size, so that a marker printed at 100 % scaling has
// the requested diameter. PNG output is a square image whose white outer ring touches
// the image edges, with fully transparent corners.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "vision/marker_family.hpp"

namespace rilbed::vision {

/// File formats the pattern writer produces.
enum class PatternFormat { kSvg, kPdf, kPng };

/// Parses "svg", "pdf" or "png" (case-insensitive); nullopt for anything else.
std::optional<PatternFormat> parse_pattern_format(std::string_view text);

/// File extension of a format without the dot: "svg", "pdf" or "png".
std::string_view pattern_extension(PatternFormat format);

/// Name of the file holding one marker: "<family>_id<N>.<ext>", e.g. "6ucp_id3.pdf".
std::string marker_file_name(const MarkerFamily& family, int id, PatternFormat format);

/// Name of the A4 sheet file of a family: "<family>_sheet.pdf", e.g. "6ucp_sheet.pdf".
std::string sheet_file_name(const MarkerFamily& family);

/// Outcome of writing a file: empty error on success, otherwise a message that names
/// the file and the reason (cairo's status text for drawing and IO failures).
struct PatternResult {
  std::string error;  ///< empty on success
  bool ok() const { return error.empty(); }
};

/// Largest PNG side the writer accepts, in pixels. A bound keeps a mistyped --px from
/// asking for gigabytes (an ARGB32 image of 8192 px is 256 MiB).
inline constexpr int kMaxPngSizePx = 8192;

/// Paper size of the sheets: A4 portrait, in millimetres (595.28 x 841.89 pt).
inline constexpr double kA4WidthMm = 210.0;
inline constexpr double kA4HeightMm = 297.0;

/// Largest marker diameter, in millimetres, that fits on an A4 sheet together with
/// the margins, the title, the ID label and the scale bar.
double max_sheet_diameter_mm();

/// Writes marker `id` of `family` as an SVG file of true size: the document is
/// diameter_mm x diameter_mm millimetres (width="<d>mm"), the marker fills it.
/// Fails (without throwing) for an invalid id, a non-positive diameter or IO errors.
PatternResult write_marker_svg(const MarkerFamily& family, int id, double diameter_mm,
                               const std::filesystem::path& path);

/// Writes marker `id` as a one-page PDF of true size: the page is diameter_mm square
/// (converted to points, 1 mm = 72/25.4 pt) and the marker fills it.
PatternResult write_marker_pdf(const MarkerFamily& family, int id, double diameter_mm,
                               const std::filesystem::path& path);

/// Writes marker `id` as a size_px x size_px ARGB PNG: centred, outer radius
/// size_px / 2 so the white outer ring touches the four edges, corners outside the
/// marker fully transparent, key slice pointing right. size_px in [1, kMaxPngSizePx].
PatternResult write_marker_png(const MarkerFamily& family, int id, int size_px, const std::filesystem::path& path);

/// Writes markers `ids` (each a valid ID of `family`) at true size diameter_mm on
/// A4 portrait pages: a title line (family, diameter), a grid of markers each with a
/// thin grey cut circle and its ID and family name under it, and a 100 mm scale bar
/// with 10 mm ticks to check the printer's scaling. Uses as many pages as needed.
/// Fails for an empty list, an invalid id, a diameter outside
/// (0, max_sheet_diameter_mm()] or IO errors.
PatternResult write_marker_sheet_pdf(const MarkerFamily& family, const std::vector<int>& ids, double diameter_mm,
                                     const std::filesystem::path& path);

}  // namespace rilbed::vision

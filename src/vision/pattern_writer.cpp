#include "vision/pattern_writer.hpp"

#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <sstream>
#include <system_error>

#include "core/geometry.hpp"

namespace rilbed::vision {
namespace {

/// PDF user space is in points (1/72 inch).
constexpr double kPtPerMm = 72.0 / 25.4;

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* cr) const { cairo_destroy(cr); }
};
using SurfacePtr = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using ContextPtr = std::unique_ptr<cairo_t, ContextDeleter>;

// ------------------------------------------------------------------ marker drawing

/// Cairo's y axis points down, so its angles grow clockwise on screen; an angle that is
/// counter-clockwise on screen (as MarkerFamily's are) is the negated cairo angle.
double cairo_angle_rad(double ccw_on_screen_deg) { return -deg_to_rad(ccw_on_screen_deg); }

void fill_disc(cairo_t* cr, double radius, double grey) {
  cairo_set_source_rgb(cr, grey, grey, grey);
  cairo_new_path(cr);
  cairo_arc(cr, 0.0, 0.0, radius, 0.0, 2.0 * kPi);
  cairo_fill(cr);
}

/// Fills the annular sector between radii inner and outer, from start_deg to end_deg
/// counter-clockwise on screen, with the current source.
void fill_annular_sector(cairo_t* cr, double inner, double outer, double start_deg, double end_deg) {
  cairo_new_path(cr);
  // On screen: outer arc from start to end counter-clockwise, i.e. cairo angles from
  // -end up to -start; then back along the inner arc.
  cairo_arc(cr, 0.0, 0.0, outer, cairo_angle_rad(end_deg), cairo_angle_rad(start_deg));
  cairo_arc_negative(cr, 0.0, 0.0, inner, cairo_angle_rad(start_deg), cairo_angle_rad(end_deg));
  cairo_close_path(cr);
  cairo_fill(cr);
}

/// The white slices of marker `id`, with neighbouring white slices merged into one run.
/// Drawing a run as one shape avoids the faint seam that two antialiased shapes sharing
/// an edge leave in raster output. Runs never wrap around the end of the list because
/// the last slice is a black guard.
std::vector<MarkerSlice> white_runs(const MarkerFamily& family, int id) {
  std::vector<MarkerSlice> runs;
  bool previous_white = false;
  for (const MarkerSlice& s : family.slices(id)) {
    if (s.white && previous_white) {
      runs.back().end_deg = s.end_deg;
    } else if (s.white) {
      runs.push_back(s);
    }
    previous_white = s.white;
  }
  return runs;
}

/// Draws marker `id` centred on the user-space origin with outer radius `radius` (user
/// units). The white outer disc goes first; one black disc then forms the black ring and
/// the ground of the hole and the black slices; the white slice runs go on top. Layering
/// (rather than tiling black and white sectors) leaves no background-coloured hairlines
/// between neighbouring shapes in any renderer.
void draw_marker(cairo_t* cr, const MarkerFamily& family, int id, double radius) {
  fill_disc(cr, radius, 1.0);
  fill_disc(cr, radius * MarkerFamily::black_ring_outer_radius, 0.0);
  cairo_set_source_rgb(cr, 1.0, 1.0, 1.0);
  for (const MarkerSlice& run : white_runs(family, id)) {
    fill_annular_sector(cr, radius * MarkerFamily::hole_radius, radius * MarkerFamily::code_outer_radius, run.start_deg,
                        run.end_deg);
  }
}

// ------------------------------------------------------------------ errors and files

/// The path in single quotes. Appended piece by piece: GCC 12 raises a false -Wrestrict
/// on `"'" + std::string`.
std::string quoted(const std::filesystem::path& path) {
  std::string text(1, '\'');
  text += path.string();
  text += '\'';
  return text;
}

PatternResult failure(std::string message) { return PatternResult{std::move(message)}; }

/// Checks the inputs every marker writer shares.
PatternResult check_id(const MarkerFamily& family, int id) {
  if (family.valid_id(id)) return {};
  return failure("ID " + std::to_string(id) + " is not in family " + family.name() + " (" +
                 std::to_string(family.min_id()) + ".." + std::to_string(family.max_id()) + ")");
}

PatternResult check_diameter(double diameter_mm) {
  if (std::isfinite(diameter_mm) && diameter_mm > 0.0) return {};
  std::ostringstream s;
  s << "marker diameter " << diameter_mm << " mm is not positive";
  return failure(s.str());
}

/// Turns a cairo status into a result naming the file; removes a partly written file
/// so that a failed run leaves nothing that looks like a valid marker.
PatternResult file_result(cairo_status_t status, const std::filesystem::path& path) {
  if (status == CAIRO_STATUS_SUCCESS) return {};
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
  return failure("cannot write " + quoted(path) + ": " + cairo_status_to_string(status));
}

/// Finishes a file-backed vector surface (which flushes it to disk) and reports the
/// first error of the drawing context or the surface.
PatternResult finish_vector(cairo_surface_t* surface, cairo_t* cr, const std::filesystem::path& path) {
  cairo_status_t status = cairo_status(cr);
  if (status == CAIRO_STATUS_SUCCESS) {
    cairo_surface_finish(surface);
    status = cairo_surface_status(surface);
  }
  return file_result(status, path);
}

void set_pdf_metadata(cairo_surface_t* surface, const std::string& title) {
  cairo_pdf_surface_set_metadata(surface, CAIRO_PDF_METADATA_TITLE, title.c_str());
  cairo_pdf_surface_set_metadata(surface, CAIRO_PDF_METADATA_CREATOR, "rilbed patterns");
}

/// "50", "52.5": a length as a person would write it.
std::string format_mm(double mm) {
  std::ostringstream s;
  s.precision(6);
  s << mm;
  return s.str();
}

// ------------------------------------------------------------------ sheet layout

/// Sheet geometry in millimetres. Sizes are chosen so that labels are readable (about
/// 10 pt) and a marker can be cut out along its grey circle without touching the next.
namespace sheet {
constexpr double margin_mm = 15.0;
constexpr double title_height_mm = 12.0;
constexpr double title_font_mm = 4.5;
constexpr double label_height_mm = 7.0;
constexpr double label_font_mm = 3.5;
constexpr double gap_mm = 6.0;
/// The grey cut circle lies this far outside the marker's outer edge, so that cutting
/// along it keeps the whole white ring.
constexpr double cut_offset_mm = 0.5;
constexpr double cut_line_mm = 0.15;
constexpr double scale_bar_height_mm = 22.0;
constexpr double scale_bar_length_mm = 100.0;
constexpr double scale_tick_step_mm = 10.0;

constexpr double usable_width_mm = kA4WidthMm - 2.0 * margin_mm;
constexpr double grid_top_mm = margin_mm + title_height_mm;
constexpr double grid_bottom_mm = kA4HeightMm - margin_mm - scale_bar_height_mm;
constexpr double grid_height_mm = grid_bottom_mm - grid_top_mm;
}  // namespace sheet

/// Where markers go on a page: a grid of equal cells, centred horizontally.
struct SheetGrid {
  int columns = 1;
  int rows = 1;
  double cell_width_mm = 0.0;   ///< marker plus cut margin on both sides
  double cell_height_mm = 0.0;  ///< that plus the label under it
  double left_mm = 0.0;         ///< left edge of the first column

  int per_page() const { return columns * rows; }
};

int cells_that_fit(double space_mm, double cell_mm) {
  return std::max(1, static_cast<int>(std::floor((space_mm + sheet::gap_mm) / (cell_mm + sheet::gap_mm))));
}

SheetGrid sheet_grid(double diameter_mm) {
  SheetGrid g;
  g.cell_width_mm = diameter_mm + 2.0 * sheet::cut_offset_mm;
  g.cell_height_mm = g.cell_width_mm + sheet::label_height_mm;
  g.columns = cells_that_fit(sheet::usable_width_mm, g.cell_width_mm);
  g.rows = cells_that_fit(sheet::grid_height_mm, g.cell_height_mm);
  const double grid_width_mm = g.columns * g.cell_width_mm + (g.columns - 1) * sheet::gap_mm;
  g.left_mm = (kA4WidthMm - grid_width_mm) / 2.0;
  return g;
}

void show_text_centred(cairo_t* cr, const std::string& text, double centre_x, double baseline_y) {
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  cairo_move_to(cr, centre_x - extents.x_bearing - extents.width / 2.0, baseline_y);
  cairo_show_text(cr, text.c_str());
}

void draw_cut_circle(cairo_t* cr, double radius_mm) {
  cairo_set_source_rgb(cr, 0.6, 0.6, 0.6);
  cairo_set_line_width(cr, sheet::cut_line_mm);
  cairo_new_path(cr);
  cairo_arc(cr, 0.0, 0.0, radius_mm + sheet::cut_offset_mm, 0.0, 2.0 * kPi);
  cairo_stroke(cr);
}

/// Draws one marker with its cut circle and label in grid cell `index` (row-major).
void draw_sheet_cell(cairo_t* cr, const MarkerFamily& family, int id, double diameter_mm, const SheetGrid& grid,
                     int index) {
  const int column = index % grid.columns;
  const int row = index / grid.columns;
  const double centre_x = grid.left_mm + column * (grid.cell_width_mm + sheet::gap_mm) + grid.cell_width_mm / 2.0;
  const double centre_y = sheet::grid_top_mm + row * (grid.cell_height_mm + sheet::gap_mm) + grid.cell_width_mm / 2.0;
  const double radius_mm = diameter_mm / 2.0;
  cairo_save(cr);
  cairo_translate(cr, centre_x, centre_y);
  draw_marker(cr, family, id, radius_mm);
  draw_cut_circle(cr, radius_mm);
  cairo_restore(cr);
  cairo_set_source_rgb(cr, 0.0, 0.0, 0.0);
  cairo_set_font_size(cr, sheet::label_font_mm);
  const double label_baseline = centre_y + grid.cell_width_mm / 2.0 + 0.75 * sheet::label_height_mm;
  show_text_centred(cr, "ID " + std::to_string(id) + "  " + family.name(), centre_x, label_baseline);
}

void draw_title(cairo_t* cr, const MarkerFamily& family, double diameter_mm, int page, int pages) {
  std::string title = "rilbed markers: family " + family.name() + ", diameter " + format_mm(diameter_mm) +
                      " mm, print at actual size (100 %)";
  if (pages > 1) title += ", page " + std::to_string(page + 1) + "/" + std::to_string(pages);
  cairo_set_source_rgb(cr, 0.0, 0.0, 0.0);
  cairo_set_font_size(cr, sheet::title_font_mm);
  // Long family names and page numbers must not run off the page: shrink to fit.
  cairo_text_extents_t extents;
  cairo_text_extents(cr, title.c_str(), &extents);
  if (extents.x_advance > sheet::usable_width_mm) {
    cairo_set_font_size(cr, sheet::title_font_mm * sheet::usable_width_mm / extents.x_advance);
  }
  cairo_move_to(cr, sheet::margin_mm, sheet::margin_mm + sheet::title_font_mm);
  cairo_show_text(cr, title.c_str());
}

/// A 100 mm bar with a tick every 10 mm (taller at 0, 50 and 100) and its caption, at
/// the bottom of the page: measuring it tells whether the printer scaled the page.
void draw_scale_bar(cairo_t* cr) {
  const double left = sheet::margin_mm;
  const double baseline = kA4HeightMm - sheet::margin_mm - sheet::scale_bar_height_mm + 8.0;
  cairo_set_source_rgb(cr, 0.0, 0.0, 0.0);
  cairo_set_line_width(cr, 0.3);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_SQUARE);
  cairo_new_path(cr);
  cairo_move_to(cr, left, baseline);
  cairo_line_to(cr, left + sheet::scale_bar_length_mm, baseline);
  const int ticks = static_cast<int>(std::lround(sheet::scale_bar_length_mm / sheet::scale_tick_step_mm));
  for (int i = 0; i <= ticks; ++i) {
    const double x = left + i * sheet::scale_tick_step_mm;
    const double tick_mm = (i % 5 == 0) ? 5.0 : 3.0;
    cairo_move_to(cr, x, baseline);
    cairo_line_to(cr, x, baseline - tick_mm);
  }
  cairo_stroke(cr);
  cairo_set_font_size(cr, sheet::label_font_mm);
  cairo_move_to(cr, left, baseline + 6.0);
  const std::string caption = format_mm(sheet::scale_bar_length_mm) + " mm \u2014 check your printer scaling";
  cairo_show_text(cr, caption.c_str());
}

PatternResult check_sheet_inputs(const MarkerFamily& family, const std::vector<int>& ids, double diameter_mm) {
  if (ids.empty()) return failure("no marker IDs to put on the sheet");
  for (int id : ids) {
    if (PatternResult r = check_id(family, id); !r.ok()) return r;
  }
  if (PatternResult r = check_diameter(diameter_mm); !r.ok()) return r;
  if (diameter_mm > max_sheet_diameter_mm()) {
    return failure("marker diameter " + format_mm(diameter_mm) + " mm does not fit on an A4 sheet (at most " +
                   format_mm(max_sheet_diameter_mm()) + " mm)");
  }
  return {};
}

}  // namespace

// ------------------------------------------------------------------ public interface

std::optional<PatternFormat> parse_pattern_format(std::string_view text) {
  std::string lower;
  for (char c : text) lower.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  if (lower == "svg") return PatternFormat::kSvg;
  if (lower == "pdf") return PatternFormat::kPdf;
  if (lower == "png") return PatternFormat::kPng;
  return std::nullopt;
}

std::string_view pattern_extension(PatternFormat format) {
  switch (format) {
    case PatternFormat::kSvg: return "svg";
    case PatternFormat::kPdf: return "pdf";
    case PatternFormat::kPng: return "png";
  }
  return "";
}

std::string marker_file_name(const MarkerFamily& family, int id, PatternFormat format) {
  return family.name() + "_id" + std::to_string(id) + "." + std::string(pattern_extension(format));
}

std::string sheet_file_name(const MarkerFamily& family) { return family.name() + "_sheet.pdf"; }

double max_sheet_diameter_mm() {
  const double width_limit = sheet::usable_width_mm;
  const double height_limit = sheet::grid_height_mm - sheet::label_height_mm;
  return std::min(width_limit, height_limit) - 2.0 * sheet::cut_offset_mm;
}

PatternResult write_marker_svg(const MarkerFamily& family, int id, double diameter_mm,
                               const std::filesystem::path& path) {
  if (PatternResult r = check_id(family, id); !r.ok()) return r;
  if (PatternResult r = check_diameter(diameter_mm); !r.ok()) return r;
  // With the document unit set to millimetres, cairo writes width="<d>mm" and a viewBox
  // of d x d, so one user unit is one millimetre and the file is true size.
  SurfacePtr surface(cairo_svg_surface_create(path.c_str(), diameter_mm, diameter_mm));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    return file_result(cairo_surface_status(surface.get()), path);
  }
  cairo_svg_surface_set_document_unit(surface.get(), CAIRO_SVG_UNIT_MM);
  ContextPtr cr(cairo_create(surface.get()));
  cairo_translate(cr.get(), diameter_mm / 2.0, diameter_mm / 2.0);
  draw_marker(cr.get(), family, id, diameter_mm / 2.0);
  return finish_vector(surface.get(), cr.get(), path);
}

PatternResult write_marker_pdf(const MarkerFamily& family, int id, double diameter_mm,
                               const std::filesystem::path& path) {
  if (PatternResult r = check_id(family, id); !r.ok()) return r;
  if (PatternResult r = check_diameter(diameter_mm); !r.ok()) return r;
  const double size_pt = diameter_mm * kPtPerMm;
  SurfacePtr surface(cairo_pdf_surface_create(path.c_str(), size_pt, size_pt));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    return file_result(cairo_surface_status(surface.get()), path);
  }
  set_pdf_metadata(surface.get(),
                   family.name() + " marker ID " + std::to_string(id) + ", " + format_mm(diameter_mm) + " mm");
  ContextPtr cr(cairo_create(surface.get()));
  cairo_scale(cr.get(), kPtPerMm, kPtPerMm);  // user units are millimetres from here on
  cairo_translate(cr.get(), diameter_mm / 2.0, diameter_mm / 2.0);
  draw_marker(cr.get(), family, id, diameter_mm / 2.0);
  return finish_vector(surface.get(), cr.get(), path);
}

PatternResult write_marker_png(const MarkerFamily& family, int id, int size_px, const std::filesystem::path& path) {
  if (PatternResult r = check_id(family, id); !r.ok()) return r;
  if (size_px < 1 || size_px > kMaxPngSizePx) {
    return failure("PNG size " + std::to_string(size_px) + " px is outside 1.." + std::to_string(kMaxPngSizePx));
  }
  // A new ARGB32 image surface is all zeros, i.e. fully transparent outside the marker.
  SurfacePtr surface(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, size_px, size_px));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    return failure("cannot render " + quoted(path) + ": " +
                   cairo_status_to_string(cairo_surface_status(surface.get())));
  }
  ContextPtr cr(cairo_create(surface.get()));
  const double radius_px = size_px / 2.0;
  cairo_translate(cr.get(), radius_px, radius_px);
  draw_marker(cr.get(), family, id, radius_px);
  cairo_surface_flush(surface.get());
  if (cairo_status(cr.get()) != CAIRO_STATUS_SUCCESS) return file_result(cairo_status(cr.get()), path);
  return file_result(cairo_surface_write_to_png(surface.get(), path.c_str()), path);
}

PatternResult write_marker_sheet_pdf(const MarkerFamily& family, const std::vector<int>& ids, double diameter_mm,
                                     const std::filesystem::path& path) {
  if (PatternResult r = check_sheet_inputs(family, ids, diameter_mm); !r.ok()) return r;
  SurfacePtr surface(cairo_pdf_surface_create(path.c_str(), kA4WidthMm * kPtPerMm, kA4HeightMm * kPtPerMm));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    return file_result(cairo_surface_status(surface.get()), path);
  }
  set_pdf_metadata(surface.get(), family.name() + " markers, " + format_mm(diameter_mm) + " mm");
  ContextPtr cr(cairo_create(surface.get()));
  cairo_scale(cr.get(), kPtPerMm, kPtPerMm);  // user units are millimetres from here on
  cairo_select_font_face(cr.get(), "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  const SheetGrid grid = sheet_grid(diameter_mm);
  const int count = static_cast<int>(ids.size());
  const int pages = (count + grid.per_page() - 1) / grid.per_page();
  for (int page = 0; page < pages; ++page) {
    draw_title(cr.get(), family, diameter_mm, page, pages);
    const int first = page * grid.per_page();
    for (int i = first; i < std::min(count, first + grid.per_page()); ++i) {
      draw_sheet_cell(cr.get(), family, ids[static_cast<std::size_t>(i)], diameter_mm, grid, i - first);
    }
    draw_scale_bar(cr.get());
    cairo_show_page(cr.get());
  }
  return finish_vector(surface.get(), cr.get(), path);
}

}  // namespace rilbed::vision

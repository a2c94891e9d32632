// Tests of the marker file writer: PNGs are read back and compared with MarkerFamily's
// definition pixel by pixel; vector files are checked for true size and page size.
#include "vision/pattern_writer.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <yaml-cpp/yaml.h>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "core/geometry.hpp"
#include "vision/marker_family.hpp"

namespace rilbed::vision {
namespace {

namespace fs = std::filesystem;

/// A fresh directory for this test's files.
fs::path scratch_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("rilbed_test_pattern_writer_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Writes marker `id` as a PNG and reads it back unchanged (BGRA).
cv::Mat render_png(const MarkerFamily& family, int id, int size_px, const fs::path& dir) {
  const fs::path path = dir / marker_file_name(family, id, PatternFormat::kPng);
  const PatternResult result = write_marker_png(family, id, size_px, path);
  EXPECT_TRUE(result.ok()) << result.error;
  return cv::imread(path.string(), cv::IMREAD_UNCHANGED);
}

/// The pixel under polar point (r as a fraction of R, angle counter-clockwise on screen
/// from +u) in a size_px image whose marker has R = size_px / 2. v grows downwards, so a
/// positive angle moves up.
cv::Point pixel_at(double r, double angle_deg, int size_px) {
  const double radius_px = size_px / 2.0;
  const double u = radius_px + r * radius_px * std::cos(deg_to_rad(angle_deg));
  const double v = radius_px - r * radius_px * std::sin(deg_to_rad(angle_deg));
  return {static_cast<int>(std::floor(u)), static_cast<int>(std::floor(v))};
}

cv::Vec4b bgra_at(const cv::Mat& image, double r, double angle_deg) {
  return image.at<cv::Vec4b>(pixel_at(r, angle_deg, image.cols));
}

bool is_opaque_white(const cv::Vec4b& p) { return p[3] == 255 && p[0] > 200 && p[1] > 200 && p[2] > 200; }
bool is_opaque_black(const cv::Vec4b& p) { return p[3] == 255 && p[0] < 55 && p[1] < 55 && p[2] < 55; }

/// True when the polar point is within margin_px of a ring or slice boundary, where
/// antialiasing and pixel quantisation make the colour legitimately uncertain.
bool near_boundary(const MarkerFamily& family, int id, double r, double angle_deg, double radius_px, double margin_px) {
  for (double ring :
       {MarkerFamily::hole_radius, MarkerFamily::code_outer_radius, MarkerFamily::black_ring_outer_radius, 1.0}) {
    if (std::abs(r - ring) * radius_px < margin_px) return true;
  }
  if (r <= MarkerFamily::hole_radius || r >= MarkerFamily::code_outer_radius) return false;
  for (const MarkerSlice& s : family.slices(id)) {
    const double off_deg = std::abs(wrap_deg_180(angle_deg - s.start_deg));
    if (deg_to_rad(off_deg) * r * radius_px < margin_px) return true;
  }
  return false;
}

/// Fraction of sampled polar points, away from boundaries, whose pixel is opaque and
/// has the colour MarkerFamily::colour_at gives.
double agreement(const MarkerFamily& family, int id, const cv::Mat& image, int* samples) {
  const double radius_px = image.cols / 2.0;
  int agree = 0;
  int total = 0;
  for (double r = 0.01; r < 0.995; r += 0.0125) {
    for (double angle = 0.0; angle < 360.0; angle += 2.5) {
      if (near_boundary(family, id, r, angle, radius_px, 2.0)) continue;
      const cv::Vec4b p = bgra_at(image, r, angle);
      const bool want_white = family.colour_at(id, r, angle) > 0.5;
      ++total;
      if (want_white ? is_opaque_white(p) : is_opaque_black(p)) ++agree;
    }
  }
  *samples = total;
  return total == 0 ? 0.0 : static_cast<double>(agree) / total;
}

void expect_matches_family(const MarkerFamily& family, int id, const fs::path& dir) {
  const cv::Mat image = render_png(family, id, 256, dir);
  ASSERT_FALSE(image.empty());
  int samples = 0;
  EXPECT_GT(agreement(family, id, image, &samples), 0.99) << family.name() << " ID " << id;
  EXPECT_GT(samples, 3000);
}

struct MediaBox {
  double width_pt = 0.0;
  double height_pt = 0.0;
};

/// Every page's /MediaBox in a PDF (cairo writes them as plain text).
std::vector<MediaBox> media_boxes(const std::string& pdf) {
  static const std::regex box(R"(/MediaBox\s*\[\s*([-\d.]+)\s+([-\d.]+)\s+([-\d.]+)\s+([-\d.]+)\s*\])");
  std::vector<MediaBox> boxes;
  for (auto it = std::sregex_iterator(pdf.begin(), pdf.end(), box); it != std::sregex_iterator(); ++it) {
    const std::smatch& m = *it;
    boxes.push_back({std::stod(m[3]) - std::stod(m[1]), std::stod(m[4]) - std::stod(m[2])});
  }
  return boxes;
}

/// Number of page objects ("/Type /Page", not "/Type /Pages").
int page_count(const std::string& pdf) {
  static const std::regex page(R"(/Type\s*/Page(?![a-zA-Z]))");
  return static_cast<int>(std::distance(std::sregex_iterator(pdf.begin(), pdf.end(), page), std::sregex_iterator()));
}

/// The value and unit of an attribute of the <svg> element, e.g. width="50mm".
std::pair<double, std::string> svg_length(const std::string& svg, const std::string& attribute) {
  const std::regex length("<svg[^>]*\\s" + attribute + "=\"([\\d.]+)([a-z]*)\"");
  std::smatch m;
  if (!std::regex_search(svg, m, length)) return {-1.0, ""};
  return {std::stod(m[1]), m[2]};
}

// ------------------------------------------------------------------ names and formats

TEST(PatternWriter, FileNamesFollowTheContract) {
  const MarkerFamily six = MarkerFamily::six_ucp();
  EXPECT_EQ(marker_file_name(six, 3, PatternFormat::kPdf), "6ucp_id3.pdf");
  EXPECT_EQ(marker_file_name(six, 8, PatternFormat::kPng), "6ucp_id8.png");
  EXPECT_EQ(marker_file_name(MarkerFamily::k_ucp(9), 64, PatternFormat::kSvg), "9ucp_id64.svg");
  EXPECT_EQ(sheet_file_name(six), "6ucp_sheet.pdf");
}

TEST(PatternWriter, ParsesFormatsCaseInsensitively) {
  EXPECT_EQ(parse_pattern_format("svg"), PatternFormat::kSvg);
  EXPECT_EQ(parse_pattern_format("PDF"), PatternFormat::kPdf);
  EXPECT_EQ(parse_pattern_format("Png"), PatternFormat::kPng);
  EXPECT_FALSE(parse_pattern_format("jpg").has_value());
  EXPECT_FALSE(parse_pattern_format("").has_value());
}

// ------------------------------------------------------------------ PNG

TEST(PatternWriter, PngOfEverySixUcpIdMatchesTheFamily) {
  const fs::path dir = scratch_dir("png6");
  const MarkerFamily family = MarkerFamily::six_ucp();
  for (int id = family.min_id(); id <= family.max_id(); ++id) expect_matches_family(family, id, dir);
  fs::remove_all(dir);
}

TEST(PatternWriter, PngOfNineUcpIdsMatchesTheFamily) {
  const fs::path dir = scratch_dir("png9");
  const MarkerFamily family = MarkerFamily::k_ucp(9);
  for (int id : {1, 2, 23, 37, 63, 64}) expect_matches_family(family, id, dir);
  fs::remove_all(dir);
}

TEST(PatternWriter, PngIsSquareBgraWithTransparentCorners) {
  const fs::path dir = scratch_dir("corners");
  const cv::Mat image = render_png(MarkerFamily::six_ucp(), 5, 200, dir);
  ASSERT_EQ(image.type(), CV_8UC4);
  ASSERT_EQ(image.cols, 200);
  ASSERT_EQ(image.rows, 200);
  for (cv::Point corner : {cv::Point(0, 0), cv::Point(199, 0), cv::Point(0, 199), cv::Point(199, 199),
                           cv::Point(20, 20), cv::Point(179, 25)}) {
    EXPECT_EQ(image.at<cv::Vec4b>(corner)[3], 0) << corner;
  }
  fs::remove_all(dir);
}

TEST(PatternWriter, PngOuterWhiteRingTouchesEveryEdge) {
  const fs::path dir = scratch_dir("edges");
  for (int size_px : {200, 201}) {
    const cv::Mat image = render_png(MarkerFamily::six_ucp(), 1, size_px, dir);
    ASSERT_FALSE(image.empty());
    const int mid = size_px / 2;
    const int last = size_px - 1;
    for (cv::Point edge : {cv::Point(mid, 0), cv::Point(mid, last), cv::Point(0, mid), cv::Point(last, mid)}) {
      const cv::Vec4b p = image.at<cv::Vec4b>(edge);
      EXPECT_GT(p[3], 128) << "size " << size_px << " at " << edge;
      EXPECT_GT(p[0], 200) << "size " << size_px << " at " << edge;
      EXPECT_GT(p[2], 200) << "size " << size_px << " at " << edge;
    }
  }
  fs::remove_all(dir);
}

TEST(PatternWriter, PngKeySlicePointsRight) {
  const fs::path dir = scratch_dir("key");
  const MarkerFamily family = MarkerFamily::six_ucp();
  for (int id = family.min_id(); id <= family.max_id(); ++id) {
    const cv::Mat image = render_png(family, id, 256, dir);
    EXPECT_TRUE(is_opaque_white(bgra_at(image, 0.4, 0.0))) << "ID " << id;
  }
  // ID 1 has only the key slice white, so the point opposite it is black.
  const cv::Mat id1 = render_png(family, 1, 256, dir);
  EXPECT_TRUE(is_opaque_black(bgra_at(id1, 0.4, 180.0)));
  fs::remove_all(dir);
}

TEST(PatternWriter, PngSlicesRunCounterClockwiseOnScreen) {
  // ID 2 has x1 = 1: the first code slice (6UCP: 97.5..152.5 degrees) is white. Counter-
  // clockwise on screen is upwards from +u, so the white slice is up-left (smaller v)
  // and its mirror image down-left is black. A y-flip mistake swaps the two.
  const fs::path dir = scratch_dir("ccw");
  const MarkerFamily family = MarkerFamily::six_ucp();
  const cv::Mat image = render_png(family, 2, 256, dir);
  const cv::Point up_left = pixel_at(0.4, 125.0, image.cols);
  EXPECT_LT(up_left.y, image.rows / 2);
  EXPECT_LT(up_left.x, image.cols / 2);
  EXPECT_TRUE(is_opaque_white(image.at<cv::Vec4b>(up_left)));
  EXPECT_TRUE(is_opaque_black(bgra_at(image, 0.4, -125.0)));
  // The same for the last code bit of 9ucp: ID 33 has only x6 set, the slice just
  // clockwise of the last black guard, i.e. below +u on screen.
  const MarkerFamily nine = MarkerFamily::k_ucp(9);
  const std::vector<MarkerSlice> slices = nine.slices(33);
  const MarkerSlice& x6 = slices[7];
  ASSERT_TRUE(x6.white);
  const double middle_deg = (x6.start_deg + x6.end_deg) / 2.0;
  const cv::Mat image9 = render_png(nine, 33, 256, dir);
  EXPECT_GT(pixel_at(0.4, middle_deg, image9.cols).y, image9.rows / 2);
  EXPECT_TRUE(is_opaque_white(bgra_at(image9, 0.4, middle_deg)));
  EXPECT_TRUE(is_opaque_black(bgra_at(image9, 0.4, -middle_deg)));
  fs::remove_all(dir);
}

TEST(PatternWriter, PngRejectsBadSizeAndId) {
  const fs::path dir = scratch_dir("bad_png");
  const MarkerFamily family = MarkerFamily::six_ucp();
  const PatternResult zero = write_marker_png(family, 1, 0, dir / "a.png");
  EXPECT_FALSE(zero.ok());
  EXPECT_NE(zero.error.find("0 px"), std::string::npos) << zero.error;
  EXPECT_FALSE(write_marker_png(family, 1, kMaxPngSizePx + 1, dir / "a.png").ok());
  const PatternResult bad_id = write_marker_png(family, 9, 64, dir / "a.png");
  EXPECT_FALSE(bad_id.ok());
  EXPECT_NE(bad_id.error.find("ID 9"), std::string::npos) << bad_id.error;
  EXPECT_FALSE(fs::exists(dir / "a.png"));
  fs::remove_all(dir);
}

// ------------------------------------------------------------------ SVG and PDF

TEST(PatternWriter, SvgIsTrueSizeInMillimetres) {
  const fs::path dir = scratch_dir("svg");
  const fs::path path = dir / "m.svg";
  const PatternResult result = write_marker_svg(MarkerFamily::six_ucp(), 6, 50.0, path);
  ASSERT_TRUE(result.ok()) << result.error;
  const std::string svg = read_text(path);
  EXPECT_NE(svg.find("<?xml"), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  const auto [width, width_unit] = svg_length(svg, "width");
  const auto [height, height_unit] = svg_length(svg, "height");
  EXPECT_NEAR(width, 50.0, 1e-3);
  EXPECT_NEAR(height, 50.0, 1e-3);
  EXPECT_EQ(width_unit, "mm");
  EXPECT_EQ(height_unit, "mm");
  EXPECT_NE(svg.find("viewBox=\"0 0 50 50\""), std::string::npos);
  EXPECT_LT(fs::file_size(path), 100u * 1024u);
  fs::remove_all(dir);
}

TEST(PatternWriter, SvgSizeFollowsDiameter) {
  const fs::path dir = scratch_dir("svg_size");
  const fs::path path = dir / "m.svg";
  ASSERT_TRUE(write_marker_svg(MarkerFamily::k_ucp(9), 40, 32.5, path).ok());
  const auto [width, unit] = svg_length(read_text(path), "width");
  EXPECT_NEAR(width, 32.5, 1e-3);
  EXPECT_EQ(unit, "mm");
  fs::remove_all(dir);
}

TEST(PatternWriter, MarkerPdfPageIsTheMarkerAtTrueSize) {
  const fs::path dir = scratch_dir("pdf");
  const fs::path path = dir / "m.pdf";
  const PatternResult result = write_marker_pdf(MarkerFamily::six_ucp(), 3, 50.0, path);
  ASSERT_TRUE(result.ok()) << result.error;
  const std::string pdf = read_text(path);
  EXPECT_EQ(pdf.rfind("%PDF-", 0), 0u);
  const std::vector<MediaBox> boxes = media_boxes(pdf);
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_NEAR(boxes[0].width_pt, 50.0 * 72.0 / 25.4, 0.01);  // 141.73 pt
  EXPECT_NEAR(boxes[0].height_pt, 50.0 * 72.0 / 25.4, 0.01);
  EXPECT_EQ(page_count(pdf), 1);
  fs::remove_all(dir);
}

TEST(PatternWriter, SheetIsOneA4PageForSixUcp) {
  const fs::path dir = scratch_dir("sheet");
  const fs::path path = dir / "6ucp_sheet.pdf";
  const PatternResult result = write_marker_sheet_pdf(MarkerFamily::six_ucp(), {1, 2, 3, 4, 5, 6, 7, 8}, 50.0, path);
  ASSERT_TRUE(result.ok()) << result.error;
  const std::string pdf = read_text(path);
  EXPECT_EQ(pdf.rfind("%PDF-", 0), 0u);
  EXPECT_EQ(page_count(pdf), 1);
  const std::vector<MediaBox> boxes = media_boxes(pdf);
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_NEAR(boxes[0].width_pt, 595.28, 0.01);
  EXPECT_NEAR(boxes[0].height_pt, 841.89, 0.01);
  EXPECT_LT(fs::file_size(path), 100u * 1024u);
  fs::remove_all(dir);
}

TEST(PatternWriter, SheetOfManyIdsUsesSeveralA4Pages) {
  const fs::path dir = scratch_dir("sheet64");
  const fs::path path = dir / "9ucp_sheet.pdf";
  std::vector<int> ids;
  for (int id = 1; id <= 64; ++id) ids.push_back(id);
  const PatternResult result = write_marker_sheet_pdf(MarkerFamily::k_ucp(9), ids, 50.0, path);
  ASSERT_TRUE(result.ok()) << result.error;
  const std::string pdf = read_text(path);
  const int pages = page_count(pdf);
  EXPECT_GE(pages, 64 / 12);  // at most 12 markers of 50 mm fit on A4 with margins
  const std::vector<MediaBox> boxes = media_boxes(pdf);
  ASSERT_EQ(static_cast<int>(boxes.size()), pages);
  for (const MediaBox& box : boxes) {
    EXPECT_NEAR(box.width_pt, 595.28, 0.01);
    EXPECT_NEAR(box.height_pt, 841.89, 0.01);
  }
  fs::remove_all(dir);
}

TEST(PatternWriter, SheetRejectsDiameterThatDoesNotFitA4) {
  const fs::path dir = scratch_dir("sheet_big");
  EXPECT_GT(max_sheet_diameter_mm(), 150.0);
  EXPECT_LT(max_sheet_diameter_mm(), kA4WidthMm);
  const PatternResult result = write_marker_sheet_pdf(MarkerFamily::six_ucp(), {1}, 250.0, dir / "s.pdf");
  EXPECT_FALSE(result.ok());
  EXPECT_NE(result.error.find("250"), std::string::npos) << result.error;
  EXPECT_FALSE(write_marker_sheet_pdf(MarkerFamily::six_ucp(), {}, 50.0, dir / "s.pdf").ok());
  EXPECT_FALSE(write_marker_sheet_pdf(MarkerFamily::six_ucp(), {1, 9}, 50.0, dir / "s.pdf").ok());
  EXPECT_TRUE(write_marker_sheet_pdf(MarkerFamily::six_ucp(), {1}, max_sheet_diameter_mm(), dir / "s.pdf").ok());
  fs::remove_all(dir);
}

TEST(PatternWriter, VectorWritersRejectNonPositiveDiameter) {
  const fs::path dir = scratch_dir("bad_diameter");
  const MarkerFamily family = MarkerFamily::six_ucp();
  for (double diameter_mm : {0.0, -5.0, std::nan("")}) {
    EXPECT_FALSE(write_marker_svg(family, 1, diameter_mm, dir / "m.svg").ok()) << diameter_mm;
    EXPECT_FALSE(write_marker_pdf(family, 1, diameter_mm, dir / "m.pdf").ok()) << diameter_mm;
  }
  EXPECT_FALSE(fs::exists(dir / "m.svg"));
  EXPECT_FALSE(fs::exists(dir / "m.pdf"));
  fs::remove_all(dir);
}

TEST(PatternWriter, IoFailuresNameThePath) {
  const fs::path missing = fs::temp_directory_path() / "rilbed_no_such_dir_for_patterns" / "deeper";
  const MarkerFamily family = MarkerFamily::six_ucp();
  const std::vector<PatternResult> results = {
      write_marker_svg(family, 1, 50.0, missing / "m.svg"),
      write_marker_pdf(family, 1, 50.0, missing / "m.pdf"),
      write_marker_png(family, 1, 64, missing / "m.png"),
      write_marker_sheet_pdf(family, {1, 2}, 50.0, missing / "s.pdf"),
  };
  for (const PatternResult& r : results) {
    EXPECT_FALSE(r.ok());
    EXPECT_NE(r.error.find(missing.string()), std::string::npos) << r.error;
  }
}

// ------------------------------------------------------------------ patterns/ folder

const fs::path kPatternsDir = fs::path(RILBED_SOURCE_DIR) / "patterns";

void expect_widths(const MarkerFamily& family, const YAML::Node& key_deg, const YAML::Node& unit_deg) {
  const std::vector<double>& widths = family.slice_widths_deg();
  EXPECT_NEAR(widths.front(), key_deg.as<double>(), 1e-5) << family.name();
  for (std::size_t i = 1; i < widths.size(); ++i) EXPECT_NEAR(widths[i], unit_deg.as<double>(), 1e-5) << family.name();
}

TEST(PatternWriter, FamiliesYamlMatchesMarkerFamily) {
  const YAML::Node doc = YAML::LoadFile((kPatternsDir / "families.yaml").string());
  const YAML::Node layout = doc["layout"];
  EXPECT_DOUBLE_EQ(layout["hole_radius"].as<double>(), MarkerFamily::hole_radius);
  EXPECT_DOUBLE_EQ(layout["code_outer_radius"].as<double>(), MarkerFamily::code_outer_radius);
  EXPECT_DOUBLE_EQ(layout["black_ring_outer_radius"].as<double>(), MarkerFamily::black_ring_outer_radius);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_DOUBLE_EQ(layout["decoder_sample_radii"][i].as<double>(), MarkerFamily::sample_radii[i]);
  }
  const MarkerFamily six = MarkerFamily::six_ucp();
  const YAML::Node six_doc = doc["families"]["6ucp"];
  EXPECT_EQ(six_doc["slice_widths_deg"].as<std::vector<double>>(), six.slice_widths_deg());
  EXPECT_EQ(six_doc["code_bits"].as<int>(), six.code_bits());
  EXPECT_EQ(six_doc["ids"][1].as<int>(), six.max_id());
  for (int k = 7; k <= 14; ++k) {
    const MarkerFamily family = MarkerFamily::k_ucp(k);
    const YAML::Node entry = doc["kucp"][family.name()];
    ASSERT_TRUE(entry.IsMap()) << family.name();
    expect_widths(family, entry["key_deg"], entry["unit_deg"]);
    EXPECT_EQ(entry["code_bits"].as<int>(), family.code_bits());
    EXPECT_EQ(entry["max_id"].as<int>(), family.max_id());
  }
}

TEST(PatternWriter, CheckedInSixUcpFilesAreFiftyMillimetres) {
  for (int id = 1; id <= 8; ++id) {
    const fs::path path = kPatternsDir / ("6ucp_id" + std::to_string(id) + ".svg");
    ASSERT_TRUE(fs::exists(path)) << path;
    EXPECT_LT(fs::file_size(path), 100u * 1024u);
    const auto [width, unit] = svg_length(read_text(path), "width");
    EXPECT_NEAR(width, 50.0, 1e-3) << path;
    EXPECT_EQ(unit, "mm") << path;
  }
  const fs::path sheet = kPatternsDir / "6ucp_sheet.pdf";
  ASSERT_TRUE(fs::exists(sheet));
  EXPECT_LT(fs::file_size(sheet), 100u * 1024u);
  const std::vector<MediaBox> boxes = media_boxes(read_text(sheet));
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_NEAR(boxes[0].width_pt, 595.28, 0.01);
  EXPECT_NEAR(boxes[0].height_pt, 841.89, 0.01);
}

/// Every number in an SVG, in order (coordinates, sizes, colours), except those in id
/// attributes: cairo numbers its surfaces with a process-wide counter.
std::vector<double> svg_numbers(const std::string& svg) {
  static const std::regex id_attribute(R"(\bid="[^"]*")");
  static const std::regex number(R"(-?\d+(\.\d+)?)");
  const std::string text = std::regex_replace(svg, id_attribute, "");
  std::vector<double> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), number); it != std::sregex_iterator(); ++it) {
    out.push_back(std::stod(it->str()));
  }
  return out;
}

TEST(PatternWriter, CheckedInSvgsMatchTheCurrentFamily) {
  // The checked-in files go stale when MarkerFamily's radii or angles change. Numbers are
  // compared rather than bytes so that another cairo's number formatting does not matter.
  const fs::path dir = scratch_dir("checked_in");
  for (int id = 1; id <= 8; ++id) {
    const std::string name = "6ucp_id" + std::to_string(id) + ".svg";
    ASSERT_TRUE(write_marker_svg(MarkerFamily::six_ucp(), id, 50.0, dir / name).ok());
    const std::vector<double> fresh = svg_numbers(read_text(dir / name));
    const std::vector<double> stored = svg_numbers(read_text(kPatternsDir / name));
    ASSERT_EQ(fresh.size(), stored.size())
        << name << " is stale: regenerate with `rilbed patterns --ids 1-8 --format svg --out patterns`"
        << " and the sheet as patterns/README.md says";
    for (std::size_t i = 0; i < fresh.size(); ++i) {
      ASSERT_NEAR(fresh[i], stored[i], 0.01) << name << " is stale (number " << i << "): regenerate it";
    }
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rilbed::vision

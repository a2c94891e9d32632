// End-to-end tests of `rilbed patterns`: the real binary, real files.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

/// Names of the regular files in dir.
std::set<std::string> file_names(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file()) names.insert(entry.path().filename().string());
  }
  return names;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) out.push_back(line);
  }
  return out;
}

std::set<std::string> expected_names(const std::string& family, int first, int last, const std::string& ext) {
  std::set<std::string> names;
  for (int id = first; id <= last; ++id) names.insert(family + "_id" + std::to_string(id) + "." + ext);
  return names;
}

/// The path in single quotes for the shell. Appended piece by piece: GCC 12 raises a
/// false -Wrestrict on `"'" + std::string`.
std::string quoted(const fs::path& p) {
  std::string text(1, '\'');
  text += p.string();
  text += '\'';
  return text;
}

/// Runs a command that must fail with a usage error naming `bad_value`, writing nothing.
void expect_usage_error(const std::string& args, const std::string& bad_value) {
  const fs::path dir = scratch_dir("patterns_bad");
  const CommandResult r = run_rilbed("patterns --out " + quoted(dir) + " " + args);
  EXPECT_EQ(r.exit_code, 2) << args << "\nstderr: " << r.err;
  EXPECT_NE(r.err.find(bad_value), std::string::npos) << args << "\nstderr: " << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_TRUE(file_names(dir).empty());
  fs::remove_all(dir);
}

TEST(PatternsCli, PngWritesOneFilePerId) {
  const fs::path dir = scratch_dir("patterns_png");
  const CommandResult r = run_rilbed("patterns --ids 1-8 --format png --px 256 --out " + quoted(dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(file_names(dir), expected_names("6ucp", 1, 8, "png"));
  const std::vector<std::string> printed = lines(r.out);
  ASSERT_EQ(printed.size(), 8u) << r.out;
  for (const std::string& line : printed) EXPECT_TRUE(fs::exists(line)) << line;
  const cv::Mat image = cv::imread((dir / "6ucp_id3.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(image.cols, 256);
  EXPECT_EQ(image.rows, 256);
  EXPECT_EQ(image.channels(), 4);
  EXPECT_EQ(image.at<cv::Vec4b>(0, 0)[3], 0);             // transparent corner
  EXPECT_EQ(image.at<cv::Vec4b>(128, 128)[0], 0);         // black hole at the centre
  EXPECT_EQ(image.at<cv::Vec4b>(128, 128 + 51)[0], 255);  // key slice to the right, r = 0.4 R
  fs::remove_all(dir);
}

TEST(PatternsCli, PdfWritesOneFilePerIdAndTheSheet) {
  const fs::path dir = scratch_dir("patterns_pdf");
  const CommandResult r = run_rilbed("patterns --ids 1-8 --format pdf --out " + quoted(dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::set<std::string> want = expected_names("6ucp", 1, 8, "pdf");
  want.insert("6ucp_sheet.pdf");
  EXPECT_EQ(file_names(dir), want);
  EXPECT_EQ(lines(r.out).size(), 9u) << r.out;
  for (const std::string& name : want) EXPECT_EQ(read_file(dir / name).rfind("%PDF-", 0), 0u) << name;
  EXPECT_NE(read_file(dir / "6ucp_sheet.pdf").find("595.27"), std::string::npos);  // A4 width in pt
  fs::remove_all(dir);
}

TEST(PatternsCli, DefaultsAreEverySixUcpIdAsFiftyMillimetrePdf) {
  const fs::path dir = scratch_dir("patterns_defaults");
  const CommandResult r = run_rilbed("patterns --out " + quoted(dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::set<std::string> want = expected_names("6ucp", 1, 8, "pdf");
  want.insert("6ucp_sheet.pdf");
  EXPECT_EQ(file_names(dir), want);
  // 50 mm = 141.73 pt.
  EXPECT_NE(read_file(dir / "6ucp_id1.pdf").find("141.73"), std::string::npos);
  fs::remove_all(dir);
}

TEST(PatternsCli, SvgHasTheRequestedDiameter) {
  const fs::path dir = scratch_dir("patterns_svg");
  const CommandResult r = run_rilbed("patterns --ids 2,5 --format svg --diameter-mm 30 --out " + quoted(dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(file_names(dir), (std::set<std::string>{"6ucp_id2.svg", "6ucp_id5.svg"}));
  const std::string svg = read_file(dir / "6ucp_id5.svg");
  EXPECT_NE(svg.find("width=\"30mm\""), std::string::npos) << svg.substr(0, 300);
  EXPECT_NE(svg.find("height=\"30mm\""), std::string::npos);
  fs::remove_all(dir);
}

TEST(PatternsCli, NineUcpFamilyWithHighIds) {
  const fs::path dir = scratch_dir("patterns_9ucp");
  const CommandResult r = run_rilbed("patterns --family 9ucp --ids 60-64 --format png --px 96 --out " + quoted(dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(file_names(dir), expected_names("9ucp", 60, 64, "png"));
  EXPECT_EQ(lines(r.out).size(), 5u);
  fs::remove_all(dir);
}

TEST(PatternsCli, CreatesAMissingOutputDirectory) {
  const fs::path dir = scratch_dir("patterns_mkdir");
  const fs::path nested = dir / "a" / "b";
  const CommandResult r = run_rilbed("patterns --ids 4 --format svg --out " + quoted(nested));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(file_names(nested), (std::set<std::string>{"6ucp_id4.svg"}));
  fs::remove_all(dir);
}

TEST(PatternsCli, BadIdListIsAUsageErrorNamingIt) {
  expect_usage_error("--ids 1-9", "1-9");
  expect_usage_error("--ids abc", "abc");
  expect_usage_error("--family 9ucp --ids 65", "65");
}

TEST(PatternsCli, UnknownFamilyIsAUsageErrorNamingIt) { expect_usage_error("--family 5ucp", "5ucp"); }

TEST(PatternsCli, BadFormatDiameterOrSizeIsAUsageError) {
  expect_usage_error("--format jpg", "jpg");
  expect_usage_error("--diameter-mm 0", "--diameter-mm");
  expect_usage_error("--diameter-mm=-12.5", "-12.5");
  expect_usage_error("--format png --px 0", "--px");
  expect_usage_error("--format pdf --diameter-mm 400", "400");
}

TEST(PatternsCli, UnwritableOutputIsAnIoError) {
  const fs::path dir = scratch_dir("patterns_io");
  const fs::path file = dir / "not_a_dir";
  std::ofstream(file) << "x";
  const fs::path out = file / "sub";
  const CommandResult r = run_rilbed("patterns --ids 1 --format png --out " + quoted(out));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(out.string()), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rilbed::e2e

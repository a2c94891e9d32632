// FrameSource: every input kind, and every kind of bad input giving a result that
// names the input instead of an exception or a stop.
#include "vision/frame_source.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

namespace rilbed::vision {
namespace {

namespace fs = std::filesystem;

// A fresh directory under the system temp dir, removed with everything in it.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    path_ = fs::temp_directory_path() /
            ("rilbed_frame_source_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const fs::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

// A 3-channel image whose every pixel is `value`, so that order can be checked after a
// lossless round trip.
cv::Mat flat_image(int value, cv::Size size = {64, 48}) {
  return cv::Mat(size, CV_8UC3, cv::Scalar(value, value, value));
}

void write_image(const std::string& path, int value, cv::Size size = {64, 48}) {
  ASSERT_TRUE(cv::imwrite(path, flat_image(value, size))) << path;
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
  ASSERT_TRUE(out.good()) << path;
}

std::string random_bytes(std::size_t n) {
  std::mt19937 rng(1234);
  std::string bytes(n, '\0');
  for (char& c : bytes) c = static_cast<char>(rng() & 0xff);
  return bytes;
}

// Every result up to and including End; the cap turns a source that never ends into a
// test failure instead of a hang.
std::vector<FrameResult> drain(FrameSource& source) {
  std::vector<FrameResult> results;
  for (int i = 0; i < 1000; ++i) {
    results.push_back(source.next());
    if (results.back().is_end()) return results;
  }
  ADD_FAILURE() << "source did not end after 1000 results";
  return results;
}

std::vector<FrameResult> frames_of(const std::vector<FrameResult>& results) {
  std::vector<FrameResult> frames;
  for (const FrameResult& r : results)
    if (r.is_frame()) frames.push_back(r);
  return frames;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

OpenResult open_ok(const std::string& input) {
  OpenResult opened = open_frame_source(input);
  EXPECT_TRUE(opened.ok()) << opened.error;
  EXPECT_TRUE(opened.error.empty());
  return opened;
}

// ------------------------------------------------------------------ directories

TEST(FrameSourceDirectory, ImagesComeSortedByNameAndOtherFilesAreIgnored) {
  TempDir dir;
  // Created out of order, with mixed-case extensions; the value encodes the rank.
  write_image(dir.file("img_03.png"), 30);
  write_image(dir.file("img_01.BMP"), 10);
  write_image(dir.file("img_04.tiff"), 40);
  write_image(dir.file("img_00.png"), 0);
  write_image(dir.file("img_02.PNG"), 20);
  write_bytes(dir.file("notes.txt"), "not an image");
  write_bytes(dir.file(".hidden.png"), random_bytes(100));
  fs::create_directory(dir.path() / "sub.png");

  OpenResult opened = open_ok(dir.path().string());
  ASSERT_TRUE(opened.ok());
  FrameSource& source = *opened.source;
  EXPECT_EQ(source.frame_count(), 5);
  EXPECT_EQ(source.fps(), 0.0);
  EXPECT_TRUE(contains(source.describe(), dir.path().string())) << source.describe();

  const std::vector<FrameResult> results = drain(source);
  ASSERT_EQ(results.size(), 6u);
  const std::vector<std::string> names = {"img_00.png", "img_01.BMP", "img_02.PNG", "img_03.png", "img_04.tiff"};
  for (int i = 0; i < 5; ++i) {
    const FrameResult& r = results[static_cast<std::size_t>(i)];
    ASSERT_TRUE(r.is_frame()) << i << ": " << r.error;
    EXPECT_EQ(r.index, i);
    EXPECT_EQ(r.name, names[static_cast<std::size_t>(i)]);
    EXPECT_EQ(r.image.size(), cv::Size(64, 48));
    EXPECT_EQ(r.image.at<cv::Vec3b>(10, 10)[0], 10 * i) << r.name;
  }
  EXPECT_TRUE(results.back().is_end());
  EXPECT_TRUE(source.next().is_end()) << "End must repeat";
}

TEST(FrameSourceDirectory, SortIsLexicographicNotNumeric) {
  TempDir dir;
  write_image(dir.file("f10.png"), 1);
  write_image(dir.file("f9.png"), 2);
  OpenResult opened = open_ok(dir.path().string());
  ASSERT_TRUE(opened.ok());
  EXPECT_EQ(opened.source->next().name, "f10.png");
  EXPECT_EQ(opened.source->next().name, "f9.png");
}

TEST(FrameSourceDirectory, CorruptImageGivesAnErrorAndLaterFramesStillCome) {
  TempDir dir;
  write_image(dir.file("img_00.png"), 0);
  write_image(dir.file("img_01.png"), 10);
  write_bytes(dir.file("img_02.png"), random_bytes(4096));
  write_image(dir.file("img_03.png"), 30);
  write_image(dir.file("img_04.png"), 40);

  OpenResult opened = open_ok(dir.path().string());
  ASSERT_TRUE(opened.ok());
  const std::vector<FrameResult> results = drain(*opened.source);
  ASSERT_EQ(results.size(), 6u);
  EXPECT_TRUE(results[0].is_frame());
  EXPECT_TRUE(results[1].is_frame());
  const FrameResult& bad = results[2];
  ASSERT_TRUE(bad.is_error());
  EXPECT_EQ(bad.index, 2);
  EXPECT_TRUE(bad.image.empty());
  EXPECT_TRUE(contains(bad.error, dir.path().string())) << bad.error;
  EXPECT_TRUE(contains(bad.error, "frame 2")) << bad.error;
  EXPECT_TRUE(contains(bad.error, "img_02.png")) << bad.error;
  ASSERT_TRUE(results[3].is_frame());
  EXPECT_EQ(results[3].index, 3);
  EXPECT_EQ(results[3].image.at<cv::Vec3b>(0, 0)[0], 30);
  ASSERT_TRUE(results[4].is_frame());
  EXPECT_EQ(results[4].index, 4);
  EXPECT_TRUE(results[5].is_end());
}

TEST(FrameSourceDirectory, FrameOfAnotherSizeIsReportedAndSkipped) {
  TempDir dir;
  write_image(dir.file("a.png"), 0);
  write_image(dir.file("b.png"), 10, {32, 24});
  write_image(dir.file("c.png"), 20);

  OpenResult opened = open_ok(dir.path().string());
  ASSERT_TRUE(opened.ok());
  const std::vector<FrameResult> results = drain(*opened.source);
  ASSERT_EQ(results.size(), 4u);
  EXPECT_TRUE(results[0].is_frame());
  ASSERT_TRUE(results[1].is_error());
  EXPECT_EQ(results[1].index, 1);
  EXPECT_EQ(results[1].name, "b.png");
  EXPECT_TRUE(results[1].image.empty());
  EXPECT_TRUE(contains(results[1].error, "32x24")) << results[1].error;
  EXPECT_TRUE(contains(results[1].error, "64x48")) << results[1].error;
  ASSERT_TRUE(results[2].is_frame());
  EXPECT_EQ(results[2].index, 2) << "a skipped frame keeps its place in the input";
  EXPECT_EQ(results[2].name, "c.png");
  EXPECT_TRUE(results[3].is_end());
}

TEST(FrameSourceDirectory, EmptyDirectoryAndDirectoryWithoutImagesAreErrors) {
  TempDir dir;
  OpenResult empty = open_frame_source(dir.path().string());
  EXPECT_FALSE(empty.ok());
  EXPECT_TRUE(contains(empty.error, dir.path().string())) << empty.error;
  EXPECT_TRUE(contains(empty.error, "empty")) << empty.error;

  write_bytes(dir.file("readme.txt"), "hello");
  OpenResult no_images = open_frame_source(dir.path().string());
  EXPECT_FALSE(no_images.ok());
  EXPECT_TRUE(contains(no_images.error, dir.path().string())) << no_images.error;
  EXPECT_TRUE(contains(no_images.error, "no image")) << no_images.error;
}

// ------------------------------------------------------------------ sequences

TEST(FrameSourceSequence, StartsAtZeroAndStopsAtTheFirstGap) {
  TempDir dir;
  for (int i = 0; i <= 3; ++i) write_image(dir.file(cv::format("seq_%04d.png", i)), 10 * i);
  write_image(dir.file("seq_0005.png"), 50);  // after the gap: not part of the sequence

  OpenResult opened = open_ok(dir.file("seq_%04d.png"));
  ASSERT_TRUE(opened.ok());
  EXPECT_EQ(opened.source->frame_count(), 4);
  const std::vector<FrameResult> results = drain(*opened.source);
  ASSERT_EQ(results.size(), 5u);
  for (int i = 0; i <= 3; ++i) {
    const FrameResult& r = results[static_cast<std::size_t>(i)];
    ASSERT_TRUE(r.is_frame()) << r.error;
    EXPECT_EQ(r.index, i);
    EXPECT_EQ(r.name, cv::format("seq_%04d.png", i));
    EXPECT_EQ(r.image.at<cv::Vec3b>(0, 0)[0], 10 * i);
  }
  EXPECT_TRUE(results[4].is_end());
}

TEST(FrameSourceSequence, StartsAtOneWithUnpaddedNumbers) {
  TempDir dir;
  for (int i = 1; i <= 3; ++i) write_image(dir.file(cv::format("f%d.png", i)), 10 * i);

  OpenResult opened = open_ok(dir.file("f%d.png"));
  ASSERT_TRUE(opened.ok());
  EXPECT_EQ(opened.source->frame_count(), 3);
  const std::vector<FrameResult> results = drain(*opened.source);
  ASSERT_EQ(results.size(), 4u);
  ASSERT_TRUE(results[0].is_frame()) << results[0].error;
  EXPECT_EQ(results[0].index, 0) << "indices are positions in the input, not file numbers";
  EXPECT_EQ(results[0].name, "f1.png");
  EXPECT_EQ(results[0].image.at<cv::Vec3b>(0, 0)[0], 10);
  EXPECT_EQ(results[2].name, "f3.png");
  EXPECT_TRUE(results[3].is_end());
}

TEST(FrameSourceSequence, MissingOrMalformedPatternsAreErrors) {
  TempDir dir;
  OpenResult missing = open_frame_source(dir.file("none_%03d.png"));
  EXPECT_FALSE(missing.ok());
  EXPECT_TRUE(contains(missing.error, dir.file("none_%03d.png"))) << missing.error;

  OpenResult two = open_frame_source(dir.file("a_%d_%d.png"));
  EXPECT_FALSE(two.ok());
  EXPECT_TRUE(contains(two.error, "a_%d_%d.png")) << two.error;

  OpenResult stray = open_frame_source(dir.file("a_%s_%d.png"));
  EXPECT_FALSE(stray.ok());
}

TEST(FrameSourceSequence, DoublePercentIsALiteralPercent) {
  TempDir dir;
  write_image(dir.file("50%_0.png"), 0);
  OpenResult opened = open_ok(dir.file("50%%_%d.png"));
  ASSERT_TRUE(opened.ok());
  EXPECT_EQ(opened.source->next().name, "50%_0.png");
}

// ------------------------------------------------------------------ single images

TEST(FrameSourceImage, SingleGreyImageGivesOneFrame) {
  TempDir dir;
  cv::Mat grey(30, 40, CV_8UC1, cv::Scalar(77));
  ASSERT_TRUE(cv::imwrite(dir.file("one.pgm"), grey));

  OpenResult opened = open_ok(dir.file("one.pgm"));
  ASSERT_TRUE(opened.ok());
  EXPECT_EQ(opened.source->frame_count(), 1);
  EXPECT_TRUE(contains(opened.source->describe(), "40x30")) << opened.source->describe();
  FrameResult r = opened.source->next();
  ASSERT_TRUE(r.is_frame()) << r.error;
  EXPECT_EQ(r.index, 0);
  EXPECT_EQ(r.name, "one.pgm");
  EXPECT_EQ(r.image.type(), CV_8UC1) << "grey stays grey";
  EXPECT_EQ(r.image.at<uchar>(5, 5), 77);
  EXPECT_TRUE(opened.source->next().is_end());
  EXPECT_TRUE(opened.source->next().is_end());
}

TEST(FrameSourceImage, MissingFileAndCorruptImageAreErrorsNamingThePath) {
  TempDir dir;
  OpenResult missing = open_frame_source(dir.file("nope.png"));
  EXPECT_FALSE(missing.ok());
  EXPECT_TRUE(contains(missing.error, dir.file("nope.png"))) << missing.error;

  OpenResult missing_video = open_frame_source(dir.file("nope.avi"));
  EXPECT_FALSE(missing_video.ok());
  EXPECT_TRUE(contains(missing_video.error, dir.file("nope.avi"))) << missing_video.error;

  write_bytes(dir.file("bad.jpg"), random_bytes(500));
  OpenResult corrupt = open_frame_source(dir.file("bad.jpg"));
  EXPECT_FALSE(corrupt.ok());
  EXPECT_TRUE(contains(corrupt.error, dir.file("bad.jpg"))) << corrupt.error;

  EXPECT_FALSE(open_frame_source("").ok());
}

// ------------------------------------------------------------------ videos

constexpr int kVideoFrames = 20;
const cv::Size kVideoSize{160, 120};

// An MJPG AVI whose frames differ (a moving square over texture), so each JPEG has
// real content and the file's bytes spread over all frames.
void write_mjpg_avi(const std::string& path) {
  cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 30.0, kVideoSize);
  ASSERT_TRUE(writer.isOpened()) << path;
  cv::RNG rng(7);
  for (int i = 0; i < kVideoFrames; ++i) {
    cv::Mat frame(kVideoSize, CV_8UC3);
    rng.fill(frame, cv::RNG::UNIFORM, 0, 256);
    cv::rectangle(frame, cv::Rect(5 * i, 40, 30, 30), cv::Scalar(255, 255, 255), cv::FILLED);
    writer.write(frame);
  }
}

void truncate_copy(const std::string& from, const std::string& to, double fraction) {
  std::ifstream in(from, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 1000u);
  write_bytes(to, bytes.substr(0, static_cast<std::size_t>(bytes.size() * fraction)));
}

TEST(FrameSourceVideo, MjpgAviReadsBackWithCountSizeAndFps) {
  TempDir dir;
  const std::string path = dir.file("clip.avi");
  write_mjpg_avi(path);

  OpenResult opened = open_ok(path);
  ASSERT_TRUE(opened.ok());
  FrameSource& source = *opened.source;
  EXPECT_EQ(source.frame_count(), kVideoFrames);
  EXPECT_NEAR(source.fps(), 30.0, 1e-6);
  const std::string text = source.describe();
  EXPECT_TRUE(contains(text, path)) << text;
  EXPECT_TRUE(contains(text, "160x120")) << text;
  EXPECT_TRUE(contains(text, "20 frames")) << text;

  const std::vector<FrameResult> results = drain(source);
  ASSERT_EQ(results.size(), static_cast<std::size_t>(kVideoFrames + 1));
  for (int i = 0; i < kVideoFrames; ++i) {
    const FrameResult& r = results[static_cast<std::size_t>(i)];
    ASSERT_TRUE(r.is_frame()) << r.error;
    EXPECT_EQ(r.index, i);
    EXPECT_EQ(r.name, "clip.avi#" + std::to_string(i));
    EXPECT_EQ(r.image.size(), kVideoSize);
    EXPECT_EQ(r.image.type(), CV_8UC3);
  }
  EXPECT_TRUE(results.back().is_end());
}

TEST(FrameSourceVideo, TruncatedAviEndsCleanlyAfterTheLastGoodFrame) {
  TempDir dir;
  write_mjpg_avi(dir.file("full.avi"));
  const std::string path = dir.file("half.avi");
  truncate_copy(dir.file("full.avi"), path, 0.5);

  OpenResult opened = open_ok(path);
  ASSERT_TRUE(opened.ok());
  const std::vector<FrameResult> results = drain(*opened.source);
  const std::vector<FrameResult> frames = frames_of(results);
  EXPECT_GE(frames.size(), 1u);
  EXPECT_LT(frames.size(), static_cast<std::size_t>(kVideoFrames));
  for (std::size_t i = 0; i < frames.size(); ++i) EXPECT_EQ(frames[i].index, static_cast<int>(i));

  // Frames, then one error saying where reading stopped, then End.
  ASSERT_EQ(results.size(), frames.size() + 2);
  const FrameResult& stop = results[results.size() - 2];
  ASSERT_TRUE(stop.is_error());
  EXPECT_EQ(stop.index, static_cast<int>(frames.size()));
  EXPECT_TRUE(contains(stop.error, path)) << stop.error;
  EXPECT_TRUE(contains(stop.error, "stopped at frame " + std::to_string(frames.size()))) << stop.error;
  EXPECT_TRUE(results.back().is_end());
  EXPECT_TRUE(opened.source->next().is_end());
}

TEST(FrameSourceVideo, TextFileNamedAviIsAnErrorNamingThePath) {
  TempDir dir;
  const std::string path = dir.file("notes.avi");
  write_bytes(path, "this is a text file, not a video\n");
  OpenResult opened = open_frame_source(path);
  EXPECT_FALSE(opened.ok());
  EXPECT_EQ(opened.source, nullptr);
  EXPECT_TRUE(contains(opened.error, path)) << opened.error;
  EXPECT_TRUE(contains(opened.error, "cannot open video")) << opened.error;
}

TEST(FrameSourceCamera, NegativeIndexIsAnErrorNamingTheCamera) {
  OpenResult opened = open_camera(-1);
  EXPECT_FALSE(opened.ok());
  EXPECT_TRUE(contains(opened.error, "camera -1")) << opened.error;
}

}  // namespace
}  // namespace rilbed::vision

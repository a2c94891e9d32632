#include "vision/frame_source.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string_view>
#include <system_error>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <opencv2/videoio/registry.hpp>

namespace rilbed::vision {

namespace fs = std::filesystem;

namespace {

// Image sequences usually start at 0 or 1; a few more cover a trimmed first frame
// without scanning the disk at random.
constexpr int kSequenceMaxFirstIndex = 9;

constexpr std::array<std::string_view, 10> kImageExtensions = {".png", ".jpg", ".jpeg", ".pgm",  ".ppm",
                                                               ".pbm", ".bmp", ".tif",  ".tiff", ".webp"};

// ------------------------------------------------------------------ small helpers

OpenResult open_failed(std::string message) { return OpenResult{nullptr, std::move(message)}; }

FrameResult end_result() { return FrameResult{}; }

FrameResult frame_result(cv::Mat image, int index, std::string name) {
  return FrameResult{FrameResult::Kind::kFrame, std::move(image), index, std::move(name), {}};
}

// Every per-frame error names the input, the frame index and the frame's own name so
// that a user can find the bad file or the bad moment in a video.
FrameResult frame_error(const std::string& input, int index, std::string name, const std::string& reason) {
  std::string message = input + ": frame " + std::to_string(index) + " (" + name + "): " + reason;
  return FrameResult{FrameResult::Kind::kError, {}, index, std::move(name), std::move(message)};
}

// "1 image", "3 images".
std::string count_text(std::size_t count, std::string_view one, std::string_view many) {
  return std::to_string(count) + " " + std::string(count == 1 ? one : many);
}

std::string size_text(cv::Size size) { return std::to_string(size.width) + "x" + std::to_string(size.height); }

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

bool has_image_extension(const fs::path& path) {
  const std::string ext = lower(path.extension().string());
  return std::find(kImageExtensions.begin(), kImageExtensions.end(), ext) != kImageExtensions.end();
}

std::string image_extension_list() {
  std::string list;
  for (std::string_view ext : kImageExtensions) {
    list += list.empty() ? "" : " ";
    list += ext;
  }
  return list;
}

// Empty Mat when the file cannot be decoded. IMREAD_ANYCOLOR keeps grey images grey
// (one channel) and gives BGR otherwise, always 8 bit.
cv::Mat read_image(const fs::path& path) {
  try {
    return cv::imread(path.string(), cv::IMREAD_ANYCOLOR);
  } catch (const cv::Exception&) {
    return {};  // e.g. an image over OpenCV's size limit: just unreadable
  }
}

// The reason a file could not be opened for reading, or an empty string if it can be.
std::string open_error(const fs::path& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return std::strerror(errno);
  std::fclose(file);
  return {};
}

// Why read_image() gave nothing: tell a vanished or unreadable file from a bad image.
std::string unreadable_reason(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return "file no longer exists";
  if (std::string why = open_error(path); !why.empty()) return "cannot open file: " + why;
  return "not a decodable image (corrupt, truncated or of another format)";
}

// ------------------------------------------------------------ sequence patterns

// "dir/img_%04d.png" split around its one integer conversion.
struct SequencePattern {
  std::string prefix;
  std::string suffix;
  int width = 0;
  bool zero_pad = false;

  std::string format(int index) const {
    std::string digits = std::to_string(index);
    const auto pad = static_cast<std::size_t>(std::max(0, width));
    if (digits.size() < pad) digits.insert(0, pad - digits.size(), zero_pad ? '0' : ' ');
    return prefix + digits + suffix;
  }
};

struct PatternParse {
  bool is_pattern = false;  // the input has at least one %d conversion
  std::string error;        // set when it has one but the pattern is unusable
  SequencePattern pattern;
};

// Parses "%d", "%Nd" or "%0Nd" at text[pos] (text[pos] == '%'); returns the index just
// past the conversion, or npos when it is not such a conversion.
std::size_t parse_conversion(const std::string& text, std::size_t pos, SequencePattern& out) {
  std::size_t i = pos + 1;
  const bool zero = i < text.size() && text[i] == '0';
  if (zero) ++i;
  int width = 0;
  while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i])) && width < 100)
    width = width * 10 + (text[i++] - '0');
  if (i >= text.size() || text[i] != 'd') return std::string::npos;
  out.zero_pad = zero;
  out.width = width;
  return i + 1;
}

// The pattern is parsed here rather than handed to snprintf: the text comes from the
// user, and a stray %s or %n in a format string would be undefined behaviour.
PatternParse parse_sequence_pattern(const std::string& input) {
  PatternParse result;
  std::string literal;
  int conversions = 0;
  bool stray_percent = false;
  for (std::size_t i = 0; i < input.size();) {
    if (input[i] != '%') {
      literal += input[i++];
    } else if (i + 1 < input.size() && input[i + 1] == '%') {
      literal += '%';
      i += 2;
    } else if (std::size_t end = parse_conversion(input, i, result.pattern); end != std::string::npos) {
      if (++conversions == 1) result.pattern.prefix = std::exchange(literal, {});
      i = end;
    } else {
      stray_percent = true;
      literal += input[i++];
    }
  }
  result.pattern.suffix = literal;
  result.is_pattern = conversions > 0;
  if (conversions > 1 || (result.is_pattern && stray_percent))
    result.error = "image sequence pattern " + input +
                   ": expected exactly one integer conversion such as %04d and no other "
                   "'%' (write a literal '%' as %%)";
  return result;
}

// ----------------------------------------------------------------- image lists

// A directory or an image sequence: a fixed list of image files, read one by one.
class ImageListSource final : public FrameSource {
 public:
  ImageListSource(std::string input, std::vector<fs::path> files, std::string description)
      : FrameSource(std::move(input)), files_(std::move(files)), description_(std::move(description)) {}

  std::optional<int> frame_count() const override { return static_cast<int>(files_.size()); }
  std::string describe() const override { return description_; }

 protected:
  FrameResult read_next() override {
    if (next_ >= files_.size()) return end_result();
    const int index = static_cast<int>(next_);
    const fs::path& path = files_[next_++];
    std::string name = path.filename().string();
    cv::Mat image = read_image(path);
    if (image.empty()) return frame_error(input(), index, std::move(name), unreadable_reason(path));
    return frame_result(std::move(image), index, std::move(name));
  }

 private:
  std::vector<fs::path> files_;
  std::string description_;
  std::size_t next_ = 0;
};

// One image, decoded when opened so that a bad file fails at open time.
class SingleImageSource final : public FrameSource {
 public:
  SingleImageSource(std::string input, cv::Mat image) : FrameSource(std::move(input)), image_(std::move(image)) {}

  std::optional<int> frame_count() const override { return 1; }
  std::string describe() const override {
    return "image file " + input() + " (" + size_text(image_.size()) +
           (image_.channels() == 1 ? ", grey)" : ", colour)");
  }

 protected:
  FrameResult read_next() override {
    if (done_) return end_result();
    done_ = true;
    return frame_result(std::move(image_), 0, fs::path(input()).filename().string());
  }

 private:
  cv::Mat image_;
  bool done_ = false;
};

// ------------------------------------------------------------------ videos

std::optional<int> known_frame_count(const cv::VideoCapture& capture) {
  const double count = capture.get(cv::CAP_PROP_FRAME_COUNT);
  if (!std::isfinite(count) || count < 1.0 || count > INT_MAX) return std::nullopt;
  return static_cast<int>(std::llround(count));
}

double known_fps(const cv::VideoCapture& capture) {
  const double fps = capture.get(cv::CAP_PROP_FPS);
  return std::isfinite(fps) && fps > 0.0 ? fps : 0.0;
}

// A video file or a live camera, read through cv::VideoCapture.
class VideoSource final : public FrameSource {
 public:
  // `capture` is open; `label` names frames ("run3.avi" gives "run3.avi#17").
  // The capture is held by unique_ptr because cv::VideoCapture has no move
  // constructor (its copies share one stream).
  VideoSource(std::string input, std::unique_ptr<cv::VideoCapture> capture, std::string label, bool live)
      : FrameSource(std::move(input)),
        capture_(std::move(capture)),
        label_(std::move(label)),
        live_(live),
        count_(live ? std::nullopt : known_frame_count(*capture_)),
        fps_(known_fps(*capture_)),
        size_(static_cast<int>(capture_->get(cv::CAP_PROP_FRAME_WIDTH)),
              static_cast<int>(capture_->get(cv::CAP_PROP_FRAME_HEIGHT))) {}

  std::optional<int> frame_count() const override { return count_; }
  double fps() const override { return fps_; }

  std::string describe() const override {
    std::string text = (live_ ? input() : "video file " + input()) + " (" + size_text(size_);
    if (!live_) text += count_ ? ", " + std::to_string(*count_) + " frames" : ", unknown length";
    if (fps_ > 0.0) text += ", " + cv::format("%g", fps_) + " fps";
    return text + ", " + capture_->getBackendName() + ")";
  }

 protected:
  FrameResult read_next() override {
    if (ended_) return end_result();
    const int index = next_index_++;
    std::string name = label_ + "#" + std::to_string(index);
    cv::Mat frame;
    if (read_frame(frame)) return frame_result(std::move(frame), index, std::move(name));
    ended_ = true;  // a capture that failed once is not trusted to resume
    return stop_result(index, std::move(name));
  }

 private:
  bool read_frame(cv::Mat& frame) {
    try {
      return capture_->read(frame) && !frame.empty();
    } catch (const cv::Exception&) {
      return false;  // a backend that throws on a corrupt packet: same as a failed read
    }
  }

  // A read failure before the promised frame count means a truncated or corrupt file;
  // at or past it (or with no count) it is the normal end of the video.
  FrameResult stop_result(int index, std::string name) {
    if (live_)
      return frame_error(input(), index, std::move(name), "camera stopped delivering frames; the stream ends here");
    if (count_ && index < *count_)
      return frame_error(input(), index, std::move(name),
                         "reading stopped at frame " + std::to_string(index) + " of " + std::to_string(*count_) +
                             " (file truncated or corrupt); the stream ends after the "
                             "last good frame");
    return end_result();
  }

  std::unique_ptr<cv::VideoCapture> capture_;
  std::string label_;
  bool live_;
  std::optional<int> count_;
  double fps_;
  cv::Size size_;
  int next_index_ = 0;
  bool ended_ = false;
};

// Every stream backend but two, FFmpeg first: it reads truncated AVIs up to the damage
// where OpenCV's own MJPEG reader refuses to open them. Left out: CAP_IMAGES (image
// sequences are handled above, and it would take "clip01.avi" for a pattern) and
// CAP_GPHOTO2 (it enumerates USB cameras for a file name and leaks in libusb, which
// fails sanitizer builds).
std::vector<cv::VideoCaptureAPIs> video_backends() {
  std::vector<cv::VideoCaptureAPIs> apis;
  for (cv::VideoCaptureAPIs api : cv::videoio_registry::getStreamBackends())
    if (api != cv::CAP_IMAGES && api != cv::CAP_GPHOTO2) apis.push_back(api);
  std::stable_partition(apis.begin(), apis.end(), [](cv::VideoCaptureAPIs api) { return api == cv::CAP_FFMPEG; });
  return apis;
}

bool open_capture(cv::VideoCapture& capture, const std::string& path, cv::VideoCaptureAPIs api) {
  try {
    return capture.open(path, api) && capture.isOpened();
  } catch (const cv::Exception&) {
    return false;
  }
}

bool looks_like_image(const std::string& path) {
  try {
    return cv::haveImageReader(path);
  } catch (const cv::Exception&) {
    return false;
  }
}

// ----------------------------------------------------------------- openers

OpenResult open_single_image(const std::string& input) {
  cv::Mat image = read_image(input);
  if (image.empty())
    return open_failed("cannot read image " + input +
                       ": not a decodable image (corrupt, truncated or of another format)");
  return OpenResult{std::make_unique<SingleImageSource>(input, std::move(image)), {}};
}

OpenResult open_video_file(const std::string& input) {
  std::string tried;
  for (cv::VideoCaptureAPIs api : video_backends()) {
    auto capture = std::make_unique<cv::VideoCapture>();
    if (open_capture(*capture, input, api)) {
      std::string label = fs::path(input).filename().string();
      return OpenResult{std::make_unique<VideoSource>(input, std::move(capture), label, false), {}};
    }
    tried += (tried.empty() ? "" : ", ") + cv::videoio_registry::getBackendName(api);
  }
  // An image with an extension we do not list (e.g. .jp2, .exr) is still an image.
  if (looks_like_image(input)) return open_single_image(input);
  return open_failed("cannot open video file " + input + ": no OpenCV video backend could read it (tried " + tried +
                     "); is it a video or image file?");
}

// What a directory holds: its image files (unsorted) and how many entries it has in
// all, so that an empty directory and one without images get different messages.
struct DirectoryListing {
  std::vector<fs::path> images;
  std::size_t entries = 0;
  std::string error;
};

// Hidden files are skipped ("._img.png" is macOS metadata, not an image), and so are
// subdirectories: the listing is not recursive.
bool is_listed_image(const fs::directory_entry& entry) {
  std::error_code ec;
  const fs::path& path = entry.path();
  return !path.filename().string().starts_with(".") && entry.is_regular_file(ec) && has_image_extension(path);
}

DirectoryListing list_directory(const std::string& input) {
  DirectoryListing listing;
  std::error_code ec;
  fs::directory_iterator it(input, ec);
  for (; !ec && it != fs::directory_iterator(); it.increment(ec)) {
    ++listing.entries;
    if (is_listed_image(*it)) listing.images.push_back(it->path());
  }
  if (ec) listing.error = "cannot read directory " + input + ": " + ec.message();
  return listing;
}

OpenResult open_directory(const std::string& input) {
  DirectoryListing listing = list_directory(input);
  if (!listing.error.empty()) return open_failed(listing.error);
  if (listing.entries == 0) return open_failed("directory " + input + " is empty");
  std::vector<fs::path>& files = listing.images;
  if (files.empty())
    return open_failed("directory " + input + " has no image files (" +
                       count_text(listing.entries, "entry", "entries") + ", none with extension " +
                       image_extension_list() + ")");
  std::sort(files.begin(), files.end(),
            [](const fs::path& a, const fs::path& b) { return a.filename().string() < b.filename().string(); });
  std::string description = "image directory " + input + " (" + count_text(files.size(), "image", "images") + ", " +
                            files.front().filename().string() + " .. " + files.back().filename().string() + ")";
  return OpenResult{std::make_unique<ImageListSource>(input, std::move(files), description), {}};
}

bool file_exists(const std::string& path) {
  std::error_code ec;
  return fs::exists(path, ec);
}

OpenResult open_sequence(const std::string& input, const SequencePattern& pattern) {
  int first = 0;
  while (first <= kSequenceMaxFirstIndex && !file_exists(pattern.format(first))) ++first;
  if (first > kSequenceMaxFirstIndex)
    return open_failed("image sequence " + input + ": no first file (looked for " + pattern.format(0) + " .. " +
                       pattern.format(kSequenceMaxFirstIndex) + ")");
  std::vector<fs::path> files;
  for (int i = first; i < INT_MAX && file_exists(pattern.format(i)); ++i) files.emplace_back(pattern.format(i));
  const int last = first + static_cast<int>(files.size()) - 1;
  std::string description = "image sequence " + input + " (" + count_text(files.size(), "image", "images") +
                            ", indices " + std::to_string(first) + ".." + std::to_string(last) + ")";
  return OpenResult{std::make_unique<ImageListSource>(input, std::move(files), description), {}};
}

OpenResult open_path(const std::string& input) {
  std::error_code ec;
  const fs::file_status status = fs::status(input, ec);
  if (!fs::exists(status)) {
    if (ec && ec != std::errc::no_such_file_or_directory)
      return open_failed("cannot access " + input + ": " + ec.message());
    return open_failed("no such file or directory: " + input);
  }
  if (fs::is_directory(status)) return open_directory(input);
  // Only plain files are probed with fopen: opening a device (/dev/video0) has effects.
  if (fs::is_regular_file(status))
    if (std::string why = open_error(input); !why.empty()) return open_failed("cannot read " + input + ": " + why);
  if (has_image_extension(input)) return open_single_image(input);
  return open_video_file(input);
}

}  // namespace

// ------------------------------------------------------------------ FrameSource

FrameResult FrameSource::next() {
  FrameResult result = read_next();
  return result.is_frame() ? check_size(std::move(result)) : result;
}

// Later stages (tracking, pixel-to-field mapping) assume one image geometry per run,
// so a frame of another size is reported and dropped rather than passed on.
FrameResult FrameSource::check_size(FrameResult result) {
  const cv::Size size = result.image.size();
  if (first_size_.empty()) {
    first_size_ = size;
    return result;
  }
  if (size == first_size_) return result;
  return frame_error(
      input_, result.index, std::move(result.name),
      "image is " + size_text(size) + " but the first frame was " + size_text(first_size_) + "; frame skipped");
}

// ------------------------------------------------------------------ factories

OpenResult open_frame_source(const std::string& input) {
  if (input.empty())
    return open_failed(
        "no input given: expected a video file, an image, a directory of "
        "images or a pattern such as frames/img_%04d.png");
  const PatternParse parsed = parse_sequence_pattern(input);
  if (!parsed.error.empty()) return open_failed(parsed.error);
  if (parsed.is_pattern) return open_sequence(input, parsed.pattern);
  return open_path(input);
}

OpenResult open_camera(int index) {
  const std::string input = "camera " + std::to_string(index);
  auto capture = std::make_unique<cv::VideoCapture>();
  bool opened = false;
  try {
    opened = index >= 0 && capture->open(index) && capture->isOpened();
  } catch (const cv::Exception&) {
    opened = false;
  }
  if (!opened) return open_failed("cannot open " + input + ": no such camera, or it is busy or not readable");
  return OpenResult{std::make_unique<VideoSource>(input, std::move(capture), "camera" + std::to_string(index), true),
                    {}};
}

}  // namespace rilbed::vision

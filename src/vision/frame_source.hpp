// Frame sources for the overhead-camera pipeline (`rilbed detect INPUT`, `--camera N`):
// one interface over a video file, a single image, a directory of images, a printf-style
// image sequence and a live camera.
//
// Bad input is a result, never an exception (ARCHITECTURE.md, "Bad input"): an input that
// cannot be opened gives an OpenResult with an error naming it; a frame that cannot be
// read gives a FrameResult of kind Error naming the input and the frame index, and the
// stream goes on with the next frame. Only the end of the input (or a video/camera that
// stops delivering) ends the stream.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>

#include <opencv2/core.hpp>

namespace rilbed::vision {

/// What one call of FrameSource::next() produced.
struct FrameResult {
  enum class Kind {
    kFrame,  ///< `image` holds a frame.
    kEnd,    ///< No more frames; every later next() call returns End too.
    kError,  ///< This frame could not be used; `error` says why. Call next() again.
  };

  Kind kind = Kind::kEnd;
  /// The frame as read: CV_8UC3 (BGR) or CV_8UC1 (grey), owned by this result (no other
  /// reference is kept by the source). Empty unless kind == Frame.
  cv::Mat image;
  /// 0-based position of the frame in input order. Skipped bad frames keep their
  /// index, so a good frame's index is its place in the input. -1 for End.
  int index = -1;
  /// Short name of the frame for messages: the image file name ("img_0007.png") or
  /// "<video file name>#<index>" ("run3.avi#17", "camera0#17"). Empty for End.
  std::string name;
  /// Human-readable reason, naming the input and the frame index; set only for Error.
  std::string error;

  bool is_frame() const { return kind == Kind::kFrame; }
  bool is_end() const { return kind == Kind::kEnd; }
  bool is_error() const { return kind == Kind::kError; }
};

/// A stream of frames in input order. Not thread-safe: one reader at a time.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  FrameSource(const FrameSource&) = delete;
  FrameSource& operator=(const FrameSource&) = delete;

  /// Returns the next frame, a per-frame error or the end of the input. Every frame
  /// must have the size of the first good frame; one of another size is returned as
  /// an Error (naming both sizes) and skipped. Grey and colour frames may mix.
  FrameResult next();

  /// Number of frames in the input if known (files, directories, sequences, videos
  /// whose container states it); std::nullopt for cameras and unknown lengths.
  /// For a video this is the container's claim, which a truncated file does not meet.
  virtual std::optional<int> frame_count() const = 0;

  /// Nominal frames per second (video: CAP_PROP_FPS; camera: as reported by the
  /// driver); 0 when unknown or meaningless (images).
  virtual double fps() const { return 0.0; }

  /// One line for humans, e.g. "video file run3.avi (640x480, 300 frames, 30 fps, FFMPEG)".
  virtual std::string describe() const = 0;

  /// The input as given to the factory (path, pattern, or "camera N").
  const std::string& input() const { return input_; }

 protected:
  explicit FrameSource(std::string input) : input_(std::move(input)) {}

  /// Reads the next frame without the size check; implemented per input kind.
  virtual FrameResult read_next() = 0;

 private:
  FrameResult check_size(FrameResult result);

  std::string input_;
  cv::Size first_size_;  // size of the first good frame; empty until one is read
};

/// Outcome of opening an input: a source, or an error naming the input.
struct OpenResult {
  /// The opened source, owned by the caller; null when opening failed.
  std::unique_ptr<FrameSource> source;
  /// Why opening failed (names the input); empty on success.
  std::string error;

  bool ok() const { return source != nullptr; }
};

/// Opens `input`, choosing the kind from the string and the file system:
///  - a path containing a printf-style integer conversion ("frames/img_%04d.png"; one
///    %d, %Nd or %0Nd, "%%" is a literal '%') is an image sequence: it starts at the
///    lowest existing index in 0..9 and stops at the first missing index after that;
///  - a directory is read as its image files (extensions png jpg jpeg pgm ppm pbm bmp
///    tif tiff webp, any case; other files, hidden files and subdirectories are
///    ignored) in plain lexicographic order of their file names; no recursion;
///  - a file with one of those image extensions is a single image, decoded here so
///    that an unreadable image fails to open;
///  - any other file is a video opened by cv::VideoCapture (every stream backend but
///    OpenCV's own image-sequence reader and GPhoto2, FFmpeg first); a file no backend
///    can open but OpenCV can decode as an image is taken as a single image.
/// Errors (missing file, unreadable file or directory, empty directory, directory
/// without images, sequence without a first file, video no backend opens) name `input`.
OpenResult open_frame_source(const std::string& input);

/// Opens live camera `index` >= 0 (as cv::VideoCapture(index)). A failed read ends the
/// stream with an Error naming the camera and frame, then End.
OpenResult open_camera(int index);

}  // namespace rilbed::vision

#include "bus/lcm_frame_source.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cctype>
#include <vector>

#include "bus/lcm_checked.hpp"
#include "bus/lcm_log_reader.hpp"

namespace rilbed::bus {

namespace {

bool is_frames_channel(const std::string& channel) {
  static const std::string kName = "RILBED_FRAMES";
  if (channel == kName) return true;
  return channel.size() > kName.size() + 1 && channel.ends_with("_" + kName);
}

// The frames' messages are kept encoded (JPEG) and decoded one at a time as read.
class LcmFrameSource final : public vision::FrameSource {
 public:
  LcmFrameSource(std::string input, std::vector<LcmLogReader::Event> events, std::string description)
      : vision::FrameSource(std::move(input)), events_(std::move(events)), description_(std::move(description)) {}

  std::optional<int> frame_count() const override { return static_cast<int>(events_.size()); }
  std::string describe() const override { return description_; }

 protected:
  vision::FrameResult read_next() override {
    vision::FrameResult r;
    if (next_ >= events_.size()) return r;  // End
    const int index = static_cast<int>(next_);
    const LcmLogReader::Event& e = events_[next_++];
    r.index = index;
    rilbed::frame_t m;
    if (!decode_checked(e.data.data(), e.data.size(), m))
      return error(r, "event " + std::to_string(e.eventnum) + " is not a rilbed.frame_t");
    r.name = "frame " + std::to_string(m.frame);
    if (m.format != "jpeg") return error(r, r.name + " is '" + m.format + "', not jpeg");
    cv::Mat image;
    try {
      image = cv::imdecode(m.data, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception&) {
      image.release();
    }
    if (image.empty() || image.cols != m.width_px || image.rows != m.height_px ||
        (image.channels() != 1 && image.channels() != 3) || image.depth() != CV_8U) {
      return error(r, r.name + " is not an 8-bit JPEG image of its stated size " + std::to_string(m.width_px) + "x" +
                          std::to_string(m.height_px));
    }
    r.kind = vision::FrameResult::Kind::kFrame;
    r.image = std::move(image);
    return r;
  }

 private:
  vision::FrameResult error(vision::FrameResult r, const std::string& why) const {
    r.kind = vision::FrameResult::Kind::kError;
    r.error = input() + ": " + why;
    return r;
  }

  std::vector<LcmLogReader::Event> events_;
  std::string description_;
  std::size_t next_ = 0;
};

}  // namespace

bool is_lcm_log_path(const std::string& path) {
  if (path.size() < 4) return false;
  std::string ext = path.substr(path.size() - 4);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".lcm";
}

vision::OpenResult open_lcm_frames(const std::string& path) {
  vision::OpenResult result;
  LcmLogReader log(path);
  if (!log.good()) {
    result.error = "cannot read the LCM log " + path;
    return result;
  }
  std::vector<LcmLogReader::Event> frames;
  long messages = 0;
  while (auto e = log.next()) {
    ++messages;
    if (is_frames_channel(e->channel)) frames.push_back(std::move(*e));
  }
  if (frames.empty()) {
    result.error = path + " holds no camera frames (" + std::to_string(messages) +
                   " messages, none on RILBED_FRAMES): record the run with --record-frames";
    return result;
  }
  const std::string description = "LCM log " + path + " (" + std::to_string(frames.size()) + " camera frames" +
                                  (log.truncated() ? ", cut short" : "") + ")";
  result.source = std::make_unique<LcmFrameSource>(path, std::move(frames), description);
  return result;
}

}  // namespace rilbed::bus

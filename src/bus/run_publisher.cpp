#include "bus/run_publisher.hpp"

#include "bus/lcm_checked.hpp"
#include "bus/lcm_conversion.hpp"
#include "bus/report_decoder.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <type_traits>
#include <utility>

namespace rilbed::bus {

// Hands what the publisher decodes to every local subscriber.
class LcmRunPublisher::Fanout final : public run::RunObserver {
 public:
  std::vector<run::RunObserver*> observers;
  bool wants_frame_images() const override {
    return std::any_of(observers.begin(), observers.end(), [](auto* o) { return o->wants_frame_images(); });
  }
  void on_world(TimeUs t, const run::WorldReport& w) override {
    each([&](auto& o) { o.on_world(t, w); });
  }
  void on_poses(TimeUs t, std::span<const run::PoseReport> p) override {
    each([&](auto& o) { o.on_poses(t, p); });
  }
  void on_wheels(TimeUs t, std::span<const run::WheelReport> w) override {
    each([&](auto& o) { o.on_wheels(t, w); });
  }
  void on_sensors(TimeUs t, std::span<const run::SensorReport> s) override {
    each([&](auto& o) { o.on_sensors(t, s); });
  }
  void on_detections(const run::FrameReport& f) override {
    each([&](auto& o) { o.on_detections(f); });
  }
  void on_frame_image(TimeUs t, std::int64_t n, const cv::Mat& image) override {
    each([&](auto& o) {
      if (o.wants_frame_images()) o.on_frame_image(t, n, image);
    });
  }
  bool wants_frame_jpegs() const override {
    return std::any_of(observers.begin(), observers.end(), [](auto* o) { return o->wants_frame_jpegs(); });
  }
  void on_frame_jpeg(TimeUs t, std::int64_t n, int w, int h, std::span<const std::uint8_t> jpeg) override {
    each([&](auto& o) {
      if (o.wants_frame_jpegs()) o.on_frame_jpeg(t, n, w, h, jpeg);
    });
  }
  void on_event(const run::RunEvent& e) override {
    each([&](auto& o) { o.on_event(e); });
  }
  void on_status(const run::StatusReport& s) override {
    each([&](auto& o) { o.on_status(s); });
  }
  void on_summary(TimeUs t, const nlohmann::json& j) override {
    each([&](auto& o) { o.on_summary(t, j); });
  }

 private:
  template <typename F>
  void each(F f) {
    for (run::RunObserver* o : observers) f(*o);
  }
};

LcmRunPublisher::LcmRunPublisher(lcm::LCM& lcm, Channels channels, Options options)
    : lcm_(lcm), channels_(std::move(channels)), options_(options) {}

LcmRunPublisher::~LcmRunPublisher() = default;

void LcmRunPublisher::add_local_subscriber(run::RunObserver& observer) {
  if (!fanout_) {
    fanout_ = std::make_unique<Fanout>();
    local_decoder_ = std::make_unique<RunReportDecoder>(channels_, *fanout_);
  }
  fanout_->observers.push_back(&observer);
}

std::unique_ptr<LcmSubscription> LcmRunPublisher::subscribe(const std::string& channel,
                                                            LcmSubscription::Handler handler) {
  auto subscription = std::make_unique<LcmSubscription>(lcm_, channel, std::move(handler));
  ++bus_subscribers_;
  return subscription;
}

template <typename Message>
void LcmRunPublisher::publish(const std::string& channel, const Message& message, bool local_only) {
  std::lock_guard lock(mutex_);
  // Encoded once: the same bytes go on the bus, into the log and to the local subscribers.
  const int room = message.getEncodedSize();
  buffer_.resize(static_cast<std::size_t>(room));
  // encode() stops a string at a NUL byte, so it may write fewer bytes than the room
  // getEncodedSize() asked for: send what it wrote.
  const int size = message.encode(buffer_.data(), 0, room);
  ChannelCount& c = counts_[channel];
  if (size < 0) {
    ++c.failures;
    return;
  }
  if (local_only) {
    if (local_decoder_) local_decoder_->decode(channel, buffer_.data(), static_cast<std::size_t>(size));
    return;
  }
  if (channel == channels_.world) last_world_.assign(buffer_.begin(), buffer_.begin() + size);
  if (channel == channels_.status) last_status_.assign(buffer_.begin(), buffer_.begin() + size);
  if (channel == channels_.summary) last_summary_.assign(buffer_.begin(), buffer_.begin() + size);
  const bool to_bus = !options_.in_process || bus_subscribers_ > 0;
  if (to_bus) {
    const int status = lcm_.publish(channel, buffer_.data(), static_cast<unsigned>(size));
    if (status != 0) ++c.failures;  // lost, as on a lossy network; the run goes on
  }
  ++c.messages;
  c.bytes += static_cast<std::uint64_t>(size);
  if (options_.log) {
    lcm::LogEvent event;
    event.eventnum = log_events_++;
    event.timestamp =
        std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
            .count();
    event.channel = channel;
    event.datalen = size;
    event.data = buffer_.data();
    options_.log->writeEvent(&event);
  }
  if (local_decoder_) local_decoder_->decode(channel, buffer_.data(), static_cast<std::size_t>(size));
  if (to_bus && options_.in_process) {
    // memq:// queues every message until handled: deliver to the in-process subscribers now.
    while (lcm_.handleTimeout(0) > 0) {}
  }
}

void LcmRunPublisher::republish_world_and_status() {
  std::lock_guard lock(mutex_);
  if (options_.in_process && bus_subscribers_ == 0) return;
  if (!last_world_.empty())
    lcm_.publish(channels_.world, last_world_.data(), static_cast<unsigned>(last_world_.size()));
  if (!last_status_.empty())
    lcm_.publish(channels_.status, last_status_.data(), static_cast<unsigned>(last_status_.size()));
}

void LcmRunPublisher::repeat_end() {
  std::lock_guard lock(mutex_);
  if (options_.in_process && bus_subscribers_ == 0) return;
  if (!last_status_.empty())
    lcm_.publish(channels_.status, last_status_.data(), static_cast<unsigned>(last_status_.size()));
  if (!last_summary_.empty()) {
    lcm_.publish(channels_.summary, last_summary_.data(), static_cast<unsigned>(last_summary_.size()));
  }
  if (options_.in_process) {
    while (lcm_.handleTimeout(0) > 0) {}
  }
}

void LcmRunPublisher::on_world(TimeUs t_us, const run::WorldReport& world) {
  if (!heard()) return;
  // The camera first: a viewer draws the world over the camera's frames.
  if (world.camera) publish(channels_.camera, to_lcm(t_us, *world.camera));
  if (!world.sensor_geometries.empty()) publish(channels_.sensor_layout, sensor_layout(t_us, world));
  if (!world.bodies.empty()) publish(channels_.robot_bodies, robot_bodies(t_us, world));
  publish(channels_.world, to_lcm(t_us, world));
}

void LcmRunPublisher::on_poses(TimeUs t_us, std::span<const run::PoseReport> poses) {
  if (!heard()) return;
  fill(poses_message_, t_us, poses);
  publish(channels_.poses, poses_message_);
}

void LcmRunPublisher::on_wheels(TimeUs t_us, std::span<const run::WheelReport> wheels) {
  if (!heard()) return;
  fill(wheels_message_, t_us, wheels);
  publish(channels_.wheels, wheels_message_);
}

void LcmRunPublisher::on_sensors(TimeUs t_us, std::span<const run::SensorReport> sensors) {
  if (!heard()) return;
  // The models' readings and marks first: a viewer joins them to the sensors_t by utime.
  if (fill(models_message_, t_us, sensors)) publish(channels_.sensor_models, models_message_);
  fill(sensors_message_, t_us, sensors);
  publish(channels_.sensors, sensors_message_);
}

void LcmRunPublisher::on_detections(const run::FrameReport& frame) {
  if (heard()) publish(channels_.detections, to_lcm(frame));
}

void LcmRunPublisher::on_frame_image(TimeUs t_us, std::int64_t frame, const cv::Mat& image) {
  if (options_.frames) {
    if (heard()) publish(channels_.frames, to_lcm(t_us, frame, image, options_.jpeg_quality));
    return;
  }
  // Only for the local subscribers (a web panel), and only as often as they show them.
  if (options_.local_frame_period_ms <= 0 || !fanout_ || !fanout_->wants_frame_jpegs()) return;
  const auto now = std::chrono::steady_clock::now();
  if (now < next_local_frame_) return;
  next_local_frame_ = now + std::chrono::milliseconds(options_.local_frame_period_ms);
  publish(channels_.frames, to_lcm(t_us, frame, image, options_.jpeg_quality), /*local_only=*/true);
}

void LcmRunPublisher::on_event(const run::RunEvent& event) {
  if (heard()) publish(channels_.events, to_lcm(event));
}

void LcmRunPublisher::on_status(const run::StatusReport& status) {
  if (!heard()) return;
  // The settings first: a decoder hands them on with the status that follows.
  if (status.vision) publish(channels_.vision, to_lcm(status.t_us, *status.vision));
  publish(channels_.status, to_lcm(status));
  if (options_.log) std::fflush(options_.log->getFilePtr());  // a run cut short keeps its log up to the last second
}

void LcmRunPublisher::on_summary(TimeUs t_us, const nlohmann::json& summary) {
  if (!heard()) return;
  publish(channels_.summary, to_lcm(t_us, summary));
  if (options_.log) std::fflush(options_.log->getFilePtr());  // the whole run is on disk once it has ended
}

std::map<std::string, ChannelCount> LcmRunPublisher::counts() const {
  std::lock_guard lock(mutex_);
  return counts_;
}

}  // namespace rilbed::bus

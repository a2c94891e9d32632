#include "session/run_outputs.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <stdexcept>
#include <thread>

namespace rilbed::session {

void CurrentPublisher::set(bus::LcmRunPublisher* publisher) {
  std::lock_guard lock(mutex_);
  publisher_ = publisher;
}

void CurrentPublisher::republish_world_and_status() {
  std::lock_guard lock(mutex_);
  if (publisher_) publisher_->republish_world_and_status();
}

RunOutputs::RunOutputs(const OutputsConfig& config, run::RunOptions& options) : config_(config) {
  lcm::LCM* bus = config.network_bus;
  if (!bus) {
    // memq:// is one per run: it is not safe with runs of a batch publishing from several threads.
    std::string error;
    own_bus_ = bus::open_lcm("memq://", error);
    if (!own_bus_) throw std::runtime_error(error);
    bus = own_bus_.get();
  }
  bus::LcmRunPublisher::Options po;
  po.in_process = !config.network_bus;
  po.log = config.recording;
  po.frames = config.record_frames;
  // The panel shows the camera at most 10 frames a second; they go to it alone.
  if (config.gui) po.local_frame_period_ms = static_cast<int>(1000.0 / gui_web::kMaxCameraFps);
  publisher_ = std::make_unique<bus::LcmRunPublisher>(*bus, config.channels, po);
  if (options.out_dir) {
    folder_ = std::make_unique<run::RunFolderWriter>(*options.out_dir);
    publisher_->add_local_subscriber(*folder_);
    options.out_dir.reset();
  }
  if (config.status_line) {
    status_line_ = std::make_unique<run::StatusLine>(config.print);
    publisher_->add_local_subscriber(*status_line_);
  }
  if (config.gui) publisher_->add_local_subscriber(*config.gui);
  options.observer = publisher_.get();
  if (config.current) config.current->set(publisher_.get());
}

RunOutputs::~RunOutputs() {
  if (config_.current) config_.current->set(nullptr);
}

void RunOutputs::after_run(std::uint64_t seed) {
  if (!config_.network_bus) return;
  for (int k = 0; k < 2; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    publisher_->repeat_end();
  }
  // A publish the network refused (a firewall's EPERM) is lost: say how many.
  std::uint64_t refused = 0;
  for (const auto& [channel, count] : publisher_->counts()) refused += count.failures;
  if (refused > 0) {
    spdlog::warn("seed {}: the bus refused {} of the run's messages (they were lost; a firewall?)", seed, refused);
  }
}

}  // namespace rilbed::session

// One run's reports on the bus: its LcmRunPublisher (on the session's network bus, or on an
// in-process bus of its own), with the run folder, the status line and the web panel as
// its local subscribers, so that the folder holds exactly what went out.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include "bus/lcm_bus.hpp"
#include "bus/run_publisher.hpp"
#include "gui_web/gui_service.hpp"
#include "run/run_folder_writer.hpp"
#include "run/run_options.hpp"
#include "run/status_line.hpp"

namespace rilbed::session {

/// The publisher of the run now going, for the console's thread (a paused run re-publishes
/// its world and status every second). Thread-safe.
class CurrentPublisher {
 public:
  void set(bus::LcmRunPublisher* publisher);
  /// The current run's last world and status again, if a run is going.
  void republish_world_and_status();

 private:
  std::mutex mutex_;
  bus::LcmRunPublisher* publisher_ = nullptr;
};

/// What every run of a session publishes with.
struct OutputsConfig {
  lcm::LCM* network_bus = nullptr;                ///< a bus other processes reach; null: each run its own memq://
  bus::Channels channels;                         ///< the channel names
  lcm::LogFile* recording = nullptr;              ///< every message also goes here (one run); may be null
  bool record_frames = false;                     ///< the camera's frames go out too (RILBED_FRAMES)
  gui_web::GuiService* gui = nullptr;             ///< the web panel, a local subscriber; may be null
  bool status_line = false;                       ///< print the per-second status line
  std::function<void(const std::string&)> print;  ///< where the status line goes
  CurrentPublisher* current = nullptr;            ///< told of each run's publisher; may be null
};

/// One run's outputs, for as long as the run goes. Not copyable.
class RunOutputs {
 public:
  /// Sets `options.observer` to the run's publisher and takes `options.out_dir` for the
  /// folder writer (the run itself then writes no folder). Throws std::runtime_error when
  /// it cannot open its in-process bus.
  RunOutputs(const OutputsConfig& config, run::RunOptions& options);
  ~RunOutputs();
  RunOutputs(const RunOutputs&) = delete;
  RunOutputs& operator=(const RunOutputs&) = delete;

  /// After the run of `seed`: on a network bus the end goes out twice more (a watcher that
  /// lost it would wait forever) and messages the bus refused are counted in a warning.
  void after_run(std::uint64_t seed);

 private:
  const OutputsConfig& config_;
  std::unique_ptr<lcm::LCM> own_bus_;
  std::unique_ptr<bus::LcmRunPublisher> publisher_;
  std::unique_ptr<run::RunFolderWriter> folder_;
  std::unique_ptr<run::StatusLine> status_line_;
};

}  // namespace rilbed::session

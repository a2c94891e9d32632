// A run's messages, as raw bytes from a bus or a log, back into a RunObserver's calls (the
// run's own folder and status line, `rilbed replay`, `rilbed watch`, `rilbed gui`).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bus/lcm_bus.hpp"
#include "rilbed/sensor_models_t.hpp"
#include "rilbed/status_t.hpp"
#include "run/run_observer.hpp"

namespace rilbed::bus {

/// Hands the messages of a run's channels, as raw bytes from a bus or a log, to a
/// RunObserver as the run reported them. Messages on other channels are ignored.
class RunReportDecoder {
 public:
  RunReportDecoder(Channels channels, run::RunObserver& observer);
  /// Decodes one message of `channel`; returns the reason when its bytes are not a
  /// message of that channel's type (the message is then skipped).
  std::optional<std::string> decode(const std::string& channel, const void* data, std::size_t size);
  /// Whether the run's summary (its last message) has come.
  bool summary_seen() const { return summary_seen_; }
  /// The last status decoded, if any.
  const std::optional<rilbed::status_t>& last_status() const { return last_status_; }
  /// The summary a recording cut short gets (no RILBED_SUMMARY came): {"truncated": true}
  /// and what its last status said of the run.
  nlohmann::json cut_short_summary() const;

 private:
  Channels channels_;
  run::RunObserver& observer_;
  std::vector<run::PoseReport> poses_;
  std::vector<run::WheelReport> wheels_;
  std::vector<environment::SensorReadings> readings_;
  std::vector<run::SensorReport> sensors_;
  std::vector<run::DetectionReport> detections_;
  bool summary_seen_ = false;
  std::optional<rilbed::status_t> last_status_;
  std::optional<run::CameraReport> camera_;             // the last camera_t, for the next world_t
  std::vector<run::SensorGeometry> sensor_geometries_;  // the last sensor_layout_t, for the next world_t
  std::map<int, int> sensor_geometry_of_;
  std::vector<run::BodyDrawing> bodies_;            // the last robot_bodies_t, for the next world_t
  std::optional<rilbed::sensor_models_t> models_;   // the last sensor_models_t, for the sensors_t of its utime
  std::set<std::string, std::less<>> model_names_;  // what readings_' model names view
  std::map<int, int> body_of_;
  std::optional<vision::VisionSettings> vision_;  // the last vision_settings_t, for the next status_t
};

}  // namespace rilbed::bus

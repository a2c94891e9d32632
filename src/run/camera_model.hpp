// The overhead camera as a DEVS model, and the camera a scenario with real robots gets.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "environment/world.hpp"
#include "run/run_observer.hpp"
#include "run/run_options.hpp"
#include "run/scenario.hpp"
#include "sim/atomic.hpp"
#include "vision/field_tracker.hpp"

namespace rilbed::run {

// The overhead camera as a DEVS model: every frame period it takes a frame, tracks the
// real robots' markers and places them in the world (World::set_observed_pose). Virtual
// robots are not on camera; they live only in the world model (paper 001).
class VisionModel final : public sim::AtomicModel<TimeUs> {  // state: time to the next frame
 public:
  using Grab = std::function<std::optional<cv::Mat>()>;
  VisionModel(environment::World& world, vision::FieldTracker tracker, Grab grab, TimeUs period_us)
      : sim::AtomicModel<TimeUs>("camera", 0),
        world_(world),
        tracker_(std::move(tracker)),
        grab_(std::move(grab)),
        period_us_(period_us) {}
  /// Tells `observer` (may be null) what every frame shows; `observer` outlives the run.
  void report_to(RunObserver* observer) {
    observer_ = observer;
    send_images_ = observer && observer->wants_frame_images();
  }
  TimeUs time_advance() const override { return state_; }
  void external_transition(TimeUs elapsed_us) override { state_ -= elapsed_us; }
  void output() override {}
  void internal_transition() override;
  long frames() const { return frames_.load(std::memory_order_relaxed); }
  /// The vision settings in use; set_vision() changes them from the next frame on (the
  /// run's thread only).
  const vision::VisionSettings& vision() const { return tracker_.settings(); }
  void set_vision(const vision::VisionSettings& settings) { tracker_.set_settings(settings); }
  long sightings() const { return sightings_; }
  /// What viewers need to draw the field over its frames.
  CameraReport camera_report(const std::string& source) const;

 private:
  void report(const cv::Mat& frame, const std::vector<vision::FieldObservation>& seen, double process_ms);

  environment::World& world_;
  vision::FieldTracker tracker_;
  Grab grab_;
  TimeUs period_us_;
  TimeUs t_us_ = 0;
  std::atomic<long> frames_{0};  // read by the monitor for the status' frame rate
  long sightings_ = 0;
  RunObserver* observer_ = nullptr;
  bool send_images_ = false;
  std::vector<DetectionReport> detections_;
};

/// The camera of a scenario with real robots, ready to add to the run (null without real
/// robots): emulated (rendering options.emulated_markers), a live camera or footage. Throws
/// ScenarioError naming the scenario's camera line for a family, calibration, device or
/// file it cannot use.
std::shared_ptr<VisionModel> make_camera(const Scenario& scenario, const RunOptions& options,
                                         environment::World& world);

}  // namespace rilbed::run

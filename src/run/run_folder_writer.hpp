// A run folder written from what a run reports (agents::RunObserver) rather than from
// inside the run: trajectories.csv, events.csv, summary.json, trajectories.svg (and
// detections.csv for a run with a camera), from the messages alone. `rilbed run` writes
// its folder with it, as a subscriber of its own bus. `rilbed replay` writes a recording's folder
// with it, so a recorded run's folder is byte for byte the live run's.
#pragma once

#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "run/run_observer.hpp"
#include "run/run_recorder.hpp"

namespace rilbed::run {

/// Writes a run folder from a run's reports. Not thread-safe.
class RunFolderWriter final : public RunObserver {
 public:
  /// The folder is created when the first report arrives. Throws std::runtime_error
  /// naming the path when it cannot be written.
  explicit RunFolderWriter(std::filesystem::path dir);
  void on_world(TimeUs t_us, const WorldReport& world) override;
  void on_poses(TimeUs t_us, std::span<const PoseReport> poses) override;
  void on_event(const RunEvent& event) override;
  /// A run with a camera also gets detections.csv (header
  /// frame,t_s,id,u_px,v_px,heading_deg,score,diameter_px,x_m,y_m,theta_deg): every marker
  /// the camera found, frame by frame (frame numbers from 1).
  void on_detections(const FrameReport& frame) override;
  void on_summary(TimeUs t_us, const nlohmann::json& summary) override;
  /// Whether the summary arrived (the folder is complete).
  bool finished() const { return finished_; }
  /// Ends a folder whose summary never came (a recording cut short) with `summary`.
  /// (A world after the summary, a run started over by the console's reset, starts the
  /// folder over.)
  void finish_without_summary(const nlohmann::json& summary);

 private:
  RunRecorder& recorder(const FieldDrawing* field = nullptr);
  std::string_view intern(std::string_view text);

  std::filesystem::path dir_;
  std::unique_ptr<RunRecorder> recorder_;
  std::set<std::string, std::less<>> names_;  // behaviours, kept for the samples' views
  std::vector<TrajectorySample> samples_;
  std::ofstream detections_;  // opened with the first camera frame
  bool finished_ = false;
};

}  // namespace rilbed::run

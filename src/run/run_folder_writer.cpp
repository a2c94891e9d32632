#include "run/run_folder_writer.hpp"

#include <cstdio>
#include <stdexcept>

namespace rilbed::run {

RunFolderWriter::RunFolderWriter(std::filesystem::path dir) : dir_(std::move(dir)) {}

RunRecorder& RunFolderWriter::recorder(const FieldDrawing* field) {
  // The run reports its world first; a recording that lost it still gets its rows.
  if (!recorder_) recorder_ = std::make_unique<RunRecorder>(dir_, field ? *field : FieldDrawing{});
  return *recorder_;
}

std::string_view RunFolderWriter::intern(std::string_view text) {
  auto it = names_.find(text);
  if (it == names_.end()) it = names_.emplace(text).first;
  return *it;
}

void RunFolderWriter::on_world(TimeUs, const WorldReport& world) {
  if (finished_) {
    // The run ended and another began on the same bus (the console's reset starts a run
    // over): the folder holds the run that goes on.
    recorder_.reset();
    samples_.clear();
    if (detections_.is_open()) detections_.close();
    finished_ = false;
  }
  FieldDrawing field = world.field;
  for (const auto& [id, index] : world.body_of) {
    if (index < 0 || static_cast<std::size_t>(index) >= world.bodies.size()) continue;
    const BodyDrawing& body = world.bodies[static_cast<std::size_t>(index)];
    field.body_radius_m[id] = body.radius_m;
    if (!body.outline_m.empty()) field.body_outline_m[id] = body.outline_m;
  }
  if (recorder_) {
    recorder_->set_field(field);
  } else {
    recorder(&field);
  }
}

void RunFolderWriter::on_poses(TimeUs t_us, std::span<const PoseReport> poses) {
  samples_.clear();
  for (const PoseReport& p : poses) {
    // trajectories.csv holds the robots whose pose the test bed knew at that step.
    if (p.seen) samples_.push_back({t_us, p.id, p.pose, intern(p.behaviour)});
  }
  recorder().add_samples(samples_);
}

void RunFolderWriter::on_event(const RunEvent& event) { recorder().add_event(event); }

void RunFolderWriter::on_detections(const FrameReport& frame) {
  RunRecorder& r = recorder();
  if (!detections_.is_open()) {
    detections_.open(r.dir() / "detections.csv");
    if (!detections_) throw std::runtime_error("cannot write " + (r.dir() / "detections.csv").string());
    detections_ << "frame,t_s,id,u_px,v_px,heading_deg,score,diameter_px,x_m,y_m,theta_deg\n";
  }
  char row[256];
  for (const DetectionReport& d : frame.detections) {
    std::snprintf(row, sizeof row, "%lld,%.3f,%d,%.3f,%.3f,%.2f,%.4f,%.2f,%.5f,%.5f,%.2f\n",
                  static_cast<long long>(frame.frame), us_to_seconds(frame.t_us), d.id, d.u_px, d.v_px, d.heading_deg,
                  d.score, d.diameter_px, d.pose.position_m.x, d.pose.position_m.y,
                  wrap_deg_360(rad_to_deg(d.pose.heading_rad)));
    detections_ << row;
  }
}

void RunFolderWriter::on_summary(TimeUs, const nlohmann::json& summary) {
  if (finished_) return;
  if (detections_.is_open()) detections_.close();
  recorder().finish(summary);
  finished_ = true;
}

void RunFolderWriter::finish_without_summary(const nlohmann::json& summary) { on_summary(0, summary); }

}  // namespace rilbed::run

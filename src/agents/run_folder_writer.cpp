#include "agents/run_folder_writer.hpp"

namespace rilbed::agents {

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
    finished_ = false;
  }
  if (recorder_) {
    recorder_->set_field(world.field);
  } else {
    recorder(&world.field);
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

void RunFolderWriter::on_summary(TimeUs, const nlohmann::json& summary) {
  if (finished_) return;
  recorder().finish(summary);
  finished_ = true;
}

void RunFolderWriter::finish_without_summary(const nlohmann::json& summary) { on_summary(0, summary); }

}  // namespace rilbed::agents

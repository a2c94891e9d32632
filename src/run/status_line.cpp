#include "run/status_line.hpp"

#include <cstdio>

namespace rilbed::run {

void StatusLine::on_poses(TimeUs, std::span<const PoseReport> poses) {
  // The views in `poses` live only during this call: keep copies of the strings.
  robots_.resize(poses.size());
  poses_.resize(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    robots_[i].id = poses[i].id;
    robots_[i].behaviour.assign(poses[i].behaviour);
    robots_[i].health.assign(poses[i].health);
  }
  for (std::size_t i = 0; i < poses.size(); ++i) {
    poses_[i] = poses[i];
    poses_[i].behaviour = robots_[i].behaviour;
    poses_[i].health = robots_[i].health;
  }
}

void StatusLine::on_status(const StatusReport& status) {
  const std::string line = format(status, poses_);
  if (!line.empty()) print_(line);
}

std::string StatusLine::format(const StatusReport& status, std::span<const PoseReport> poses) {
  if (status.state == "ended") return {};
  char t[48];
  std::snprintf(t, sizeof t, "t=%.1fs", static_cast<double>(status.t_us) * 1e-6);
  std::string line = t;
  if (status.state == "paused") return line + "  paused";
  for (const PoseReport& p : poses) {
    line += "  " + std::to_string(p.id) + ":" + std::string(p.behaviour);
    if (p.health != "ok") line += "(" + std::string(p.health) + ")";
  }
  if (status.formed) line += "  [formed]";
  return line;
}

}  // namespace rilbed::run

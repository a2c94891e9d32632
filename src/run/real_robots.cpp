#include "run/real_robots.hpp"

#include <stdlib.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <system_error>
#include <thread>

namespace rilbed::run {

namespace {

const serial::RobotModel& model_named(const std::string& name, const std::string& where) {
  if (name == "khepera2" || name == "khepera") return serial::khepera2_model();
  if (name == "epuck" || name == "e-puck") return serial::epuck_model();
  throw run::ScenarioError(where + ": unknown robot model '" + name + "' (khepera2, epuck)");
}

serial::EmulatorConfig emulator_config(const run::RobotSpec& spec, const serial::RobotModel& model, const Pose2& pose) {
  serial::EmulatorConfig emu;
  emu.model = model;
  emu.initial_pose = pose;
  emu.seed = static_cast<std::uint64_t>(spec.id);
  emu.faults = spec.link->faults;
  return emu;
}

}  // namespace

RealRobots::RealRobots(const run::Scenario& scenario, serial::LogCallback log)
    : scenario_(scenario), log_(std::move(log)) {}

RealRobots::~RealRobots() {
  std::map<int, std::shared_ptr<serial::KheperaLink>> links;
  {
    std::lock_guard lock(mutex_);
    links = std::move(links_);
  }
  for (auto& [id, link] : links) link->stop();
  links.clear();  // closes the ports (bodies may hold the last references, and are gone by now)
  std::lock_guard lock(mutex_);
  emulators_.clear();
  if (!emulator_dir_.empty()) {
    std::error_code ignored;
    std::filesystem::remove_all(emulator_dir_, ignored);
  }
}

std::string RealRobots::emulator_link_path(int id) {
  // Under the caller's lock. The emulated robot is reached through a symlink that follows
  // its pty across an unplug: a replugged pty may get another number, and its old
  // /dev/pts/N may by then be another program's robot (as /dev/ttyUSB0 may after a real
  // replug; on a real rig, use /dev/serial/by-id/).
  if (emulator_dir_.empty()) {
    std::string pattern = (std::filesystem::temp_directory_path() / "rilbed-robots-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw std::system_error(errno, std::generic_category(), "cannot make a folder for the emulated robots' ports");
    }
    emulator_dir_ = pattern;
  }
  return (emulator_dir_ / ("robot-" + std::to_string(id))).string();
}

std::shared_ptr<serial::KheperaLink> RealRobots::connect(const run::RobotSpec& spec, const Pose2& pose_if_new) {
  {
    std::lock_guard lock(mutex_);
    if (const auto it = links_.find(spec.id); it != links_.end()) return it->second;
  }
  const std::string where =
      scenario_.source.string() + ":" + std::to_string(spec.line) + ": robot " + std::to_string(spec.id);
  if (!spec.link) throw run::ScenarioError(where + ": a real robot needs a link");
  serial::LinkConfig config;
  config.model = model_named(spec.link->model, where);
  // The robot's own parts where its model file gives them (the emulator moves with them).
  config.model.wheel_base_m = spec.body.wheel_base_m;
  if (spec.link->speed_unit_mps) config.model.speed_unit_mps = *spec.link->speed_unit_mps;
  if (spec.link->counter_pulse_m) config.model.counter_pulse_m = *spec.link->counter_pulse_m;
  config.baud = static_cast<unsigned>(spec.link->baud);
  // Messages name the robot as well as the port (the link names the port).
  if (log_) {
    config.log = [log = log_, id = spec.id](serial::LogLevel level, const std::string& message) {
      log(level, "robot " + std::to_string(id) + ": " + message);
    };
  }
  config.reply_timeout_ms = spec.link->reply_timeout_ms;
  config.retries = spec.link->retries;
  // Proximity is read once per control step (RealBody::sense asks for the next one);
  // the wheel counters at their own rate.
  config.counters_period_ms = spec.link->counters_period_ms;
  if (spec.link->emulate) {
    std::lock_guard lock(mutex_);
    serial::EmulatorConfig emu = emulator_config(spec, config.model, pose_if_new);
    emu.stable_path = emulator_link_path(spec.id);
    auto emulator = std::make_unique<serial::KheperaEmulator>(emu);
    config.port = emulator->device_path();
    emulators_[spec.id] = std::move(emulator);
  } else {
    config.port = spec.link->port;
  }
  std::shared_ptr<serial::KheperaLink> link;
  try {
    link = std::make_shared<serial::KheperaLink>(config);
  } catch (const std::invalid_argument& e) {
    throw run::ScenarioError(where + ": " + e.what());
  }
  if (const auto error = link->start()) throw run::ScenarioError(where + ": " + *error);
  // The robot must answer before a run relies on it.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (link->state() != serial::LinkState::kOk && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (link->state() != serial::LinkState::kOk) {
    const std::string why = link->status().last_error;
    link->stop(200);
    throw run::ScenarioError(where + ": " + config.port + " does not answer" + (why.empty() ? "" : ": " + why));
  }
  std::lock_guard lock(mutex_);
  links_[spec.id] = link;
  return link;
}

run::RealBodyFactory RealRobots::body_factory() {
  return [this](const run::RobotSpec& spec, environment::World& world) -> std::unique_ptr<agents::Body> {
    std::shared_ptr<serial::KheperaLink> link = connect(spec, world.robot(spec.id).pose);
    RealBodyConfig body;
    body.lost_timeout_ms = scenario_.lost_timeout_ms;
    body.geofence_margin_m = scenario_.geofence_margin_m;
    return std::make_unique<RealBody>(spec.id, world, std::move(link), body);
  };
}

std::vector<vision::SceneMarker> RealRobots::emulated_markers() const {
  std::lock_guard lock(mutex_);
  std::vector<vision::SceneMarker> out;
  for (const auto& [id, emulator] : emulators_) {
    const Pose2 p = emulator->true_pose();
    vision::SceneMarker m{id, p.position_m.x, p.position_m.y, p.heading_rad, 0.05};
    // The robot under its marker, as its body is described (the camera renders its top).
    const auto spec = std::find_if(scenario_.robots.begin(), scenario_.robots.end(),
                                   [&](const run::RobotSpec& r) { return r.id == id; });
    if (spec != scenario_.robots.end()) {
      m.body_radius_m = spec->body.radius_m;
      for (const Vec2& v : spec->body.outline_m) m.body_outline_m.emplace_back(v.x, v.y);
    }
    out.push_back(std::move(m));
  }
  return out;
}

std::map<int, const serial::KheperaEmulator*> RealRobots::emulators() const {
  std::lock_guard lock(mutex_);
  std::map<int, const serial::KheperaEmulator*> out;
  for (const auto& [id, e] : emulators_) out[id] = e.get();
  return out;
}

serial::KheperaEmulator* RealRobots::emulator(int id) {
  std::lock_guard lock(mutex_);
  const auto it = emulators_.find(id);
  return it == emulators_.end() ? nullptr : it->second.get();
}

}  // namespace rilbed::run

#include "gui_web/gui_service.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <nlohmann/json.hpp>

namespace rilbed::gui_web {

namespace {

constexpr std::size_t kMaxQueuedCommands = 16;
constexpr std::string_view kVisionPrefix = "vision.";

std::string number_text(double v) {
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

std::string seconds_text(double s) {
  std::ostringstream out;
  out.precision(3);
  out << s;
  return out.str();
}

}  // namespace

GuiService::GuiService(WebServerConfig config, ConsoleSink sink, ManualDriveConfig drive)
    : config_(std::move(config)), sink_(std::move(sink)), drive_(drive) {
  if (!sink_) throw std::invalid_argument("gui: no console sink");
  if (drive_.key_timeout_ms <= 0 || drive_.tick_ms <= 0 || !(drive_.hold_wall_s > 0.0)) {
    throw std::invalid_argument("gui: manual driving's times must be above 0");
  }
  WebServer::Handlers handlers;
  handlers.on_client_message = [this](const std::string& client, const std::string& topic, const std::string&,
                                      std::string_view payload) { return on_client_message(client, topic, payload); };
  handlers.on_client_gone = [this](const std::string& client) { on_client_gone(client); };
  handlers.on_set_parameters = [this](const std::string& client, const std::vector<foxglove::Parameter>& parameters,
                                      const std::optional<std::string>& id) {
    on_set_parameters(client, parameters, id);
  };
  server_ = std::make_unique<WebServer>(config_, std::move(handlers));
  channels_ = std::make_unique<RunChannels>(*server_);
  thread_ = std::thread([this] { loop(); });
}

GuiService::~GuiService() {
  {
    std::lock_guard lock(mutex_);
    for (auto& [id, hold] : holds_) hold.ending = true;
    stopping_ = true;
    wake_pending_ = true;
  }
  wake_.notify_all();
  thread_.join();  // sends the last stops
  // The channels' thread publishes on the server: it ends (publishing what it holds) first.
  channels_.reset();
  server_.reset();
}

std::string GuiService::url() const {
  return "http://" + config_.bind_address + ":" + std::to_string(server_->port()) + "/?token=" + config_.token;
}

bool GuiService::flush(std::chrono::milliseconds timeout) {
  const auto start = Clock::now();
  if (!channels_->flush(timeout)) return false;
  const auto left = timeout - std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - start);
  return server_->flush(std::max(left, std::chrono::milliseconds(0)));
}

GuiCounters GuiService::counters() const {
  std::lock_guard lock(mutex_);
  return counts_;
}

// ------------------------------------------------------------------ from the browsers

std::optional<std::string> GuiService::on_client_message(const std::string& client, const std::string& topic,
                                                         std::string_view payload) {
  if (topic == "/rilbed/drive") return on_drive_message(client, payload);
  if (topic != "/rilbed/console")
    return "this server takes messages on /rilbed/console and /rilbed/drive, not " + topic;
  const auto j = nlohmann::json::parse(payload, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("command") || !j["command"].is_string()) {
    return std::string("a console message is {\"command\": \"pause\", \"args\": []}");
  }
  ConsoleRequest request{client, j["command"].get<std::string>(), {}, std::nullopt, std::nullopt};
  if (j.contains("args")) {
    if (!j["args"].is_array() || j["args"].size() > 12) return std::string("args must be a list of at most 12 strings");
    for (const auto& a : j["args"]) {
      if (!a.is_string() && !a.is_number()) return std::string("args must be strings or numbers");
      request.args.push_back(a.is_string() ? a.get<std::string>() : a.dump());
    }
  }
  std::lock_guard lock(mutex_);
  if (requests_.size() >= kMaxQueuedCommands) return std::string("too many console commands waiting");
  requests_.push_back(std::move(request));
  wake_locked();
  return std::nullopt;
}

std::optional<std::string> GuiService::on_drive_message(const std::string& client, std::string_view payload) {
  const auto j = nlohmann::json::parse(payload, nullptr, false);
  const char* usage = "a drive message is {\"id\": 4, \"left\": 20, \"right\": 20} or {\"id\": 4, \"release\": true}";
  if (j.is_discarded() || !j.is_object() || !j.contains("id") || !j["id"].is_number_integer())
    return std::string(usage);
  const long long id = j["id"].get<long long>();
  if (id < 0 || id > 1'000'000) return "'" + j["id"].dump() + "' is not a robot ID";
  const int robot = static_cast<int>(id);
  std::lock_guard lock(mutex_);
  ++counts_.drive_messages;
  if (j.value("release", false)) {
    const auto it = holds_.find(robot);
    if (it == holds_.end() || it->second.client != client || it->second.ending)
      return "robot " + std::to_string(robot) + " is not yours to release";
    it->second.ending = true;
    wake_locked();
    return std::nullopt;
  }
  if (!j.contains("left") || !j.contains("right") || !j["left"].is_number_integer() ||
      !j["right"].is_number_integer()) {
    return std::string(usage);
  }
  const long long left = j["left"].get<long long>(), right = j["right"].get<long long>();
  if (std::llabs(left) > 127 || std::llabs(right) > 127)
    return std::string("wheel speeds are -127..127 (Khepera units)");
  // One robot per client: taking another gives the first one back.
  for (auto& [other, hold] : holds_) {
    if (other != robot && hold.client == client) hold.ending = true;
  }
  Hold& hold = holds_[robot];
  if (hold.client != client) {
    // A new driver (or a take-over: the last driver's hold ends here, without a gap).
    // Told to the last driver alone (a status on its socket): its page lets go of the robot.
    if (!hold.client.empty()) {
      server_->tell(hold.client, foxglove::Level::kWarning,
                    "robot " + std::to_string(robot) + " taken over by " + client);
    }
    hold = Hold{};
    hold.client = client;
  }
  hold.ending = false;
  const bool changed = hold.left != left || hold.right != right;
  hold.left = static_cast<int>(left);
  hold.right = static_cast<int>(right);
  hold.last_key = now();
  if (changed || !hold.sent) wake_locked();
  return std::nullopt;
}

void GuiService::on_set_parameters(const std::string& client, const std::vector<foxglove::Parameter>& parameters,
                                   const std::optional<std::string>& id) {
  ConsoleRequest request{client, "vision", {}, std::vector<std::string>{}, id};
  std::optional<std::string> refusal;
  for (const foxglove::Parameter& p : parameters) {
    request.parameters->push_back(p.name);
    if (refusal) continue;
    if (p.name.rfind(kVisionPrefix, 0) != 0) {
      refusal = "unknown parameter '" + p.name.substr(0, 64) + "' (this server's are vision.*)";
    } else if (!p.value.is_number()) {
      refusal = p.name + " must be a number";
    } else {
      request.args.push_back(p.name.substr(kVisionPrefix.size()));
      request.args.push_back(number_text(p.value.get<double>()));
    }
  }
  if (!refusal && parameters.empty()) refusal = "no parameter to set";
  std::lock_guard lock(mutex_);
  if (!refusal && requests_.size() >= kMaxQueuedCommands) refusal = "too many console commands waiting";
  if (refusal) {
    server_->tell(client, foxglove::Level::kError, *refusal);
    server_->answer_parameters(client, *request.parameters, id);
    return;
  }
  requests_.push_back(std::move(request));
  wake_locked();
}

void GuiService::answer(const ConsoleRequest& request, const ConsoleAnswer& answer) {
  if (!request.parameters) {
    channels_->console_reply(0, answer.accepted, answer.reason, request.client);
    return;
  }
  if (answer.accepted) {
    // The run has them now; its next status says so again.
    std::vector<foxglove::Parameter> values;
    for (std::size_t i = 0; i + 1 < request.args.size(); i += 2) {
      values.push_back({std::string(kVisionPrefix) + request.args[i], std::stod(request.args[i + 1])});
    }
    server_->set_parameters(std::move(values));
  } else {
    server_->tell(request.client, foxglove::Level::kError, "vision settings refused: " + answer.reason);
  }
  server_->answer_parameters(request.client, *request.parameters, request.parameters_id);
}

void GuiService::on_client_gone(const std::string& client) {
  std::lock_guard lock(mutex_);
  bool any = false;
  for (auto& [id, hold] : holds_) {
    if (hold.client == client) any = hold.ending = true;
  }
  if (any) wake_locked();
}

// ------------------------------------------------------------------ to the run

void GuiService::loop() {
  std::unique_lock lock(mutex_);
  for (;;) {
    const auto woken = [this] { return wake_pending_; };
    if (drive_.clock) {
      wake_.wait(lock, woken);  // a clock of its own: no tick by the wall's
    } else {
      wake_.wait_for(lock, std::chrono::milliseconds(drive_.tick_ms), woken);
    }
    wake_pending_ = false;
    // Driving first: a stop must not wait behind console commands.
    const std::uint64_t asked = ticks_asked_;
    drive_tick(lock);
    ticks_done_ = std::max(ticks_done_, asked);
    ticked_.notify_all();
    if (stopping_ && holds_.empty()) return;
    while (!requests_.empty() && !stopping_) {
      ConsoleRequest request = std::move(requests_.front());
      requests_.pop_front();
      ++counts_.console_commands;
      lock.unlock();
      answer(request, sink_(request));
      lock.lock();
      drive_tick(lock);
    }
  }
}

void GuiService::tick() {
  std::unique_lock lock(mutex_);
  const std::uint64_t wanted = ++ticks_asked_;
  wake_locked();
  ticked_.wait(lock, [&] { return ticks_done_ >= wanted || stopping_; });
}

void GuiService::drive_tick(std::unique_lock<std::mutex>& lock) {
  const auto now = this->now();
  const double hold_s = drive_.hold_wall_s * std::max(1.0, rt_factor_);
  // A third: a renewal may come a whole third late (a busy machine) before the hold lapses.
  const auto renew_after = std::chrono::duration<double>(drive_.hold_wall_s / 3);
  // What to send, chosen under the lock, sent without it.
  struct Order {
    int robot;
    std::string client;
    int left, right;
    bool final_stop;
  };
  std::vector<Order> orders;
  for (auto it = holds_.begin(); it != holds_.end();) {
    Hold& hold = it->second;
    if (hold.ending) {
      orders.push_back({it->first, hold.client, 0, 0, true});
      it = holds_.erase(it);
      continue;
    }
    const bool keys_alive = now - hold.last_key <= std::chrono::milliseconds(drive_.key_timeout_ms);
    const std::pair<int, int> wheels = keys_alive ? std::pair{hold.left, hold.right} : std::pair{0, 0};
    if (!hold.sent || *hold.sent != wheels || now - hold.sent_at >= renew_after) {
      hold.sent = wheels;
      hold.sent_at = now;
      orders.push_back({it->first, hold.client, wheels.first, wheels.second, false});
    }
    ++it;
  }
  if (orders.empty()) return;
  lock.unlock();
  std::vector<std::pair<int, ConsoleAnswer>> refusals;
  for (const Order& o : orders) {
    const ConsoleAnswer answer =
        sink_({o.client,
               "drive",
               {std::to_string(o.robot), std::to_string(o.left), std::to_string(o.right), seconds_text(hold_s)},
               std::nullopt,
               std::nullopt});
    if (!answer.accepted) refusals.emplace_back(o.robot, answer);
    if (o.final_stop)
      channels_->console_reply(0, answer.accepted,
                               "robot " + std::to_string(o.robot) + " stopped and given back to its controller",
                               o.client);
  }
  lock.lock();
  counts_.drive_commands += orders.size();
  for (const Order& o : orders) counts_.drive_stops += o.final_stop ? 1 : 0;
  // A refusal (a paused run, no such robot) is told to its driver once, not every tick.
  for (const auto& [robot, answer] : refusals) {
    const auto it = holds_.find(robot);
    if (it == holds_.end() || it->second.last_refusal == answer.reason) continue;
    it->second.last_refusal = answer.reason;
    channels_->console_reply(0, false, "drive robot " + std::to_string(robot) + ": " + answer.reason,
                             it->second.client);
  }
}

// ------------------------------------------------------------------ the run's reports

bool GuiService::wants_steps() const { return server_->clients() > 0; }

void GuiService::on_world(TimeUs t_us, const run::WorldReport& world) { channels_->on_world(t_us, world); }
void GuiService::on_poses(TimeUs t_us, std::span<const run::PoseReport> poses) { channels_->on_poses(t_us, poses); }
void GuiService::on_wheels(TimeUs t_us, std::span<const run::WheelReport> wheels) {
  channels_->on_wheels(t_us, wheels);
}
void GuiService::on_sensors(TimeUs t_us, std::span<const run::SensorReport> sensors) {
  channels_->on_sensors(t_us, sensors);
}
void GuiService::on_detections(const run::FrameReport& frame) { channels_->on_detections(frame); }
void GuiService::on_frame_jpeg(TimeUs t_us, std::int64_t, int, int, std::span<const std::uint8_t> jpeg) {
  if (server_->clients() == 0) return;
  const auto now = Clock::now();
  if (now < next_camera_frame_) return;
  next_camera_frame_ = now + std::chrono::microseconds(static_cast<long>(1e6 / kMaxCameraFps));
  channels_->camera_frame(t_us, jpeg);
}
void GuiService::on_event(const run::RunEvent& event) { channels_->on_event(event); }
void GuiService::on_status(const run::StatusReport& status) {
  {
    std::lock_guard lock(mutex_);
    if (status.rt_factor > 0.0 && std::isfinite(status.rt_factor)) rt_factor_ = status.rt_factor;
  }
  if (status.vision || had_vision_) {
    std::vector<foxglove::Parameter> values;
    for (const std::string_view name : vision::kVisionSettingNames) {
      nlohmann::json value;  // null: gone with the camera
      if (status.vision) value = *vision::vision_setting(*status.vision, name);
      values.push_back({std::string(kVisionPrefix) + std::string(name), std::move(value)});
    }
    server_->set_parameters(std::move(values));
    had_vision_ = status.vision.has_value();
  }
  channels_->on_status(status);
}
void GuiService::on_summary(TimeUs t_us, const nlohmann::json& summary) { channels_->on_summary(t_us, summary); }

}  // namespace rilbed::gui_web

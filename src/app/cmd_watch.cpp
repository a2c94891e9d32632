// `rilbed watch --lcm URL`: a terminal display of a run on an LCM bus: its status once per
// simulated second with every robot's behaviour and health, and its events as they come.
// It only listens: any number may join and leave at any time without any effect on the
// run. It says so when no run is heard on the URL.
#include <signal.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/commands.hpp"
#include "app/interrupt.hpp"
#include "bus/lcm_bus.hpp"
#include "bus/report_decoder.hpp"

namespace rilbed::app {

namespace {

struct WatchArgs {
  std::string url;
  std::string prefix;
  double for_s = 0.0;        // 0: until interrupted
  bool until_ended = false;  // end when the run does
  double silence_s = 2.0;    // say so when nothing is heard this long
};

// What the watcher knows of the run, kept from the messages (decoded, and checked, by
// links::RunReportDecoder: a corrupt or hostile message is refused, never decoded blindly).
class Watcher final : public run::RunObserver {
 public:
  explicit Watcher(const WatchArgs& args) : args_(args) {}

  void on_world(TimeUs, const run::WorldReport& w) override {
    heard();
    if (world_scenario_ != w.scenario) {
      world_scenario_ = w.scenario;
      std::printf("watching %s on %s: %zu robots (%zu real), field %.2f x %.2f m\n", w.scenario.c_str(),
                  args_.url.c_str(), w.robot_ids.size(), w.field.real_robot_ids.size(), w.field.width_m,
                  w.field.height_m);
      std::fflush(stdout);
    }
  }
  void on_poses(TimeUs, std::span<const run::PoseReport> poses) override {
    heard();
    robots_.clear();
    for (const run::PoseReport& p : poses) {
      std::string text = std::to_string(p.id) + ":" + std::string(p.behaviour);
      if (p.health != "ok") text += "(" + std::string(p.health) + ")";
      robots_.push_back(std::move(text));
    }
  }
  void on_event(const run::RunEvent& e) override {
    heard();
    if (e.kind == "behaviour" || e.kind == "collision") return;  // too many to read; the status line shows them
    std::printf("  %7.1fs  %s", us_to_seconds(e.t_us), e.kind.c_str());
    if (e.id != 0) std::printf(" robot %d", e.id);
    std::printf(": %s\n", e.detail.c_str());
    std::fflush(stdout);
  }
  void on_status(const run::StatusReport& s) override {
    heard();
    // The same status again (a paused run, or the end, is published more than once).
    if (last_status_ && last_status_->first == s.t_us && last_status_->second == s.state) return;
    last_status_ = std::make_pair(s.t_us, s.state);
    std::string line = "t=" + one_decimal(us_to_seconds(s.t_us)) + "s " + s.state;
    if (s.realtime) line += " x" + one_decimal(s.rt_factor);
    for (const std::string& r : robots_) line += "  " + r;
    if (s.formed && s.formation_time_s) line += "  [formed at " + one_decimal(*s.formation_time_s) + " s]";
    // How the loop keeps up: behind the wall clock by a millisecond or more, the camera's rate.
    if (s.realtime && s.loop_latency_ms >= 1.0) line += "  [loop " + one_decimal(s.loop_latency_ms) + " ms late]";
    if (s.frames > 0) line += "  [camera " + one_decimal(s.camera_fps) + " fps]";
    if (s.state == "ended") line += "  (ended by " + s.ended_by + ")";
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
    // A reset run starts over: the watcher stays for the run that follows.
    if (s.state == "ended" && s.ended_by != "reset") {
      ended_ = true;
      unheard_end_.reset();
    }
  }

  void on_summary(TimeUs, const nlohmann::json& summary) override {
    heard();
    const std::string ended_by = summary.value("ended_by", std::string("?"));
    if (ended_ || ended_by == "reset" || unheard_end_) return;
    // The run's last status was lost on the way, or is still to come: the run sends the
    // end's status and summary three times each, interleaved, so a later copy of the
    // status may follow. Wait a moment for it before saying it was not heard.
    unheard_end_ = UnheardEnd{ended_by, std::chrono::steady_clock::now() + kLateStatusWait};
  }
  /// Once the wait for a late ended status is over: says the run ended without it.
  void check_unheard_end(std::chrono::steady_clock::time_point now) {
    if (!unheard_end_ || now < unheard_end_->give_up) return;
    std::printf("run ended (ended by %s; its last status was not heard)\n", unheard_end_->ended_by.c_str());
    std::fflush(stdout);
    unheard_end_.reset();
    ended_ = true;
  }

  // A message as it came off the bus.
  void on_message(const std::string& channel, const void* data, std::size_t size) {
    if (const auto problem = decoder_->decode(channel, data, size)) {
      if (++bad_messages_ <= 5) spdlog::warn("watch: {} (skipped)", *problem);
    }
  }
  void set_decoder(bus::RunReportDecoder* decoder) { decoder_ = decoder; }

  bool ended() const { return ended_; }
  bool heard_anything() const { return heard_anything_; }
  /// Says once when the bus has been silent for the silence time.
  void check_silence(std::chrono::steady_clock::time_point now) {
    if (silent_reported_ || now - last_heard_ < std::chrono::duration<double>(args_.silence_s)) return;
    silent_reported_ = true;
    std::printf("no rilbed run heard on %s for %.0f s (channels %sRILBED_*)%s\n", args_.url.c_str(), args_.silence_s,
                args_.prefix.c_str(),
                heard_anything_ && !ended_ ? ": the run went silent before its end was heard" : "");
    std::fflush(stdout);
  }

 private:
  static std::string one_decimal(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f", v);
    return buf;
  }
  void heard() {
    heard_anything_ = true;
    last_heard_ = std::chrono::steady_clock::now();
    silent_reported_ = false;
  }

  const WatchArgs& args_;
  bus::RunReportDecoder* decoder_ = nullptr;
  std::string world_scenario_;
  std::vector<std::string> robots_;
  std::optional<std::pair<TimeUs, std::string>> last_status_;  // time and state of the last shown
  bool ended_ = false;
  // A summary came before any ended status: the end as the summary tells it, and when to
  // stop waiting for a late copy of the status.
  struct UnheardEnd {
    std::string ended_by;
    std::chrono::steady_clock::time_point give_up;
  };
  static constexpr std::chrono::milliseconds kLateStatusWait{500};
  std::optional<UnheardEnd> unheard_end_;
  bool heard_anything_ = false;
  bool silent_reported_ = false;
  long bad_messages_ = 0;
  std::chrono::steady_clock::time_point last_heard_ = std::chrono::steady_clock::now();
};

int watch_command(const WatchArgs& args) {
  if (const auto problem = bus::check_channel_prefix(args.prefix)) {
    spdlog::error("watch: {}", *problem);
    return kExitUsage;
  }
  std::string error;
  std::unique_ptr<lcm::LCM> lcm = bus::open_lcm(args.url, error);
  if (!lcm) {
    spdlog::error("watch: {}", error);
    return kExitFailure;
  }
  const bus::Channels channels = bus::Channels::with_prefix(args.prefix);
  Watcher watcher(args);
  bus::RunReportDecoder decoder(channels, watcher);
  watcher.set_decoder(&decoder);
  // Raw bytes, decoded by the checked decoder.
  std::vector<std::unique_ptr<bus::LcmSubscription>> subscriptions;
  for (const std::string* channel :
       {&channels.world, &channels.poses, &channels.events, &channels.status, &channels.summary}) {
    subscriptions.push_back(std::make_unique<bus::LcmSubscription>(
        *lcm, *channel,
        [&watcher](const std::string& c, const void* data, std::size_t size) { watcher.on_message(c, data, size); }));
  }
  const InterruptFlag interrupt;
  const auto start = std::chrono::steady_clock::now();
  while (!interrupt.raised()) {
    const int handled = lcm->handleTimeout(100);
    if (handled < 0 && interrupt.raised()) break;  // Ctrl-C while waiting: not a failure
    if (handled < 0) {
      spdlog::error("watch: reading the LCM bus {} failed", args.url);
      return kExitFailure;
    }
    const auto now = std::chrono::steady_clock::now();
    watcher.check_silence(now);
    watcher.check_unheard_end(now);
    if (args.until_ended && watcher.ended()) break;
    if (args.for_s > 0.0 && now - start >= std::chrono::duration<double>(args.for_s)) break;
  }
  return watcher.heard_anything() ? 0 : kExitFailure;
}

}  // namespace

void add_watch_command(CLI::App& app) {
  auto args = std::make_shared<WatchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "watch", "Show a run on an LCM bus: its status each second, every robot's behaviour and health, its events");
  cmd->add_option("--lcm", args->url, "LCM URL of the run's bus (e.g. udpm://239.255.76.67:7667?ttl=0)")->required();
  cmd->add_option("--channel-prefix", args->prefix, "The run's channel prefix (rilbed run --channel-prefix)");
  cmd->add_option("--for", args->for_s, "Stop after this many seconds (default: until Ctrl-C)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--until-ended", args->until_ended, "Stop when the run ends");
  cmd->add_option("--silence", args->silence_s, "Say so when nothing is heard for this many seconds")
      ->check(CLI::PositiveNumber)
      ->default_val(2.0);
  cmd->callback([args] { exit_code() = watch_command(*args); });
}

}  // namespace rilbed::app

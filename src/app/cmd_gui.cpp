// `rilbed gui --lcm URL`: the web control panel's server for any run (or `rilbed replay`)
// that publishes on URL. It subscribes to the run's channels and serves them over the
// Foxglove WebSocket protocol (src/gui_web), and sends the console commands that browsers
// publish on /rilbed/console ({"command": "pause", "args": []}) to the run over LCM, with
// the run's token; the run's answers go back on /rilbed/console_reply.
#include <spdlog/spdlog.h>

#include <atomic>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "agents/builtin_controllers.hpp"
#include "app/commands.hpp"
#include "app/interrupt.hpp"
#include "app/panel_options.hpp"
#include "bus/lcm_bus.hpp"
#include "bus/lcm_console.hpp"
#include "bus/report_decoder.hpp"
#include "gui_web/gui_service.hpp"

namespace rilbed::app {

namespace {

struct GuiArgs {
  std::string url;
  std::string prefix;
  std::string run_token;  // the run's console token (default: its token file)
  session::PanelOptions panel;
};

// The console sink of `rilbed gui`: each command goes to the run over LCM with the run's
// token, and waits (up to a second, resending) for its answer. Called on the GUI service's
// thread only, which owns this LCM instance.
gui_web::ConsoleSink lcm_console_sink(const GuiArgs& args) {
  auto lcm = std::shared_ptr<lcm::LCM>();
  return [&args, lcm](const gui_web::ConsoleRequest& request) mutable -> gui_web::ConsoleAnswer {
    std::string error;
    if (!lcm) lcm = bus::open_lcm(args.url, error);
    if (!lcm) return {false, "cannot reach the bus " + args.url + ": " + error};
    std::string token = args.run_token;
    if (token.empty()) token = bus::read_token(bus::token_path(args.prefix)).value_or("");
    const auto reply = bus::send_console_command(*lcm, bus::Channels::with_prefix(args.prefix), token, request.command,
                                                 request.args, 1000, 200, request.client);
    if (!reply) return {false, "no run answered on " + args.url + " within a second"};
    return {reply->accepted != 0, reply->reason};
  };
}

int gui_command(const GuiArgs& args) {
  if (const auto problem = bus::check_channel_prefix(args.prefix)) {
    spdlog::error("gui: {}", *problem);
    return kExitUsage;
  }
  if (const auto problem = session::check_panel_options(args.panel)) {
    spdlog::error("gui: {}", *problem);
    return kExitUsage;
  }
  if (args.url.rfind("memq://", 0) == 0) {
    spdlog::error(
        "gui: memq:// is a bus inside one process, and no run can be heard on it from here: give the run's "
        "URL (rilbed run --lcm 'udpm://239.255.76.67:7667?ttl=0')");
    return kExitUsage;
  }
  std::string error;
  std::unique_ptr<lcm::LCM> lcm = bus::open_lcm(args.url, error);
  if (!lcm) {
    spdlog::error("gui: {}", error);
    return kExitFailure;
  }
  // The panel's own token: the run's stays with the run (it goes only into console commands).
  std::unique_ptr<gui_web::GuiService> gui =
      session::start_panel(args.panel, "", lcm_console_sink(args), *agents::default_controllers());
  if (!gui) return kExitFailure;
  const bus::Channels run_channels = bus::Channels::with_prefix(args.prefix);
  bus::RunReportDecoder decoder(run_channels, *gui);
  std::vector<std::unique_ptr<bus::LcmSubscription>> subscriptions;
  long bad = 0;
  for (const std::string* c :
       {&run_channels.world, &run_channels.poses, &run_channels.events, &run_channels.status, &run_channels.summary,
        &run_channels.wheels, &run_channels.sensors, &run_channels.detections, &run_channels.camera,
        &run_channels.frames, &run_channels.sensor_layout, &run_channels.robot_bodies, &run_channels.sensor_models,
        &run_channels.vision}) {
    subscriptions.push_back(
        std::make_unique<bus::LcmSubscription>(*lcm, *c, [&](const std::string& ch, const void* d, std::size_t n) {
          if (const auto problem = decoder.decode(ch, d, n)) {
            if (++bad <= 5) spdlog::warn("gui: {} (skipped)", *problem);
          }
        }));
  }
  std::printf("rilbed gui: %s (the run on %s)\n", gui->url().c_str(), args.url.c_str());
  std::fflush(stdout);
  const InterruptFlag interrupt;
  while (!interrupt.raised()) {
    if (lcm->handleTimeout(100) < 0 && !interrupt.raised()) {
      spdlog::error("gui: reading the LCM bus {} failed", args.url);
      return kExitFailure;
    }
  }
  return 0;
}

}  // namespace

void add_gui_command(CLI::App& app) {
  auto args = std::make_shared<GuiArgs>();
  CLI::App* cmd =
      app.add_subcommand("gui", "Serve the web control panel (Foxglove WebSocket protocol) for a run on an LCM bus");
  cmd->add_option("--lcm", args->url, "LCM URL of the run's bus (e.g. udpm://239.255.76.67:7667?ttl=0)")->required();
  cmd->add_option("--channel-prefix", args->prefix, "The run's channel prefix");
  cmd->add_option("--token", args->run_token, "The run's console token (default: from the run's token file)");
  add_panel_options(*cmd, args->panel);
  cmd->callback([args] { exit_code() = gui_command(*args); });
}

}  // namespace rilbed::app

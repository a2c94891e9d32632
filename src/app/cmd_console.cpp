// `rilbed console --lcm URL COMMAND`: steers a running run over its LCM bus: pause,
// resume, exit, reset, rt-factor F, mode central|distributed, drive ID LEFT RIGHT --for S,
// vision NAME VALUE... (the camera's vision settings).
// Every command carries the run's token (from --token, or the run's token file when this
// user can read it) and gets an answer; the exit status is 0
// when the run accepted it, 1 when it refused it (the reason is printed) or no run
// answered within the timeout.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/commands.hpp"
#include "bus/lcm_bus.hpp"
#include "bus/lcm_console.hpp"

namespace rilbed::app {

namespace {

struct ConsoleArgs {
  std::string url;
  std::string prefix;
  std::string token;
  int timeout_ms = 1000;
  std::vector<std::string> words;  // the command and its arguments
  std::optional<double> for_s;     // drive: for how long
};

int console_command(const ConsoleArgs& args) {
  if (const auto problem = bus::check_channel_prefix(args.prefix)) {
    spdlog::error("console: {}", *problem);
    return kExitUsage;
  }
  std::string token = args.token;
  if (token.empty()) {
    const auto path = bus::token_path(args.prefix);
    if (const auto from_file = bus::read_token(path)) token = *from_file;
  }
  std::string error;
  std::unique_ptr<lcm::LCM> lcm = bus::open_lcm(args.url, error);
  if (!lcm) {
    spdlog::error("console: {}", error);
    return kExitFailure;
  }
  std::vector<std::string> rest(args.words.begin() + 1, args.words.end());
  if (args.words.front() == "drive") {
    // drive ID LEFT RIGHT --for S: the seconds travel as the fourth argument.
    if (rest.size() != 3 || !args.for_s) {
      spdlog::error("console: drive takes ID LEFT RIGHT and --for SECONDS (e.g. drive 3 40 40 --for 2)");
      return kExitUsage;
    }
    rest.push_back(fmt::format("{}", *args.for_s));
  } else if (args.for_s) {
    spdlog::error("console: --for goes with drive only");
    return kExitUsage;
  }
  const auto reply = bus::send_console_command(*lcm, bus::Channels::with_prefix(args.prefix), token, args.words.front(),
                                               rest, args.timeout_ms);
  if (!reply) {
    std::fprintf(stderr, "rilbed console: no run answered on %s within %d ms (channel %sRILBED_CONSOLE)\n",
                 args.url.c_str(), args.timeout_ms, args.prefix.c_str());
    return kExitFailure;
  }
  if (!reply->accepted) {
    std::fprintf(stderr, "rilbed console: refused: %s\n", reply->reason.c_str());
    return kExitFailure;
  }
  std::printf("accepted: %s\n", reply->reason.c_str());
  return 0;
}

}  // namespace

void add_console_command(CLI::App& app) {
  auto args = std::make_shared<ConsoleArgs>();
  CLI::App* cmd = app.add_subcommand(
      "console",
      "Steer a running run over its LCM bus: pause | resume | exit | reset | rt-factor F | mode | drive | "
      "vision (needs the run's token)");
  cmd->add_option("--lcm", args->url, "LCM URL of the run's bus")->required();
  cmd->add_option("--channel-prefix", args->prefix, "The run's channel prefix");
  cmd->add_option("--token", args->token, "The run's token (default: from the run's token file, if you can read it)");
  cmd->add_option("--timeout-ms", args->timeout_ms, "How long to wait for the run's answer")
      ->check(CLI::PositiveNumber)
      ->default_val(1000);
  cmd->add_option(
         "command", args->words,
         "pause | resume | exit | reset | rt-factor F | mode central|distributed | drive ID LEFT RIGHT --for S "
         "(wheel speeds in Khepera units, -127..127, 8 mm/s each) | vision NAME VALUE [NAME VALUE]... "
         "(brightness -128..128, contrast 0.2..5, threshold 1..255, min_diameter_px and max_diameter_px "
         "6..4000, min_score 0..1)")
      ->required()
      ->expected(1, 13);
  cmd->add_option("--for", args->for_s, "With drive: seconds (simulated) to drive, then the robot's controller again")
      ->check(CLI::PositiveNumber);
  cmd->callback([args] { exit_code() = console_command(*args); });
}

}  // namespace rilbed::app

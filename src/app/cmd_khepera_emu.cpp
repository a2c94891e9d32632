// `rilbed khepera-emu`: an emulated Khepera (or e-puck) on a pseudo-terminal, for trying
// `rilbed khepera` and real-robot runs without a robot. Prints the device to open as its
// first line, serves until SIGINT/SIGTERM, then prints what the robot was last told.
#include <signal.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>

#include "app/commands.hpp"
#include "serial/khepera_emulator.hpp"

namespace rilbed::app {

namespace {

struct EmulatorArgs {
  std::string model = "khepera2";
  int delay_ms = 0;
  double drop = 0.0;
  double garbage = 0.0;
  double corrupt = 0.0;
  double disconnect_after_s = 0.0;
  double replug_after_s = 0.0;
  std::string pose = "0,0,0";
  std::string stable_path;
  std::uint64_t seed = 1;
  // How the firmware words its replies (ReplyStyle), and its versions text.
  std::string versions;
  bool upper_case = false;
  std::string line_end = "crlf";
  std::string extra_fields;
  int trailing_spaces = 0;
  bool spaces_after_commas = false;
  bool echo = false;
};

// `--versions TEXT`: for a Khepera the text after "b," (its first field the BIOS, the
// second the protocol version), for an e-puck the text after "v,"; read as the link reads
// the reply that carries it.
serial::FirmwareVersions versions_from_text(const serial::RobotModel& model, const std::string& text) {
  const std::string reply = std::string(1, model.reply_letter(serial::CommandKind::kReadVersions)) + "," + text;
  const serial::Result<serial::Reply> decoded = serial::decode_reply(model, serial::CommandKind::kReadVersions, reply);
  return decoded.ok() ? decoded->versions : serial::FirmwareVersions{text, "", text};
}

// "x,y,theta_deg" (metres, metres, degrees).
std::optional<Pose2> parse_pose(const std::string& text) {
  std::istringstream in(text);
  double x = 0, y = 0, theta_deg = 0;
  char comma1 = 0, comma2 = 0;
  if (!(in >> x >> comma1 >> y >> comma2 >> theta_deg) || comma1 != ',' || comma2 != ',') return std::nullopt;
  in >> std::ws;
  if (!in.eof() || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(theta_deg)) return std::nullopt;
  return Pose2{{x, y}, deg_to_rad(theta_deg)};
}

int emulator_command(const EmulatorArgs& args) {
  const serial::RobotModel* model = serial::find_robot_model(args.model);
  const std::optional<Pose2> pose = parse_pose(args.pose);
  if (model == nullptr || !pose) {
    spdlog::error("khepera-emu: {}", model == nullptr ? "unknown model '" + args.model + "'"
                                                      : "--pose '" + args.pose + "' is not x,y,theta_deg");
    return kExitUsage;
  }
  serial::EmulatorConfig config;
  config.model = *model;
  config.initial_pose = *pose;
  config.seed = args.seed;
  config.stable_path = args.stable_path;
  config.faults.reply_delay_ms = args.delay_ms;
  config.faults.drop_probability = args.drop;
  config.faults.garbage_probability = args.garbage;
  config.faults.corrupt_probability = args.corrupt;
  config.faults.disconnect_after_s = args.disconnect_after_s;
  config.faults.replug_after_s = args.replug_after_s;
  if (!args.versions.empty()) config.versions = versions_from_text(*model, args.versions);
  config.style.upper_case_letter = args.upper_case;
  config.style.line_end = args.line_end == "lf" ? "\n" : args.line_end == "cr" ? "\r" : "\r\n";
  config.style.extra_fields = args.extra_fields;
  config.style.trailing_spaces = args.trailing_spaces;
  config.style.spaces_after_commas = args.spaces_after_commas;
  config.style.echo = args.echo;

  // Blocked before the emulator's thread exists (it inherits the mask); the main thread
  // takes them with sigwait.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  ::pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  std::unique_ptr<serial::KheperaEmulator> emulator;
  try {
    emulator = std::make_unique<serial::KheperaEmulator>(config);
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return kExitUsage;
  } catch (const std::system_error& e) {
    spdlog::error("{}", e.what());
    return kExitFailure;
  }
  std::printf("%s\n", emulator->device_path().c_str());
  std::fflush(stdout);
  spdlog::info("emulated {} on {} (until SIGINT or SIGTERM)", args.model, emulator->slave_path());

  int signal = 0;
  while (::sigwait(&signals, &signal) != 0) {}
  const serial::WheelSpeeds last = emulator->last_speeds();
  const Pose2 final_pose = emulator->true_pose();
  const environment::OdometryReading counters = emulator->counters();
  std::printf("last speed %d %d\n", last.left_units, last.right_units);
  std::printf("pose %.4f %.4f %.2f\n", final_pose.position_m.x, final_pose.position_m.y,
              rad_to_deg(final_pose.heading_rad));
  std::printf("counters %lld %lld\n", static_cast<long long>(counters.left_pulses),
              static_cast<long long>(counters.right_pulses));
  std::printf("commands %llu speeds, %llu bad\n",
              static_cast<unsigned long long>(emulator->commands_received(serial::CommandKind::kSetSpeeds)),
              static_cast<unsigned long long>(emulator->bad_commands()));
  std::fflush(stdout);
  return 0;
}

}  // namespace

void add_khepera_emu_command(CLI::App& app) {
  auto args = std::make_shared<EmulatorArgs>();
  CLI::App* cmd =
      app.add_subcommand("khepera-emu",
                         "Emulate a Khepera on a pseudo-terminal: prints the device path, serves until SIGINT/SIGTERM, "
                         "then prints the last commanded speeds");
  cmd->add_option("--model", args->model, "Robot model")
      ->check(CLI::IsMember({"khepera2", "epuck"}))
      ->default_val("khepera2");
  cmd->add_option("--delay-ms", args->delay_ms, "Delay every reply by this many milliseconds")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--drop", args->drop, "Probability that a reply is not sent")->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--garbage", args->garbage, "Probability of random bytes before a reply")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--corrupt", args->corrupt, "Probability that a reply is corrupted (letter, field count, number)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--disconnect-after", args->disconnect_after_s, "Unplug after this many seconds")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--replug-after", args->replug_after_s,
                  "Plug back in this many seconds after an unplug (with --link the path stays the same)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--pose", args->pose, "Initial true pose x,y,theta_deg (metres, degrees)")->default_val("0,0,0");
  cmd->add_option("--link", args->stable_path,
                  "Keep a symlink here to the current pty (survives a replug; printed instead of the pty)");
  cmd->add_option("--seed", args->seed, "Seed of the fault dice")->default_val(1);
  // Firmware that words its replies differently (other BIOS versions, independent peers).
  cmd->add_option(
      "--versions", args->versions,
      "What the versions reply carries after its letter (Khepera: BIOS,protocol, any text, e.g. 5.02,5.01)");
  cmd->add_flag("--upper-case", args->upper_case, "Reply letters in upper case (N,... instead of n,...)");
  cmd->add_option("--line-end", args->line_end, "What ends a reply")
      ->check(CLI::IsMember({"crlf", "lf", "cr"}))
      ->default_val("crlf");
  cmd->add_option("--extra-fields", args->extra_fields, "Text appended to every reply's fields (e.g. ,0,ok)");
  cmd->add_option("--trailing-spaces", args->trailing_spaces, "Spaces before each reply's line end")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--spaces-after-commas", args->spaces_after_commas, "A space after every comma of a reply");
  cmd->add_flag("--echo", args->echo, "Echo every command line before its reply");
  cmd->callback([args] { exit_code() = emulator_command(*args); });
}

}  // namespace rilbed::app

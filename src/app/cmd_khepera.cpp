// `rilbed khepera --port DEV [--baud B] [--model khepera2|epuck] info|drive`: one real (or
// emulated) robot over its serial link: print its versions and sensors, or drive it for a
// while and stop it. Whatever goes wrong, a stop is sent if the line allows.
#include <signal.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>

#include "app/commands.hpp"
#include "serial/khepera_link.hpp"

namespace rilbed::app {

namespace {

struct KheperaArgs {
  std::string port;
  unsigned baud = 0;
  std::string model = "khepera2";
  int timeout_ms = 250;
  int retries = 3;
  bool verbose = false;
  int left_units = 0;
  int right_units = 0;
  double drive_s = 1.0;
};

/// Exit status when a drive was interrupted by SIGINT/SIGTERM (the robot was stopped).
constexpr int kExitInterrupted = 130;

serial::LinkConfig link_config(const KheperaArgs& args, const serial::RobotModel& model) {
  serial::LinkConfig config;
  config.port = args.port;
  config.baud = args.baud;
  config.model = model;
  config.reply_timeout_ms = args.timeout_ms;
  config.retries = args.retries;
  const bool verbose = args.verbose;
  // Retries and clamps are worth a warning; a failure is reported once, by the command
  // itself (with what it means for the robot), so the link's own error line is only shown
  // with --verbose, as is the chatter.
  config.log = [verbose](serial::LogLevel level, const std::string& message) {
    if (level == serial::LogLevel::kWarning) {
      spdlog::warn("{}", message);
    } else if (verbose) {
      spdlog::info("{}", message);
    }
  };
  return config;
}

// SIGINT and SIGTERM are blocked in every thread (the link's thread inherits the mask)
// and taken with sigtimedwait by the main thread, so that an interrupt is a plain event
// in the drive loop rather than a handler racing the link.
sigset_t termination_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  return set;
}

// Waits up to `wait` for SIGINT or SIGTERM; returns the signal or 0.
int wait_for_signal(std::chrono::milliseconds wait) {
  const sigset_t set = termination_signals();
  timespec timeout{};
  timeout.tv_sec = static_cast<time_t>(wait.count() / 1000);
  timeout.tv_nsec = static_cast<long>((wait.count() % 1000) * 1'000'000);
  const int signal = ::sigtimedwait(&set, nullptr, &timeout);
  return signal > 0 ? signal : 0;
}

std::string join_values(const environment::ProximityValues& values) {
  std::string text;
  for (const int v : values) text += (text.empty() ? "" : " ") + std::to_string(v);
  return text;
}

// How long a query may wait: its own budget, after a safety stop's that may be ahead of it.
std::chrono::milliseconds query_timeout(const serial::KheperaLink& link) {
  return std::chrono::milliseconds(2 * link.command_budget_ms() + 200);
}

// Waits for the link's handshake (it reads the versions on opening): true once the robot
// answered; false, with the reason logged, when it could not.
bool wait_for_handshake(const serial::KheperaLink& link) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(link.command_budget_ms() + 500);
  while (std::chrono::steady_clock::now() < deadline) {
    const serial::LinkState state = link.state();
    if (state == serial::LinkState::kOk && link.versions()) return true;
    if (state == serial::LinkState::kUnresponsive || state == serial::LinkState::kLost) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const serial::LinkStatus status = link.status();
  spdlog::error(
      "{}", status.last_error.empty() ? "khepera " + link.port() + ": no reply to the handshake" : status.last_error);
  return false;
}

int info_command(serial::KheperaLink& link) {
  const auto budget = query_timeout(link);
  if (!wait_for_handshake(link)) return kExitFailure;
  const serial::FirmwareVersions versions = *link.versions();
  const auto proximity = link.query(serial::Command::read_proximity(), budget);
  if (!proximity) {
    spdlog::error("{}", proximity.error());
    return kExitFailure;
  }
  const auto counters = link.query(serial::Command::read_counters(), budget);
  if (!counters) {
    spdlog::error("{}", counters.error());
    return kExitFailure;
  }
  const serial::LinkConfig& config = link.config();
  std::printf("port %s: %s at %u baud\n", config.port.c_str(), std::string(config.model.name).c_str(), config.baud);
  std::printf("versions: %s\n", versions.text.c_str());
  std::printf("proximity: %s\n", join_values(proximity->sensors).c_str());
  std::printf("counters: left %lld right %lld pulses\n", static_cast<long long>(counters->wheels.left),
              static_cast<long long>(counters->wheels.right));
  return 0;
}

int drive_command(serial::KheperaLink& link, const KheperaArgs& args) {
  const auto budget = query_timeout(link);
  if (!wait_for_handshake(link)) return kExitFailure;
  const auto go = link.query(serial::Command::set_speeds(args.left_units, args.right_units), budget);
  if (!go) {
    spdlog::error("{}", go.error());
    return kExitFailure;
  }
  std::printf("driving %d %d for %.2f s\n", args.left_units, args.right_units, args.drive_s);
  std::fflush(stdout);
  const auto started = std::chrono::steady_clock::now();
  const auto end = started + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                 std::chrono::duration<double>(args.drive_s));
  int signal = 0;
  bool lost = false;
  while (std::chrono::steady_clock::now() < end) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(end - std::chrono::steady_clock::now());
    signal = wait_for_signal(std::min(left, std::chrono::milliseconds(100)));
    if (signal != 0) break;
    if (link.state() == serial::LinkState::kLost) {
      lost = true;
      break;
    }
  }
  const double drove_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (lost) {
    spdlog::error("{}; cannot send a stop", link.status().last_error);
    return kExitFailure;
  }
  // The stop, confirmed, then the counters; stop() sends D,0,0 once more on the way out.
  const auto stop = link.query(serial::Command::set_speeds(0, 0), budget);
  if (!stop) {
    spdlog::error("{} (the robot may still be moving)", stop.error());
    return kExitFailure;
  }
  const auto counters = link.query(serial::Command::read_counters(), budget);
  if (signal != 0) {
    std::printf("interrupted after %.2f s; stopped\n", drove_s);
  } else {
    std::printf("drove %d %d for %.2f s; stopped\n", args.left_units, args.right_units, drove_s);
  }
  if (counters) {
    std::printf("counters: left %lld right %lld pulses\n", static_cast<long long>(counters->wheels.left),
                static_cast<long long>(counters->wheels.right));
  } else {
    spdlog::warn("counters not read: {}", counters.error());
  }
  return signal != 0 ? kExitInterrupted : 0;
}

enum class Action { kInfo, kDrive };

int khepera_command(const KheperaArgs& args, Action action) {
  const serial::RobotModel* model = serial::find_robot_model(args.model);
  if (model == nullptr) {
    spdlog::error("khepera {}: unknown robot model '{}'", args.port, args.model);
    return kExitUsage;
  }
  std::unique_ptr<serial::KheperaLink> link;
  try {
    link = std::make_unique<serial::KheperaLink>(link_config(args, *model));
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return kExitUsage;
  }
  // Before the link's thread exists, so that it inherits the mask.
  const sigset_t signals = termination_signals();
  ::pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  if (const auto failure = link->start()) {
    spdlog::error("{}", *failure);
    link->stop(0);
    return kExitFailure;
  }
  const int code = action == Action::kInfo ? info_command(*link) : drive_command(*link, args);
  // Nothing else is in flight now: one command's budget is enough for the stop.
  if (!link->stop(link->command_budget_ms() + 100) && code == 0 && action == Action::kDrive) {
    spdlog::error("khepera {}: the final stop was not acknowledged", args.port);
    return kExitFailure;
  }
  return code;
}

}  // namespace

void add_khepera_command(CLI::App& app) {
  auto args = std::make_shared<KheperaArgs>();
  CLI::App* cmd = app.add_subcommand("khepera", "Talk to one Khepera (or e-puck) over its serial port");
  cmd->add_option("--port", args->port, "Serial device (/dev/ttyUSB0, /dev/rfcomm0, an emulator's pty)")->required();
  cmd->add_option("--baud", args->baud, "Baud rate (default: the model's: khepera2 38400, epuck 115200)")
      ->check(CLI::IsMember({9600u, 19200u, 38400u, 57600u, 115200u}));
  cmd->add_option("--model", args->model, "Robot model")
      ->check(CLI::IsMember({"khepera2", "epuck"}))
      ->default_val("khepera2");
  cmd->add_option("--timeout-ms", args->timeout_ms, "Reply timeout per attempt, milliseconds")
      ->check(CLI::PositiveNumber)
      ->default_val(250);
  cmd->add_option("--retries", args->retries, "Further attempts before a command fails")
      ->check(CLI::NonNegativeNumber)
      ->default_val(3);
  cmd->add_flag("--verbose", args->verbose, "Log every retry, stray line and reopen");
  cmd->require_subcommand(1);

  CLI::App* info =
      cmd->add_subcommand("info", "Print the firmware versions, the 8 proximity values and the wheel counters");
  info->fallthrough();
  info->callback([args] { exit_code() = khepera_command(*args, Action::kInfo); });

  CLI::App* drive =
      cmd->add_subcommand("drive",
                          "Drive at wheel speeds L R (units of 8 mm/s on a Khepera) for --for seconds, then stop "
                          "(SIGINT/SIGTERM stop it early; exit status 130)");
  drive->fallthrough();
  drive->add_option("left", args->left_units, "Left wheel speed, units")->required();
  drive->add_option("right", args->right_units, "Right wheel speed, units")->required();
  drive->add_option("--for", args->drive_s, "Seconds to drive")->required()->check(CLI::PositiveNumber);
  drive->callback([args] { exit_code() = khepera_command(*args, Action::kDrive); });
}

}  // namespace rilbed::app

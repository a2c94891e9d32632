// The console over LCM: a running run answers console commands (pause, resume, exit,
// rt-factor F) on its bus, and `rilbed console` sends them. LCM has no authentication:
// anyone who reaches the bus can publish, so every command carries the run's token (made
// at the run's start, printed, and written to a file only its user can read); a command
// without the right token is refused, answered with why, and recorded as an event.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <variant>
#include <vector>

#include "bus/lcm_bus.hpp"
#include "rilbed/console_command_t.hpp"
#include "rilbed/console_reply_t.hpp"
#include "run/run_control.hpp"

namespace rilbed::bus {

/// A new run token: 128 random bits as 32 hex digits.
std::string make_run_token();

/// Where a run with channel prefix `prefix` keeps its token:
/// $XDG_RUNTIME_DIR/rilbed/<prefix>token, else /tmp/rilbed-<uid>/<prefix>token.
std::filesystem::path token_path(const std::string& prefix);

/// Writes `token` at `path` readable by its user only (the folder is made 0700 and must
/// belong to the user). Returns the reason when it cannot.
std::optional<std::string> write_token(const std::filesystem::path& path, const std::string& token);

/// Reads a token written by write_token(), if the file is there and readable.
std::optional<std::string> read_token(const std::filesystem::path& path);

/// What a console command asks, checked: the action for the run, or why it is refused.
/// `command` is "pause", "resume", "exit", "reset" (no arguments), "rt-factor" (the
/// factor), "mode" ("central" or "distributed") or "drive" (ID, left and right speed in
/// Khepera units, seconds).
std::variant<run::ControlAction, std::string> parse_console_command(const rilbed::console_command_t& command);

/// The run's side: answers every command on `channels.console` with a reply on
/// `channels.console_reply`, and hands accepted ones to `control`. LCM's file descriptor
/// is served by an Asio io_context on a thread of its own (no polling; a handler never
/// blocks). A repeated command (same client and seq: a client retrying after a loss) gets
/// the first answer again and is not applied twice.
class LcmConsoleServer {
 public:
  /// `lcm` and `control` must outlive the server. `log` (may be empty) is told of every
  /// command and refusal. With `own_thread` the server handles `lcm` on a thread of its
  /// own (nothing else may handle it then: liblcm's memq:// provider is not safe with two
  /// handling threads); without, whoever handles `lcm` delivers the commands.
  /// `while_paused` (may be empty) is called on the server's thread every second while the
  /// run is paused (the run then reports nothing; it re-publishes its world and status).
  LcmConsoleServer(lcm::LCM& lcm, Channels channels, std::string token, run::RunControl& control,
                   std::function<void(const std::string&)> log, bool own_thread = true,
                   std::function<void()> while_paused = {});
  /// Stops serving and joins its thread.
  ~LcmConsoleServer();
  LcmConsoleServer(const LcmConsoleServer&) = delete;
  LcmConsoleServer& operator=(const LcmConsoleServer&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The console's side: sends `command` (with `args`) and waits up to `timeout_ms` for
/// the run's reply, sending it again every `resend_ms` (LCM over UDP loses messages).
/// The run names the sender as this host and process, followed by `on_behalf_of` when
/// given (the browser a GUI relays for). Returns the reply, or nullopt when no run
/// answered in time.
std::optional<rilbed::console_reply_t> send_console_command(lcm::LCM& lcm, const Channels& channels,
                                                            const std::string& token, const std::string& command,
                                                            const std::vector<std::string>& args, int timeout_ms,
                                                            int resend_ms = 200, const std::string& on_behalf_of = "");

}  // namespace rilbed::bus

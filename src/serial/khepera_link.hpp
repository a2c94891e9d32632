// The serial link to one real Khepera (or e-puck): Boost.Asio on its own thread, one
// command in flight with a reply timeout, strict reply checks, retries within a budget,
// resynchronisation after noise, and reopening a port that vanished.
//
// Threading model: a KheperaLink owns an io_context and the one thread that runs it;
// every byte, timer and retry is handled there. The public members are thread-safe and
// never wait for the robot, except start() (one open attempt), stop(), and query() (which
// waits up to the caller's timeout). A simulation thread calls set_speeds() and reads
// latest_proximity() / latest_counters() at any rate without being held up by the serial
// line: set_speeds() records the wish and returns; the link sends the latest wish as soon
// as the line is free ("latest wins", older unsent speeds are never sent).
//
// Order of commands: speeds first (a robot must obey its controller without waiting for
// sensor polls), then queued requests (polls, query()) in order; after a speeds command
// failed, one queued request goes before the speeds are tried again, so a dead robot
// cannot starve the rest.
//
// Replies are read tolerantly (see khepera_protocol.hpp): an exact echo of the command in
// flight is skipped, the reply letter may be either case, fields rilbed does not compute
// with are kept as text or ignored.
//
// Errors: a reply that does not decode counts as bad and the command is retried at once if
// the line looked like its reply (right letter), otherwise the line is counted as stray
// and ignored (garbage, a late reply to an earlier attempt). No reply within
// reply_timeout_ms: the partial line is dropped (resynchronising at the next line end) and
// the command is sent again, up to `retries` more times; then it fails, the link's state
// becomes kUnresponsive, and (stop_on_failure) a stop `D,0,0` is queued unless newer
// speeds are already waiting. A read or write error, or end of file, means the port
// vanished: the state becomes kLost, pending requests fail, and the link tries to reopen
// the same path every reopen_interval_ms; when it opens again, the link reads the versions
// (a handshake) and sends the latest wished speeds again. Every such event is counted in
// LinkCounters and reported to the log callback, prefixed with the port.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "environment/sensor_readings.hpp"
#include "serial/khepera_protocol.hpp"

namespace rilbed::serial {

/// How bad a log message is.
enum class LogLevel { kDebug, kInfo, kWarning, kError };

/// Receives the link's messages (each already names the port). Called on the link's own
/// thread (and on the caller's thread inside start() and stop()): it must not block for
/// long or call the link's waiting members (stop(), query()).
using LogCallback = std::function<void(LogLevel level, const std::string& message)>;

/// How to reach one robot.
struct LinkConfig {
  /// The serial device (/dev/ttyUSB0, /dev/rfcomm0, an emulator's /dev/pts/N or symlink).
  std::string port;
  /// 9600, 19200, 38400, 57600 or 115200; 0 means the model's default. Always 8 data
  /// bits, no parity, 2 stop bits, no flow control.
  unsigned baud = 0;
  /// The firmware's dialect (letters, ranges).
  RobotModel model = khepera2_model();
  /// How long to wait for a reply to one attempt, milliseconds.
  int reply_timeout_ms = 250;
  /// Further attempts after the first before a command fails.
  int retries = 3;
  /// Read the proximity sensors (`N`) this often, milliseconds; 0: only on request.
  int proximity_period_ms = 0;
  /// Read the wheel counters (`H`) this often, milliseconds; 0: only on request.
  int counters_period_ms = 0;
  /// While the port is lost, try to reopen it this often, milliseconds.
  int reopen_interval_ms = 500;
  /// Queue a stop when a command fails after its retries (see the file comment).
  bool stop_on_failure = true;
  /// Where messages go; may be empty.
  LogCallback log;
  /// Called on the link's thread each time the bytes of a set-speeds command (`D`) have
  /// been written to the port, with the speeds and the instant the write completed: what
  /// a loop-latency measurement needs. May be empty; must return quickly.
  std::function<void(const Command& command, std::chrono::steady_clock::time_point written)> on_speeds_written;
};

/// What the link is doing.
enum class LinkState {
  kConnecting,    ///< port open, no valid reply yet (or reopened, handshake pending)
  kOk,            ///< the last command was answered
  kUnresponsive,  ///< port open, the last command failed after its retries
  kLost,          ///< the port vanished or cannot be opened; reopening at intervals
  kStopped,       ///< stop() was called (or start() never was)
};
/// "connecting", "ok", "unresponsive", "lost", "stopped".
std::string_view link_state_name(LinkState state);

/// Event counts since the link was made.
struct LinkCounters {
  std::uint64_t commands_sent = 0;    ///< attempts written, retries included
  std::uint64_t replies_ok = 0;       ///< replies that passed the checks
  std::uint64_t bad_replies = 0;      ///< lines shaped like the awaited reply that failed the checks
  std::uint64_t stray_lines = 0;      ///< lines that answered nothing in flight (garbage, late replies)
  std::uint64_t echoed_lines = 0;     ///< exact echoes of the command in flight, skipped
  std::uint64_t timeouts = 0;         ///< attempts without a reply in time
  std::uint64_t retries = 0;          ///< attempts beyond the first
  std::uint64_t failed_commands = 0;  ///< commands given up after their retries
  std::uint64_t clamped_speeds = 0;   ///< speed commands clamped to the model's range
  std::uint64_t noise_bytes = 0;      ///< non-printable bytes dropped by the line assembler
  std::uint64_t overlong_lines = 0;   ///< lines dropped for length
  std::uint64_t port_losses = 0;      ///< times the port vanished
  std::uint64_t reopens = 0;          ///< times it was opened again after a loss
  std::uint64_t reopen_failures = 0;  ///< attempts to open it again that failed (every reopen_interval_ms while lost)
};

/// A snapshot of the link's health.
struct LinkStatus {
  LinkState state = LinkState::kStopped;
  LinkCounters counters;
  std::string last_error;  ///< the latest failure, naming the port; empty if none yet
};

/// A value read from the robot and when it arrived.
template <typename T>
struct Stamped {
  T value;
  std::chrono::steady_clock::time_point received;
};

/// The serial link to one robot. Not copyable or movable; all members thread-safe.
class KheperaLink {
 public:
  /// Checks the config; opens nothing yet. Throws std::invalid_argument, naming the
  /// port, for an empty port, an unsupported baud rate or a non-positive timeout.
  explicit KheperaLink(LinkConfig config);
  /// stop(): the robot gets a stop if the line allows, the port closes, the thread ends.
  ~KheperaLink();
  KheperaLink(const KheperaLink&) = delete;
  KheperaLink& operator=(const KheperaLink&) = delete;

  /// Opens the port once, now, and starts the link's thread (handshake: read versions;
  /// polls as configured). Returns nullopt when the port opened, else the reason (e.g.
  /// "khepera /dev/ttyUSB0: cannot open: No such file or directory"); the link then keeps
  /// trying to open it in the background (state kLost), and the caller decides whether
  /// to wait or give up. Call once.
  std::optional<std::string> start();

  /// Sends a stop (`D,0,0`) and waits up to `timeout_ms` (default: the time the current
  /// command and the stop may take with all their retries) for the robot to acknowledge
  /// it, then closes the port and ends the thread. Returns whether the stop was
  /// acknowledged (false if the port was lost, the robot did not answer, or the link
  /// never started). Later calls return the first call's result at once.
  bool stop(std::optional<int> timeout_ms = std::nullopt);

  /// Stops the robot (`D,0,0`) and waits up to `timeout_ms` (default as stop()) for it to
  /// acknowledge, keeping the link open: between the runs of a batch. Returns whether the
  /// robot acknowledged (false if the link is not running, lost, or the robot did not
  /// answer). Later set_speeds() calls drive it again.
  bool halt(std::optional<int> timeout_ms = std::nullopt);

  /// Wishes wheel speeds, in the model's units (Khepera: +-127, 8 mm/s per unit); values
  /// beyond the range are clamped when sent (counted in clamped_speeds). Never blocks on
  /// the line; the latest wish is sent when the line is free.
  void set_speeds(int left_units, int right_units);
  /// The speeds the robot last acknowledged, if any.
  std::optional<WheelSpeeds> acknowledged_speeds() const;
  /// The speeds last wished (set_speeds, stop, halt), sent or not; nullopt before the first.
  std::optional<WheelSpeeds> wished_speeds() const;

  /// Asks for a proximity reading (`N`) as soon as the line is free, unless one is
  /// already queued. latest_proximity() shows it when it arrives.
  void request_proximity();
  /// Asks for the wheel counters (`H`/`Q`) likewise.
  void request_counters();
  /// The latest proximity reading (0..model.max_sensor_value, firmware order).
  std::optional<Stamped<environment::ProximityValues>> latest_proximity() const;
  /// The latest wheel counters, pulses (model.counter_pulse_m each).
  std::optional<Stamped<environment::OdometryReading>> latest_counters() const;
  /// The firmware versions from the latest handshake or read-versions reply.
  std::optional<FirmwareVersions> versions() const;

  /// Sends `command` (queued behind commands already waiting, after wished speeds) and
  /// waits up to `timeout` for its checked reply. Fails at once if the link is not started
  /// or the port is lost, and on timeout: a command still queued then is withdrawn (one
  /// already on the line completes unseen). A successful set-speeds query counts as
  /// acknowledged speeds; once stop() has begun, queued set-speeds queries are dropped.
  /// Must not be called from the log callback.
  Result<Reply> query(const Command& command, std::chrono::milliseconds timeout);

  /// What the link is doing now.
  LinkState state() const;
  /// State, counters and the latest error.
  LinkStatus status() const;
  /// The configured port.
  const std::string& port() const;
  /// The configuration in use (baud resolved to a number).
  const LinkConfig& config() const;

  /// The time one command may take with all its retries, milliseconds.
  int command_budget_ms() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rilbed::serial

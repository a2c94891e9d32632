// The Khepera serial protocol as bytes: commands encoded, replies decoded, per-model
// letters and ranges, and the line assembler that cuts a byte stream into lines and
// resynchronises after noise. Pure functions and plain values: no I/O, no threads, no
// exceptions for bad bytes (a bad reply is a Result holding the reason).
//
// Khepera II (K-Team firmware), see ARCHITECTURE.md "Khepera serial protocol": one command
// per line, an upper-case letter and comma-separated integers, ended by CR; the reply
// starts with the same letter in lower case and ends with CR LF.
//
// Replies are read tolerantly, because firmware differs between robots and BIOS versions
// and independent peers (other emulators, other boards) answer in their own ways:
//   - the reply letter may be upper or lower case, the line may end in CR LF, LF or CR,
//     and spaces or tabs around the line and around each field are ignored;
//   - fields after the ones rilbed computes with are ignored (`d,0` acknowledges `D`;
//     `n` with ten values gives the first eight);
//   - fields rilbed only shows (the versions of `B`/`V`) are kept as text, whatever they
//     hold (`b,5.02,5.01`, `b,K2 BIOS`);
//   - only a field rilbed computes with (a speed, a counter, a sensor value) that is
//     missing, not an integer or out of range makes the reply bad; the reason names the
//     command and the field.
// The link skips an exact echo of its command (some firmware and terminal servers echo
// what they receive) before a line is decoded as a reply.
//
// e-puck (GCtronic "advanced sercom" / BTcom, ASCII mode): the same framing and the same
// D, E, N, O, L letters, but
//   - versions are `V` -> `v,<free text>` (the Khepera's `B` sets the e-puck's body LED),
//   - position counters are set with `P,l,r` -> `p` and read with `Q` -> `q,l,r` (the
//     Khepera's `G` and `H` mean IR receiver and help on the e-puck),
//   - speeds are motor steps per second, +-1000; sensors are 12-bit (0..4095); 8 LEDs;
//   - 115200 baud.
// Those letters come from GCtronic's published command table; RobotModel's letter table
// is a plain value a caller can change for a firmware that differs.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/result.hpp"
#include "environment/sensor_readings.hpp"

namespace rilbed::serial {

// ---------------------------------------------------------------- results

/// Bad bytes from a robot are ordinary input, so decoding returns a core::Result (a value
/// or the reason there is none) rather than throwing.
using core::Failure;
using core::Result;

// ---------------------------------------------------------------- commands

/// What a command does, independent of the letter a robot model uses for it.
enum class CommandKind : std::uint8_t {
  kReadVersions,   ///< Khepera `B` / e-puck `V`
  kSetSpeeds,      ///< `D,l,r`: wheel speeds
  kReadSpeeds,     ///< `E`
  kSetCounters,    ///< Khepera `G,l,r` / e-puck `P,l,r`: wheel position counters
  kReadCounters,   ///< Khepera `H` / e-puck `Q`
  kReadProximity,  ///< `N`: eight IR proximity sensors
  kReadAmbient,    ///< `O`: eight ambient light sensors
  kSetLed,         ///< `L,n,s`: LED n off/on/toggle
};
/// Number of CommandKind values (the size of RobotModel::letters).
inline constexpr std::size_t kCommandKindCount = 8;

/// A short English name of a command kind ("read proximity"), for messages.
std::string_view command_kind_name(CommandKind kind);

/// What `L,n,s` does to LED n.
enum class LedAction : std::uint8_t { kOff = 0, kOn = 1, kToggle = 2 };

/// One command with its arguments. Which arguments mean something depends on `kind`:
/// speeds (units of the model, see RobotModel), counters (pulses), or LED number and
/// action. Build it with the named constructors.
struct Command {
  CommandKind kind = CommandKind::kReadVersions;
  std::int64_t first = 0;   ///< left speed, left counter or LED number
  std::int64_t second = 0;  ///< right speed, right counter or LED action

  static Command read_versions() { return {CommandKind::kReadVersions}; }
  static Command set_speeds(int left_units, int right_units) {
    return {CommandKind::kSetSpeeds, left_units, right_units};
  }
  static Command read_speeds() { return {CommandKind::kReadSpeeds}; }
  static Command set_counters(std::int64_t left_pulses, std::int64_t right_pulses) {
    return {CommandKind::kSetCounters, left_pulses, right_pulses};
  }
  static Command read_counters() { return {CommandKind::kReadCounters}; }
  static Command read_proximity() { return {CommandKind::kReadProximity}; }
  static Command read_ambient() { return {CommandKind::kReadAmbient}; }
  static Command set_led(int led, LedAction action) { return {CommandKind::kSetLed, led, static_cast<int>(action)}; }
  bool operator==(const Command&) const = default;
};

/// Wheel speeds in a model's units (Khepera: pulses per 10 ms, 1 unit = 8 mm/s).
struct WheelSpeeds {
  int left_units = 0;
  int right_units = 0;
  bool operator==(const WheelSpeeds&) const = default;
};

// ---------------------------------------------------------------- robot models

/// How one robot model speaks the protocol and what its numbers mean. A plain value:
/// copy one of the built-in models and change it for a firmware that differs.
struct RobotModel {
  /// Name used on the command line ("khepera2", "epuck").
  std::string_view name;
  /// Upper-case command letter per CommandKind (index = static_cast<size_t>(kind)); the
  /// reply letter is its lower case.
  std::array<char, kCommandKindCount> letters{};
  /// true: the versions reply is `b,<bios>,<protocol>` (Khepera); false: `v,<free text>`
  /// (e-puck). Either way the versions are kept as text.
  bool bios_protocol_versions = true;
  /// Largest wheel speed magnitude the firmware takes, in its units.
  int max_speed_units = 127;
  /// Largest proximity or ambient value (sensors report 0..this).
  int max_sensor_value = 1023;
  /// Number of LEDs `L` addresses (0..led_count-1).
  int led_count = 2;
  /// Ground speed of one speed unit, metres per second.
  double speed_unit_mps = 0.008;
  /// Wheel travel of one counter pulse, metres.
  double counter_pulse_m = 0.08e-3;
  /// Distance between the wheels, metres.
  double wheel_base_m = 0.053;
  /// Baud rate the firmware uses unless told otherwise.
  unsigned default_baud = 38400;

  /// The command letter of `kind`.
  char command_letter(CommandKind kind) const { return letters[static_cast<std::size_t>(kind)]; }
  /// The reply letter of `kind` (the command letter in lower case).
  char reply_letter(CommandKind kind) const;
};

/// Khepera II with K-Team's firmware: B, D, E, G, H, N, O, L; speeds +-127 (8 mm/s per
/// unit), counters 0.08 mm per pulse, sensors 0..1023, LEDs 0 and 1, 38400 baud.
const RobotModel& khepera2_model();
/// e-puck with GCtronic's advanced sercom (ASCII mode): V, D, E, P, Q, N, O, L; speeds
/// +-1000 steps/s, 1000 steps per wheel turn of 41 mm diameter (0.129 mm per step),
/// sensors 0..4095, LEDs 0..7, 115200 baud. See this file's head for the assumptions.
const RobotModel& epuck_model();
/// The built-in model named `name` ("khepera2", "epuck"), or nullptr.
const RobotModel* find_robot_model(std::string_view name);

// ---------------------------------------------------------------- encoding commands

/// A command as bytes, ready to write.
struct EncodedCommand {
  std::string bytes;     ///< e.g. "D,10,-10\r"
  bool clamped = false;  ///< a speed was outside the model's range and was clamped
};

/// Encodes `command` for `model`: letter, comma-separated integers, CR. Speeds are
/// clamped to +-model.max_speed_units (reported in `clamped`); counters outside 32-bit
/// integers, an LED number outside 0..led_count-1 or an LED action outside 0..2 fail.
Result<EncodedCommand> encode_command(const RobotModel& model, const Command& command);

/// Decodes one command line (terminator optional) as K-Team's firmware does: the letter,
/// then exactly the integers the command takes. Used by the emulator.
Result<Command> decode_command(const RobotModel& model, std::string_view line);

// ---------------------------------------------------------------- replies

/// Firmware versions as `B` (Khepera) or `V` (e-puck) reports them. rilbed only shows
/// them, so they are text, whatever the firmware puts there ("5", "5.02", "K2-BIOS").
struct FirmwareVersions {
  std::string bios;      ///< Khepera: the first field after "b,"; e-puck: empty
  std::string protocol;  ///< Khepera: the second field; e-puck: empty
  /// For people: Khepera "bios B, protocol P", with any further fields in brackets after
  /// it (or the whole text after "b," when there are not two fields); e-puck: the free
  /// text after "v,".
  std::string text;
  bool operator==(const FirmwareVersions&) const = default;
};

/// Two integers for the two wheels: speeds (units) for `e`, counters (pulses) for `h`/`q`.
struct WheelPair {
  std::int64_t left = 0;
  std::int64_t right = 0;
  bool operator==(const WheelPair&) const = default;
};

/// Eight sensor values in firmware order (proximity for `n`, ambient light for `o`).
using SensorArray = environment::ProximityValues;

/// A decoded reply. Which member means something depends on `kind`: `wheels` for read
/// speeds and read counters, `sensors` for read proximity and read ambient, `versions`
/// for read versions; the acknowledgements (`d`, `g`/`p`, `l`) carry nothing.
struct Reply {
  CommandKind kind = CommandKind::kReadVersions;
  WheelPair wheels{};
  SensorArray sensors{};
  FirmwareVersions versions{};
  bool operator==(const Reply&) const = default;
};

/// Decodes `line` as the reply to a command of kind `expected`, tolerantly (see the file
/// comment). The line may still carry its CR LF (or LF, or CR). Checks, in order: not
/// empty; the firmware's `z` (protocol error) reply; the reply letter (either case); then,
/// for the fields rilbed computes with, each one present, an integer (an optional sign,
/// then digits), and in range (sensors 0..max_sensor_value, speeds +-max_speed_units,
/// counters 32-bit). The failure reason quotes the line with control bytes escaped and
/// names the command and the field ("field 4 (proximity sensor 3)").
Result<Reply> decode_reply(const RobotModel& model, CommandKind expected, std::string_view line);

/// Whether `line` is shaped like a reply to `expected` (its letter in either case alone,
/// or followed by a comma, space or tab), or like the firmware's `z` error, whatever
/// follows. The link uses it to tell a corrupted reply to its command (retry at once)
/// from a stray line (ignored).
bool looks_like_reply_to(const RobotModel& model, CommandKind expected, std::string_view line);

/// Encodes `reply` as the firmware sends it ("n,0,0,...,0\r\n"). Used by the emulator.
std::string encode_reply(const RobotModel& model, const Reply& reply);

/// Whether `line` (terminator optional, surrounding spaces ignored) is exactly the
/// encoded `command`: an echo of it, never its reply.
bool is_echo_of(const RobotModel& model, const Command& command, std::string_view line);

/// The firmware's reply to a line it does not understand (Khepera: "z,Protocol error").
inline constexpr std::string_view kProtocolErrorReply = "z,Protocol error\r\n";

/// `bytes` quoted for a message, with CR, LF, NUL and other non-printable bytes escaped
/// (\r, \n, \0, \xNN), cut after `max_chars` characters with "...".
std::string printable(std::string_view bytes, std::size_t max_chars = 80);

// ---------------------------------------------------------------- line assembler

/// Cuts a byte stream from a serial port into lines and resynchronises after noise:
///   - a line ends at CR or LF; CR LF, LF alone and CR alone all work, and the empty
///     line between CR and LF is not reported;
///   - bytes outside printable ASCII (NUL, line noise at a wrong baud rate, 0x80..0xff)
///     are dropped and counted, so noise glued to a reply does not break it;
///   - a line longer than `max_line_bytes` is dropped whole: bytes are skipped up to the
///     next line end, and counted;
///   - printable garbage stays in its line; the decoder rejects such a line.
/// Not thread-safe; one per byte stream.
class LineAssembler {
 public:
  /// Longest reply the protocol has is ~50 bytes (`n` with eight 4-digit values); 128
  /// leaves room for an e-puck version text.
  static constexpr std::size_t kDefaultMaxLineBytes = 128;

  /// What was dropped so far.
  struct Counters {
    std::uint64_t lines = 0;           ///< complete lines returned
    std::uint64_t noise_bytes = 0;     ///< non-printable bytes dropped (NUL included)
    std::uint64_t overlong_lines = 0;  ///< lines dropped for being too long
  };

  explicit LineAssembler(std::size_t max_line_bytes = kDefaultMaxLineBytes);

  /// Feeds received bytes; appends each line completed by them (without its
  /// terminator) to `lines`.
  void feed(std::string_view bytes, std::vector<std::string>& lines);
  /// Convenience: feed() into a fresh vector.
  std::vector<std::string> feed(std::string_view bytes);
  /// Forgets a partial line (after a timeout: a reply's tail arriving later becomes a
  /// line of its own instead of corrupting the next reply).
  void discard_partial();
  /// Bytes of the partial line held.
  std::size_t partial_bytes() const { return partial_.size(); }
  const Counters& counters() const { return counters_; }

 private:
  std::size_t max_line_bytes_;
  std::string partial_;
  bool skipping_overlong_ = false;
  Counters counters_;
};

}  // namespace rilbed::serial

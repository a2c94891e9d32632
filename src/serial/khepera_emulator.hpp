// An emulated Khepera (or e-puck) on a pseudo-terminal: it answers the serial protocol as
// the firmware does, drives a true pose with exact differential-drive arcs, and can be
// made to misbehave (slow, silent, noisy, corrupt, unplugged) so that the link's recovery
// can be tested against real file descriptors and a real tty driver.
//
// The pty: the emulator owns the master side and also keeps one descriptor of the slave
// side open, so that a client (the link, `rilbed khepera`) closing and reopening the slave
// never hangs the pty up. "Unplugging" closes both: the client's reads fail (EIO or end
// of file) as when a USB serial adapter is pulled, and the kernel removes /dev/pts/N.
// "Replugging" opens a new pty pair, whose /dev/pts/N may or may not be the old N (the
// kernel hands out the lowest free index, and the old one stays taken while a client still
// holds it). To give clients a path that survives a replug, set
// EmulatorConfig::stable_path: the emulator keeps a symlink there pointing to the current
// slave, removes it while unplugged (so a reopen fails instead of opening a stranger's
// terminal) and recreates it on replug.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "core/geometry.hpp"
#include "environment/sensor_readings.hpp"
#include "serial/khepera_protocol.hpp"

namespace rilbed::serial {

/// Misbehaviours of the emulated robot. All off by default. Probabilities are per reply.
struct EmulatorFaults {
  /// Every reply is sent this many milliseconds after its command arrived.
  int reply_delay_ms = 0;
  /// Chance that a reply is not sent at all (the command still takes effect, as when the
  /// reply is lost on the wire).
  double drop_probability = 0.0;
  /// Chance that 1..12 random bytes (any value but CR and LF, sometimes followed by a
  /// CR LF of their own) are sent just before a reply.
  double garbage_probability = 0.0;
  /// Chance that a reply is corrupted: wrong letter, a missing value, or a value that is
  /// not a number.
  double corrupt_probability = 0.0;
  /// Unplug this many seconds after the emulator started (0: never). Once only.
  double disconnect_after_s = 0.0;
  /// After an unplug (timed or by unplug()), plug back in after this many seconds
  /// (0: stay unplugged until replug()).
  double replug_after_s = 0.0;
};

/// How the emulated firmware words its replies: K-Team's style by default. The other
/// settings play firmware that differs (other BIOS versions, independent peers), to try
/// the link's tolerance against real bytes on a real tty.
struct ReplyStyle {
  bool upper_case_letter = false;    ///< "N,1,..." instead of "n,1,..."
  std::string line_end = "\r\n";     ///< what ends a reply: "\r\n", "\n" or "\r"
  std::string extra_fields;          ///< appended after the reply's own fields, e.g. ",0,ok"
  int trailing_spaces = 0;           ///< spaces before the line end
  bool spaces_after_commas = false;  ///< "n, 1, 2, ..."
  bool echo = false;                 ///< echo each command line, at once, before its reply
};

/// How an emulator starts.
struct EmulatorConfig {
  /// Which firmware to speak (letters, ranges, units, see RobotModel).
  RobotModel model = khepera2_model();
  /// The true pose at start, field frame (metres, radians counter-clockwise).
  Pose2 initial_pose;
  /// Proximity values reported by `N` until set_proximity() changes them.
  environment::ProximityValues proximity{};
  /// Ambient light values reported by `O` (Khepera: about 500 in an ordinary room).
  environment::ProximityValues ambient = {500, 500, 500, 500, 500, 500, 500, 500};
  /// Versions reported by `B` (Khepera: bios and protocol, any text) or `V` (e-puck: text).
  FirmwareVersions versions{"5", "4", "rilbed emulated e-puck"};
  /// How replies are worded.
  ReplyStyle style;
  EmulatorFaults faults;
  /// Seed of the fault dice, so a faulty run can be repeated.
  std::uint64_t seed = 1;
  /// If not empty: a symlink kept pointing to the current slave device (see the file
  /// comment). An existing file or symlink there is replaced.
  std::string stable_path;
  /// The time the emulated robot lives in (its motion, reply delays, timed unplugs): the
  /// wall's (steady_clock) when empty. A test's own clock makes the motion exact; the
  /// serving thread sees a new time when it next wakes (a byte from the port, a request).
  /// Called from any of the emulator's threads: it must be thread-safe.
  std::function<std::chrono::steady_clock::time_point()> clock;
};

/// One emulated robot on a pseudo-terminal, served by its own thread from construction
/// to destruction. All public members are thread-safe.
class KheperaEmulator {
 public:
  /// Opens the pty pair (raw mode) and starts serving. Throws std::system_error if the
  /// pty cannot be opened, std::invalid_argument for a bad fault setting.
  explicit KheperaEmulator(EmulatorConfig config = {});
  /// Stops the thread, closes the pty (a client sees the port vanish) and removes the
  /// stable symlink.
  ~KheperaEmulator();
  KheperaEmulator(const KheperaEmulator&) = delete;
  KheperaEmulator& operator=(const KheperaEmulator&) = delete;

  /// The path a client should open: stable_path if configured, else the current slave.
  std::string device_path() const;
  /// The current slave device (/dev/pts/N); empty while unplugged.
  std::string slave_path() const;

  /// The true pose now (integrated up to this instant), field frame.
  Pose2 true_pose() const;
  /// The wheel position counters now, in pulses (model.counter_pulse_m each).
  environment::OdometryReading counters() const;
  /// The wheel speeds last commanded with `D` (units), whether or not its reply got out.
  WheelSpeeds last_speeds() const;
  /// Commands understood so far, of one kind.
  std::uint64_t commands_received(CommandKind kind) const;
  /// Lines that were not a valid command (answered with the protocol error reply).
  std::uint64_t bad_commands() const;

  /// Sets what `N` reports from now on (e.g. virtual readings computed by the world).
  void set_proximity(const environment::ProximityValues& values);
  /// Puts the robot at `pose` (field frame) now, as a hand placing it: the wheels keep
  /// their speeds and the counters are unchanged.
  void place(const Pose2& pose);
  /// Sets what `O` reports from now on.
  void set_ambient(const environment::ProximityValues& values);
  /// Changes the faults from now on (a disconnect_after_s counts from the start).
  void set_faults(const EmulatorFaults& faults);

  /// Pulls the plug now: closes the pty, drops replies not yet sent. Returns when done.
  void unplug();
  /// Plugs back in now with a fresh pty (see the file comment about its path). Returns
  /// when done; does nothing if plugged. Throws std::system_error if no pty can be opened.
  void replug();
  /// Whether a pty is open.
  bool plugged() const;

 private:
  struct State;
  void serve();
  std::unique_ptr<State> state_;
  std::thread thread_;
};

}  // namespace rilbed::serial

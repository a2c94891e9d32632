// SIGINT and SIGTERM as a flag that a command's work polls (a run after every control
// step, a loop over frames or messages): the work then ends cleanly, every robot stopped
// and every file written.
#pragma once

#include <atomic>
#include <csignal>

namespace rilbed::app {

/// While it lives, SIGINT and SIGTERM set its flag instead of killing the process; the
/// handlers before it come back when it goes. One at a time per process (a signal handler
/// can only reach a flag of the program's).
class InterruptFlag {
 public:
  /// Clears the flag and installs the handlers.
  InterruptFlag();
  ~InterruptFlag();
  InterruptFlag(const InterruptFlag&) = delete;
  InterruptFlag& operator=(const InterruptFlag&) = delete;

  /// Whether a signal came (or raise() was called).
  bool raised() const { return flag().load(); }
  /// Sets the flag from the program itself (an agent process whose lifeline closed; any
  /// thread, even after this object is gone).
  static void raise();
  /// The flag, for work that polls it (RunOptions::interrupt and the like); lives as long
  /// as the program.
  const std::atomic<bool>& flag() const;

 private:
  using Handler = void (*)(int);
  Handler previous_int_;
  Handler previous_term_;
};

}  // namespace rilbed::app

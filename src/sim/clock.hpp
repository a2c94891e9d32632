// Clocks that pace the coordinator: as fast as possible, or real time scaled by a factor.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>

#include "sim/time.hpp"

namespace rilbed::sim {

/// How Clock::wait_until ended.
enum class WaitResult {
  kReached,  ///< simulated time reached the deadline
  kWoken,    ///< notify() woke it early (an external event, or the coordinator stopping)
  kStopped,  ///< the clock was stopped: every wait now returns at once
};

/// The strategy that maps simulated time to the world. The coordinator calls
/// start() when a run begins and wait_until() before every event; other threads call
/// notify() and stop(). Implementations say which calls are thread-safe.
class Clock {
 public:
  virtual ~Clock();
  /// Declares that simulated time is `sim_t_us` now (a run begins at that time).
  virtual void start(TimeUs sim_t_us) = 0;
  /// Blocks until simulated time reaches `sim_t_us` (kInfinity: until woken or
  /// stopped), or until notify() or stop(). A notify() made while nobody waits makes
  /// the next wait return `woken` at once, so no wake-up is lost.
  virtual WaitResult wait_until(TimeUs sim_t_us) = 0;
  /// Wakes the current (or next) wait_until early. Thread-safe.
  virtual void notify() = 0;
  /// Makes every wait, current and future, return `stopped`. Thread-safe.
  virtual void stop() = 0;
  /// The current simulated time in microseconds. Thread-safe.
  virtual TimeUs now_us() const = 0;
};

/// As fast as possible: wait_until returns `reached` at once and simulated time jumps
/// to the deadline (now_us() is the last time waited for). No wall time is involved,
/// so runs are reproducible. notify() does nothing (the coordinator checks for
/// external events before every event anyway). All members thread-safe.
class FastClock final : public Clock {
 public:
  void start(TimeUs sim_t_us) override;
  WaitResult wait_until(TimeUs sim_t_us) override;
  void notify() override {}
  void stop() override;
  TimeUs now_us() const override;

 private:
  std::atomic<TimeUs> now_us_{0};
  std::atomic<bool> stopped_{false};
};

/// Real time scaled by a factor: simulated time advances as wall time (steady_clock)
/// times `factor` from an anchor, so factor 10 runs ten times faster than real time.
/// Waits sleep until absolute deadlines, recomputed when the factor changes or the
/// clock resumes, so sleeps never accumulate drift. While paused, simulated time
/// stands still and waits do not reach their deadline. Every member is thread-safe;
/// one thread (the coordinator's) is expected to wait at a time.
class RealTimeClock final : public Clock {
 public:
  /// `factor` > 0 (finite) simulated seconds per wall second; throws
  /// std::invalid_argument otherwise. Simulated time 0 is the moment of construction
  /// until start() says otherwise.
  explicit RealTimeClock(double factor = 1.0);

  /// Changes the factor; simulated time stays continuous (the clock re-anchors at the
  /// current time) and a current wait recomputes its deadline. Throws like the
  /// constructor.
  void set_factor(double factor);
  /// The current factor.
  double factor() const;
  /// Freezes simulated time (idempotent).
  void pause();
  /// Lets simulated time run again from where pause() froze it (idempotent).
  void resume();
  /// True between pause() and resume().
  bool paused() const;
  /// How many wait_until() calls are asleep in it now (a test, or a watchdog, knows so that
  /// a wait has begun and not yet been woken).
  int waiters() const;

  void start(TimeUs sim_t_us) override;
  WaitResult wait_until(TimeUs sim_t_us) override;
  void notify() override;
  void stop() override;
  TimeUs now_us() const override;

 private:
  using WallClock = std::chrono::steady_clock;
  static double checked_factor(double factor);
  TimeUs now_locked(WallClock::time_point wall_now) const;  // caller holds mutex_
  void reanchor_locked(WallClock::time_point wall_now);     // caller holds mutex_

  mutable std::mutex mutex_;
  std::condition_variable changed_;  // notified on notify, stop, factor change, resume
  double factor_;
  WallClock::time_point anchor_wall_;  // wall time at which simulated time was anchor_sim_us_
  TimeUs anchor_sim_us_ = 0;
  bool paused_ = false;
  int waiters_ = 0;  // wait_until() calls asleep now
  bool stopped_ = false;
  bool notified_ = false;
};

}  // namespace rilbed::sim

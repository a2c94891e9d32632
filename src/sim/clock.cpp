// Clock implementations. RealTimeClock keeps one anchor (wall time, simulated time)
// and derives everything from it: now = anchor_sim + (wall - anchor_wall) * factor.
#include "sim/clock.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rilbed::sim {

Clock::~Clock() = default;

// ---------------------------------------------------------------- FastClock

void FastClock::start(TimeUs sim_t_us) { now_us_.store(sim_t_us); }

WaitResult FastClock::wait_until(TimeUs sim_t_us) {
  if (stopped_.load()) return WaitResult::kStopped;
  // "Never" is not a time to jump to: keep the last finite time as now.
  if (sim_t_us != kInfinity && sim_t_us > now_us_.load()) now_us_.store(sim_t_us);
  return WaitResult::kReached;
}

void FastClock::stop() { stopped_.store(true); }

TimeUs FastClock::now_us() const { return now_us_.load(); }

// ---------------------------------------------------------------- RealTimeClock

double RealTimeClock::checked_factor(double factor) {
  if (!(factor > 0.0) || !std::isfinite(factor))
    throw std::invalid_argument("sim: a real-time factor must be positive and finite, not " + std::to_string(factor));
  return factor;
}

RealTimeClock::RealTimeClock(double factor) : factor_(checked_factor(factor)), anchor_wall_(WallClock::now()) {}

TimeUs RealTimeClock::now_locked(WallClock::time_point wall_now) const {
  if (paused_) return anchor_sim_us_;
  const double wall_us = std::chrono::duration<double, std::micro>(wall_now - anchor_wall_).count();
  return anchor_sim_us_ + static_cast<TimeUs>(std::floor(wall_us * factor_));
}

void RealTimeClock::reanchor_locked(WallClock::time_point wall_now) {
  anchor_sim_us_ = now_locked(wall_now);
  anchor_wall_ = wall_now;
}

void RealTimeClock::set_factor(double factor) {
  const double checked = checked_factor(factor);
  {
    std::lock_guard lock(mutex_);
    reanchor_locked(WallClock::now());
    factor_ = checked;
  }
  changed_.notify_all();
}

double RealTimeClock::factor() const {
  std::lock_guard lock(mutex_);
  return factor_;
}

void RealTimeClock::pause() {
  std::lock_guard lock(mutex_);
  if (paused_) return;
  reanchor_locked(WallClock::now());
  paused_ = true;
}

void RealTimeClock::resume() {
  {
    std::lock_guard lock(mutex_);
    if (!paused_) return;
    anchor_wall_ = WallClock::now();  // simulated time continues from the frozen value
    paused_ = false;
  }
  changed_.notify_all();
}

bool RealTimeClock::paused() const {
  std::lock_guard lock(mutex_);
  return paused_;
}

void RealTimeClock::start(TimeUs sim_t_us) {
  std::lock_guard lock(mutex_);
  anchor_sim_us_ = sim_t_us;
  anchor_wall_ = WallClock::now();
}

WaitResult RealTimeClock::wait_until(TimeUs sim_t_us) {
  // Longest single sleep; the loop sleeps again. Keeps far deadlines (and kInfinity)
  // from overflowing time_point arithmetic.
  constexpr auto kMaxSleep = std::chrono::hours(1);
  std::unique_lock lock(mutex_);
  for (;;) {
    if (stopped_) return WaitResult::kStopped;
    if (notified_) {
      notified_ = false;
      return WaitResult::kWoken;
    }
    if (paused_) {
      ++waiters_;
      changed_.wait(lock);
      --waiters_;
      continue;
    }
    const auto wall_now = WallClock::now();
    auto deadline = wall_now + kMaxSleep;
    if (sim_t_us != kInfinity) {
      // The deadline is absolute, computed from the anchor and rounded up so that
      // waking at it means the simulated time has been reached.
      const double wall_ns = (static_cast<double>(sim_t_us) - static_cast<double>(anchor_sim_us_)) * 1e3 / factor_;
      if (wall_ns < std::chrono::duration<double, std::nano>(deadline - anchor_wall_).count()) {
        const auto due = anchor_wall_ + std::chrono::nanoseconds(static_cast<std::int64_t>(std::ceil(wall_ns)));
        if (wall_now >= due) return WaitResult::kReached;
        deadline = due;
      }
    }
    ++waiters_;
    changed_.wait_until(lock, deadline);
    --waiters_;
  }
}

int RealTimeClock::waiters() const {
  std::lock_guard lock(mutex_);
  return waiters_;
}

void RealTimeClock::notify() {
  {
    std::lock_guard lock(mutex_);
    notified_ = true;
  }
  changed_.notify_all();
}

void RealTimeClock::stop() {
  {
    std::lock_guard lock(mutex_);
    stopped_ = true;
  }
  changed_.notify_all();
}

TimeUs RealTimeClock::now_us() const {
  std::lock_guard lock(mutex_);
  return now_locked(WallClock::now());
}

}  // namespace rilbed::sim

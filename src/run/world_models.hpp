// The world as DEVS models: its integration step, and the sweep of every robot's sensors
// at each control instant.
#pragma once

#include <chrono>
#include <utility>
#include <vector>

#include "environment/world.hpp"
#include "sim/atomic.hpp"

namespace rilbed::run {

// The world as a DEVS model: one integration step every physics step. Collisions are
// kept for the monitor, which drains them.
class WorldModel final : public sim::AtomicModel<TimeUs> {  // state: time to the next step
 public:
  WorldModel(environment::World& world, TimeUs step_us)
      : sim::AtomicModel<TimeUs>("world", step_us), world_(world), step_us_(step_us) {}
  TimeUs time_advance() const override { return state_; }
  void internal_transition() override {
    for (const auto& e : world_.step(step_us_)) collisions_.push_back(e);
    state_ = step_us_;
  }
  void external_transition(TimeUs elapsed_us) override { state_ -= elapsed_us; }
  void output() override {}
  std::vector<environment::CollisionEvent> drain() { return std::exchange(collisions_, {}); }

 private:
  environment::World& world_;
  TimeUs step_us_;
  std::vector<environment::CollisionEvent> collisions_;
};

// The world's sensors swept at every control instant, before the agents read them
// (World::sense_ahead): one pass over the robots in memory order, spread over the
// workers, instead of each agent computing its own reading where it happens to be. The
// readings are the same either way; the sweep keeps neighbours in cache.
class SensingModel final : public sim::AtomicModel<TimeUs> {  // state: time to the next sweep
 public:
  SensingModel(environment::World& world, TimeUs period_us, TimeUs first_us)
      : sim::AtomicModel<TimeUs>("sensing", first_us), world_(world), period_us_(period_us), t_us_(first_us) {}
  TimeUs time_advance() const override { return state_; }
  void internal_transition() override {
    using Clock = std::chrono::steady_clock;
    const Clock::time_point start = profiled_ ? Clock::now() : Clock::time_point{};
    world_.sense_ahead(t_us_);
    if (profiled_) sensing_s_ += std::chrono::duration<double>(Clock::now() - start).count();
    t_us_ += period_us_;
    state_ = period_us_;
  }
  void external_transition(TimeUs elapsed_us) override { state_ -= elapsed_us; }
  void output() override {}
  void set_profile(bool on) { profiled_ = on; }
  double sensing_s() const { return sensing_s_; }

 private:
  environment::World& world_;
  TimeUs period_us_;
  TimeUs t_us_;  // the instant of the next sweep
  bool profiled_ = false;
  double sensing_s_ = 0.0;
};

}  // namespace rilbed::run

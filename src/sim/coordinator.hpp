// The root coordinator: runs a DEVS model (flattened) against a clock.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/worker_pool.hpp"
#include "sim/atomic.hpp"
#include "sim/clock.hpp"
#include "sim/coupled.hpp"
#include "sim/event_heap.hpp"

namespace rilbed::sim {

/// An exception thrown by a model (or a broken time advance), wrapped with the path of
/// the atomic and the simulated time. The coordinator is unusable afterwards.
class ModelError : public std::runtime_error {
 public:
  ModelError(std::string model_path, const std::string& message)
      : std::runtime_error(message), model_path_(std::move(model_path)) {}
  /// Path of the atomic that failed ("top/mid/proc").
  const std::string& model_path() const { return model_path_; }

 private:
  std::string model_path_;
};

/// What one step did, for per-step observers.
struct StepReport {
  TimeUs t_us;                            ///< simulated time of the step
  std::span<Atomic* const> transitioned;  ///< atomics that changed state, flat order
};

/// Runs a model: the root is flattened once, at construction, into atomics in
/// depth-first insertion order ("flat order"), and every atomic output port (and root
/// input port) is resolved to the atomic input ports and root output ports it reaches
/// through any chain of couplings (each destination once). The model's structure must
/// not change afterwards.
///
/// One step at time t (the earliest next-event time, or the clock's time when an
/// external event arrives first): output() of the imminent atomics that have output ports, in flat order;
/// messages routed (a bag keeps the order: sender in flat order, port, message);
/// injected messages delivered; root-output listeners called; then each influenced or
/// imminent atomic in flat order gets its confluent, internal or external transition;
/// bags are cleared and the schedule updated; step observers are called. With a
/// FastClock nothing depends on wall time, so runs are reproducible.
///
/// Worker threads (set_workers): in a step, each run of consecutive active atomics (in
/// flat order) whose transitions_concurrent() is true has its transitions spread over
/// the pool's threads; everything else stays on the running thread and in flat order.
/// Since such models do not depend on each other's transitions, the run's results are
/// the same for any number of threads. (Not after a model error: the other threads'
/// models of that step may have made their transitions, which on one thread they would
/// not have; the run is over then, and what it left is not compared.)
///
/// Threading: run_until(), step() and the registration calls belong to one thread;
/// inject(), stop() and now_us() may be called from any thread. Listeners and
/// observers run on the running thread.
class Coordinator {
 public:
  /// Takes shared ownership of `root` (an Atomic or a Coupled) and borrows `clock`,
  /// which must outlive the coordinator. Initialises every atomic at simulated time 0
  /// (calls time_advance()). Throws std::invalid_argument for a null root or a
  /// component that is neither atomic nor coupled, ModelError for a bad time advance.
  Coordinator(std::shared_ptr<Component> root, Clock& clock);
  ~Coordinator();
  Coordinator(const Coordinator&) = delete;
  Coordinator& operator=(const Coordinator&) = delete;

  /// Runs every event with time <= t_end_us, pacing through the clock (started at
  /// now_us()), then leaves now_us() at t_end_us (unless t_end_us is kInfinity).
  /// Returns early after stop() or when the clock stops. Throws ModelError when a model
  /// throws, std::invalid_argument when t_end_us < now_us().
  void run_until(TimeUs t_end_us);
  /// Performs the next step (the next internal event, or pending injected messages),
  /// waiting for it through the clock (started at now_us(), like run_until). Returns false when stopped, or when there
  /// is no event at all and the clock does not block (a FastClock). Throws like run_until().
  bool step();
  /// Ends the current run_until()/step() soon and makes later ones return at once
  /// (sticky). Thread-safe.
  void stop();
  /// True once stop() was called. Thread-safe.
  bool stopped() const { return stop_requested_.load(); }

  /// Simulated time of the last step (or the end of the last run_until). Thread-safe.
  TimeUs now_us() const { return now_us_.load(std::memory_order_relaxed); }
  /// The earliest scheduled internal event, or kInfinity.
  TimeUs next_event_us() const { return schedule_.top_time_us(); }
  /// The atomics in flat order (non-owning; they live as long as the root).
  const std::vector<Atomic*>& atomics() const { return atomics_; }

  /// Delivers `message` on `root_input` (an input port of the root) as an external
  /// event at the current simulated time (the clock's now, kept between the last step
  /// and the next scheduled event), waking a waiting clock. Messages injected
  /// before one step are delivered together, in injection order. Thread-safe. Throws
  /// std::invalid_argument when the port is not a root input.
  template <class T>
  void inject(Port<T>& root_input, T message) {
    check_root_port(root_input, PortDirection::kInput);
    {
      std::lock_guard lock(injections_mutex_);
      injections_.push_back(
          [&root_input, message = std::move(message)]() mutable { root_input.add(std::move(message)); });
    }
    has_injections_.store(true, std::memory_order_release);
    clock_.notify();
  }

  /// Calls `listener(t_us, messages)` for every step in which `root_output` (an output
  /// port of the root) carries messages. Listeners run in registration order. Throws
  /// std::invalid_argument when the port is not a root output.
  template <class T>
  void on_output(Port<T>& root_output, std::function<void(TimeUs t_us, const std::vector<T>& messages)> listener) {
    check_root_port(root_output, PortDirection::kOutput);
    output_listeners_.push_back({&root_output, [&root_output, listener = std::move(listener)](TimeUs t_us) {
                                   listener(t_us, root_output.messages());
                                 }});
  }

  /// Calls `observer` after every step (after all transitions of that step).
  void on_step(std::function<void(const StepReport&)> observer);

  /// Runs concurrent transitions on `pool` from now on (null: all on the running thread).
  /// The pool must outlive the coordinator's runs.
  void set_workers(core::WorkerPool* pool) { workers_ = pool; }

 private:
  static constexpr std::size_t kNotAtomic = static_cast<std::size_t>(-1);
  // A step is "bulk" when at least 1/kBulkShare of the atomics take part (see do_step).
  static constexpr std::size_t kBulkShare = 8;
  // In bulk steps, how many models ahead of the one transitioning Atomic::prefetch(1) is
  // called; prefetch(0) twice as far, the model's own bytes three times as far.
  static constexpr std::size_t kPrefetchAhead = 4;
  struct Destination {
    PortBase* port;
    std::size_t atomic;  // flat index of the owner, or kNotAtomic for a root output
  };
  struct Route {
    PortBase* source;
    std::vector<Destination> destinations;
  };
  struct Slot {
    Atomic* model;
    std::vector<Route> outputs;  // one per output port, declaration order
    TimeUs last_t_us = 0;
    bool concurrent = false;         // model->transitions_concurrent(), asked once
    std::size_t prefetch_bytes = 0;  // model->prefetch_bytes(), asked once
  };
  struct OutputListener {
    PortBase* port;
    std::function<void(TimeUs)> call;
  };
  enum class Progress { kStepped, kLimitReached, kStopped };

  void check_root_port(const PortBase& port, PortDirection direction) const;
  void check_usable() const;
  Progress advance(TimeUs t_limit_us);
  void do_step(TimeUs t_us);
  void transition(std::size_t index, TimeUs t_us);
  void transitions(TimeUs t_us, bool bulk);
  void settle(std::size_t k, TimeUs t_us, TimeUs next_us, bool bulk);
  // In a bulk step, before transitioning active_[k] (whose run of models ends at `end`):
  // the hints for the models 1, 2 and 3 times kPrefetchAhead ahead.
  void prefetch_ahead(std::size_t k, std::size_t end) const;
  void route(const Route& route);
  void deliver_injections();
  TimeUs next_time(std::size_t index, TimeUs t_us) const;

  std::shared_ptr<Component> root_;
  Clock& clock_;
  bool root_is_atomic_ = false;
  std::vector<Atomic*> atomics_;
  std::vector<Slot> slots_;
  std::vector<Route> root_input_routes_;  // declaration order
  detail::EventHeap schedule_;
  // Per slot, apart from the slots (a byte each: the passes of a step over every imminent
  // model read only these, 100 KB at 100,000 models rather than their 5.6 MB of slots).
  static constexpr std::uint8_t kImminent = 1, kInfluenced = 2, kHasOutputs = 4;
  std::vector<std::uint8_t> marks_;
  std::vector<std::size_t> emitting_;    // scratch: the imminent indices with output ports, flat order
  std::vector<std::size_t> active_;      // scratch: imminent then influenced indices
  std::vector<Atomic*> transitioned_;    // scratch for StepReport
  core::WorkerPool* workers_ = nullptr;  // runs concurrent transitions, when set
  std::vector<TimeUs> next_times_;       // scratch: next event time of active_[k]
  std::vector<OutputListener> output_listeners_;
  std::vector<std::function<void(const StepReport&)>> step_observers_;
  std::atomic<TimeUs> now_us_{0};
  std::atomic<bool> stop_requested_{false};
  bool failed_ = false;

  std::mutex injections_mutex_;
  std::vector<std::function<void()>> injections_;  // guarded by injections_mutex_
  std::vector<std::function<void()>> delivering_;  // run thread only
  std::atomic<bool> has_injections_{false};
};

}  // namespace rilbed::sim

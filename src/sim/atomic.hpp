// Atomic DEVS models (Parallel DEVS): explicit state, time advance, transitions, output.
#pragma once

#include <cstddef>
#include <string>
#include <utility>

#include "sim/component.hpp"
#include "sim/time.hpp"

namespace rilbed::sim {

/// An atomic Parallel DEVS model. The coordinator calls, at each instant t where the
/// model is imminent (its time advance has run out) or receives input:
///  - output() first, for imminent models only, before any transition at t;
///  - then exactly one of internal_transition() (imminent, no input),
///    external_transition(elapsed_us) (input, not imminent) or
///    confluent_transition(elapsed_us) (both);
///  - then time_advance() for the next event.
/// Typical use: declare ports as reference members initialised with
/// add_input<T>("name") / add_output<T>("name") in the constructor.
/// Models know no absolute time: only durations. Not thread-safe (the coordinator's
/// thread calls everything), except that a model whose transitions_concurrent() is true
/// may have its transitions run on a worker thread at the same time as other such
/// models' (Coordinator::set_workers).
class Atomic : public Component {
 public:
  using Component::Component;

  /// Time from the last transition to the next internal event, in microseconds;
  /// >= 0, or kInfinity when passive. A negative value is a model error.
  virtual TimeUs time_advance() const = 0;
  /// The internal transition (δint), when the time advance has run out.
  virtual void internal_transition() = 0;
  /// The external transition (δext): reads the bags of the input ports; `elapsed_us`
  /// is the time since the last transition (0 <= elapsed_us <= time_advance()).
  virtual void external_transition(TimeUs elapsed_us) = 0;
  /// The confluent transition (δcon), when input arrives exactly as the time advance
  /// runs out; `elapsed_us` equals the time advance. Default: internal_transition()
  /// then external_transition(0).
  virtual void confluent_transition(TimeUs elapsed_us);
  /// The output function (λ), called just before an internal or confluent transition:
  /// writes messages to the output ports and must not change the state.
  virtual void output() = 0;
  /// Whether this model's transitions may run at the same time as those of other models
  /// that say so, in the same step: they touch only the model's own state and data that
  /// no other such model writes, and their result does not depend on which of them runs
  /// first. Default false (always run on the coordinator's thread, in flat order). Asked
  /// once, when the coordinator is built: the answer must not change.
  virtual bool transitions_concurrent() const { return false; }
  /// A hint, in a step where many models transition: ask the CPU for
  /// (__builtin_prefetch) the memory the transition will touch, so that it arrives while
  /// the models before it run. Called twice before the transition: `round` 0 some models
  /// ahead (the model's own lines have been asked for already, see prefetch_bytes: ask for
  /// what its pointers point to), then `round` 1 nearer (what was asked for in round 0 has
  /// arrived: ask for what that points to). Must not change anything and must cost next
  /// to nothing. Default: nothing. (A swarm's agents each sit on their own page of
  /// memory, where the CPU's own prefetcher does not follow: the first touch of each
  /// was a cache miss that stalled the step, and so was reading a cold model to ask it.)
  virtual void prefetch([[maybe_unused]] int round) const {}
  /// How many bytes from its own address (`this`) the coordinator asks the CPU for, by
  /// address alone, before prefetch(0). Asked once, when the coordinator is built.
  /// Default 0 (nothing).
  virtual std::size_t prefetch_bytes() const { return 0; }
};

/// An atomic model whose whole state is one value of type State, so that tests,
/// recorders and displays can read it (state()) without knowing the model.
template <class State>
class AtomicModel : public Atomic {
 public:
  AtomicModel(std::string id, State initial_state) : Atomic(std::move(id)), state_(std::move(initial_state)) {}

  /// The current state (read-only; valid until the next transition).
  const State& state() const { return state_; }

 protected:
  /// The state, changed only by the transitions of the derived model.
  State state_;
};

}  // namespace rilbed::sim

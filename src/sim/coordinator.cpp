// The root coordinator. Per-event work is kept to flat arrays: routes are resolved
// once at construction, the schedule is an indexed heap, and scratch vectors are reused.
#include "sim/coordinator.hpp"

#include <algorithm>
#include <unordered_map>
#include <unordered_set>

namespace rilbed::sim {

namespace {

// Lookups only (never iterated), so hashing does not affect any order.
using CouplingsFrom = std::unordered_map<const PortBase*, std::vector<PortBase*>>;

void flatten(Component& component, std::vector<Atomic*>& atomics, CouplingsFrom& couplings_from) {
  if (auto* atomic = dynamic_cast<Atomic*>(&component)) {
    atomics.push_back(atomic);
    return;
  }
  auto* coupled = dynamic_cast<Coupled*>(&component);
  if (!coupled) throw std::invalid_argument("sim: '" + component.path() + "' is neither Atomic nor Coupled");
  for (const auto& coupling : coupled->couplings()) couplings_from[coupling.from].push_back(coupling.to);
  for (const auto& child : coupled->children()) flatten(*child, atomics, couplings_from);
}

template <class Body>
void guarded(const Atomic& model, const char* what, TimeUs t_us, Body&& body) {
  const auto wrap = [&](const std::string& why) {
    return ModelError(model.path(), "sim: model '" + model.path() + "' failed in " + what +
                                        " at t=" + std::to_string(t_us) + " us: " + why);
  };
  try {
    body();
  } catch (const ModelError&) {
    throw;
  } catch (const std::exception& error) {
    throw wrap(error.what());
  } catch (...) {
    throw wrap("unknown exception");
  }
}

}  // namespace

Coordinator::Coordinator(std::shared_ptr<Component> root, Clock& clock) : root_(std::move(root)), clock_(clock) {
  if (!root_) throw std::invalid_argument("sim: the coordinator needs a root model");
  CouplingsFrom couplings_from;
  flatten(*root_, atomics_, couplings_from);
  root_is_atomic_ = dynamic_cast<Atomic*>(root_.get()) != nullptr;

  std::unordered_map<const Component*, std::size_t> flat_index;  // lookups only
  for (std::size_t i = 0; i < atomics_.size(); ++i) flat_index.emplace(atomics_[i], i);

  // Follows couplings depth-first in the order they were made; a coupled model's port
  // is a relay, an atomic's input or a root output ends the chain. Each destination
  // is kept once even when several chains reach it (couplings form a set).
  const auto resolve = [&](PortBase& source) {
    Route route{&source, {}};
    std::unordered_set<const PortBase*> seen;  // lookups only
    const auto follow = [&](const PortBase& port, const auto& self) -> void {
      const auto found = couplings_from.find(&port);
      if (found == couplings_from.end()) return;
      for (PortBase* to : found->second) {
        if (!seen.insert(to).second) continue;
        if (const auto atomic = flat_index.find(&to->owner()); atomic != flat_index.end())
          route.destinations.push_back({to, atomic->second});
        else if (&to->owner() == root_.get())
          route.destinations.push_back({to, kNotAtomic});
        else
          self(*to, self);
      }
    };
    follow(source, follow);
    return route;
  };

  slots_.reserve(atomics_.size());
  for (Atomic* atomic : atomics_) {
    Slot slot{atomic, {}};
    slot.concurrent = atomic->transitions_concurrent();
    slot.prefetch_bytes = atomic->prefetch_bytes();
    for (const auto& port : atomic->outputs()) slot.outputs.push_back(resolve(*port));
    marks_.push_back(slot.outputs.empty() ? 0 : kHasOutputs);
    slots_.push_back(std::move(slot));
  }
  for (const auto& port : root_->inputs())
    root_input_routes_.push_back(root_is_atomic_ ? Route{port.get(), {}} : resolve(*port));

  std::vector<TimeUs> first_times_us(atomics_.size());
  for (std::size_t i = 0; i < atomics_.size(); ++i) first_times_us[i] = next_time(i, 0);
  schedule_.assign(std::move(first_times_us));
}

Coordinator::~Coordinator() = default;

void Coordinator::on_step(std::function<void(const StepReport&)> observer) {
  step_observers_.push_back(std::move(observer));
}

void Coordinator::check_root_port(const PortBase& port, PortDirection direction) const {
  if (&port.owner() != root_.get() || port.direction() != direction)
    throw std::invalid_argument("sim: " + port.describe() + " is not an " +
                                (direction == PortDirection::kInput ? "input" : "output") +
                                " port of the root model '" + root_->path() + "'");
}

void Coordinator::check_usable() const {
  if (failed_) throw std::logic_error("sim: the coordinator cannot go on after a model error");
}

void Coordinator::stop() {
  stop_requested_.store(true);
  clock_.notify();
}

void Coordinator::run_until(TimeUs t_end_us) {
  check_usable();
  if (t_end_us < now_us())
    throw std::invalid_argument("sim: run_until(" + std::to_string(t_end_us) + " us) is before the current time " +
                                std::to_string(now_us()) + " us");
  clock_.start(now_us());
  try {
    while (advance(t_end_us) == Progress::kStepped) {}
  } catch (...) {
    failed_ = true;
    throw;
  }
}

bool Coordinator::step() {
  check_usable();
  clock_.start(now_us());
  try {
    return advance(kInfinity) == Progress::kStepped;
  } catch (...) {
    failed_ = true;
    throw;
  }
}

Coordinator::Progress Coordinator::advance(TimeUs t_limit_us) {
  for (;;) {
    if (stop_requested_.load()) return Progress::kStopped;
    const TimeUs t_next_us = schedule_.top_time_us();
    const TimeUs target_us = std::min(t_next_us, t_limit_us);
    if (has_injections_.load(std::memory_order_acquire)) {
      // External events happen "now", but never before the last step nor after the
      // next scheduled event (a late wake-up must not skip it).
      do_step(std::clamp(clock_.now_us(), now_us(), target_us));
      return Progress::kStepped;
    }
    switch (clock_.wait_until(target_us)) {
      case WaitResult::kStopped: return Progress::kStopped;
      case WaitResult::kWoken: continue;  // an injection or stop(): the checks above decide
      case WaitResult::kReached:
        if (t_next_us <= t_limit_us && t_next_us != kInfinity) {
          do_step(t_next_us);
          return Progress::kStepped;
        }
        if (t_limit_us != kInfinity) now_us_.store(t_limit_us, std::memory_order_relaxed);
        return Progress::kLimitReached;
    }
  }
}

TimeUs Coordinator::next_time(std::size_t index, TimeUs t_us) const {
  const Atomic& model = *atomics_[index];
  TimeUs advance_us = 0;
  guarded(model, "time_advance", t_us, [&] { advance_us = model.time_advance(); });
  if (advance_us < 0)
    throw ModelError(model.path(), "sim: model '" + model.path() + "' returned a negative time advance (" +
                                       std::to_string(advance_us) + " us) at t=" + std::to_string(t_us) + " us");
  return advance_us > kInfinity - t_us ? kInfinity : t_us + advance_us;
}

void Coordinator::route(const Route& route) {
  if (route.source->empty()) return;
  for (const Destination& destination : route.destinations) {
    destination.port->append_from(*route.source);
    if (destination.atomic == kNotAtomic) continue;
    std::uint8_t& marks = marks_[destination.atomic];
    if (marks & kInfluenced) continue;
    marks |= kInfluenced;
    if (!(marks & kImminent)) active_.push_back(destination.atomic);  // imminent ones are listed
  }
}

void Coordinator::deliver_injections() {
  {
    std::lock_guard lock(injections_mutex_);
    delivering_.swap(injections_);
    has_injections_.store(false, std::memory_order_relaxed);
  }
  for (auto& deliver : delivering_) deliver();
  delivering_.clear();
  for (const Route& root_input : root_input_routes_) {
    if (root_input.source->empty()) continue;
    if (root_is_atomic_) {
      // The root's input is the atomic's own input: nothing to copy, nothing to clear.
      std::uint8_t& marks = marks_[0];
      if (!(marks & (kInfluenced | kImminent))) active_.push_back(0);
      marks |= kInfluenced;
    } else {
      route(root_input);
      root_input.source->clear();
    }
  }
}

void Coordinator::transition(std::size_t index, TimeUs t_us) {
  Slot& slot = slots_[index];
  Atomic& model = *slot.model;
  const TimeUs elapsed_us = t_us - slot.last_t_us;
  const std::uint8_t marks = marks_[index];
  if ((marks & kImminent) && (marks & kInfluenced))
    guarded(model, "confluent_transition", t_us, [&] { model.confluent_transition(elapsed_us); });
  else if (marks & kImminent)
    guarded(model, "internal_transition", t_us, [&] { model.internal_transition(); });
  else
    guarded(model, "external_transition", t_us, [&] { model.external_transition(elapsed_us); });
}

void Coordinator::settle(std::size_t k, TimeUs t_us, TimeUs next_us, bool bulk) {
  const std::size_t index = active_[k];
  Slot& slot = slots_[index];
  Atomic& model = *slot.model;
  if (marks_[index] & kInfluenced)
    for (const auto& input : model.inputs()) input->clear();
  marks_[index] &= kHasOutputs;
  slot.last_t_us = t_us;
  if (bulk)
    schedule_.set_time_unordered(index, next_us);  // distinct items: safe from several threads
  else
    schedule_.update(index, next_us);
  transitioned_[k] = &model;
}

void Coordinator::prefetch_ahead(std::size_t k, std::size_t end) const {
  // In stages, each far enough ahead for the last to have arrived: the model's own lines
  // by address alone (the models of a swarm are cold, and reading one to ask it
  // stalls); then the model, reading its own pointers (now in cache); then again, for
  // what those pointed to.
  if (k + 3 * kPrefetchAhead < end) {
    const Slot& far = slots_[active_[k + 3 * kPrefetchAhead]];
    const char* bytes = reinterpret_cast<const char*>(far.model);
    for (std::size_t offset = 0; offset < far.prefetch_bytes; offset += 64) __builtin_prefetch(bytes + offset, 1);
  }
  if (k + 2 * kPrefetchAhead < end) slots_[active_[k + 2 * kPrefetchAhead]].model->prefetch(0);
  if (k + kPrefetchAhead < end) slots_[active_[k + kPrefetchAhead]].model->prefetch(1);
}

void Coordinator::transitions(TimeUs t_us, bool bulk) {
  const std::size_t n = active_.size();
  transitioned_.resize(n);
  next_times_.resize(n);
  for (std::size_t k = 0; k < n;) {
    std::size_t end = k;
    if (workers_ && workers_->threads() > 1)
      while (end < n && slots_[active_[end]].concurrent) ++end;
    if (end - k < 2) {
      if (bulk) prefetch_ahead(k, n);
      transition(active_[k], t_us);  // flat order, this thread
      settle(k, t_us, next_time(active_[k], t_us), bulk);
      ++k;
      continue;
    }
    // A run of concurrent models: split over the workers, each model's bookkeeping with
    // it when the schedule is re-keyed in bulk. The pool rethrows the lowest chunk's
    // error, which is the first in flat order among the chunks that failed.
    const std::size_t first = k;
    workers_->for_chunks(end - first, [&](std::size_t b, std::size_t e) {
      for (std::size_t j = first + b; j < first + e; ++j) {
        if (bulk) prefetch_ahead(j, first + e);
        transition(active_[j], t_us);
        next_times_[j] = next_time(active_[j], t_us);
        if (bulk) settle(j, t_us, next_times_[j], true);
      }
    });
    if (!bulk)
      for (std::size_t j = first; j < end; ++j) settle(j, t_us, next_times_[j], false);
    k = end;
  }
}

void Coordinator::do_step(TimeUs t_us) {
  active_.clear();
  // Many due at once (at least 1/kBulkShare of the atomics: every agent of a swarm at a
  // control instant): list them in flat order by one pass over all rather than walking
  // the heap and sorting, and re-key them all with one O(n) reheap rather than a sift
  // each (a sift per agent was half of the kernel's time at 10,000 robots). The heap
  // walk stops as soon as the step is known to be bulk.
  const std::size_t most_not_bulk = (slots_.size() + kBulkShare - 1) / kBulkShare - 1;
  const bool bulk = !schedule_.collect_at(t_us, active_, most_not_bulk);
  if (bulk) {
    active_.clear();
    schedule_.collect_all_at(t_us, active_);
  } else {
    std::sort(active_.begin(), active_.end());
  }
  const std::size_t imminent_count = active_.size();

  // Parallel DEVS: every imminent output is collected before any transition.
  emitting_.clear();
  for (std::size_t i = 0; i < imminent_count; ++i) {
    std::uint8_t& marks = marks_[active_[i]];
    marks |= kImminent;
    // A model without output ports has nothing to output (output() must not change its
    // state): not calling it spares a swarm's agents a visit each.
    if (marks & kHasOutputs) emitting_.push_back(active_[i]);
  }
  for (const std::size_t index : emitting_) {
    Atomic& model = *slots_[index].model;
    guarded(model, "output", t_us, [&] { model.output(); });
  }
  for (const std::size_t index : emitting_)
    for (const Route& output : slots_[index].outputs) route(output);
  if (has_injections_.load(std::memory_order_acquire)) deliver_injections();

  for (const OutputListener& listener : output_listeners_)
    if (!listener.port->empty()) listener.call(t_us);
  for (const std::size_t index : emitting_)
    for (const Route& output : slots_[index].outputs) output.source->clear();
  for (const auto& port : root_->outputs()) port->clear();

  // Influenced atomics were appended after the imminent ones: restore flat order (the
  // imminent ones are sorted already, so with no message in flight there is nothing to do).
  if (active_.size() > imminent_count) std::sort(active_.begin(), active_.end());
  transitions(t_us, bulk);
  if (bulk) schedule_.reheap();
  now_us_.store(t_us, std::memory_order_relaxed);

  if (!step_observers_.empty()) {
    const StepReport report{t_us, transitioned_};
    for (const auto& observer : step_observers_) observer(report);
  }
}

}  // namespace rilbed::sim

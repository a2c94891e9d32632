// Small DEVS models shared by the sim tests: generator -> processor -> sink, with an
// event log that every model appends to.
#pragma once

#include <deque>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "sim/atomic.hpp"

namespace rilbed::sim::testing {

/// What the models did, in call order ("gen:out 1", "proc:ext e=100 [1]", ...).
using EventLog = std::vector<std::string>;

inline std::string join(const std::vector<int>& values) {
  std::string text = "[";
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i) text += ',';
    text += std::to_string(values[i]);
  }
  return text + "]";
}

struct GeneratorState {
  int sent = 0;
};

/// Emits base+1, base+2, ..., base+count on "out", one every period_us (the first at
/// period_us).
class Generator : public AtomicModel<GeneratorState> {
 public:
  Generator(std::string id, TimeUs period_us, int count, std::shared_ptr<EventLog> log = nullptr, int base = 0)
      : AtomicModel(std::move(id), {}),
        out(add_output<int>("out")),
        period_us_(period_us),
        count_(count),
        base_(base),
        log_(std::move(log)) {}

  Port<int>& out;

  TimeUs time_advance() const override { return state_.sent < count_ ? period_us_ : kInfinity; }
  void output() override {
    out.add(base_ + state_.sent + 1);
    note("out " + std::to_string(base_ + state_.sent + 1));
  }
  void internal_transition() override {
    ++state_.sent;
    note("int");
  }
  void external_transition(TimeUs) override { note("ext?"); }

 private:
  void note(const std::string& what) {
    if (log_) log_->push_back(id() + ":" + what);
  }
  TimeUs period_us_;
  int count_;
  int base_;
  std::shared_ptr<EventLog> log_;
};

struct ProcessorState {
  std::deque<int> queue;
  TimeUs remaining_us = kInfinity;  // until the job at the front is done
};

/// A FIFO server: each job takes service_us; a finished job leaves on "out".
class Processor : public AtomicModel<ProcessorState> {
 public:
  Processor(std::string id, TimeUs service_us, std::shared_ptr<EventLog> log = nullptr)
      : AtomicModel(std::move(id), {}),
        in(add_input<int>("in")),
        out(add_output<int>("out")),
        service_us_(service_us),
        log_(std::move(log)) {}

  Port<int>& in;
  Port<int>& out;

  TimeUs time_advance() const override { return state_.remaining_us; }
  void output() override {
    out.add(state_.queue.front());
    note("out " + std::to_string(state_.queue.front()));
  }
  void internal_transition() override {
    state_.queue.pop_front();
    state_.remaining_us = state_.queue.empty() ? kInfinity : service_us_;
    note("int");
  }
  void external_transition(TimeUs elapsed_us) override {
    note("ext e=" + std::to_string(elapsed_us) + " " + join(in.messages()));
    if (state_.queue.empty())
      state_.remaining_us = service_us_;
    else
      state_.remaining_us -= elapsed_us;
    for (int job : in.messages()) state_.queue.push_back(job);
  }
  void confluent_transition(TimeUs elapsed_us) override {
    note("conf e=" + std::to_string(elapsed_us));
    Atomic::confluent_transition(elapsed_us);  // the default: internal, then external(0)
  }

 private:
  void note(const std::string& what) {
    if (log_) log_->push_back(id() + ":" + what);
  }
  TimeUs service_us_;
  std::shared_ptr<EventLog> log_;
};

struct SinkState {
  TimeUs local_t_us = 0;  // sum of elapsed times: the absolute time of the last input
  std::vector<std::pair<TimeUs, int>> received;
};

/// Passive; records (time, message) for every input, time being the sum of the
/// elapsed times it was given.
class Sink : public AtomicModel<SinkState> {
 public:
  explicit Sink(std::string id, std::shared_ptr<EventLog> log = nullptr)
      : AtomicModel(std::move(id), {}), in(add_input<int>("in")), log_(std::move(log)) {}

  Port<int>& in;

  TimeUs time_advance() const override { return kInfinity; }
  void output() override {}
  void internal_transition() override {}
  void external_transition(TimeUs elapsed_us) override {
    state_.local_t_us += elapsed_us;
    for (int value : in.messages()) state_.received.emplace_back(state_.local_t_us, value);
    if (log_) log_->push_back(id() + ":ext e=" + std::to_string(elapsed_us) + " " + join(in.messages()));
  }

 private:
  std::shared_ptr<EventLog> log_;
};

}  // namespace rilbed::sim::testing

// The coordinator: event times, Parallel DEVS ordering, ties, injection, errors,
// determinism and scale.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "sim/coordinator.hpp"
#include "support/eventually.hpp"
#include "test_models.hpp"

using namespace rilbed::sim;
using namespace rilbed::sim::testing;
using rilbed::TimeUs;

namespace {

using rilbed::testing::eventually;

constexpr TimeUs kMs = 1000;
using Received = std::vector<std::pair<TimeUs, int>>;

/// gen -> proc -> sink, all logging to one log.
struct Chain {
  std::shared_ptr<EventLog> log = std::make_shared<EventLog>();
  std::shared_ptr<Coupled> top = std::make_shared<Coupled>("top");
  Generator* gen;
  Processor* proc;
  Sink* sink;

  Chain(TimeUs period_us, int count, TimeUs service_us) {
    gen = &top->emplace<Generator>("gen", period_us, count, log);
    proc = &top->emplace<Processor>("proc", service_us, log);
    sink = &top->emplace<Sink>("sink", log);
    top->couple(gen->out, proc->in);
    top->couple(proc->out, sink->in);
  }
  /// Marks the end of every step in the log with "@<t_us>".
  void mark_steps(Coordinator& coordinator) {
    coordinator.on_step([log = log](const StepReport& report) { log->push_back("@" + std::to_string(report.t_us)); });
  }
};

}  // namespace

TEST(Coordinator, ChainEventTimesMatchHandComputation) {
  // Jobs at 100, 200, 300 ms; 150 ms each, FIFO: done at 250, 400, 550 ms.
  Chain chain(100 * kMs, 3, 150 * kMs);
  FastClock clock;
  Coordinator coordinator(chain.top, clock);
  chain.mark_steps(coordinator);
  coordinator.run_until(1000 * kMs);
  EXPECT_EQ(chain.sink->state().received, (Received{{250 * kMs, 1}, {400 * kMs, 2}, {550 * kMs, 3}}));
  EXPECT_EQ(*chain.log, (EventLog{
                            "gen:out 1",  "gen:int",  "proc:ext e=100000 [1]", "@100000",
                            "gen:out 2",  "gen:int",  "proc:ext e=100000 [2]", "@200000",
                            "proc:out 1", "proc:int", "sink:ext e=250000 [1]", "@250000",
                            "gen:out 3",  "gen:int",  "proc:ext e=50000 [3]",  "@300000",
                            "proc:out 2", "proc:int", "sink:ext e=150000 [2]", "@400000",
                            "proc:out 3", "proc:int", "sink:ext e=150000 [3]", "@550000",
                        }));
  EXPECT_EQ(coordinator.now_us(), 1000 * kMs);
  EXPECT_EQ(coordinator.next_event_us(), kInfinity);
  EXPECT_TRUE(chain.proc->state().queue.empty());
}

TEST(Coordinator, ConfluentWhenInputArrivesAsTimeAdvanceRunsOut) {
  // Service time equals the period: each new job arrives as the last one finishes.
  Chain chain(100 * kMs, 3, 100 * kMs);
  FastClock clock;
  Coordinator coordinator(chain.top, clock);
  chain.mark_steps(coordinator);
  coordinator.run_until(1000 * kMs);
  EXPECT_EQ(chain.sink->state().received, (Received{{200 * kMs, 1}, {300 * kMs, 2}, {400 * kMs, 3}}));
  // All outputs of an instant come before its transitions; confluent gets the elapsed
  // time (= time advance) and by default runs internal, then external with 0.
  EXPECT_EQ(*chain.log, (EventLog{
                            "gen:out 1",
                            "gen:int",
                            "proc:ext e=100000 [1]",
                            "@100000",
                            "gen:out 2",
                            "proc:out 1",
                            "gen:int",
                            "proc:conf e=100000",
                            "proc:int",
                            "proc:ext e=0 [2]",
                            "sink:ext e=200000 [1]",
                            "@200000",
                            "gen:out 3",
                            "proc:out 2",
                            "gen:int",
                            "proc:conf e=100000",
                            "proc:int",
                            "proc:ext e=0 [3]",
                            "sink:ext e=100000 [2]",
                            "@300000",
                            "proc:out 3",
                            "proc:int",
                            "sink:ext e=100000 [3]",
                            "@400000",
                        }));
}

TEST(Coordinator, TiesFollowInsertionOrderNotNames) {
  auto top = std::make_shared<Coupled>("top");
  auto log = std::make_shared<EventLog>();
  auto& c = top->emplace<Generator>("c", 100, 1, log, 300);
  auto& a = top->emplace<Generator>("a", 100, 1, log, 100);
  auto& b = top->emplace<Generator>("b", 100, 1, log, 200);
  auto& sink = top->emplace<Sink>("sink", log);
  for (Generator* gen : {&a, &b, &c}) top->couple(gen->out, sink.in);  // coupling order a, b, c
  FastClock clock;
  Coordinator coordinator(top, clock);
  std::vector<std::string> transitioned;
  coordinator.on_step([&](const StepReport& report) {
    for (const Atomic* atomic : report.transitioned) transitioned.push_back(atomic->id());
  });
  coordinator.run_until(1000);
  EXPECT_EQ(*log, (EventLog{"c:out 301", "a:out 101", "b:out 201", "c:int", "a:int", "b:int",
                            "sink:ext e=100 [301,101,201]"}));
  EXPECT_EQ(transitioned, (std::vector<std::string>{"c", "a", "b", "sink"}));
}

TEST(Coordinator, StepAdvancesOneInstantAtATime) {
  Chain chain(100, 2, 30);
  FastClock clock;
  Coordinator coordinator(chain.top, clock);
  std::vector<TimeUs> times;
  while (coordinator.step()) times.push_back(coordinator.now_us());
  EXPECT_EQ(times, (std::vector<TimeUs>{100, 130, 200, 230}));
  EXPECT_FALSE(coordinator.step());
}

TEST(Coordinator, RunInPiecesEqualsOneRun) {
  Chain whole(70, 5, 45);
  Chain pieces(70, 5, 45);
  FastClock clock_whole, clock_pieces;
  Coordinator run_whole(whole.top, clock_whole);
  Coordinator run_pieces(pieces.top, clock_pieces);
  run_whole.run_until(1000);
  for (TimeUs t_us : {0, 70, 100, 139, 140, 333, 1000}) run_pieces.run_until(t_us);
  EXPECT_EQ(*whole.log, *pieces.log);
  EXPECT_EQ(whole.sink->state().received, pieces.sink->state().received);
  EXPECT_EQ(whole.sink->state().received.size(), 5u);
  EXPECT_THROW(run_pieces.run_until(999), std::invalid_argument);
}

TEST(Coordinator, InjectedMessagesArriveAtTheCurrentTime) {
  auto top = std::make_shared<Coupled>("top");
  auto& command = top->add_input<int>("command");
  auto& sink = top->emplace<Sink>("sink");
  auto& gen = top->emplace<Generator>("gen", 100, 1);
  top->couple(command, sink.in);
  FastClock clock;
  Coordinator coordinator(top, clock);
  coordinator.inject(command, 7);
  coordinator.inject(command, 8);
  coordinator.run_until(150);
  coordinator.inject(command, 9);
  coordinator.run_until(400);
  EXPECT_EQ(sink.state().received, (Received{{0, 7}, {0, 8}, {150, 9}}));
  EXPECT_TRUE(command.empty());
  EXPECT_THROW(coordinator.inject(sink.in, 1), std::invalid_argument);  // not a root port
  EXPECT_THROW(coordinator.inject(gen.out, 1), std::invalid_argument);
}

TEST(Coordinator, AtomicRootTakesInjectionsAndReportsOutputs) {
  auto proc = std::make_shared<Processor>("proc", 40);
  FastClock clock;
  Coordinator coordinator(proc, clock);
  std::vector<std::pair<TimeUs, std::vector<int>>> outputs;
  coordinator.on_output<int>(
      proc->out, [&](TimeUs t_us, const std::vector<int>& messages) { outputs.emplace_back(t_us, messages); });
  EXPECT_THROW(coordinator.on_output<int>(proc->in, [](TimeUs, const std::vector<int>&) {}), std::invalid_argument);
  coordinator.run_until(10);
  coordinator.inject(proc->in, 5);
  coordinator.run_until(100);
  EXPECT_EQ(outputs, (std::vector<std::pair<TimeUs, std::vector<int>>>{{50, {5}}}));
  EXPECT_TRUE(proc->in.empty());
}

namespace {

struct FailingState {
  int steps = 0;
};
class Failing : public AtomicModel<FailingState> {
 public:
  Failing(std::string id, int fail_at_step, TimeUs bad_advance_us = 10)
      : AtomicModel(std::move(id), {}), fail_at_step_(fail_at_step), bad_advance_us_(bad_advance_us) {}
  TimeUs time_advance() const override { return state_.steps == fail_at_step_ ? bad_advance_us_ : 10; }
  void output() override {}
  void internal_transition() override {
    if (++state_.steps == fail_at_step_ && bad_advance_us_ >= 0) throw std::runtime_error("boom");
  }
  void external_transition(TimeUs) override {}

 private:
  int fail_at_step_;
  TimeUs bad_advance_us_;
};

}  // namespace

TEST(Coordinator, ModelExceptionsCarryTheModelPath) {
  auto top = std::make_shared<Coupled>("top");
  auto& mid = top->emplace<Coupled>("mid");
  mid.emplace<Failing>("bad", 3);
  FastClock clock;
  Coordinator coordinator(top, clock);
  try {
    coordinator.run_until(1000);
    FAIL() << "no exception";
  } catch (const ModelError& error) {
    EXPECT_EQ(error.model_path(), "top/mid/bad");
    const std::string what = error.what();
    EXPECT_NE(what.find("'top/mid/bad' failed in internal_transition at t=30 us: boom"), std::string::npos) << what;
  }
  EXPECT_EQ(coordinator.now_us(), 20);  // the last complete step
  EXPECT_THROW(coordinator.run_until(2000), std::logic_error);
}

TEST(Coordinator, NegativeTimeAdvanceIsAModelError) {
  FastClock clock;
  EXPECT_THROW(Coordinator(std::make_shared<Failing>("initially_bad", 0, -5), clock), ModelError);
  Coordinator coordinator(std::make_shared<Failing>("later_bad", 2, -1), clock);
  EXPECT_THROW(coordinator.run_until(1000), ModelError);
}

TEST(Coordinator, RejectsRootsThatAreNotModels) {
  FastClock clock;
  EXPECT_THROW(Coordinator(nullptr, clock), std::invalid_argument);
  class Neither : public Component {
   public:
    using Component::Component;
  };
  EXPECT_THROW(Coordinator(std::make_shared<Neither>("neither"), clock), std::invalid_argument);
}

namespace {

/// A busier model: two chains with prime periods, a shared sink and an extra fan-in.
EventLog run_busy_model() {
  auto log = std::make_shared<EventLog>();
  auto top = std::make_shared<Coupled>("top");
  auto& g1 = top->emplace<Generator>("g1", 30, 40, log, 0);
  auto& g2 = top->emplace<Generator>("g2", 45, 30, log, 1000);
  auto& g3 = top->emplace<Generator>("g3", 90, 15, log, 2000);
  auto& p1 = top->emplace<Processor>("p1", 25, log);
  auto& p2 = top->emplace<Processor>("p2", 60, log);
  auto& sink = top->emplace<Sink>("sink", log);
  top->couple(g1.out, p1.in);
  top->couple(g2.out, p1.in);
  top->couple(g2.out, p2.in);
  top->couple(g3.out, p2.in);
  top->couple(p1.out, sink.in);
  top->couple(p2.out, sink.in);
  FastClock clock;
  Coordinator coordinator(top, clock);
  coordinator.on_step([&](const StepReport& report) { log->push_back("@" + std::to_string(report.t_us)); });
  coordinator.run_until(10'000);
  return *log;
}

}  // namespace

TEST(Coordinator, FastRunsAreIdentical) {
  const EventLog first = run_busy_model();
  const EventLog second = run_busy_model();
  EXPECT_GT(first.size(), 400u);
  EXPECT_EQ(first, second);
  // 90 us is a three-way tie (g1, g2, g3), right after p1's event at 80 us: the
  // outputs come in flat order.
  const auto g3_first = std::find(first.begin(), first.end(), "g3:out 2001");
  ASSERT_GE(g3_first - first.begin(), 3);
  EXPECT_EQ(*std::prev(g3_first, 3), "@80");
  EXPECT_EQ(*std::prev(g3_first, 2), "g1:out 3");
  EXPECT_EQ(*std::prev(g3_first, 1), "g2:out 1002");
}

TEST(Coordinator, TenThousandAtomicsRun) {
  auto top = std::make_shared<Coupled>("top");
  std::vector<Sink*> sinks;
  for (int i = 0; i < 5000; ++i) {
    // Periods 100 ms and 100 ms + 1 us: two large tie groups per round.
    auto& gen = top->emplace<Generator>("gen" + std::to_string(i), 100 * kMs + i % 2, 10, nullptr, i * 100);
    auto& sink = top->emplace<Sink>("sink" + std::to_string(i));
    top->couple(gen.out, sink.in);
    sinks.push_back(&sink);
  }
  FastClock clock;
  Coordinator coordinator(top, clock);
  ASSERT_EQ(coordinator.atomics().size(), 10'000u);
  std::size_t steps = 0, transitions = 0;
  coordinator.on_step([&](const StepReport& report) {
    ++steps;
    transitions += report.transitioned.size();
  });
  coordinator.run_until(2000 * kMs);
  EXPECT_EQ(steps, 20u);
  EXPECT_EQ(transitions, 10'000u * 10u);
  for (int i = 0; i < 5000; ++i) {
    const auto& received = sinks[i]->state().received;
    ASSERT_EQ(received.size(), 10u) << i;
    for (int k = 0; k < 10; ++k) {
      ASSERT_EQ(received[k].first, (k + 1) * (100 * kMs + i % 2)) << i;
      ASSERT_EQ(received[k].second, i * 100 + k + 1) << i;
    }
  }
}

TEST(Coordinator, RealTimeRunIsPacedAndGivesTheSameResults) {
  Chain fast(50 * kMs, 3, 20 * kMs);
  Chain paced(50 * kMs, 3, 20 * kMs);
  FastClock fast_clock;
  RealTimeClock real_clock(10.0);
  Coordinator fast_run(fast.top, fast_clock);
  Coordinator paced_run(paced.top, real_clock);
  fast_run.run_until(200 * kMs);
  const auto wall_start = std::chrono::steady_clock::now();
  paced_run.run_until(200 * kMs);
  const auto wall_elapsed = std::chrono::steady_clock::now() - wall_start;
  EXPECT_GE(wall_elapsed, std::chrono::milliseconds(20));  // 200 ms simulated at 10x
  EXPECT_LT(wall_elapsed, std::chrono::seconds(2));
  EXPECT_EQ(*fast.log, *paced.log);
  EXPECT_EQ(paced.sink->state().received, (Received{{70 * kMs, 1}, {120 * kMs, 2}, {170 * kMs, 3}}));
  EXPECT_EQ(paced_run.now_us(), 200 * kMs);
}

TEST(Coordinator, InjectFromAnotherThreadWakesARealTimeRun) {
  auto top = std::make_shared<Coupled>("top");
  auto& command = top->add_input<int>("command");
  auto& sink = top->emplace<Sink>("sink");
  top->emplace<Generator>("starter", 10 * kMs, 1);  // one event at 10 ms, then passive
  top->couple(command, sink.in);
  RealTimeClock clock(1.0);
  Coordinator coordinator(top, clock);
  std::atomic<TimeUs> last_step_us{-1};
  std::atomic<int> delivered{0};
  coordinator.on_step([&](const StepReport& report) {
    for (const Atomic* atomic : report.transitioned)
      if (atomic == &sink) delivered.fetch_add(1);
    last_step_us.store(report.t_us);
  });
  std::thread runner([&] { coordinator.run_until(100'000 * kMs); });
  // Once the starter has fired the run has begun and nothing is scheduled: the
  // coordinator sleeps until the injection wakes it.
  ASSERT_TRUE(eventually([&] { return last_step_us.load() == 10 * kMs; }));
  // Asleep in the clock, and well after the last step (so that the delivery's time tells
  // the clock's from the last step's).
  ASSERT_TRUE(eventually([&] { return clock.waiters() == 1 && clock.now_us() >= 30 * kMs; }));
  const TimeUs injected_at_least_us = clock.now_us();
  coordinator.inject(command, 42);
  const bool arrived = eventually([&] { return delivered.load() == 1; });
  coordinator.stop();
  runner.join();
  ASSERT_TRUE(arrived);
  ASSERT_EQ(sink.state().received.size(), 1u);
  EXPECT_EQ(sink.state().received[0].second, 42);
  // Delivered at the clock's time when it woke, not at the last step (10 ms).
  EXPECT_GE(injected_at_least_us, 30 * kMs);
  EXPECT_GE(sink.state().received[0].first, injected_at_least_us);
  EXPECT_LT(sink.state().received[0].first, injected_at_least_us + 5'000 * kMs);
  EXPECT_TRUE(coordinator.stopped());
  EXPECT_FALSE(coordinator.step());  // stop is sticky
}

TEST(Coordinator, StopEndsAnEndlessRealTimeRun) {
  auto sink = std::make_shared<Sink>("idle");  // nothing ever happens
  RealTimeClock clock(1.0);
  Coordinator coordinator(sink, clock);
  const auto wall_start = std::chrono::steady_clock::now();
  std::thread runner([&] { coordinator.run_until(kInfinity); });
  ASSERT_TRUE(eventually([&] { return clock.waiters() == 1; }));  // the run sleeps in its clock
  coordinator.stop();
  runner.join();
  EXPECT_LT(std::chrono::steady_clock::now() - wall_start, std::chrono::seconds(2));
}

TEST(Coordinator, StoppedClockEndsTheRun) {
  Chain chain(100, 100, 10);
  RealTimeClock clock(1.0);
  Coordinator coordinator(chain.top, clock);
  clock.stop();
  coordinator.run_until(1'000'000 * kMs);  // returns at once
  EXPECT_TRUE(chain.sink->state().received.empty());
}

namespace {

// A model that may run concurrently: counts its internal transitions every period, and
// throws at a given count (0: never).
class Ticker final : public AtomicModel<int> {
 public:
  Ticker(std::string id, TimeUs period_us, int throw_at = 0)
      : AtomicModel<int>(std::move(id), 0), period_us_(period_us), throw_at_(throw_at) {}
  TimeUs time_advance() const override { return period_us_; }
  void internal_transition() override {
    ++state_;
    if (state_ == throw_at_) throw std::runtime_error("tick " + std::to_string(state_));
  }
  void external_transition(TimeUs) override {}
  void output() override {}
  bool transitions_concurrent() const override { return true; }

 private:
  TimeUs period_us_;
  int throw_at_;
};

// Not concurrent: at each of its transitions, notes the counts of the tickers before and
// after it in flat order.
class Watcher final : public AtomicModel<int> {
 public:
  explicit Watcher(TimeUs period_us) : AtomicModel<int>("watcher", 0), period_us_(period_us) {}
  void watch(std::vector<const Ticker*> before, std::vector<const Ticker*> after) {
    before_ = std::move(before);
    after_ = std::move(after);
  }
  TimeUs time_advance() const override { return period_us_; }
  void internal_transition() override {
    ++state_;
    for (const Ticker* t : before_) ok_ = ok_ && t->state() == state_;     // already stepped
    for (const Ticker* t : after_) ok_ = ok_ && t->state() == state_ - 1;  // not yet
  }
  void external_transition(TimeUs) override {}
  void output() override {}
  bool ok() const { return ok_; }

 private:
  std::vector<const Ticker*> before_, after_;
  TimeUs period_us_;
  bool ok_ = true;
};

struct TickerWorld {
  std::shared_ptr<Coupled> top = std::make_shared<Coupled>("top");
  std::vector<Ticker*> tickers;
  Watcher* watcher = nullptr;
  // 40 tickers, the watcher in the middle of flat order; ticker `failing` throws at its 3rd tick.
  explicit TickerWorld(int failing = -1, int second_failing = -1) {
    std::vector<const Ticker*> before, after;
    for (int i = 0; i < 20; ++i) {
      tickers.push_back(
          &top->emplace<Ticker>("t" + std::to_string(i), 10 * kMs, i == failing || i == second_failing ? 3 : 0));
      before.push_back(tickers.back());
    }
    watcher = &top->emplace<Watcher>(10 * kMs);
    for (int i = 20; i < 40; ++i) {
      tickers.push_back(
          &top->emplace<Ticker>("t" + std::to_string(i), 10 * kMs, i == failing || i == second_failing ? 3 : 0));
      after.push_back(tickers.back());
    }
    watcher->watch(before, after);
  }
};

}  // namespace

TEST(Coordinator, WorkersRunConcurrentModelsAroundTheOthersInFlatOrder) {
  for (const int threads : {1, 2, 3}) {
    TickerWorld world;
    FastClock clock;
    Coordinator coordinator(world.top, clock);
    rilbed::core::WorkerPool pool(threads);
    coordinator.set_workers(&pool);
    coordinator.run_until(1000 * kMs);
    for (const Ticker* t : world.tickers) EXPECT_EQ(t->state(), 100) << t->path() << " on " << threads << " threads";
    EXPECT_EQ(world.watcher->state(), 100);
    EXPECT_TRUE(world.watcher->ok()) << "the watcher saw the tickers out of flat order on " << threads << " threads";
  }
}

TEST(Coordinator, AConcurrentModelsErrorNamesTheFirstFailingModelInFlatOrder) {
  TickerWorld world(27, 33);
  FastClock clock;
  Coordinator coordinator(world.top, clock);
  rilbed::core::WorkerPool pool(3);
  coordinator.set_workers(&pool);
  try {
    coordinator.run_until(1000 * kMs);
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.model_path(), "top/t27");
    EXPECT_NE(std::string(e.what()).find("tick 3"), std::string::npos) << e.what();
  }
}

namespace {
// Counts the prefetch hints it was given, and whether each came before its transition
// of the same instant.
class Hinted final : public AtomicModel<int> {
 public:
  Hinted(std::string id, TimeUs period_us) : AtomicModel<int>(std::move(id), 0), period_us_(period_us) {}
  TimeUs time_advance() const override { return period_us_; }
  void internal_transition() override {
    if (hinted_at_ == state_) ++hinted_before_;
    ++state_;
  }
  void external_transition(TimeUs) override {}
  void output() override {}
  bool transitions_concurrent() const override { return true; }
  void prefetch(int round) const override {
    if (round == 0) {
      round0_at_ = state_;
      return;
    }
    ++hints_;
    if (round0_at_ == state_) ++paired_;
    hinted_at_ = state_;
  }
  std::size_t prefetch_bytes() const override { return sizeof(*this); }
  // Round 1 hints that came after a round 0 hint of the same instant.
  int paired() const { return paired_; }
  int hints() const { return hints_; }
  int hinted_before() const { return hinted_before_; }

 private:
  TimeUs period_us_;
  mutable int hints_ = 0;
  mutable int round0_at_ = -1;
  mutable int paired_ = 0;
  mutable int hinted_at_ = -1;
  int hinted_before_ = 0;
};
}  // namespace

// In a step where many models transition, the coordinator asks each a few models ahead
// to prefetch (a hint), in two rounds (0 then 1): all but the first few of each
// thread's chunk, before their transition; a model that steps alone is never asked.
// Results do not change.
TEST(Coordinator, ModelsAheadAreAskedToPrefetchInBulkSteps) {
  for (const int threads : {1, 2}) {
    auto top = std::make_shared<Coupled>("top");
    std::vector<Hinted*> crowd;
    for (int i = 0; i < 40; ++i) crowd.push_back(&top->emplace<Hinted>("h" + std::to_string(i), 10 * kMs));
    Hinted& loner = top->emplace<Hinted>("loner", 7 * kMs);  // steps at its own instants (and with the crowd at 70 ms)
    FastClock clock;
    Coordinator coordinator(top, clock);
    rilbed::core::WorkerPool pool(threads);
    coordinator.set_workers(&pool);
    coordinator.run_until(1000 * kMs);
    int hints = 0, before = 0, paired = 0;
    for (const Hinted* h : crowd) {
      EXPECT_EQ(h->state(), 100);
      hints += h->hints();
      before += h->hinted_before();
      paired += h->paired();
    }
    EXPECT_GE(hints, 100 * (40 - 4 * threads - 1)) << "on " << threads << " threads";
    EXPECT_EQ(before, hints) << "every hint should come before the model's transition";
    EXPECT_GE(paired, 100 * (40 - 8 * threads - 1)) << "round 0 should come before round 1 (" << threads << " threads)";
    EXPECT_EQ(loner.state(), 142);
    EXPECT_LE(loner.hints(), 14) << "asked only in the steps it shares with the crowd";
  }
}

// Clocks: fast clock jumps, real-time clock pacing, factor changes, pause, wake-ups.
// Wall-time assertions are lower bounds, or very generous upper bounds.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <thread>

#include "sim/clock.hpp"
#include "support/eventually.hpp"

using namespace rilbed::sim;
using rilbed::TimeUs;
using namespace std::chrono_literals;
using WallClock = std::chrono::steady_clock;
using rilbed::testing::eventually;

TEST(FastClock, JumpsToEachDeadline) {
  FastClock clock;
  EXPECT_EQ(clock.now_us(), 0);
  EXPECT_EQ(clock.wait_until(1'000'000'000), WaitResult::kReached);
  EXPECT_EQ(clock.now_us(), 1'000'000'000);
  EXPECT_EQ(clock.wait_until(kInfinity), WaitResult::kReached);
  EXPECT_EQ(clock.now_us(), 1'000'000'000);  // "never" is not a time
  clock.start(5);
  EXPECT_EQ(clock.now_us(), 5);
  clock.stop();
  EXPECT_EQ(clock.wait_until(10), WaitResult::kStopped);
  EXPECT_EQ(clock.now_us(), 5);
}

TEST(RealTimeClock, RejectsBadFactors) {
  EXPECT_THROW(RealTimeClock(0.0), std::invalid_argument);
  EXPECT_THROW(RealTimeClock(-1.0), std::invalid_argument);
  RealTimeClock clock(2.0);
  EXPECT_THROW(clock.set_factor(std::numeric_limits<double>::infinity()), std::invalid_argument);
  EXPECT_THROW(clock.set_factor(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  EXPECT_DOUBLE_EQ(clock.factor(), 2.0);
}

TEST(RealTimeClock, FactorTenTakesATenthOfTheWallTime) {
  RealTimeClock clock(10.0);
  const auto wall_start = WallClock::now();
  clock.start(0);
  EXPECT_EQ(clock.wait_until(200'000), WaitResult::kReached);
  const auto wall_elapsed = WallClock::now() - wall_start;
  EXPECT_GE(wall_elapsed, 20ms);
  EXPECT_LT(wall_elapsed, 2s);
  EXPECT_GE(clock.now_us(), 200'000);
}

TEST(RealTimeClock, ManySmallWaitsDoNotLoseTime) {
  // 50 deadlines 2 ms apart at factor 1: absolute deadlines, so at least 100 ms in total
  // and the clock is never behind the last deadline.
  RealTimeClock clock(1.0);
  const auto wall_start = WallClock::now();
  clock.start(1'000);
  for (TimeUs t_us = 3'000; t_us <= 101'000; t_us += 2'000) {
    ASSERT_EQ(clock.wait_until(t_us), WaitResult::kReached);
    ASSERT_GE(clock.now_us(), t_us);
  }
  EXPECT_GE(WallClock::now() - wall_start, 100ms);
}

TEST(RealTimeClock, PastDeadlinesAreReachedAtOnce) {
  RealTimeClock clock(1.0);
  clock.start(1'000'000);
  const auto wall_start = WallClock::now();
  EXPECT_EQ(clock.wait_until(500'000), WaitResult::kReached);
  EXPECT_EQ(clock.wait_until(1'000'000), WaitResult::kReached);
  EXPECT_LT(WallClock::now() - wall_start, 2s);
}

TEST(RealTimeClock, SetFactorWhileWaitingTakesEffect) {
  RealTimeClock clock(1.0);
  clock.start(0);
  const auto wall_start = WallClock::now();
  // 20 s of simulated time at factor 1 would take 20 s.
  auto waiting = std::async(std::launch::async, [&] { return clock.wait_until(20'000'000); });
  ASSERT_TRUE(eventually([&] { return clock.waiters() == 1; }));  // asleep in its wait
  clock.set_factor(1000.0);                                       // the rest takes about 20 ms
  EXPECT_EQ(waiting.get(), WaitResult::kReached);
  EXPECT_LT(WallClock::now() - wall_start, 10s);
  EXPECT_GE(clock.now_us(), 20'000'000);
}

TEST(RealTimeClock, SetFactorKeepsSimulatedTimeContinuous) {
  RealTimeClock clock(1.0);
  clock.start(7'000'000);
  clock.pause();
  const TimeUs before_us = clock.now_us();
  clock.set_factor(1000.0);
  EXPECT_EQ(clock.now_us(), before_us);  // no jump when the factor changes
  clock.resume();
  clock.set_factor(1.0);
  const TimeUs running_us = clock.now_us();
  clock.set_factor(3.0);
  const TimeUs after_us = clock.now_us();
  EXPECT_GE(running_us, before_us);
  EXPECT_GE(after_us, running_us);
  EXPECT_LT(after_us - running_us, 1'000'000);  // a jump would be ~14 s (7 s anchor x 2)
}

TEST(RealTimeClock, PauseFreezesTimeAndWaits) {
  RealTimeClock clock(1000.0);
  clock.start(0);
  clock.pause();
  EXPECT_TRUE(clock.paused());
  const TimeUs frozen_us = clock.now_us();
  std::atomic<bool> done{false};
  auto waiting = std::async(std::launch::async, [&] {
    const WaitResult result = clock.wait_until(frozen_us + 1'000);  // 1 us of wall time at 1000x
    done.store(true);
    return result;
  });
  // Asleep in its wait although its deadline (1 us of wall time) has long passed: the
  // pause holds it.
  ASSERT_TRUE(eventually([&] { return clock.waiters() == 1; }));
  EXPECT_FALSE(done.load());
  EXPECT_EQ(clock.now_us(), frozen_us);
  clock.resume();
  EXPECT_FALSE(clock.paused());
  EXPECT_EQ(waiting.get(), WaitResult::kReached);
  EXPECT_GE(clock.now_us(), frozen_us + 1'000);
}

TEST(RealTimeClock, NotifyWakesAWaitEarly) {
  RealTimeClock clock(1.0);
  clock.start(0);
  const auto wall_start = WallClock::now();
  auto waiting = std::async(std::launch::async, [&] { return clock.wait_until(100'000'000); });
  ASSERT_TRUE(eventually([&] { return clock.waiters() == 1; }));  // woken, not told before it waited
  clock.notify();
  EXPECT_EQ(waiting.get(), WaitResult::kWoken);
  EXPECT_LT(WallClock::now() - wall_start, 10s);
  EXPECT_LT(clock.now_us(), 100'000'000);
}

TEST(RealTimeClock, NotifyBeforeWaitIsNotLost) {
  RealTimeClock clock(1.0);
  clock.start(0);
  clock.notify();
  EXPECT_EQ(clock.wait_until(kInfinity), WaitResult::kWoken);
  // Consumed: the next wait runs to its deadline.
  EXPECT_EQ(clock.wait_until(clock.now_us() + 1'000), WaitResult::kReached);
}

TEST(RealTimeClock, StopEndsEveryWait) {
  RealTimeClock clock(1.0);
  clock.start(0);
  auto first = std::async(std::launch::async, [&] { return clock.wait_until(kInfinity); });
  auto second = std::async(std::launch::async, [&] { return clock.wait_until(50'000'000); });
  ASSERT_TRUE(eventually([&] { return clock.waiters() == 2; }));  // both asleep
  clock.stop();
  EXPECT_EQ(first.get(), WaitResult::kStopped);
  EXPECT_EQ(second.get(), WaitResult::kStopped);
  EXPECT_EQ(clock.wait_until(1), WaitResult::kStopped);
}

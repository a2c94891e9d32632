#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "sim/event_heap.hpp"

using rilbed::TimeUs;
using rilbed::sim::kInfinity;
using rilbed::sim::detail::EventHeap;

TEST(EventHeap, EmptyHeapHasNoEvent) {
  EventHeap heap;
  heap.assign({});
  EXPECT_EQ(heap.top_time_us(), kInfinity);
  std::vector<std::size_t> due;
  heap.collect_at(0, due);
  EXPECT_TRUE(due.empty());
}

TEST(EventHeap, CollectsExactlyTheDueItems) {
  EventHeap heap;
  heap.assign({50, 10, 10, kInfinity, 10, 20});
  EXPECT_EQ(heap.top_time_us(), 10);
  std::vector<std::size_t> due;
  heap.collect_at(10, due);
  std::sort(due.begin(), due.end());
  EXPECT_EQ(due, (std::vector<std::size_t>{1, 2, 4}));
  heap.update(1, 30);
  heap.update(2, 30);
  heap.update(4, 5);
  EXPECT_EQ(heap.top_time_us(), 5);
  heap.update(4, kInfinity);
  EXPECT_EQ(heap.top_time_us(), 20);
}

TEST(EventHeap, MatchesBruteForceUnderRandomUpdates) {
  std::mt19937 random(12345);
  const std::size_t n = 257;
  std::vector<TimeUs> reference(n);
  std::uniform_int_distribution<TimeUs> time_us(0, 40);  // few values: many ties
  for (auto& t : reference) t = time_us(random);
  EventHeap heap;
  heap.assign(reference);
  std::uniform_int_distribution<std::size_t> item(0, n - 1);
  for (int round = 0; round < 5000; ++round) {
    const std::size_t changed = item(random);
    reference[changed] = round % 17 == 0 ? kInfinity : time_us(random);
    heap.update(changed, reference[changed]);
    const TimeUs earliest = *std::min_element(reference.begin(), reference.end());
    ASSERT_EQ(heap.top_time_us(), earliest);
    if (round % 50 == 0) {
      std::vector<std::size_t> due, expected;
      heap.collect_at(earliest, due);
      for (std::size_t i = 0; i < n; ++i)
        if (reference[i] == earliest) expected.push_back(i);
      std::sort(due.begin(), due.end());
      ASSERT_EQ(due, expected);
    }
  }
}

// With a limit, collecting says whether every due item was listed: exactly when there are
// no more than the limit, and then it lists them all.
TEST(EventHeap, CollectingStopsPastItsLimit) {
  std::mt19937 random(77);
  for (int round = 0; round < 200; ++round) {
    const std::size_t n = 1 + random() % 300;
    std::vector<TimeUs> times(n);
    for (auto& t : times) t = static_cast<TimeUs>(random() % 3);
    EventHeap heap;
    heap.assign(times);
    const TimeUs earliest = heap.top_time_us();
    const auto due_count = static_cast<std::size_t>(std::count(times.begin(), times.end(), earliest));
    const std::size_t limit = random() % (n + 1);
    std::vector<std::size_t> due{12345};  // appended to, never cleared
    const bool complete = heap.collect_at(earliest, due, limit);
    EXPECT_EQ(complete, due_count <= limit) << "round " << round;
    EXPECT_EQ(due.front(), 12345u);
    if (complete) {
      EXPECT_EQ(due.size() - 1, due_count);
    } else {
      EXPECT_EQ(due.size() - 1, limit + 1) << "it should stop at once past the limit";
    }
    for (std::size_t k = 1; k < due.size(); ++k) EXPECT_EQ(times[due[k]], earliest);
  }
}

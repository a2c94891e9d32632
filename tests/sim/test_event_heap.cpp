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

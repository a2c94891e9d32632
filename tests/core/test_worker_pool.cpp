// WorkerPool: every index once, on up to N threads, errors passed back in chunk order.
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/worker_pool.hpp"

namespace rilbed::core {
namespace {

TEST(WorkerPool, CoversEveryIndexOnceForAnyCountAndThreads) {
  for (const int threads : {1, 2, 3, 5}) {
    WorkerPool pool(threads);
    EXPECT_EQ(pool.threads(), threads);
    for (const std::size_t count :
         {std::size_t{0}, std::size_t{1}, std::size_t{2}, std::size_t{7}, std::size_t{1000}}) {
      std::vector<std::atomic<int>> hits(count);
      std::atomic<int> calls{0};
      pool.for_chunks(count, [&](std::size_t begin, std::size_t end) {
        ASSERT_LT(begin, end);
        ++calls;
        for (std::size_t i = begin; i < end; ++i) ++hits[i];
      });
      for (std::size_t i = 0; i < count; ++i) EXPECT_EQ(hits[i].load(), 1) << "index " << i << " of " << count;
      EXPECT_EQ(calls.load(), static_cast<int>(std::min<std::size_t>(count, static_cast<std::size_t>(threads))));
    }
  }
}

TEST(WorkerPool, RunsChunksOnSeveralThreadsAtOnce) {
  WorkerPool pool(2);
  // Each chunk waits for the other to start: only two threads at once get through.
  std::atomic<int> started{0};
  std::mutex m;
  std::set<std::thread::id> ids;
  pool.for_chunks(2, [&](std::size_t, std::size_t) {
    ++started;
    while (started.load() < 2) std::this_thread::yield();
    std::lock_guard lock(m);
    ids.insert(std::this_thread::get_id());
  });
  EXPECT_EQ(ids.size(), 2u);
  EXPECT_TRUE(ids.contains(std::this_thread::get_id()));  // the caller works too
}

TEST(WorkerPool, RethrowsTheLowestChunksErrorAfterAllChunksEnd) {
  WorkerPool pool(3);
  std::atomic<int> finished{0};
  try {
    pool.for_chunks(3, [&](std::size_t begin, std::size_t) {
      if (begin > 0) {
        ++finished;
        throw std::runtime_error("chunk at " + std::to_string(begin));
      }
      ++finished;
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "chunk at 1");
  }
  EXPECT_EQ(finished.load(), 3);
  // The pool goes on working after an error.
  std::atomic<int> sum{0};
  pool.for_chunks(10, [&](std::size_t b, std::size_t e) { sum += static_cast<int>(e - b); });
  EXPECT_EQ(sum.load(), 10);
}

TEST(WorkerPool, RefusesLessThanOneThread) {
  EXPECT_THROW(WorkerPool(0), std::invalid_argument);
  EXPECT_THROW(WorkerPool(-2), std::invalid_argument);
}

TEST(WorkerPool, ReportsItsWorkersCpuTime) {
  WorkerPool pool(2);
  pool.for_chunks(2, [](std::size_t begin, std::size_t) {
    if (begin == 0) return;
    volatile double x = 0;
    for (int i = 0; i < 20'000'000; ++i) x = x + 1.0;
  });
  EXPECT_GT(pool.worker_cpu_seconds(), 0.0);
}

}  // namespace
}  // namespace rilbed::core

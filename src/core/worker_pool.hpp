// A fixed set of worker threads that run one loop's iterations at a time, split into
// contiguous chunks (`--threads N` steps the world on N threads). The caller's
// thread works too, so a pool of N threads starts N - 1.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace rilbed::core {

/// Runs `body(begin, end)` over a range split into one contiguous chunk per thread, and
/// returns once every chunk is done. What each iteration computes must not depend on the
/// chunk it falls in (results stay the same for any thread count); the pool gives no
/// other guarantee of order. One loop at a time: for_chunks() belongs to one thread, and
/// a body must not call for_chunks() on the same pool. Idle threads poll for a few tens of
/// microseconds before they sleep: give a pool no more threads than there are cores.
class WorkerPool {
 public:
  /// `threads` >= 1 (1: no thread is started and loops run on the caller's thread).
  /// Throws std::invalid_argument for less than 1.
  explicit WorkerPool(int threads);
  /// Stops and joins the workers.
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  /// Number of threads a loop runs on, the caller's included.
  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  /// CPU time the worker threads (not the caller's) have used so far, seconds.
  double worker_cpu_seconds() const;

  /// Calls body(begin, end) on contiguous chunks covering [0, count), one per thread
  /// (fewer when count is smaller), the first chunk on the caller's thread, and waits for
  /// all. If bodies throw, rethrows the exception of the lowest chunk that threw, after
  /// every chunk has ended. A count of 0 does nothing.
  void for_chunks(std::size_t count, const std::function<void(std::size_t begin, std::size_t end)>& body);

 private:
  void work(std::size_t worker);
  void stop_workers();
  void run_chunk(std::size_t chunk);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  // The loop in progress: set by for_chunks before it bumps the generation.
  const std::function<void(std::size_t, std::size_t)>* body_ = nullptr;
  std::size_t count_ = 0;
  std::size_t chunks_ = 0;
  std::atomic<unsigned long> generation_{0};  // bumped for each loop; workers wait for a new one
  std::atomic<std::size_t> pending_{0};       // workers not yet done with the loop
  std::atomic<bool> stopping_{false};
  std::vector<std::exception_ptr> errors_;  // per chunk
};

}  // namespace rilbed::core

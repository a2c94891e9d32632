#include "core/worker_pool.hpp"

#include <pthread.h>
#include <time.h>

#include <stdexcept>
#include <string>

namespace rilbed::core {

WorkerPool::WorkerPool(int threads) {
  if (threads < 1) throw std::invalid_argument("worker pool: threads must be >= 1, not " + std::to_string(threads));
  workers_.reserve(static_cast<std::size_t>(threads - 1));
  for (int w = 0; w + 1 < threads; ++w) workers_.emplace_back([this, w] { work(static_cast<std::size_t>(w) + 1); });
}

double WorkerPool::worker_cpu_seconds() const {
  double total_s = 0.0;
  for (const std::thread& t : workers_) {
    clockid_t clock{};
    timespec ts{};
    if (pthread_getcpuclockid(const_cast<std::thread&>(t).native_handle(), &clock) == 0 && clock_gettime(clock, &ts) == 0)
      total_s += static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
  }
  return total_s;
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  start_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void WorkerPool::run_chunk(std::size_t chunk) {
  const std::size_t begin = count_ * chunk / chunks_;
  const std::size_t end = count_ * (chunk + 1) / chunks_;
  try {
    if (begin < end) (*body_)(begin, end);
  } catch (...) {
    errors_[chunk] = std::current_exception();
  }
}

void WorkerPool::for_chunks(std::size_t count, const std::function<void(std::size_t, std::size_t)>& body) {
  if (count == 0) return;
  const std::size_t chunks = std::min<std::size_t>(count, static_cast<std::size_t>(threads()));
  if (chunks == 1) {
    body(0, count);
    return;
  }
  {
    std::lock_guard lock(mutex_);
    body_ = &body;
    count_ = count;
    chunks_ = chunks;
    errors_.assign(chunks, nullptr);
    pending_ = chunks - 1;
    ++generation_;
  }
  start_.notify_all();
  run_chunk(0);
  {
    std::unique_lock lock(mutex_);
    done_.wait(lock, [this] { return pending_ == 0; });
    body_ = nullptr;
  }
  for (const std::exception_ptr& e : errors_)
    if (e) std::rethrow_exception(e);
}

void WorkerPool::work(std::size_t worker) {
  unsigned long seen = 0;
  for (;;) {
    std::size_t chunks = 0;
    {
      std::unique_lock lock(mutex_);
      start_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
      chunks = chunks_;
    }
    // A loop with fewer chunks than threads leaves the higher workers out.
    if (worker < chunks) {
      run_chunk(worker);
      std::lock_guard lock(mutex_);
      if (--pending_ == 0) done_.notify_one();
    }
  }
}

}  // namespace rilbed::core

#include "core/worker_pool.hpp"

#include <pthread.h>
#include <time.h>

#include <stdexcept>
#include <string>

namespace rilbed::core {

namespace {
// How long a thread polls for the next loop, or for the workers to finish, before it
// sleeps on a condition variable: a run hands out several loops per step, each a few
// microseconds to a millisecond apart, and a wake-up from sleep costs about 15 us.
constexpr int kSpins = 4000;

// Tells the CPU that this thread is polling (it yields its core's shared resources to
// the sibling hardware thread, if any); nothing where the compiler knows no such hint.
inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__) || defined(__arm__)
  __asm__ __volatile__("yield");
#endif
}
}  // namespace

WorkerPool::WorkerPool(int threads) {
  if (threads < 1) throw std::invalid_argument("worker pool: threads must be >= 1, not " + std::to_string(threads));
  workers_.reserve(static_cast<std::size_t>(threads - 1));
  try {
    for (int w = 0; w + 1 < threads; ++w) workers_.emplace_back([this, w] { work(static_cast<std::size_t>(w) + 1); });
  } catch (...) {
    stop_workers();  // the threads started so far; the destructor will not run
    throw;
  }
}

void WorkerPool::stop_workers() {
  {
    std::lock_guard lock(mutex_);
    stopping_.store(true);
    generation_.fetch_add(1, std::memory_order_release);
  }
  start_.notify_all();
  for (std::thread& t : workers_) t.join();
}

double WorkerPool::worker_cpu_seconds() const {
  double total_s = 0.0;
  for (const std::thread& t : workers_) {
    clockid_t clock{};
    timespec ts{};
    if (pthread_getcpuclockid(const_cast<std::thread&>(t).native_handle(), &clock) == 0 &&
        clock_gettime(clock, &ts) == 0)
      total_s += static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
  }
  return total_s;
}

WorkerPool::~WorkerPool() { stop_workers(); }

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
  // The loop's description is published by the generation's release and read after the
  // workers' acquire of it.
  body_ = &body;
  count_ = count;
  chunks_ = chunks;
  errors_.assign(chunks, nullptr);
  // Every worker reports back, those without a chunk too, so that none still reads this
  // loop's description when the next one is written.
  pending_.store(workers_.size(), std::memory_order_relaxed);
  {
    std::lock_guard lock(mutex_);  // a worker about to sleep sees the new generation
    generation_.fetch_add(1, std::memory_order_release);
  }
  start_.notify_all();
  run_chunk(0);
  for (int spin = 0; spin < kSpins && pending_.load(std::memory_order_acquire) != 0; ++spin) cpu_relax();
  if (pending_.load(std::memory_order_acquire) != 0) {
    std::unique_lock lock(mutex_);
    done_.wait(lock, [this] { return pending_.load(std::memory_order_acquire) == 0; });
  }
  body_ = nullptr;
  for (const std::exception_ptr& e : errors_)
    if (e) std::rethrow_exception(e);
}

void WorkerPool::work(std::size_t worker) {
  unsigned long seen = 0;
  for (;;) {
    unsigned long now = generation_.load(std::memory_order_acquire);
    for (int spin = 0; spin < kSpins && now == seen; ++spin) {
      cpu_relax();
      now = generation_.load(std::memory_order_acquire);
    }
    if (now == seen) {
      std::unique_lock lock(mutex_);
      start_.wait(lock, [&] { return generation_.load(std::memory_order_acquire) != seen; });
      now = generation_.load(std::memory_order_acquire);
    }
    seen = now;
    if (stopping_.load()) return;
    // A loop with fewer chunks than threads leaves the higher workers out.
    if (worker < chunks_) run_chunk(worker);
    if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
      std::lock_guard lock(mutex_);  // the caller either sees 0 or is woken
      done_.notify_one();
    }
  }
}

}  // namespace rilbed::core

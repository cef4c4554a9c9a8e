#include "runtime/integrate/worker_pool.h"

#include <chrono>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace fmpc::sim {

namespace {

// A hint to the core that this is a spin-wait loop (lets a sibling hardware thread run, saves power).
inline void relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

}  // namespace

WorkerPool::WorkerPool(unsigned threads, std::size_t grain, PoolWait wait)
    : grain_(grain),
      spin_(wait == PoolWait::Spin ||
            (wait == PoolWait::Automatic && threads >= kSpinFromThreads &&
             threads <= std::thread::hardware_concurrency())) {
  for (unsigned i = 1; i < threads; ++i) workers_.emplace_back([this, i] { work(i); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_.store(true, std::memory_order_release);
  }
  start_.notify_all();
  for (std::thread& worker : workers_) worker.join();
}

template <class Ready>
void WorkerPool::wait_until(std::condition_variable& signal, const Ready& ready) {
  if (spin_) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(kSpinMicroseconds);
    for (unsigned k = 1;; ++k) {
      if (ready()) return;
      if (k % 64 == 0 && std::chrono::steady_clock::now() > until) break;
      relax();
    }
  }
  std::unique_lock<std::mutex> lock(mutex_);
  signal.wait(lock, ready);
}

void WorkerPool::work(unsigned index) {
  std::size_t seen = 0;
  for (;;) {
    wait_until(start_, [&] {
      return stopping_.load(std::memory_order_acquire) || generation_.load(std::memory_order_acquire) != seen;
    });
    if (stopping_.load(std::memory_order_acquire)) return;
    seen = generation_.load(std::memory_order_acquire);
    if (index < parts_) {
      const auto [begin, end] = chunk_range(count_, parts_, index);
      (*task_)(index, begin, end);
    }
    if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
      // Under the mutex, so that a caller between its last check and its sleep cannot miss the notification.
      std::lock_guard<std::mutex> lock(mutex_);
      done_.notify_one();
    }
  }
}

unsigned WorkerPool::parts(std::size_t count, std::size_t min_per_thread) const {
  const std::size_t minimum = grain_ > 0 ? grain_ : min_per_thread;
  return size() == 1 || count < 2 * minimum ? 1 : size();
}

void WorkerPool::run_parts(std::size_t count, const std::function<void(unsigned, std::size_t, std::size_t)>& task,
                           std::size_t min_per_thread) {
  const unsigned total = parts(count, min_per_thread);
  if (total == 1) {
    task(0, 0, count);
    return;
  }
  task_ = &task;
  count_ = count;
  parts_ = total;
  pending_.store(static_cast<unsigned>(workers_.size()), std::memory_order_relaxed);
  {
    // Published under the mutex, so that a worker between its last check and its sleep cannot miss it.
    std::lock_guard<std::mutex> lock(mutex_);
    generation_.fetch_add(1, std::memory_order_release);
  }
  start_.notify_all();
  const auto [begin, end] = chunk_range(count, total, 0);
  task(0, begin, end);
  wait_until(done_, [&] { return pending_.load(std::memory_order_acquire) == 0; });
}

void WorkerPool::run(std::size_t count, const std::function<void(std::size_t, std::size_t)>& task,
                     std::size_t min_per_thread) {
  run_parts(count, [&task](unsigned, std::size_t begin, std::size_t end) { task(begin, end); }, min_per_thread);
}

void advise_huge_pages(const void* data, std::size_t bytes) {
#if defined(MADV_HUGEPAGE)
  const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
  const auto begin = reinterpret_cast<std::uintptr_t>(data) / page * page;
  const auto end = reinterpret_cast<std::uintptr_t>(data) + bytes;
  // Advice only: a kernel without THP refuses it, and the memory works the same.
  (void)madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

unsigned resolve_thread_count(unsigned requested, std::size_t work_items, std::size_t serial_below) {
  if (requested > 0) return requested;
  if (work_items < serial_below) return 1;
  return std::max(1u, std::thread::hardware_concurrency());
}

}  // namespace fmpc::sim

#include "runtime/integrate/worker_pool.h"

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace fmpc::sim {

WorkerPool::WorkerPool(unsigned threads, std::size_t grain) : grain_(grain) {
  for (unsigned i = 1; i < threads; ++i) workers_.emplace_back([this, i] { work(i); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  start_.notify_all();
  for (std::thread& worker : workers_) worker.join();
}

void WorkerPool::work(unsigned index) {
  std::size_t seen = 0;
  for (;;) {
    const std::function<void(unsigned, std::size_t, std::size_t)>* task = nullptr;
    std::size_t count = 0;
    unsigned parts = 1;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
      task = task_;
      count = count_;
      parts = parts_;
    }
    if (index < parts) {
      const auto [begin, end] = chunk_range(count, parts, index);
      (*task)(index, begin, end);
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (--pending_ == 0) done_.notify_one();
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
  {
    std::lock_guard<std::mutex> lock(mutex_);
    task_ = &task;
    count_ = count;
    parts_ = total;
    pending_ = static_cast<unsigned>(workers_.size());
    ++generation_;
  }
  start_.notify_all();
  const auto [begin, end] = chunk_range(count, total, 0);
  task(0, begin, end);
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [&] { return pending_ == 0; });
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

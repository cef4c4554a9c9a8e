#include "runtime/integrate/worker_pool.h"

namespace fmpc::sim {

namespace {
std::pair<std::size_t, std::size_t> chunk(std::size_t count, unsigned parts, unsigned index) {
  const std::size_t begin = count * index / parts;
  const std::size_t end = count * (index + 1) / parts;
  return {begin, end};
}
}  // namespace

WorkerPool::WorkerPool(unsigned threads) {
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
    const std::function<void(std::size_t, std::size_t)>* task = nullptr;
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
      const auto [begin, end] = chunk(count, parts, index);
      (*task)(begin, end);
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (--pending_ == 0) done_.notify_one();
    }
  }
}

void WorkerPool::run(std::size_t count, const std::function<void(std::size_t, std::size_t)>& task,
                     std::size_t min_per_thread) {
  const unsigned total = size();
  if (total == 1 || count < 2 * min_per_thread) {
    task(0, count);
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
  const auto [begin, end] = chunk(count, total, 0);
  task(begin, end);
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [&] { return pending_ == 0; });
}

}  // namespace fmpc::sim

#pragma once
// Persistent CPU worker threads with a fixed partition of the index range: chunk t always goes to worker t and
// every index is written by exactly one worker, so results never depend on the thread count or timing.
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace fmpc::sim {

class WorkerPool {
 public:
  explicit WorkerPool(unsigned threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Runs task(begin, end) over [0, count) split into equal contiguous chunks, and waits for all of them. Ranges
  // smaller than min_per_thread per worker run on the calling thread.
  void run(std::size_t count, const std::function<void(std::size_t, std::size_t)>& task,
           std::size_t min_per_thread = 2048);
  unsigned size() const { return static_cast<unsigned>(workers_.size()) + 1; }

 private:
  void work(unsigned index);
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  const std::function<void(std::size_t, std::size_t)>* task_ = nullptr;
  std::size_t count_ = 0;
  unsigned parts_ = 1;
  unsigned pending_ = 0;
  std::size_t generation_ = 0;
  bool stopping_ = false;
};

}  // namespace fmpc::sim

#pragma once
// Persistent CPU worker threads with a fixed partition of the index range: chunk t always goes to worker t and
// every index is written by exactly one worker, so results never depend on the thread count or timing.
//
// Besides the integrators' loops, the host setup (mesh checks, springs, CSR, masses) builds on the deterministic
// building blocks below: per-part outputs concatenated in part order, a merge sort under a total order, and a
// grouping of items by key whose groups list their items in increasing order. Each gives the same result for any
// thread count.
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace fmpc::sim {

// How a pool's waits wait: spinning first where the pool is large enough and has a core per thread (Automatic, see
// kSpinMicroseconds), or always (Spin: for tests of that path on a small machine), or never (Sleep).
enum class PoolWait { Automatic, Spin, Sleep };

class WorkerPool {
 public:
  // grain > 0 replaces every call's min_per_thread (1: split even the smallest ranges, as tests of the parallel
  // paths on small inputs need).
  explicit WorkerPool(unsigned threads, std::size_t grain = 0, PoolWait wait = PoolWait::Automatic);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Runs task(begin, end) over [0, count) split into equal contiguous chunks, and waits for all of them. Ranges
  // smaller than min_per_thread per worker run on the calling thread.
  void run(std::size_t count, const std::function<void(std::size_t, std::size_t)>& task,
           std::size_t min_per_thread = 2048);
  // How many chunks run() and run_parts() cut [0, count) into: size(), or 1 below 2 x min_per_thread.
  unsigned parts(std::size_t count, std::size_t min_per_thread = 2048) const;
  // Runs task(part, begin, end) for part = 0 .. parts(count, min_per_thread) - 1 over the same chunks as run(), so
  // a caller can give each part its own output and join them in part order.
  void run_parts(std::size_t count, const std::function<void(unsigned, std::size_t, std::size_t)>& task,
                 std::size_t min_per_thread = 2048);
  unsigned size() const { return static_cast<unsigned>(workers_.size()) + 1; }
  // Whether its waits spin before they sleep (see kSpinMicroseconds).
  bool spins() const { return spin_; }

 private:
  void work(unsigned index);
  // Returns once ready() holds: spinning for up to kSpinMicroseconds first where the pool spins, then asleep on
  // `signal` (notified under mutex_ by whoever makes ready() true).
  template <class Ready>
  void wait_until(std::condition_variable& signal, const Ready& ready);
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  // Written by the caller before it publishes a generation, read by the workers after they see it.
  const std::function<void(unsigned, std::size_t, std::size_t)>* task_ = nullptr;
  std::size_t count_ = 0;
  unsigned parts_ = 1;
  std::atomic<unsigned> pending_{0};
  std::atomic<std::size_t> generation_{0};
  std::atomic<bool> stopping_{false};
  std::size_t grain_ = 0;
  bool spin_ = false;
};

// How long a wait of the pool spins before it sleeps, in a pool of at least kSpinFromThreads threads and no more
// than the machine has hardware threads. A sleeping worker costs a futex wake, a reschedule and a turn at the mutex
// at every run() (tens of microseconds with 16 workers), and implicit Euler's step is about a hundred short runs (its
// CG: three an iteration); a spinning one picks the next run up within a microsecond, as OpenMP's default wait
// policy does. Smaller pools, and pools with more threads than cores, never spin: on a machine with more runnable
// threads than cores (2 cores shared by several processes: CI, the build machine) a spinning thread takes the core
// from the one doing the work, and a run took 10 times as long (docs/performance.md, "Implicit Euler on the CPU").
inline constexpr int kSpinMicroseconds = 50;
inline constexpr unsigned kSpinFromThreads = 4;

// The threads a `threads` setting asks for: the given count; for 0, every hardware thread, or 1 when the work has
// fewer than serial_below items (starting threads would cost more than they save).
unsigned resolve_thread_count(unsigned requested, std::size_t work_items, std::size_t serial_below = 65536);

// The pool a function runs on: the caller's, or (given null) one of its own with
// resolve_thread_count(threads, work_items) threads.
class PoolLease {
 public:
  PoolLease(WorkerPool* given, unsigned threads, std::size_t work_items)
      : own_(given ? nullptr : std::make_unique<WorkerPool>(resolve_thread_count(threads, work_items))),
        pool_(given ? given : own_.get()) {}
  WorkerPool& pool() { return *pool_; }

 private:
  std::unique_ptr<WorkerPool> own_;
  WorkerPool* pool_;
};

// Asks the kernel to back [data, data + bytes) with transparent huge pages (Linux: madvise MADV_HUGEPAGE), so that
// the first touch faults 2 MiB at a time instead of 4 KiB where THP is "always" or "madvise" (Debian's and Ubuntu's
// default); nothing elsewhere. The setup's arrays are touched once each, so their page faults are a large share of
// its time without it.
void advise_huge_pages(const void* data, std::size_t bytes);

// Below this, advice would cost a system call for no page fault saved worth it.
constexpr std::size_t kHugePageAdviceBytes = std::size_t{4} << 20;

// values.resize(n), with a large array advised huge pages before its first touch.
template <class T>
void resize_large(std::vector<T>& values, std::size_t n) {
  if (n > values.capacity() && n * sizeof(T) >= kHugePageAdviceBytes) {
    values.reserve(n);
    advise_huge_pages(values.data(), n * sizeof(T));
  }
  values.resize(n);
}

// [begin, end) of chunk `part` of `parts` over [0, count): the partition run() and run_parts() use.
inline std::pair<std::size_t, std::size_t> chunk_range(std::size_t count, unsigned parts, unsigned part) {
  return {count * part / parts, count * (part + 1) / parts};
}

// Sorts `items` under `less`, which must be a strict total order (no two items equivalent: break ties by an
// index), so that the result is the one sorted sequence whatever the thread count: sorted chunks, then rounds of
// pairwise merges whose output is split evenly over the workers (merge path co-ranks).
template <class T, class Less>
void parallel_sort(WorkerPool& pool, std::vector<T>& items, Less less) {
  const std::size_t n = items.size();
  const unsigned parts = pool.parts(n, 16384);
  if (parts <= 1) {
    std::sort(items.begin(), items.end(), less);
    return;
  }
  std::vector<std::size_t> runs(parts + 1);
  for (unsigned p = 0; p <= parts; ++p) runs[p] = chunk_range(n, parts, p).first;
  pool.run_parts(n, [&](unsigned part, std::size_t begin, std::size_t end) {
    (void)part;
    std::sort(items.begin() + static_cast<std::ptrdiff_t>(begin), items.begin() + static_cast<std::ptrdiff_t>(end),
              less);
  }, 16384);
  std::vector<T> buffer;
  resize_large(buffer, n);
  std::vector<T>* from = &items;
  std::vector<T>* to = &buffer;
  while (runs.size() > 2) {
    // Pair k merges runs [runs[2k], runs[2k+1]) and [runs[2k+1], runs[2k+2]); an odd last run is copied.
    std::vector<std::size_t> merged;
    for (std::size_t r = 0; r < runs.size() - 1; r += 2) merged.push_back(runs[r]);
    merged.push_back(n);
    const std::vector<T>& source = *from;
    std::vector<T>& target = *to;
    // How many of the first d outputs of the merge of [a0, a1) and [a1, b1) come from [a0, a1).
    const auto co_rank = [&](std::size_t a0, std::size_t a1, std::size_t b1, std::size_t d) {
      const std::size_t na = a1 - a0, nb = b1 - a1;
      std::size_t lo = d > nb ? d - nb : 0, hi = std::min(d, na);
      while (lo < hi) {
        const std::size_t mid = lo + (hi - lo) / 2;
        if (less(source[a1 + (d - mid - 1)], source[a0 + mid]))
          hi = mid;
        else
          lo = mid + 1;
      }
      return lo;
    };
    pool.run_parts(n, [&](unsigned part, std::size_t out_begin, std::size_t out_end) {
      (void)part;
      for (std::size_t r = 0; r + 1 < runs.size(); r += 2) {
        const std::size_t a0 = runs[r];
        const std::size_t a1 = runs[r + 1];
        const std::size_t b1 = r + 2 < runs.size() ? runs[r + 2] : a1;
        const std::size_t lo = std::max(out_begin, a0), hi = std::min(out_end, b1);
        if (lo >= hi) continue;
        const std::size_t i0 = co_rank(a0, a1, b1, lo - a0), i1 = co_rank(a0, a1, b1, hi - a0);
        const std::size_t j0 = (lo - a0) - i0, j1 = (hi - a0) - i1;
        std::merge(source.begin() + static_cast<std::ptrdiff_t>(a0 + i0),
                   source.begin() + static_cast<std::ptrdiff_t>(a0 + i1),
                   source.begin() + static_cast<std::ptrdiff_t>(a1 + j0),
                   source.begin() + static_cast<std::ptrdiff_t>(a1 + j1),
                   target.begin() + static_cast<std::ptrdiff_t>(lo), less);
      }
    }, 16384);
    runs = merged;
    std::swap(from, to);
  }
  if (from != &items) items.swap(buffer);
}

// Items grouped by key, in CSR form: the items of key k are item[offset[k] .. offset[k+1]), in increasing order.
struct KeyGroups {
  std::vector<std::int64_t> offset;  // key_count + 1
  std::vector<std::int32_t> item;
};

// Groups items 0 .. item_count-1 (fewer than 2^31) under key_count keys. keys_of(i, emit) calls emit(k) once for
// every key k of item i (each key at most once per item). Counts and places with atomic counters, then sorts each
// group, so the groups do not depend on the thread count or the order in which the workers ran.
template <class KeysOf>
KeyGroups group_by_key(WorkerPool& pool, std::size_t key_count, std::size_t item_count, const KeysOf& keys_of) {
  KeyGroups groups;
  std::unique_ptr<std::atomic<std::uint32_t>[]> count(new std::atomic<std::uint32_t>[key_count]);
  pool.run(key_count, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) count[k].store(0, std::memory_order_relaxed);
  });
  pool.run(item_count, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      keys_of(i, [&](std::size_t k) { count[k].fetch_add(1, std::memory_order_relaxed); });
  });
  resize_large(groups.offset, key_count + 1);
  groups.offset[0] = 0;
  for (std::size_t k = 0; k < key_count; ++k) {
    groups.offset[k + 1] = groups.offset[k] + count[k].load(std::memory_order_relaxed);
    count[k].store(0, std::memory_order_relaxed);
  }
  resize_large(groups.item, static_cast<std::size_t>(groups.offset[key_count]));
  pool.run(item_count, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      keys_of(i, [&](std::size_t k) {
        const std::uint32_t slot = count[k].fetch_add(1, std::memory_order_relaxed);
        groups.item[static_cast<std::size_t>(groups.offset[k]) + slot] = static_cast<std::int32_t>(i);
      });
    }
  });
  count.reset();
  pool.run(key_count, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const auto first = groups.item.begin() + groups.offset[k], last = groups.item.begin() + groups.offset[k + 1];
      if (last - first <= 32) {
        for (auto it = first + (first != last ? 1 : 0); it < last; ++it) {  // insertion sort: groups are short
          const std::int32_t value = *it;
          auto hole = it;
          for (; hole != first && *(hole - 1) > value; --hole) *hole = *(hole - 1);
          *hole = value;
        }
      } else {
        std::sort(first, last);
      }
    }
  });
  return groups;
}

}  // namespace fmpc::sim

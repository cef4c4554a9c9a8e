#pragma once
// Which variant runs next when `fmpc trade --max-error E` decides on the CPU (docs/trade.md, "Cheapest first"): each
// variant's full cost is estimated from a timed prefix of its own run, the variants go on cheapest estimate first,
// and one whose estimate is above the cheapest run already known to meet E is skipped: it could only win if its
// estimate were wrong by that margin. Pure bookkeeping (no clocks, no threads): the caller serialises the calls and
// says what each run cost.
#include <cmath>
#include <cstddef>
#include <optional>
#include <vector>

namespace fmpc::sim {

class CheapestFirstSchedule {
 public:
  // `bound`: the CPU seconds of the cheapest run already known to meet E (HUGE_VAL: none yet).
  explicit CheapestFirstSchedule(double bound = HUGE_VAL) : bound_(bound) {}

  // A run to schedule, with its estimated CPU seconds (a NaN goes last and is never skipped: nothing is known
  // against it). Every run is added before the first next().
  void add(std::size_t id, double estimate);

  // The next run to go on: the cheapest estimate left (ties in the order added), or nullopt when none is left. Each
  // run passed over on the way has an estimate strictly above the bound (one exactly at it runs: it may tie or win)
  // and is recorded in skipped().
  std::optional<std::size_t> next();

  // A run finished after `seconds` of CPU time; one that meets E lowers the bound to its cost. A run finished before
  // it was scheduled (its prefix was the whole run) is told here too.
  void finished(double seconds, bool meets);

  // Whether a run that has already used `seconds` of CPU time cannot be cheaper than the bound (its full cost is at
  // least that): strictly above it.
  bool beyond_bound(double seconds) const { return seconds > bound_; }

  double bound() const { return bound_; }

  struct Skip {
    std::size_t id;
    double estimate;
    double bound;  // the bound when it was skipped (the final one is at most this)
  };
  const std::vector<Skip>& skipped() const { return skipped_; }

 private:
  struct Entry {
    std::size_t id;
    double estimate;
  };
  std::vector<Entry> queue_;  // sorted on the first next()
  std::size_t cursor_ = 0;
  bool sorted_ = false;
  double bound_;
  std::vector<Skip> skipped_;
};

}  // namespace fmpc::sim

#include "runtime/scene/trade_schedule.h"

#include <algorithm>

namespace fmpc::sim {

void CheapestFirstSchedule::add(std::size_t id, double estimate) {
  queue_.push_back(Entry{id, estimate});
  sorted_ = false;
}

std::optional<std::size_t> CheapestFirstSchedule::next() {
  if (!sorted_) {
    // NaN last: an unordered estimate compares false both ways, so it is placed by hand.
    std::stable_sort(queue_.begin() + static_cast<std::ptrdiff_t>(cursor_), queue_.end(),
                     [](const Entry& a, const Entry& b) {
                       if (std::isnan(a.estimate) || std::isnan(b.estimate))
                         return !std::isnan(a.estimate) && std::isnan(b.estimate);
                       return a.estimate < b.estimate;
                     });
    sorted_ = true;
  }
  while (cursor_ < queue_.size()) {
    const Entry entry = queue_[cursor_++];
    if (entry.estimate > bound_) {
      skipped_.push_back(Skip{entry.id, entry.estimate, bound_});
      continue;
    }
    return entry.id;
  }
  return std::nullopt;
}

void CheapestFirstSchedule::finished(double seconds, bool meets) {
  if (meets && seconds < bound_) bound_ = seconds;
}

}  // namespace fmpc::sim

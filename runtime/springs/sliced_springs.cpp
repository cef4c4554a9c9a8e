#include "runtime/springs/sliced_springs.h"

#include <algorithm>
#include <limits>

#include "kernels/integrator_math.h"
#include "runtime/integrate/worker_pool.h"

namespace fmpc::sim {

bool slice_spring_entries(const int* offsets, const unsigned char* fixed, int vertex_count, int window,
                          WorkerPool& pool, SlicedSpringLayout& layout) {
  const auto n = static_cast<std::size_t>(vertex_count < 0 ? 0 : vertex_count);
  const auto span = static_cast<std::size_t>(valid_slice_window(window) ? window : kDefaultSliceWindow);
  const std::size_t windows = (n + span - 1) / span;
  const std::size_t slices = (n + kernels::kSliceRows - 1) / kernels::kSliceRows;
  const auto count = [&](int v) { return offsets[v + 1] - offsets[v]; };
  const auto walked = [&](int v) { return fixed != nullptr && fixed[v] == kernels::kAllAxesFixed ? 0 : count(v); };
  layout.vertex_order.resize(n);
  layout.row.resize(n);
  std::vector<std::int64_t> slice_begin(slices + 1, 0);
  pool.run(
      windows,
      [&](std::size_t first, std::size_t last) {
        for (std::size_t w = first; w < last; ++w) {
          const std::size_t begin = w * span, end = std::min(n, begin + span);
          int* order = layout.vertex_order.data();
          for (std::size_t r = begin; r < end; ++r) order[r] = static_cast<int>(r);
          std::stable_sort(order + begin, order + end, [&](int a, int b) { return walked(a) > walked(b); });
          // A slice is as wide as its longest row (held vertices sort by no entries, but hold all theirs).
          for (std::size_t r = begin; r < end; r += kernels::kSliceRows) {
            int width = 0;
            for (std::size_t i = r; i < std::min(end, r + kernels::kSliceRows); ++i)
              width = std::max(width, count(order[i]));
            slice_begin[r / kernels::kSliceRows + 1] = std::int64_t{kernels::kSliceRows} * width;
          }
        }
      },
      16);
  for (std::size_t s = 0; s < slices; ++s) slice_begin[s + 1] += slice_begin[s];
  layout.entries = slice_begin[slices];
  if (layout.entries > std::numeric_limits<int>::max()) return false;
  pool.run(n, [&](std::size_t first, std::size_t last) {
    for (std::size_t r = first; r < last; ++r) {
      const int v = layout.vertex_order[r];
      const std::int64_t at = slice_begin[r / kernels::kSliceRows] + static_cast<std::int64_t>(r % kernels::kSliceRows);
      layout.row[r] = {static_cast<int>(at), count(v)};
    }
  });
  return true;
}

}  // namespace fmpc::sim

#pragma once
// The sliced ELLPACK layout of a spring network's CSR entries (kernels/spring_math.h, SlicedRow): which vertex each
// GPU thread takes and where each vertex's row of entries lies. Built on the host from the CSR offsets alone; the
// GPU fills the entries (kernels::write_sliced_row).
#include <cstdint>
#include <vector>

#include "kernels/spring_math.h"

namespace fmpc::sim {

class WorkerPool;

// Vertices per sorting window, by default. A window's vertices are sorted by the entries their gather walks
// (largest first), so that a warp's 32 vertices walk nearly the same number: the generated boxes alternate vertices
// of 26 and 10 springs along x (one thread per vertex in CSR order leaves a third of the lanes idle), and a vertex
// held on every axis walks none. A block of 256 threads waits for its slowest warp, so the window spans several
// blocks: sorted, whole blocks walk alike. A warp's own vertices then come from 1,024 consecutive ones (their state
// is 4 KB per array), which cost less than the idle lanes: on the 240^3 box (H100) windows of 32, 64, 256, 512 and
// 1,024 measured 2,433, 2,133, 2,124, 2,029 and 1,988 us per step, the CSR order 2,554 (docs/performance.md).
constexpr int kDefaultSliceWindow = 1024;

// Whether `window` is a window slice_spring_entries takes: a power of two from 32 to 1024.
constexpr bool valid_slice_window(int window) { return window >= 32 && window <= 1024 && (window & (window - 1)) == 0; }

struct SlicedSpringLayout {
  // Row r (thread r of the per-vertex kernels) takes vertex vertex_order[r]: a permutation of [0, n) that keeps
  // every window [W w, W w + W) in place, sorted by the entries walked, largest first (ties by vertex index).
  std::vector<int> vertex_order;
  std::vector<kernels::SlicedRow> row;  // per row: vertex_order[r]'s
  // Entries in the layout, padding included: each slice of 32 rows is as wide as its longest row.
  std::int64_t entries = 0;
};

// The layout of the CSR with `vertex_count` + 1 `offsets` (non-decreasing, offsets[0] = 0), sorted within windows
// of `window` vertices (valid_slice_window; others take kDefaultSliceWindow). `fixed` (per vertex, null: none held)
// is the loads' mask: a vertex held on every axis (kernels::kAllAxesFixed) sorts as walking no entries, since
// kernels::vertex_acceleration returns before its gather; its row still holds all its entries. Fails (returns false)
// only where the layout would hold more than 2^31 - 1 entries, which its int indices cannot address; the caller
// then keeps the CSR order.
bool slice_spring_entries(const int* offsets, const unsigned char* fixed, int vertex_count, int window,
                          WorkerPool& pool, SlicedSpringLayout& layout);

}  // namespace fmpc::sim

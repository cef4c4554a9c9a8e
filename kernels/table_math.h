#pragma once
// Multilinear interpolation in an N-D lookup table (the `--target table` back end), shared by the CPU loader, the
// CUDA kernels and generated code. Axes hold strictly increasing breakpoints (uniform or refined). Values are
// stored row-major with the LAST axis fastest, and all outputs of one grid point together:
//   index(i_0, ..., i_{d-1}, o) = ((i_0 * n_1 + i_1) * n_2 + ... + i_{d-1}) * outputs + o.
// Queries outside an axis are clamped to it (a table never extrapolates; the caller flags out-of-range inputs the
// way the interpreter does). A NaN query gives NaN.
#include "kernels/fmpc_hd.h"

namespace fmpc {

inline constexpr int kMaxTableAxes = 8;

template <typename T>
struct TableView {
  int axes = 0;
  int outputs = 0;
  const int* counts = nullptr;           // breakpoints per axis, each >= 2
  const double* const* breakpoints = nullptr;  // per axis, strictly increasing
  const T* values = nullptr;
};

// The cell of `x` on one axis: i with breakpoints[i] <= x <= breakpoints[i + 1], and the fraction t in [0, 1].
// Binary search: refined axes are not uniform.
FMPC_HD void locate_on_axis(const double* breakpoints, int count, double x, int& cell, double& fraction) {
  if (!(x > breakpoints[0])) {  // also catches x == first breakpoint
    cell = 0;
    fraction = 0.0;
    return;
  }
  if (!(x < breakpoints[count - 1])) {  // exactly at the upper end, or above: the last cell's far corner
    cell = count - 2;
    fraction = 1.0;
    return;
  }
  int lo = 0, hi = count - 1;  // invariant: breakpoints[lo] <= x < breakpoints[hi]
  while (hi - lo > 1) {
    const int mid = lo + (hi - lo) / 2;
    if (breakpoints[mid] <= x)
      lo = mid;
    else
      hi = mid;
  }
  cell = lo;
  fraction = (x - breakpoints[lo]) / (breakpoints[lo + 1] - breakpoints[lo]);
}

// Interpolates every output at `query` (one value per axis) into `out` (table.outputs values).
// 2^d corner loop: d <= kMaxTableAxes keeps it bounded and register-friendly for the usual d <= 5.
template <typename T>
FMPC_HD void interpolate_table(const TableView<T>& table, const double* query, T* out) {
  int cell[kMaxTableAxes];
  double fraction[kMaxTableAxes];
  bool nan_query = false;
  for (int a = 0; a < table.axes; ++a) {
    nan_query = nan_query || query[a] != query[a];
    locate_on_axis(table.breakpoints[a], table.counts[a], query[a], cell[a], fraction[a]);
  }
  for (int o = 0; o < table.outputs; ++o) out[o] = T(0);
  if (nan_query) {
    for (int o = 0; o < table.outputs; ++o) out[o] = T(0) / T(0);
    return;
  }
  const int corners = 1 << table.axes;
  for (int corner = 0; corner < corners; ++corner) {
    double weight = 1.0;
    long long index = 0;
    for (int a = 0; a < table.axes; ++a) {
      const int upper = (corner >> (table.axes - 1 - a)) & 1;
      weight *= upper ? fraction[a] : 1.0 - fraction[a];
      index = index * table.counts[a] + cell[a] + upper;
    }
    if (weight == 0.0) continue;  // at a breakpoint only one corner per axis counts; skip the rest
    for (int o = 0; o < table.outputs; ++o)
      out[o] += static_cast<T>(weight * static_cast<double>(table.values[index * table.outputs + o]));
  }
}

}  // namespace fmpc

#pragma once
// Multilinear interpolation in an N-D lookup table (the `--target table` back end), shared by the CPU loader, the
// CUDA kernels and generated code. Axes hold strictly increasing breakpoints (uniform or refined). Values are
// stored row-major with the LAST axis fastest, and all outputs of one grid point together:
//   index(i_0, ..., i_{d-1}, o) = ((i_0 * n_1 + i_1) * n_2 + ... + i_{d-1}) * outputs + o.
// Queries outside an axis are clamped to it (a table never extrapolates; the caller flags out-of-range inputs the
// way the interpreter does). A NaN query gives NaN. Values must be finite (validate_table checks it): a corner
// whose weight is 0 still enters the interpolation as 0 * value.
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

namespace table_detail {

// (1 - t) a + t b, not a + t (b - a): it is exact at both ends (t = 0 gives a, t = 1 gives b), with or without
// FMA contraction, so lookups at breakpoints and at the upper ends return the stored values bit for bit.
template <typename T>
FMPC_HD T lerp(T a, T b, T t) {
  return (T(1) - t) * a + t * b;
}

}  // namespace table_detail

// The cell of `x` on one axis: i with breakpoints[i] <= x < breakpoints[i + 1] (the last cell at and above the
// upper end), and the fraction t in [0, 1]. The cell is first guessed by proportion, which on a uniform axis is
// the cell itself up to rounding (checked against the two breakpoints, one step either way); on a refined axis a
// wrong guess still bounds a binary search. Either way the cell is the unique one above, so the result does not
// depend on the spacing.
FMPC_HD void locate_on_axis(const double* breakpoints, int count, double x, int& cell, double& fraction) {
  const double first = breakpoints[0], last = breakpoints[count - 1];
  if (!(x > first)) {  // also catches x == first breakpoint and NaN
    cell = 0;
    fraction = 0.0;
    return;
  }
  if (!(x < last)) {  // exactly at the upper end, or above: the last cell's far corner
    cell = count - 2;
    fraction = 1.0;
    return;
  }
  // first < x < last, so position >= 0; a NaN or huge position (breakpoints spanning more than the largest
  // double) falls to the last cell and is corrected below.
  const double position = (x - first) / (last - first) * static_cast<double>(count - 1);
  int lo = position < static_cast<double>(count - 2) ? static_cast<int>(position) : count - 2;
  int hi = lo + 1;
  // Invariant from here: breakpoints[lo] <= x < breakpoints[hi].
  double at_lo = breakpoints[lo], at_hi = breakpoints[hi];
  if (x < at_lo) {  // guessed too high: lo >= 1, since breakpoints[0] < x
    hi = lo;
    at_hi = at_lo;
    lo = hi - 1;
    at_lo = breakpoints[lo];
    if (x < at_lo) {
      hi = lo;
      at_hi = at_lo;
      lo = 0;
      at_lo = first;
    }
  } else if (!(x < at_hi)) {  // guessed too low: hi <= count - 2, since x < breakpoints[count - 1]
    lo = hi;
    at_lo = at_hi;
    hi = lo + 1;
    at_hi = breakpoints[hi];
    if (!(x < at_hi)) {
      lo = hi;
      at_lo = at_hi;
      hi = count - 1;
      at_hi = last;
    }
  }
  while (hi - lo > 1) {
    const int mid = lo + (hi - lo) / 2;
    const double at_mid = breakpoints[mid];
    if (at_mid <= x) {
      lo = mid;
      at_lo = at_mid;
    } else {
      hi = mid;
      at_hi = at_mid;
    }
  }
  cell = lo;
  fraction = (x - at_lo) / (at_hi - at_lo);
}

namespace table_detail {

// The lookup for a table of `Axes` axes (0: table.axes, known only at run time). The 2^d corner values are blended
// by successive linear interpolation, innermost along the last axis (whose two corners are adjacent in memory):
// 2^d - 1 lerps in the value type instead of 2^d products of d weights. Corners are visited in binary order and
// partial[k] holds the pending lower half of a block of 2^(k+1) corners, so any d needs only d partial values.
// With Axes fixed every loop has a constant trip count and unrolls into straight-line code.
template <int Axes, typename T>
FMPC_HD void interpolate_cells(const TableView<T>& table, const double* query, T* out) {
  const int axes = Axes > 0 ? Axes : table.axes;
  constexpr int kSlots = Axes > 0 ? Axes : kMaxTableAxes;
  long long stride[kSlots];  // in values, corner offset of the upper neighbour along each axis
  T weight[kSlots];          // the fraction along each axis, in the value type
  long long base = 0;        // index of the cell's lower corner, in grid points
  bool nan_query = false;
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int a = 0; a < axes; ++a) {
    const double x = query[a];
    nan_query = nan_query || x != x;
    const int count = table.counts[a];
    int cell = 0;
    double fraction = 0.0;
    locate_on_axis(table.breakpoints[a], count, x, cell, fraction);
    base = base * count + cell;
    weight[a] = static_cast<T>(fraction);
  }
  const int outputs = table.outputs;
  if (nan_query) {
    for (int o = 0; o < outputs; ++o) out[o] = T(0) / T(0);
    return;
  }
  long long span = outputs;
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int a = axes - 1; a >= 0; --a) {
    stride[a] = span;
    span *= table.counts[a];
  }
  const T* const lower_corner = table.values + base * outputs;
  const int corners = 1 << axes;
  for (int o = 0; o < outputs; ++o) {
    T partial[kSlots];
    T value = T(0);
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
    for (int corner = 0; corner < corners; ++corner) {
      long long offset = o;
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
      for (int a = 0; a < axes; ++a) offset += ((corner >> (axes - 1 - a)) & 1) * stride[a];
      value = lower_corner[offset];
      // Bit k of `corner` is the corner's side along axis axes-1-k: a 0 leaves the value pending at level k,
      // a 1 completes the pair there and carries the blend one level up.
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
      for (int k = 0; k < axes; ++k) {
        if (((corner >> k) & 1) == 0) {
          partial[k] = value;
          break;
        }
        value = lerp(partial[k], value, weight[axes - 1 - k]);
      }
    }
    out[o] = value;  // the last corner (all ones) carried the blend through every level
  }
}

}  // namespace table_detail

// Interpolates every output at `query` (one value per axis) into `out` (table.outputs values). Arithmetic after
// locating the cell is in the value type T (float tables interpolate in float).
template <typename T>
FMPC_HD void interpolate_table(const TableView<T>& table, const double* query, T* out) {
  // The usual dimensions get straight-line code; more axes take the general loop.
  switch (table.axes) {
    case 1: return table_detail::interpolate_cells<1>(table, query, out);
    case 2: return table_detail::interpolate_cells<2>(table, query, out);
    case 3: return table_detail::interpolate_cells<3>(table, query, out);
    case 4: return table_detail::interpolate_cells<4>(table, query, out);
    case 5: return table_detail::interpolate_cells<5>(table, query, out);
    default: return table_detail::interpolate_cells<0>(table, query, out);
  }
}

// The same for a table whose number of axes is known when compiling (generated headers: kAxes); table.axes must
// equal Axes. Only this dimension's code is instantiated, which keeps a kernel's register count to what it needs.
template <int Axes, typename T>
FMPC_HD void interpolate_table_with_axes(const TableView<T>& table, const double* query, T* out) {
  static_assert(Axes >= 1 && Axes <= kMaxTableAxes, "a table has 1 to kMaxTableAxes axes");
  table_detail::interpolate_cells<Axes>(table, query, out);
}

}  // namespace fmpc

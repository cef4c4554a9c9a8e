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

// Locates `query` on every axis: the cell's lower corner per axis and the fraction along it (in T). Returns
// false for a NaN query.
template <int Axes, typename T>
FMPC_HD bool locate_cell(int axes, const int* counts, const double* const* breakpoints, const double* query,
                         int* cell, T* weight) {
  bool nan_query = false;
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int a = 0; a < (Axes > 0 ? Axes : axes); ++a) {
    const double x = query[a];
    nan_query = nan_query || x != x;
    double fraction = 0.0;
    locate_on_axis(breakpoints[a], counts[a], x, cell[a], fraction);
    weight[a] = static_cast<T>(fraction);
  }
  return !nan_query;
}

// Blends the 2^d corner values of a cell by successive linear interpolation, innermost along the last axis:
// 2^d - 1 lerps in the value type instead of 2^d products of d weights. corner_value(c) is the value at corner c,
// whose bit d-1-a is its side along axis a, so corners come in binary order; partial[k] holds the pending lower
// half of a block of 2^(k+1) corners, so any d needs only d partial values. Both layouts (grid and sector-packed)
// blend through here, in the same order, so they give the same bits.
template <int Axes, typename T, typename CornerValue>
FMPC_HD T blend_corners(int axes, const T* weight, CornerValue corner_value) {
  constexpr int kSlots = Axes > 0 ? Axes : kMaxTableAxes;
  T partial[kSlots];
  T value = T(0);
  const int corners = 1 << axes;
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int corner = 0; corner < corners; ++corner) {
    value = corner_value(corner);
    // A 0 in bit k leaves the value pending at level k, a 1 completes the pair there and carries the blend up.
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
  return value;  // the last corner (all ones) carried the blend through every level
}

template <typename T>
FMPC_HD void fill_nan(T* out, int outputs) {
  for (int o = 0; o < outputs; ++o) out[o] = T(0) / T(0);
}

// The lookup for a table of `Axes` axes (0: table.axes, known only at run time). With Axes fixed every loop has a
// constant trip count and unrolls into straight-line code.
template <int Axes, typename T>
FMPC_HD void interpolate_cells(const TableView<T>& table, const double* query, T* out) {
  const int axes = Axes > 0 ? Axes : table.axes;
  constexpr int kSlots = Axes > 0 ? Axes : kMaxTableAxes;
  int cell[kSlots];
  T weight[kSlots];
  if (!locate_cell<Axes>(axes, table.counts, table.breakpoints, query, cell, weight))
    return fill_nan(out, table.outputs);
  const int outputs = table.outputs;
  long long stride[kSlots];  // in values, the offset of the upper neighbour along each axis
  long long base = 0;        // index of the cell's lower corner, in grid points
  long long span = outputs;
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int a = axes - 1; a >= 0; --a) {
    stride[a] = span;
    span *= table.counts[a];
  }
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int a = 0; a < axes; ++a) base = base * table.counts[a] + cell[a];
  for (int o = 0; o < outputs; ++o) {
    const T* const lower_corner = table.values + base * outputs + o;
    out[o] = blend_corners<Axes>(axes, weight, [&](int corner) {
      long long offset = 0;
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
      for (int a = 0; a < axes; ++a) offset += ((corner >> (axes - 1 - a)) & 1) * stride[a];
      return lower_corner[offset];
    });
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

// ---- Sector-packed layout ----
// A random lookup in the grid layout gathers 2^d values from 2^(d-1) places: on a GPU a table larger than an SM's
// L1 turns each into an L2 sector read (32 bytes for 8 or 16 useful), and the 5-D liver table at 9^5 points in
// double is L2-bound at a third of the target rate (docs/performance.md). The packed layout stores, for every
// cell of the last P axes and every grid point of the others, the cell's 2^P corner values together:
//   group(u, c, o) = ((u * inner_cells + c) * outputs + o) * 2^P,   value = group + corner bits (first packed axis
// most significant), u = the grid point on axes 0..d-P-1 (row-major), c = the cell on axes d-P..d-1 (row-major
// over counts - 1). With 2^P values in one 32-byte sector a lookup reads 2^(d-P) sectors instead of about
// 2^(d-1) + (straddles); memory grows by about 2^P.
template <typename T>
struct PackedTableView {
  int axes = 0;
  int outputs = 0;
  const int* counts = nullptr;
  const double* const* breakpoints = nullptr;
  int packed_axes = 0;      // P, 1 <= P <= axes
  const T* groups = nullptr;  // packed_table_size values; 32-byte aligned for the device's vector loads
};

// Which layout a device launcher uses. Automatic: packed where packed_layout_pays.
enum class TableLayout { Automatic, Grid, SectorPacked };

// What an SM's L1 holds of a table, about (H100: up to 256 KiB of L1 and shared memory, the rest of the kernel's
// working set beside it).
inline constexpr unsigned long long kL1TableBytes = 160ULL * 1024;

// Where the packed copy (read by lane pairs on the device) is faster than the grid: tables of 3 or more axes,
// unless the grid fits in L1 and the 2^P-times larger packed copy does not. Measured on an H100, 5-D liver
// tables (docs/performance.md, "Table lookups by layout"): 9^5 double (461 KiB grid) 1.47e10 packed vs 7.2e9
// grid, 9^5 float 2.63e10 vs 1.73e10, 5^5 double (24 KiB; packed 64 KiB) 2.91e10 vs 2.36e10, but 7^5 double
// (131 KiB; packed 395 KiB) 1.81e10 vs 2.07e10. Tables of 1 or 2 axes gather 2 or 4 values (1 or 2 sectors) a
// lookup: packing gains them nothing.
FMPC_HD constexpr bool packed_layout_pays(int axes, unsigned long long grid_bytes, unsigned long long packed_bytes) {
  return axes >= 3 && (grid_bytes > kL1TableBytes || packed_bytes <= kL1TableBytes);
}

// P for value type T: a group of 2^P values fills one 32-byte sector (double: 4 values, P = 2; float: 8, P = 3),
// at most every axis.
template <typename T>
FMPC_HD constexpr int packed_lookup_axes(int axes) {
  const int fill = sizeof(T) >= 8 ? 2 : sizeof(T) >= 4 ? 3 : 4;
  return axes < fill ? axes : fill;
}

// Values in the packed copy of a table with these counts.
FMPC_HD long long packed_table_size(int axes, const int* counts, int outputs, int packed_axes) {
  long long size = static_cast<long long>(outputs) << packed_axes;
  for (int a = 0; a < axes; ++a) size *= a < axes - packed_axes ? counts[a] : counts[a] - 1;
  return size;
}

// The value at `index` of the packed copy of `table` (every index in [0, packed_table_size)): what a packing
// kernel or loop writes.
template <typename T>
FMPC_HD T packed_table_value(const TableView<T>& table, int packed_axes, long long index) {
  const int axes = table.axes, outer = axes - packed_axes;
  const long long corner = index & ((1LL << packed_axes) - 1);
  long long rest = index >> packed_axes;
  const int o = static_cast<int>(rest % table.outputs);
  rest /= table.outputs;
  // rest = u * inner_cells + c: peel c's digits (last axis first), then u's.
  long long point = 0, scale = 1;  // the corner's grid point, row-major, built from the last axis
  for (int a = axes - 1; a >= 0; --a) {
    const int count = table.counts[a];
    long long coordinate;
    if (a >= outer) {
      coordinate = rest % (count - 1) + ((corner >> (axes - 1 - a)) & 1);
      rest /= count - 1;
    } else {
      coordinate = rest % count;
      rest /= count;
    }
    point += coordinate * scale;
    scale *= count;
  }
  return table.values[point * table.outputs + o];
}

namespace table_detail {

// Reads one group of N values. On the device, with N values filling whole 16-byte words, as 16-byte vector loads
// through the read-only path (the group is 16-byte aligned: groups are 32-byte aligned when 2^P values fill a
// sector, and N * sizeof(T) is a multiple of 16).
template <int N, typename T>
FMPC_HD void load_group(const T* group, T* out) {
#if defined(__CUDA_ARCH__)
  if constexpr (sizeof(T) == 8 && N % 2 == 0) {
#pragma unroll
    for (int k = 0; k < N / 2; ++k) {
      const double2 pair = __ldg(reinterpret_cast<const double2*>(group) + k);
      out[2 * k] = pair.x;
      out[2 * k + 1] = pair.y;
    }
  } else if constexpr (sizeof(T) == 4 && N % 4 == 0) {
#pragma unroll
    for (int k = 0; k < N / 4; ++k) {
      const float4 quad = __ldg(reinterpret_cast<const float4*>(group) + k);
      out[4 * k] = quad.x;
      out[4 * k + 1] = quad.y;
      out[4 * k + 2] = quad.z;
      out[4 * k + 3] = quad.w;
    }
  } else {
#pragma unroll
    for (int k = 0; k < N; ++k) out[k] = __ldg(group + k);
  }
#else
  for (int k = 0; k < N; ++k) out[k] = group[k];
#endif
}

// The group (in groups of all outputs) of the cell's lower corner, and in stride[a] the step to the upper
// neighbour on each outer axis a < Axes - PackedAxes.
template <int Axes, int PackedAxes>
FMPC_HD long long first_packed_group(const int* counts, const int* cell, long long* stride) {
  constexpr int kOuter = Axes - PackedAxes;
  long long inner_cells = 1, inner_cell = 0, outer_point = 0;
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int a = kOuter; a < Axes; ++a) {
    inner_cell = inner_cell * (counts[a] - 1) + cell[a];
    inner_cells *= counts[a] - 1;
  }
  long long span = inner_cells;
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int a = kOuter - 1; a >= 0; --a) {
    stride[a] = span;
    span *= counts[a];
  }
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int a = 0; a < kOuter; ++a) outer_point = outer_point * counts[a] + cell[a];
  return outer_point * inner_cells + inner_cell;
}

}  // namespace table_detail

// interpolate_table on the packed copy: the same cell, weights and blend order, so the same bits. Axes and
// PackedAxes are compile-time (generated headers: kAxes and kPackedAxes) and must equal table.axes and
// table.packed_axes.
template <int Axes, int PackedAxes, typename T>
FMPC_HD void interpolate_packed_table(const PackedTableView<T>& table, const double* query, T* out) {
  static_assert(Axes >= 1 && Axes <= kMaxTableAxes && PackedAxes >= 1 && PackedAxes <= Axes,
                "1 <= PackedAxes <= Axes <= kMaxTableAxes");
  constexpr int kOuter = Axes - PackedAxes, kGroup = 1 << PackedAxes;
  int cell[Axes];
  T weight[Axes];
  if (!table_detail::locate_cell<Axes>(Axes, table.counts, table.breakpoints, query, cell, weight))
    return table_detail::fill_nan(out, table.outputs);
  long long stride[kOuter > 0 ? kOuter : 1];  // in groups of all outputs, the upper neighbour on each outer axis
  const long long first_group = table_detail::first_packed_group<Axes, PackedAxes>(table.counts, cell, stride);
  const int outputs = table.outputs;
  for (int o = 0; o < outputs; ++o) {
    T group[kGroup] = {};  // written at each group's first corner, before any read (GCC cannot see it)
    out[o] = table_detail::blend_corners<Axes>(Axes, weight, [&](int corner) {
      const int in_group = corner & (kGroup - 1);
      if (in_group == 0) {
        long long g = first_group;
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
        for (int a = 0; a < kOuter; ++a) g += ((corner >> (Axes - 1 - a)) & 1) * stride[a];
        table_detail::load_group<kGroup>(table.groups + (g * outputs + o) * kGroup, group);
      }
      return group[in_group];
    });
  }
}

#if defined(__CUDACC__)
// interpolate_packed_table for a warp on the device, with the lanes of each even/odd pair sharing their two
// lookups' groups: for a group of 32 bytes, both lanes read one 16-byte half of the SAME group, in two passes
// (the even lane's lookup, then the odd lane's). A random lookup's loads are limited by the L1's tag lookups, one
// per distinct line an instruction touches; pairing halves them (16 lines per load instead of 32). Each lane
// blends its half (the first packed axis at 0 or 1) over the other axes with the owner's weights, the halves are
// swapped with one shuffle, and the owner lerps along the first packed axis last. That moves the first packed
// axis's lerp from innermost to outermost: the same multilinear interpolant, rounded in another order (within a
// few ulp of interpolate_packed_table, not bit for bit). Every lane of the warp must call it together (the loop
// around it warp-uniform); a lane without a lookup passes active = false with any valid query and writes
// nothing. Requires 2^PackedAxes * sizeof(T) == 32.
template <int Axes, int PackedAxes, typename T>
__device__ __forceinline__ void interpolate_packed_table_lane_pairs(const PackedTableView<T>& table,
                                                                    const double* query, T* out, bool active) {
  static_assert(Axes >= 1 && Axes <= kMaxTableAxes && PackedAxes >= 1 && PackedAxes <= Axes,
                "1 <= PackedAxes <= Axes <= kMaxTableAxes");
  static_assert((sizeof(T) << PackedAxes) == 32, "a group fills one 32-byte sector");
  constexpr int kOuter = Axes - PackedAxes, kGroup = 1 << PackedAxes, kHalf = kGroup / 2;
  constexpr unsigned kWarp = 0xffffffffu;
  int cell[Axes];
  T weight[Axes];
  const bool valid = table_detail::locate_cell<Axes>(Axes, table.counts, table.breakpoints, query, cell, weight);
  long long stride[kOuter > 0 ? kOuter : 1];
  const long long first_group = table_detail::first_packed_group<Axes, PackedAxes>(table.counts, cell, stride);
  const int half = static_cast<int>(threadIdx.x & 1u);
  const int outputs = table.outputs;
  for (int o = 0; o < outputs; ++o) {
    T mine = T(0), theirs = T(0);  // this lane's half of its own lookup, and of its partner's
#pragma unroll
    for (int pass = 0; pass < 2; ++pass) {
      const int owner = static_cast<int>(threadIdx.x & 31u & ~1u) + pass;
      const long long group0 = __shfl_sync(kWarp, first_group, owner);
      // The outer corners in binary order, each one's half-group blended over the packed axes after the first:
      // the blend_corners tree over kOuter + PackedAxes - 1 axes, with that axis left out, on the owner's weights
      // (the first packed axis is blended outside this lane).
      T packed_weights[Axes];
      int k = 0;
#pragma unroll
      for (int a = 0; a < Axes; ++a)
        if (a != kOuter) packed_weights[k++] = __shfl_sync(kWarp, weight[a], owner);
      T values[kHalf] = {};
      const T value = table_detail::blend_corners<Axes - 1>(
          Axes - 1, packed_weights, [&](int corner) {
            const int in_half = corner & (kHalf - 1);
            const int outer_corner = corner >> (PackedAxes - 1);
            if (in_half == 0) {
              long long g = group0;
#pragma unroll
              for (int a = 0; a < kOuter; ++a) g += ((outer_corner >> (kOuter - 1 - a)) & 1) * stride[a];
              table_detail::load_group<kHalf>(table.groups + (g * outputs + o) * kGroup + half * kHalf, values);
            }
            return values[in_half];
          });
      if (pass == half) mine = value;
      else theirs = value;
    }
    const T other = __shfl_xor_sync(kWarp, theirs, 1);
    const T low = half == 0 ? mine : other, high = half == 0 ? other : mine;
    if (active) out[o] = valid ? table_detail::lerp(low, high, weight[kOuter]) : T(0) / T(0);
  }
}

// The device's packed reader for a warp (every lane calls it, as above): lane pairs where a group fills one
// 32-byte sector, else (float tables of 1 or 2 axes, double tables of 1: groups of 8 or 16 bytes) each lane alone.
template <int Axes, int PackedAxes, typename T>
__device__ __forceinline__ void interpolate_packed_table_in_warp(const PackedTableView<T>& table, const double* query,
                                                                 T* out, bool active) {
  if constexpr ((sizeof(T) << PackedAxes) == 32) {
    interpolate_packed_table_lane_pairs<Axes, PackedAxes>(table, query, out, active);
  } else {
    if (active) interpolate_packed_table<Axes, PackedAxes>(table, query, out);
  }
}
#endif  // __CUDACC__

}  // namespace fmpc

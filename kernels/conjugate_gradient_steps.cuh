// The conjugate gradient's steps on the GPU, each one device function that every launch of implicit Euler's solve
// runs (the per-iteration kernels, the fused stages, the cooperative grid and the one-block kernel,
// kernels/implicit_step.cu), so that all give the same bits: a row of A p after the elements' products, an entry's
// start, update and direction, the fixed-shape trees of the dot products and the scalars they set.
#pragma once

#include <cfloat>

#include "kernels/implicit_math.h"
#include "kernels/integrator_math.h"
#include "kernels/step_device.cuh"

namespace fmpc::gpu {

// Adds to out[j] the values c0 + j (j < C) of the corner slots begin to end - 1 (a vertex's run of the corner CSR,
// 3 values per slot), in slot order. The run is contiguous (node_slot), so an unrolled stretch's loads depend neither
// on each other nor on the sums, and a vertex's gather is not a chain of dependent loads.
// Eight slots' loads in flight for one entry, four for a whole row (whose 12 values a slot would otherwise take more
// registers than the one-block kernel's 128 a thread).
template <int C>
__device__ inline void gather_corner_run(int begin, int end, const double* values, int c0, double (&out)[C]) {
  constexpr int kInFlight = C == 1 ? 8 : 4;
#pragma unroll kInFlight
  for (int k = begin; k < end; ++k)
    for (int j = 0; j < C; ++j) out[j] += values[3 * k + c0 + j];
}

// Entries c0 to c0 + C - 1 of row v of A p into out (fixed vertices and axes: identity rows), after the elements'
// product: the whole row (C = 3, c0 = 0) for a thread per vertex, one entry (C = 1) for a thread per degree of
// freedom. Each entry's additions are the same in either, so both give the same bits.
template <int C, typename Real>
__device__ inline void apply_row_part(const ImplicitArguments<Real>& a, int v, int c0, double (&out)[C]) {
  const double* own = a.p + 3 * v;
  const unsigned char held = a.loads.fixed[v];
  if (held == kernels::kAllAxesFixed) {
    for (int j = 0; j < C; ++j) out[j] = own[c0 + j];
    return;
  }
  double sum[C];
  for (int j = 0; j < C; ++j) sum[j] = a.diagonal[v] * own[c0 + j];
  const kernels::SpringNetworkView<Real>& springs = a.model.springs;
  for (int e = springs.adjacency_offset[v]; e < springs.adjacency_offset[v + 1]; ++e) {
    const int s = springs.adjacency_spring[e], o = springs.adjacency_neighbour[e];
    const unsigned char other = a.loads.fixed[o];
    double relative[3];
    for (int c = 0; c < 3; ++c) relative[c] = own[c] - (kernels::axis_fixed(other, c) ? 0.0 : a.p[3 * o + c]);
    for (int j = 0; j < C; ++j) sum[j] += kernels::symmetric_row(a.blocks + 12 * s + 6, c0 + j, relative);
  }
  if (a.extra_blocks != nullptr) {
    double free_own[3];
    for (int c = 0; c < 3; ++c) free_own[c] = kernels::axis_fixed(held, c) ? 0.0 : own[c];
    for (int j = 0; j < C; ++j) sum[j] += kernels::symmetric_row(a.extra_blocks + 6 * v, c0 + j, free_own);
  }
  if (a.elements.count > 0)
    gather_corner_run(a.model.corners.offset[v], a.model.corners.offset[v + 1], a.elements.product, c0, sum);
  for (int j = 0; j < C; ++j) out[j] = kernels::axis_fixed(held, c0 + j) ? own[c0 + j] : sum[j];
}

// Row v of A p into ap.
template <typename Real>
__device__ inline void apply_row(const ImplicitArguments<Real>& a, int v) {
  double row[3];
  apply_row_part(a, v, 0, row);
  for (int c = 0; c < 3; ++c) a.ap[3 * v + c] = row[c];
}

// The partial sums of virtual block `block` of the fixed dot-product shape (kEnergyBlocks blocks of kEnergyThreads
// threads striding over [0, count)): thread t of the calling block (blockDim.x == kEnergyThreads) visits
// terms(i, sum, other) for i = block kEnergyThreads + t, then a stride of kEnergyBlocks kEnergyThreads on, and the
// block's trees sum `sum` and `other` (the second only where `pair`). A per-iteration kernel is virtual block
// blockIdx.x; the cooperative kernel's blocks take the virtual blocks in turn. Ends with a barrier, so the cache
// may be reused at once. A virtual block past the end sums nothing: its trees of +0.0 would give +0.0, so it skips
// them (and their barriers: the whole block takes the branch) -- on a small mesh nearly every virtual block is such,
// and each cooperative block would otherwise run a tree for a third of the kEnergyBlocks in every dot product.
template <typename Terms>
__device__ inline void virtual_block_sums(int block, int count, bool pair, double* cache, Terms&& terms,
                                          double& total, double& other_total) {
  if (static_cast<long long>(block) * kEnergyThreads >= count) {
    total = 0.0;
    other_total = 0.0;
    return;
  }
  double sum = 0.0, other = 0.0;
  const long long stride = static_cast<long long>(kEnergyBlocks) * kEnergyThreads;
  for (long long i = static_cast<long long>(block) * kEnergyThreads + threadIdx.x; i < count; i += stride)
    terms(static_cast<int>(i), sum, other);
  total = block_tree_sum(sum, cache);
  __syncthreads();  // every thread has read cache[0] before the next tree overwrites it
  other_total = pair ? block_tree_sum(other, cache) : 0.0;
  __syncthreads();
}

// The sums of the kEnergyBlocks partial sums in `partial` (and of the next kEnergyBlocks where `pair`), by one
// block of kEnergyThreads threads in a fixed tree; every thread gets them. Ends with a barrier.
__device__ inline void sum_partials(const double* partial, bool pair, double* cache, double& total,
                                    double& other_total) {
  double sum = 0.0, other = 0.0;
  for (int i = static_cast<int>(threadIdx.x); i < kEnergyBlocks; i += kEnergyThreads) {
    sum += partial[i];
    if (pair) other += partial[kEnergyBlocks + i];
  }
  total = block_tree_sum(sum, cache);
  __syncthreads();
  other_total = pair ? block_tree_sum(other, cache) : 0.0;
  __syncthreads();
}

// One degree of freedom at the start of a solve: x = 0, r = b, z = p = M^-1 r.
template <typename Real>
__device__ inline void cg_start_entry(const ImplicitArguments<Real>& a, int i) {
  a.x[i] = 0.0;
  a.r[i] = a.rhs[i];
  a.z[i] = a.inverse_jacobi[i] * a.r[i];
  a.p[i] = a.z[i];
}

// One degree of freedom's next direction: p = z + beta p.
template <typename Real>
__device__ inline void cg_direction_entry(const ImplicitArguments<Real>& a, double beta, int i) {
  a.p[i] = a.z[i] + beta * a.p[i];
}

// The scalars after p.Ap: alpha = rz / p.Ap.
__device__ inline void cg_set_alpha(ConjugateGradientScalars& s, double p_ap) {
  s.p_ap = p_ap;
  s.alpha = s.rz / p_ap;
}

// One degree of freedom's update after alpha: x += alpha p, r -= alpha ap, z = M^-1 r.
template <typename Real>
__device__ inline void cg_update_entry(const ImplicitArguments<Real>& a, double alpha, int i) {
  a.x[i] += alpha * a.p[i];
  a.r[i] -= alpha * a.ap[i];
  a.z[i] = a.inverse_jacobi[i] * a.r[i];
}

// The scalars after an iteration's residual sums, and the stopping test of the host loop it replaces
// (while |r|^2 >= threshold and iterations < cap): a NaN residual stops, as there.
__device__ inline void cg_finish_iteration(ConjugateGradientScalars& s, double rr, double rz_next, int limit) {
  s.rr = rr;
  s.rz_next = rz_next;
  s.beta = rz_next / s.rz;
  ++s.iterations;
  s.done = !(rr >= s.threshold) || s.iterations >= limit ? 1 : 0;
}

enum class CgStage : int { Start = 0, Alpha = 1, Residual = 2 };

// The scalars at the start of a solve from b.b (total) and r.z (other_total). Every field written, so that no later
// read (the cooperative kernel's copy, the host's) meets memory never written.
__device__ inline void cg_start_scalars(ConjugateGradientScalars& s, double total, double other_total,
                                        double tolerance, int limit) {
  s.rhs_norm2 = total;
  s.rz = other_total;
  s.p_ap = 0.0;
  s.alpha = 0.0;
  s.rr = total;
  s.rz_next = 0.0;
  s.beta = 0.0;
  const double threshold = tolerance * tolerance * total;
  s.threshold = threshold < DBL_MIN ? DBL_MIN : threshold;
  s.iterations = 0;
  // As the CPU backend: a right-hand side this small means the system is at rest to double precision; dv = 0 (the
  // start's x) and the positions still move with their velocities.
  s.at_rest = sqrt(total) < 1e-150 ? 1 : 0;
  s.done = s.at_rest || !(total >= s.threshold) || limit <= 0 ? 1 : 0;
  s.arrivals = 0;
}

// The scalars a stage's sums set: the start's, alpha, or the iteration's end and its stopping test.
__device__ inline void set_stage_scalars(ConjugateGradientScalars& s, CgStage stage, double total,
                                         double other_total, double tolerance, int limit) {
  switch (stage) {
    case CgStage::Start:
      cg_start_scalars(s, total, other_total, tolerance, limit);
      break;
    case CgStage::Alpha:
      cg_set_alpha(s, total);
      break;
    case CgStage::Residual:
      cg_finish_iteration(s, total, other_total, limit);
      break;
  }
}

// block_tree_reduce's sum of 256 values by one warp, the same additions in the same order: lane l holds values
// l, l + 32, ..., l + 224 in v; the widths 128, 64 and 32 pair values within a lane, 16 to 1 across lanes. Every lane
// returns the sum.
__device__ inline double warp_tree_sum(double (&v)[8]) {
  static_assert(kEnergyThreads == 256, "eight values per lane");
  for (int k = 0; k < 4; ++k) v[k] = v[k] + v[k + 4];
  for (int k = 0; k < 2; ++k) v[k] = v[k] + v[k + 2];
  double sum = v[0] + v[1];
  for (int width = 16; width > 0; width /= 2) sum = sum + __shfl_down_sync(0xffffffffu, sum, width);
  return __shfl_sync(0xffffffffu, sum, 0);
}

// warp_tree_sum of the 256 values at `values`.
__device__ inline double warp_tree_sum(const double* values) {
  const int lane = static_cast<int>(threadIdx.x) % 32;
  double v[8];
  for (int k = 0; k < 8; ++k) v[k] = values[lane + 32 * k];
  return warp_tree_sum(v);
}

// sum_partials by one warp (every lane gets the sum): thread t of kEnergyThreads starts at 0.0 and adds partial[t]
// for t < kEnergyBlocks, then the block's tree; partials from `used` on are +0.0 and not read.
__device__ inline double partials_warp_sum(const double* partial, int used) {
  static_assert(kEnergyBlocks <= kEnergyThreads, "one partial sum per thread");
  const int lane = static_cast<int>(threadIdx.x) % 32;
  double v[8];
  for (int k = 0; k < 8; ++k) {
    const int t = lane + 32 * k;
    v[k] = 0.0;
    if (t < kEnergyBlocks) v[k] += t < used ? partial[t] : 0.0;
  }
  return warp_tree_sum(v);
}

}  // namespace fmpc::gpu

// Implicit Euler on the GPU (gpu_launch.h): the system's assembly from the springs' blocks and the elements'
// linearisation, and the Jacobi-preconditioned conjugate gradient's kernels with their fixed-shape dot products.
#include <cooperative_groups.h>

#include <algorithm>
#include <cfloat>
#include <type_traits>

#include "kernels/conjugate_gradient_steps.cuh"
#include "kernels/implicit_contact_math.h"
#include "kernels/step_device.cuh"
#include "runtime/gpu/launch_plan.h"

namespace fmpc::gpu {

static_assert(kCgThreads == kEnergyThreads, "the cooperative CG's blocks are the dot products' virtual blocks");

namespace {

template <typename Real>
__global__ void implicit_spring_blocks_kernel(ImplicitArguments<Real> a) {
  const int s = vertex_index();
  if (s >= a.spring_count) return;
  const int p = a.first[s], q = a.second[s];
  const kernels::SpringNetworkView<Real>& springs = a.model.springs;
  const kernels::SpringLawParameters<double> law{springs.law.law, static_cast<double>(springs.law.k2_over_k1),
                                                 static_cast<double>(springs.law.xc)};
  kernels::implicit_spring_blocks(static_cast<double>(a.state.x[q]) - static_cast<double>(a.state.x[p]),
                                  static_cast<double>(a.state.y[q]) - static_cast<double>(a.state.y[p]),
                                  static_cast<double>(a.state.z[q]) - static_cast<double>(a.state.z[p]),
                                  a.rest_length[s], static_cast<double>(springs.stiffness[s]),
                                  springs.damping ? static_cast<double>(springs.damping[s]) : 0.0, law, a.h,
                                  a.blocks + 12 * s, a.blocks + 12 * s + 6);
}

// Element e's share of one term of the implicit system: its linearisation at the step's start (into
// `linearisation`), h^2 K v0 for the right-hand side and the diagonal of (h^2 + h beta) K_aa for the preconditioner;
// the first term writes them, each later one adds (Accumulate). Arrays of 3 values per node are indexed by the node's
// corner slot (kernels::node_slot: its entry in its vertex's run of the corner CSR), so that a vertex's gather reads
// its run contiguously, with no index to load before each value.
template <typename Real, typename Element, typename Law, bool Accumulate>
__global__ void implicit_element_kernel(ImplicitArguments<Real> a, kernels::ElementTermView<double> term,
                                        typename Element::template Linearisation<Law>* linearisation) {
  constexpr int N = Element::kNodes;
  const int e = vertex_index();
  const ImplicitElements& f = a.elements;
  if (e >= f.count) return;
  double x[N][3], v[N][3], kv[N][3], diagonal[N][3];
  for (int c = 0; c < N; ++c) {
    const int vertex = term.corners[N * e + c];
    x[c][0] = static_cast<double>(a.state.x[vertex]);
    x[c][1] = static_cast<double>(a.state.y[vertex]);
    x[c][2] = static_cast<double>(a.state.z[vertex]);
    v[c][0] = static_cast<double>(a.state.vx[vertex]);
    v[c][1] = static_cast<double>(a.state.vy[vertex]);
    v[c][2] = static_cast<double>(a.state.vz[vertex]);
  }
  typename Element::template Linearisation<Law> lin;
  Element::template linearise<Law>(term, e, x, lin);
  linearisation[e] = lin;
  Element::template stiffness_action<Law>(term, e, lin, v, kv);
  Element::template stiffness_diagonal<Law>(term, e, lin, diagonal);
  const double beta = term.stiffness_damping ? term.stiffness_damping[e] : 0.0;
  const double scale = a.h * a.h + a.h * beta;
  for (int c = 0; c < N; ++c) {
    const int slot = kernels::node_slot<N>(term, e, c);
    for (int i = 0; i < 3; ++i) {
      double& rhs = f.rhs_part[3 * slot + i];
      double& out = f.diagonal_part[3 * slot + i];
      rhs = Accumulate ? rhs + a.h * a.h * kv[c][i] : a.h * a.h * kv[c][i];
      out = Accumulate ? out + scale * diagonal[c][i] : scale * diagonal[c][i];
    }
  }
}

// (h^2 + h beta) K p of element e for one term, with the nodes at fixed vertices taken as zero (their rows are
// identity); the first term writes, each later one adds (accumulate). The per-iteration kernel and the cooperative
// one both call it, so their products have the same bits.
template <typename Real, typename Element, typename Law>
__device__ void element_apply(const ImplicitArguments<Real>& a, const kernels::ElementTermView<double>& term,
                              const typename Element::template Linearisation<Law>* linearisation, int e,
                              bool accumulate) {
  constexpr int N = Element::kNodes;
  const ImplicitElements& f = a.elements;
  double p[N][3], kp[N][3];
  for (int c = 0; c < N; ++c) {
    const int vertex = term.corners[N * e + c];
    const unsigned char held = a.loads.fixed[vertex];
    for (int i = 0; i < 3; ++i) p[c][i] = kernels::axis_fixed(held, i) ? 0.0 : a.p[3 * vertex + i];
  }
  Element::template stiffness_action<Law>(term, e, linearisation[e], p, kp);
  const double beta = term.stiffness_damping ? term.stiffness_damping[e] : 0.0;
  const double scale = a.h * a.h + a.h * beta;
  for (int c = 0; c < N; ++c) {
    double* product = f.product + 3 * kernels::node_slot<N>(term, e, c);
    for (int i = 0; i < 3; ++i) product[i] = accumulate ? product[i] + scale * kp[c][i] : scale * kp[c][i];
  }
}

// Every term's element products (element_apply) of elements first, first + stride, ...: the cooperative kernel's
// grid-stride loop and the one-block kernel's, each term's law found at run time.
template <typename Real>
__device__ void element_products_strided(const ImplicitArguments<Real>& a, int first, int stride) {
  for (int t = 0; t < a.elements.term_count; ++t) {
    const kernels::ElementTermView<double>& term = a.elements.terms[t];
    kernels::visit_element_term_on_device(term.element, term.law, [&](auto kind, auto element_law) {
      using Element = decltype(kind);
      using Law = decltype(element_law);
      using Linearisation = typename Element::template Linearisation<Law>;
      const auto* linearisation = static_cast<const Linearisation*>(a.elements.linearisation[t]);
      for (int e = first; e < a.elements.count; e += stride)
        element_apply<Real, Element, Law>(a, term, linearisation, e, t > 0);
    });
  }
}

template <typename Real, typename Element, typename Law, bool Accumulate>
__global__ void implicit_element_apply_kernel(ImplicitArguments<Real> a, kernels::ElementTermView<double> term,
                                              const typename Element::template Linearisation<Law>* linearisation) {
  const int e = vertex_index();
  if (e >= a.elements.count || a.scalars->done) return;
  element_apply<Real, Element, Law>(a, term, linearisation, e, Accumulate);
}

// launch(Element, Law, term index) for each element term, its element kind and law template arguments; the first
// error stops.
template <typename Launch>
cudaError_t for_each_term(const ImplicitElements& elements, Launch&& launch) {
  for (int t = 0; t < elements.term_count; ++t) {
    const kernels::ElementTermView<double>& term = elements.terms[t];
    const cudaError_t status = kernels::visit_element_term(term.element, term.law, [&](auto kind, auto element_law) {
      launch(kind, element_law, t);
      return cudaGetLastError();
    });
    if (status != cudaSuccess) return status;
  }
  return cudaSuccess;
}

template <typename Real, GatherKind K>
__global__ void implicit_vertex_kernel(ImplicitArguments<Real> a) {
  const int row = vertex_index();
  if (row >= a.vertex_count) return;
  const int v = vertex_of_row(a.model, row);
  double* b = a.rhs + 3 * v;
  const unsigned char held = a.loads.fixed[v];
  if (held == kernels::kAllAxesFixed) {
    a.diagonal[v] = 1.0;
    for (int c = 0; c < 3; ++c) {
      b[c] = 0.0;
      a.inverse_jacobi[3 * v + c] = 1.0;
    }
    return;
  }
  Real acceleration[3];
  const kernels::StateView<Real> state{a.state.x, a.state.y, a.state.z, a.state.vx, a.state.vy, a.state.vz};
  kernels::vertex_acceleration(v, forces_of<Real, K>(a.model, row), state, a.loads, acceleration[0], acceleration[1],
                               acceleration[2]);
  for (int c = 0; c < 3; ++c) b[c] = a.h * a.mass[v] * static_cast<double>(acceleration[c]);
  const double own_velocity[3] = {static_cast<double>(a.state.vx[v]), static_cast<double>(a.state.vy[v]),
                                  static_cast<double>(a.state.vz[v])};
  const double dx = static_cast<double>(a.state.x[v]) - a.rest_position[3 * v];
  const double dy = static_cast<double>(a.state.y[v]) - a.rest_position[3 * v + 1];
  const double dz = static_cast<double>(a.state.z[v]) - a.rest_position[3 * v + 2];
  const double diagonal = kernels::implicit_vertex_diagonal(
      a.mass[v], a.h, static_cast<double>(a.loads.gamma0), static_cast<double>(a.loads.gamma1),
      sqrt(dx * dx + dy * dy + dz * dz), static_cast<double>(a.loads.mass_damping));
  double jacobi[3] = {diagonal, diagonal, diagonal};
  const kernels::SpringNetworkView<Real>& springs = a.model.springs;
  for (int e = springs.adjacency_offset[v]; e < springs.adjacency_offset[v + 1]; ++e) {
    const int s = springs.adjacency_spring[e], o = springs.adjacency_neighbour[e];
    const double* stiffness = a.blocks + 12 * s;
    const double* system = stiffness + 6;
    const double relative[3] = {own_velocity[0] - static_cast<double>(a.state.vx[o]),
                                own_velocity[1] - static_cast<double>(a.state.vy[o]),
                                own_velocity[2] - static_cast<double>(a.state.vz[o])};
    double kv[3];
    kernels::symmetric_multiply(stiffness, relative, kv);
    for (int c = 0; c < 3; ++c) {
      b[c] -= a.h * a.h * kv[c];
      jacobi[c] += system[kernels::symmetric_index(c, c)];
    }
  }
  if (a.extra_blocks != nullptr) {
    // The caller's linear part (ImplicitArguments::extra_blocks): its block on the diagonal, its values into b.
    for (int c = 0; c < 3; ++c) {
      b[c] += a.extra_rhs[3 * v + c];
      jacobi[c] += a.extra_blocks[6 * v + kernels::symmetric_index(c, c)];
    }
  }
  if (a.elements.count > 0) {
    const int begin = a.model.corners.offset[v], end = a.model.corners.offset[v + 1];
    double kv[3] = {0.0, 0.0, 0.0}, element_diagonal[3] = {0.0, 0.0, 0.0};
    gather_corner_run(begin, end, a.elements.rhs_part, 0, kv);
    gather_corner_run(begin, end, a.elements.diagonal_part, 0, element_diagonal);
    for (int c = 0; c < 3; ++c) {
      b[c] -= kv[c];
      jacobi[c] += element_diagonal[c];
    }
  }
  a.diagonal[v] = diagonal;
  for (int c = 0; c < 3; ++c) {
    // A held axis is an identity row with a zero right-hand side.
    if (kernels::axis_fixed(held, c)) {
      b[c] = 0.0;
      jacobi[c] = 1.0;
    }
    a.inverse_jacobi[3 * v + c] = jacobi[c] != 0.0 ? 1.0 / jacobi[c] : 1.0;
  }
}

template <typename Real>
__global__ void implicit_apply_kernel(ImplicitArguments<Real> a) {
  const int v = vertex_index();
  if (v >= a.vertex_count || a.scalars->done) return;
  apply_row(a, v);
}

// Partial sums of first . second (and of third . fourth when third is not null) over [0, count), in the fixed
// shape of the energy sums; block b writes partial[b] and partial[kEnergyBlocks + b]. Nothing once `stop` (null
// for the start's sums, which come before the step's `done` is set) is done.
__global__ void dot_partial_kernel(const double* first, const double* second, const double* third, const double* fourth,
                                   int count, double* partial, const ConjugateGradientScalars* stop) {
  __shared__ double cache[kEnergyThreads];
  if (stop != nullptr && stop->done) return;
  const bool pair = third != nullptr;
  double total = 0.0, other_total = 0.0;
  virtual_block_sums(
      static_cast<int>(blockIdx.x), count, pair, cache,
      [&](int i, double& sum, double& other) {
        sum += first[i] * second[i];
        if (pair) other += third[i] * fourth[i];
      },
      total, other_total);
  if (threadIdx.x == 0) {
    partial[blockIdx.x] = total;
    partial[kEnergyBlocks + blockIdx.x] = other_total;
  }
}

// The stage's scalars from the partial sums. Every thread reads `done` before the trees' barriers and only thread
// 0 writes after them, so the block agrees on it.
__global__ void cg_scalars_kernel(const double* partial, ConjugateGradientScalars* scalars, CgStage stage,
                                  double tolerance, int limit) {
  __shared__ double cache[kEnergyThreads];
  if (stage != CgStage::Start && scalars->done) return;
  double total = 0.0, other_total = 0.0;
  sum_partials(partial, stage != CgStage::Alpha, cache, total, other_total);
  if (threadIdx.x == 0) set_stage_scalars(*scalars, stage, total, other_total, tolerance, limit);
}

// Per degree of freedom: x = 0, r = b, z = p = M^-1 r.
template <typename Real>
__global__ void cg_start_kernel(ImplicitArguments<Real> a) {
  const int i = vertex_index();
  if (i >= 3 * a.vertex_count) return;
  cg_start_entry(a, i);
}

template <typename Real>
__global__ void cg_update_kernel(ImplicitArguments<Real> a) {
  const int i = vertex_index();
  if (i >= 3 * a.vertex_count || a.scalars->done) return;
  cg_update_entry(a, a.scalars->alpha, i);
}

// p = z + beta p, unless the iteration just made stopped the solve; thread 0 then moves rz_next into rz, which
// nothing in this kernel reads.
template <typename Real>
__global__ void cg_direction_kernel(ImplicitArguments<Real> a) {
  const int i = vertex_index();
  if (i >= 3 * a.vertex_count || a.scalars->done) return;
  cg_direction_entry(a, a.scalars->beta, i);
  if (i == 0) a.scalars->rz = a.scalars->rz_next;
}

// A stage of the conjugate gradient in one launch where every degree of freedom has a thread of the dot products'
// first stride (3 n <= kFusedStageDofs; LaunchPlan::cg_fused_stages): block b is virtual block b, and thread i (from
// 0) does entry i's part of the stage and its dot terms -- the start (cg_start_entry; b.b, r.z), the matrix product (a
// row entry, apply_row_part; p.Ap) or the update (cg_update_entry; r.r, r.z) -- with the values the separate launches
// (the entry kernel, then dot_partial_kernel, then cg_scalars_kernel) would load, and the same trees. The last block
// to store its partial sums (counted in the scalars' `arrivals`, which it resets) sums them all and sets the scalars,
// so the iteration takes two launches for these six and gives their bits. Launched as kEnergyBlocks blocks (empty
// ones store +0.0). No block reads the scalars after the last one writes them: it arrives only after its reads.
template <typename Real, CgStage Stage>
__global__ void __launch_bounds__(kEnergyThreads) cg_fused_stage_kernel(ImplicitArguments<Real> a) {
  __shared__ double values[2 * kEnergyThreads];
  __shared__ bool last;
  ConjugateGradientScalars* const scalars = a.scalars;
  if (Stage != CgStage::Start && scalars->done) return;
  const double alpha = Stage == CgStage::Residual ? scalars->alpha : 0.0;
  constexpr bool pair = Stage != CgStage::Alpha;
  const int t = static_cast<int>(threadIdx.x), warp = t / 32, lane = t % 32;
  // virtual_block_sums' terms (a thread's entries in turn from 0.0: one where 3 n <= kFusedStageDofs), then its trees
  // by a warp each (warp_tree_sum: the same additions), so that one barrier, not one per level, stands before them.
  double sum = 0.0, other = 0.0;
  const long long stride = static_cast<long long>(kEnergyBlocks) * kEnergyThreads;
  for (long long i = static_cast<long long>(blockIdx.x) * kEnergyThreads + t; i < 3LL * a.vertex_count; i += stride) {
    const int entry = static_cast<int>(i);
    if constexpr (Stage == CgStage::Start) {
      cg_start_entry(a, entry);
      sum += a.rhs[entry] * a.rhs[entry];
      other += a.r[entry] * a.z[entry];
    } else if constexpr (Stage == CgStage::Alpha) {
      double row[1];
      apply_row_part(a, entry / 3, entry % 3, row);
      a.ap[entry] = row[0];
      sum += a.p[entry] * row[0];
    } else {
      cg_update_entry(a, alpha, entry);
      sum += a.r[entry] * a.r[entry];
      other += a.r[entry] * a.z[entry];
    }
  }
  values[t] = sum;
  values[kEnergyThreads + t] = other;
  __syncthreads();
  double* const partial = a.partial;
  if (warp < (pair ? 2 : 1)) {
    const double total = warp_tree_sum(values + warp * kEnergyThreads);
    if (lane == 0) {
      partial[warp * kEnergyBlocks + blockIdx.x] = total;
      __threadfence();  // the sum is visible before the arrival that counts it
    }
  }
  __syncthreads();
  if (t == 0) last = atomicAdd(&scalars->arrivals, 1u) == gridDim.x - 1;
  __syncthreads();
  if (!last) return;
  __threadfence();  // every other block's sums, counted before this arrival, are read after it
  if (warp < (pair ? 2 : 1)) {
    const double total = partials_warp_sum(partial + warp * kEnergyBlocks, kEnergyBlocks);
    if (lane == 0) values[warp] = total;
  }
  __syncthreads();
  if (t == 0) {
    scalars->arrivals = 0;
    set_stage_scalars(*scalars, Stage, values[0], pair ? values[1] : 0.0, a.tolerance, a.iteration_limit);
  }
}

template <typename Real, CgStage Stage>
cudaError_t launch_fused_stage(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  cg_fused_stage_kernel<Real, Stage><<<kEnergyBlocks, kEnergyThreads, 0, stream>>>(a);
  return cudaGetLastError();
}

// The cooperative conjugate gradient (launch_cg_persistent): launch_cg_iterations' kernels as phases between grid
// barriers, each thread taking the entries its kernel's thread would in turn (grid-stride), the dot products by the
// same virtual blocks, and the scalars computed by every block from the same partial sums (so every block holds
// the same bits and takes the same branch; block 0 stores them at the end). The alpha sums go to the second pair
// of partial arrays: a block may write the residual's sums while another still reads alpha's.
template <typename Real>
__global__ void __launch_bounds__(kEnergyThreads) cg_persistent_kernel(ImplicitArguments<Real> a) {
  namespace cg = cooperative_groups;
  __shared__ double cache[kEnergyThreads];
  cg::grid_group grid = cg::this_grid();
  ConjugateGradientScalars s = *a.scalars;
  const int dofs = 3 * a.vertex_count;
  const int thread = vertex_index();
  const int threads = static_cast<int>(gridDim.x) * static_cast<int>(blockDim.x);
  double* residual_partial = a.partial;
  double* alpha_partial = a.partial + 2 * kEnergyBlocks;
  const int block = static_cast<int>(blockIdx.x), blocks = static_cast<int>(gridDim.x);
  while (!s.done) {
    if (a.elements.count > 0) {
      element_products_strided(a, thread, threads);
      grid.sync();
    }
    for (int v = thread; v < a.vertex_count; v += threads) apply_row(a, v);
    grid.sync();
    for (int b = block; b < kEnergyBlocks; b += blocks) {
      double total = 0.0, unused = 0.0;
      virtual_block_sums(
          b, dofs, false, cache, [&](int i, double& sum, double&) { sum += a.p[i] * a.ap[i]; }, total, unused);
      if (threadIdx.x == 0) alpha_partial[b] = total;
    }
    grid.sync();
    {
      double p_ap = 0.0, unused = 0.0;
      sum_partials(alpha_partial, false, cache, p_ap, unused);
      cg_set_alpha(s, p_ap);
    }
    // The update of an entry and its residual terms by the one thread that sums them: the values are those the
    // per-iteration dot kernel would load after the update kernel.
    for (int b = block; b < kEnergyBlocks; b += blocks) {
      double total = 0.0, other_total = 0.0;
      virtual_block_sums(
          b, dofs, true, cache,
          [&](int i, double& sum, double& other) {
            cg_update_entry(a, s.alpha, i);
            sum += a.r[i] * a.r[i];
            other += a.r[i] * a.z[i];
          },
          total, other_total);
      if (threadIdx.x == 0) {
        residual_partial[b] = total;
        residual_partial[kEnergyBlocks + b] = other_total;
      }
    }
    grid.sync();
    {
      double rr = 0.0, rz_next = 0.0;
      sum_partials(residual_partial, true, cache, rr, rz_next);
      cg_finish_iteration(s, rr, rz_next, a.iteration_limit);
    }
    if (s.done) break;
    for (int i = thread; i < dofs; i += threads) cg_direction_entry(a, s.beta, i);
    s.rz = s.rz_next;
    grid.sync();
  }
  // Only after an iteration: every block then read *a.scalars before the first barrier.
  if (block == 0 && threadIdx.x == 0 && s.iterations > 0) *a.scalars = s;
}

// v += dv, x += h v at vertex v (dv in a.x); fixed vertices stay.
template <typename Real>
__device__ void implicit_finish_vertex(const ImplicitArguments<Real>& a, int v) {
  if (a.loads.fixed[v] == kernels::kAllAxesFixed) return;
  const Real h = static_cast<Real>(a.h);
  a.state.vx[v] += static_cast<Real>(a.x[3 * v]);
  a.state.vy[v] += static_cast<Real>(a.x[3 * v + 1]);
  a.state.vz[v] += static_cast<Real>(a.x[3 * v + 2]);
  a.state.x[v] += h * a.state.vx[v];
  a.state.y[v] += h * a.state.vy[v];
  a.state.z[v] += h * a.state.vz[v];
}

template <typename Real>
__global__ void implicit_finish_kernel(ImplicitArguments<Real> a) {
  const int v = vertex_index();
  if (v >= a.vertex_count) return;
  implicit_finish_vertex(a, v);
}

// dot_partial_kernel's and cg_scalars_kernel's sums (virtual_block_sums over kEnergyBlocks virtual blocks, then
// sum_partials) by one block of kCgBlockThreads threads with the terms and partial sums in shared memory: the same
// additions in the same order, so the same bits. terms(i, sum, other) as virtual_block_sums' (count at most
// kEnergyBlocks x kEnergyThreads, so one entry per virtual thread); `values` holds two arrays of count rounded up to
// kEnergyThreads, `partial` kEnergyBlocks (2 x where pair). Every thread gets the sums. Begins and ends with what a
// caller's barrier must separate: it reads what the block wrote before and writes `values` and `partial`.
template <typename Terms>
__device__ void block_fixed_shape_sums(int count, bool pair, double* values, double* partial, Terms&& terms,
                                       double& total, double& other_total) {
  const int used = (count + kEnergyThreads - 1) / kEnergyThreads;  // the virtual blocks that sum anything
  const int padded = used * kEnergyThreads;
  for (int i = static_cast<int>(threadIdx.x); i < padded; i += kCgBlockThreads) {
    double sum = 0.0, other = 0.0;
    if (i < count) terms(i, sum, other);
    values[i] = sum;
    if (pair) values[padded + i] = other;
  }
  __syncthreads();
  const int warp = static_cast<int>(threadIdx.x) / 32, lane = static_cast<int>(threadIdx.x) % 32;
  for (int b = warp; b < used; b += kCgBlockThreads / 32) {
    const double sum = warp_tree_sum(values + b * kEnergyThreads);
    const double other = pair ? warp_tree_sum(values + padded + b * kEnergyThreads) : 0.0;
    if (lane == 0) {
      partial[b] = sum;
      if (pair) partial[kEnergyBlocks + b] = other;
    }
  }
  __syncthreads();
  // Each warp sums the partials itself; an empty virtual block's partial is +0.0, and 0.0 + 0.0 is what its thread of
  // sum_partials holds.
  total = partials_warp_sum(partial, used);
  other_total = pair ? partials_warp_sum(partial + kEnergyBlocks, used) : 0.0;
}

// Which element terms a one-block solve's kernel is compiled for: none (springs alone), one term of a given element
// kind and law (the usual run: no dispatch, and registers for that law alone), or any number of any (each term
// visited at run time).
struct NoElementTerms {};
struct AnyElementTerms {};
template <typename Element, typename Law>
struct OneElementTerm {
  using element = Element;
  using law = Law;
};

// The element products of A p into s.elements.product, element e by thread e (then e + kCgBlockThreads, ...).
template <typename Real, typename Terms>
__device__ void block_element_products(const ImplicitArguments<Real>& s) {
  const int t = static_cast<int>(threadIdx.x);
  if constexpr (std::is_same_v<Terms, AnyElementTerms>) {
    element_products_strided(s, t, kCgBlockThreads);
  } else if constexpr (!std::is_same_v<Terms, NoElementTerms>) {
    using Element = typename Terms::element;
    using Law = typename Terms::law;
    using Linearisation = typename Element::template Linearisation<Law>;
    const auto* linearisation = static_cast<const Linearisation*>(s.elements.linearisation[0]);
    for (int e = t; e < s.elements.count; e += kCgBlockThreads)
      element_apply<Real, Element, Law>(s, s.elements.terms[0], linearisation, e, false);
  }
}

// A step's whole solve by one block (launch_cg_block), with its vectors in shared memory at `layout`: the start
// (launch_cg_start), the iterations of cg_persistent_kernel with block barriers in place of grid barriers, and, where
// `finish`, v += dv and x += h v (launch_implicit_finish). The same arithmetic in the same order as the per-iteration
// kernels, so the same bits. dv is written back to a.x and the scalars to *a.scalars.
template <typename Real, typename Terms>
__global__ void __launch_bounds__(kCgBlockThreads) cg_block_kernel(ImplicitArguments<Real> a, CgBlockLayout layout,
                                                                   bool finish) {
  extern __shared__ double shared[];
  const int n = a.vertex_count, dofs = 3 * n, t = static_cast<int>(threadIdx.x);
  ImplicitArguments<Real> s = a;  // the same arguments with the vectors in shared memory
  s.x = shared + layout.x;
  s.r = shared + layout.r;
  s.z = shared + layout.z;
  s.p = shared + layout.p;
  s.ap = shared + layout.ap;
  s.inverse_jacobi = shared + layout.inverse_jacobi;
  s.diagonal = shared + layout.diagonal;
  s.elements.product = shared + layout.product;
  double* const terms = shared + layout.terms;
  double* const alpha_partial = shared + layout.alpha_partial;
  double* const residual_partial = shared + layout.residual_partial;
  for (int i = t; i < dofs; i += kCgBlockThreads) {
    s.inverse_jacobi[i] = a.inverse_jacobi[i];
    cg_start_entry(s, i);
  }
  for (int v = t; v < n; v += kCgBlockThreads) s.diagonal[v] = a.diagonal[v];
  __syncthreads();
  ConjugateGradientScalars scalars;
  {
    double total = 0.0, other_total = 0.0;
    block_fixed_shape_sums(
        dofs, true, terms, residual_partial,
        [&](int i, double& sum, double& other) {
          sum += a.rhs[i] * a.rhs[i];
          other += s.r[i] * s.z[i];
        },
        total, other_total);
    cg_start_scalars(scalars, total, other_total, a.tolerance, a.iteration_limit);
  }
  while (!scalars.done) {
    if (a.elements.count > 0) {
      block_element_products<Real, Terms>(s);
      __syncthreads();
    }
    for (int v = t; v < n; v += kCgBlockThreads) apply_row(s, v);
    __syncthreads();
    {
      double p_ap = 0.0, unused = 0.0;
      block_fixed_shape_sums(
          dofs, false, terms, alpha_partial, [&](int i, double& sum, double&) { sum += s.p[i] * s.ap[i]; }, p_ap,
          unused);
      cg_set_alpha(scalars, p_ap);
    }
    {
      double rr = 0.0, rz_next = 0.0;
      block_fixed_shape_sums(
          dofs, true, terms, residual_partial,
          [&](int i, double& sum, double& other) {
            cg_update_entry(s, scalars.alpha, i);
            sum += s.r[i] * s.r[i];
            other += s.r[i] * s.z[i];
          },
          rr, rz_next);
      cg_finish_iteration(scalars, rr, rz_next, a.iteration_limit);
    }
    if (scalars.done) break;
    for (int i = t; i < dofs; i += kCgBlockThreads) cg_direction_entry(s, scalars.beta, i);
    scalars.rz = scalars.rz_next;
    __syncthreads();
  }
  __syncthreads();
  for (int i = t; i < dofs; i += kCgBlockThreads) a.x[i] = s.x[i];
  if (finish)
    for (int v = t; v < n; v += kCgBlockThreads) implicit_finish_vertex(s, v);
  if (t == 0) *a.scalars = scalars;
}

// The tools' contact as the system's linear part (kernels/implicit_contact_math.h, as the CPU's ImplicitContact):
// the vertex's active set at the state (predicted false) or after moving by h (v0 + dv) on its free axes with dv the
// solution in x; a set that changes counts into *contact_changes; the vertex's part for its set into extra_blocks
// and extra_rhs (zero for a vertex no tool can touch).
template <typename Real>
__global__ void contact_part_kernel(ImplicitArguments<Real> a, bool predicted) {
  const int v = vertex_index();
  if (v >= a.vertex_count) return;
  const double k = static_cast<double>(a.loads.contact.stiffness[v]);
  double* block = a.extra_blocks + 6 * v;
  double* rhs = a.extra_rhs + 3 * v;
  if (!(k > 0.0)) {
    if (predicted) return;
    for (int i = 0; i < 6; ++i) block[i] = 0.0;
    for (int c = 0; c < 3; ++c) rhs[c] = 0.0;
    return;
  }
  const unsigned char held = a.loads.fixed[v];
  const double x0[3] = {static_cast<double>(a.state.x[v]), static_cast<double>(a.state.y[v]),
                        static_cast<double>(a.state.z[v])};
  const double v0[3] = {static_cast<double>(a.state.vx[v]), static_cast<double>(a.state.vy[v]),
                        static_cast<double>(a.state.vz[v])};
  const auto set = static_cast<unsigned char>(
      predicted ? kernels::predicted_contact_set(a.loads.contact, held, a.h, x0, v0, a.x + 3 * v)
                : kernels::contact_set(a.loads.contact, x0[0], x0[1], x0[2], nullptr));
  if (predicted) {
    if (set == a.contact_active[v]) return;
    atomicAdd(a.contact_changes, 1u);
  }
  a.contact_active[v] = set;
  kernels::contact_system_part(a.loads.contact, set, k, a.h, x0, v0, held, block, rhs);
}

cudaError_t launch_dots(const double* first, const double* second, const double* third, const double* fourth, int count,
                        double* partial, ConjugateGradientScalars* scalars, CgStage stage, double tolerance, int limit,
                        cudaStream_t stream) {
  dot_partial_kernel<<<kEnergyBlocks, kEnergyThreads, 0, stream>>>(first, second, third, fourth, count, partial,
                                                                   stage == CgStage::Start ? nullptr : scalars);
  const cudaError_t status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  cg_scalars_kernel<<<1, kEnergyThreads, 0, stream>>>(partial, scalars, stage, tolerance, limit);
  return cudaGetLastError();
}

}  // namespace

// Threads per block of the assembly's per-element and per-vertex kernels (implicit_element_kernel,
// implicit_vertex_kernel): a thread's element or vertex is a long chain of double arithmetic (a polar decomposition
// or an SVD, the stiffness action and diagonal) or of loads, which a few warps per multiprocessor hide as well as
// many; small blocks spread a mesh's blocks over every multiprocessor where blocks of 256 would load a few (SOFA's
// liver: 3 of 132 for its elements; the 20^3 box: 37 for its vertices). Any block size gives the same bits (one
// element or vertex per thread).
constexpr int kLinearisationThreads = 32;
constexpr int kAssemblyVertexThreads = 64;

template <typename Real>
cudaError_t launch_implicit_assemble(const ImplicitArguments<Real>& a, bool linearise, cudaStream_t stream) {
  if (linearise && a.spring_count > 0) {
    implicit_spring_blocks_kernel<Real><<<blocks_for(a.spring_count), kThreadsPerBlock, 0, stream>>>(a);
    const cudaError_t status = cudaGetLastError();
    if (status != cudaSuccess) return status;
  }
  if (linearise && a.elements.count > 0) {
    // The element pass at the state (f0 in b) and the elements' linearisation, before the per-vertex kernel.
    cudaError_t status = launch_element_forces(
        a.model, kernels::StateView<Real>{a.state.x, a.state.y, a.state.z, a.state.vx, a.state.vy, a.state.vz}, stream);
    if (status != cudaSuccess) return status;
    status = for_each_term(a.elements, [&](auto kind, auto element_law, int t) {
      using Element = decltype(kind);
      using Law = decltype(element_law);
      using Linearisation = typename Element::template Linearisation<Law>;
      auto* linearisation = static_cast<Linearisation*>(a.elements.linearisation[t]);
      const int threads = kLinearisationThreads;
      const int blocks = (a.elements.count + threads - 1) / threads;
      if (t == 0) {
        implicit_element_kernel<Real, Element, Law, false>
            <<<blocks, threads, 0, stream>>>(a, a.elements.terms[t], linearisation);
      } else {
        implicit_element_kernel<Real, Element, Law, true>
            <<<blocks, threads, 0, stream>>>(a, a.elements.terms[t], linearisation);
      }
    });
    if (status != cudaSuccess) return status;
  }
  if (a.vertex_count <= 0) return cudaSuccess;
  return with_kind(a.model.kind, [&](auto kind) {
    const int blocks = (a.vertex_count + kAssemblyVertexThreads - 1) / kAssemblyVertexThreads;
    implicit_vertex_kernel<Real, decltype(kind)::value><<<blocks, kAssemblyVertexThreads, 0, stream>>>(a);
    return cudaGetLastError();
  });
}

template <typename Real>
cudaError_t launch_cg_start(const ImplicitArguments<Real>& a, bool fused, cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  if (fused) return launch_fused_stage<Real, CgStage::Start>(a, stream);
  cg_start_kernel<Real><<<blocks_for(3 * a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  const cudaError_t status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  return launch_dots(a.rhs, a.rhs, a.r, a.z, 3 * a.vertex_count, a.partial, a.scalars, CgStage::Start, a.tolerance,
                     a.iteration_limit, stream);
}

// An iteration's steps between the element products and the direction, a launch per step: the rows of A p, p.Ap and
// alpha, the update, r.r and r.z and the stopping test.
template <typename Real>
cudaError_t launch_separate_stages(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  const int dofs = 3 * a.vertex_count;
  implicit_apply_kernel<Real><<<blocks_for(a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  cudaError_t status = cudaGetLastError();
  if (status == cudaSuccess)
    status = launch_dots(a.p, a.ap, nullptr, nullptr, dofs, a.partial, a.scalars, CgStage::Alpha, a.tolerance,
                         a.iteration_limit, stream);
  if (status == cudaSuccess) {
    cg_update_kernel<Real><<<blocks_for(dofs), kThreadsPerBlock, 0, stream>>>(a);
    status = cudaGetLastError();
  }
  if (status == cudaSuccess)
    status = launch_dots(a.r, a.r, a.r, a.z, dofs, a.partial, a.scalars, CgStage::Residual, a.tolerance,
                         a.iteration_limit, stream);
  return status;
}

// The same steps with the rows, p.Ap and alpha in one launch and the update, its sums and the test in another
// (cg_fused_stage_kernel): the same bits in two launches for six.
template <typename Real>
cudaError_t launch_fused_stages(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  const cudaError_t status = launch_fused_stage<Real, CgStage::Alpha>(a, stream);
  return status == cudaSuccess ? launch_fused_stage<Real, CgStage::Residual>(a, stream) : status;
}

template <typename Real>
cudaError_t launch_cg_iterations(const ImplicitArguments<Real>& a, int count, bool fused, cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  for (int iteration = 0; iteration < count; ++iteration) {
    if (a.elements.count > 0) {
      const cudaError_t status = for_each_term(a.elements, [&](auto kind, auto element_law, int t) {
        using Element = decltype(kind);
        using Law = decltype(element_law);
        using Linearisation = typename Element::template Linearisation<Law>;
        const auto* linearisation = static_cast<const Linearisation*>(a.elements.linearisation[t]);
        if (t == 0) {
          implicit_element_apply_kernel<Real, Element, Law, false>
              <<<blocks_for(a.elements.count), kThreadsPerBlock, 0, stream>>>(a, a.elements.terms[t], linearisation);
        } else {
          implicit_element_apply_kernel<Real, Element, Law, true>
              <<<blocks_for(a.elements.count), kThreadsPerBlock, 0, stream>>>(a, a.elements.terms[t], linearisation);
        }
      });
      if (status != cudaSuccess) return status;
    }
    cudaError_t status = fused ? launch_fused_stages(a, stream) : launch_separate_stages(a, stream);
    if (status != cudaSuccess) return status;
    cg_direction_kernel<Real><<<blocks_for(3 * a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
    status = cudaGetLastError();
    if (status != cudaSuccess) return status;
  }
  return cudaSuccess;
}

template <typename Real>
cudaError_t cg_persistent_block_limit(int& blocks) {
  blocks = 0;
  int device = 0, cooperative = 0, multiprocessors = 0, per_multiprocessor = 0;
  cudaError_t status = cudaGetDevice(&device);
  if (status == cudaSuccess) status = cudaDeviceGetAttribute(&cooperative, cudaDevAttrCooperativeLaunch, device);
  if (status == cudaSuccess) status = cudaDeviceGetAttribute(&multiprocessors, cudaDevAttrMultiProcessorCount, device);
  if (status != cudaSuccess || cooperative == 0) return status;
  status =
      cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_multiprocessor, cg_persistent_kernel<Real>, kEnergyThreads, 0);
  if (status == cudaSuccess) blocks = per_multiprocessor * multiprocessors;
  return status;
}

template <typename Real>
cudaError_t launch_cg_persistent(const ImplicitArguments<Real>& a, int blocks, cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  if (blocks <= 0) return cudaErrorInvalidValue;
  ImplicitArguments<Real> copy = a;
  void* parameters[] = {&copy};
  return cudaLaunchCooperativeKernel(reinterpret_cast<const void*>(cg_persistent_kernel<Real>), dim3(blocks),
                                     dim3(kEnergyThreads), parameters, 0, stream);
}

// Calls with(Terms{}) for every element-terms choice cg_block_kernel is compiled for; the first error stops.
template <typename With>
cudaError_t for_each_block_terms(With&& with) {
  cudaError_t status = with(NoElementTerms{});
  if (status == cudaSuccess) status = with(AnyElementTerms{});
  for (int pair = 0; status == cudaSuccess && pair < kernels::ElementTermTypes::count; ++pair)
    status = kernels::visit_element_term(pair / kernels::ElementLaws::count, pair % kernels::ElementLaws::count,
                                         [&](auto kind, auto element_law) {
                                           return with(OneElementTerm<decltype(kind), decltype(element_law)>{});
                                         });
  return status;
}

template <typename Real>
cudaError_t cg_block_shared_limit(long long& bytes) {
  bytes = 0;
  int device = 0, optin = 0;
  cudaFuncAttributes attributes{};
  cudaError_t status = cudaGetDevice(&device);
  if (status == cudaSuccess) status = cudaDeviceGetAttribute(&optin, cudaDevAttrMaxSharedMemoryPerBlockOptin, device);
  // Every instantiation has no static shared memory and kCgBlockThreads as its bound; the one for any terms stands
  // for all.
  if (status == cudaSuccess) status = cudaFuncGetAttributes(&attributes, cg_block_kernel<Real, AnyElementTerms>);
  if (status != cudaSuccess || attributes.maxThreadsPerBlock < kCgBlockThreads) return status;
  const int dynamic = std::max(0, optin - static_cast<int>(attributes.sharedSizeBytes));
  // Above 48 KiB a kernel must ask for its dynamic shared memory, and the attribute is each function's: every
  // instantiation asks here, once, for what a launch may then take, so that no launch asks again.
  status = for_each_block_terms([&](auto terms) {
    return cudaFuncSetAttribute(cg_block_kernel<Real, decltype(terms)>, cudaFuncAttributeMaxDynamicSharedMemorySize,
                                dynamic);
  });
  if (status == cudaSuccess) bytes = dynamic;
  return status;
}

template <typename Real>
cudaError_t launch_cg_block(const ImplicitArguments<Real>& a, const CgBlockLayout& layout, long long bytes, bool finish,
                            cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  if (bytes <= 0) return cudaErrorInvalidValue;
  const auto launch = [&](auto terms) {
    cg_block_kernel<Real, decltype(terms)>
        <<<1, kCgBlockThreads, static_cast<std::size_t>(bytes), stream>>>(a, layout, finish);
    return cudaGetLastError();
  };
  if (a.elements.count <= 0) return launch(NoElementTerms{});
  if (a.elements.term_count != 1) return launch(AnyElementTerms{});
  return kernels::visit_element_term(a.elements.terms[0].element, a.elements.terms[0].law,
                                     [&](auto kind, auto element_law) {
                                       return launch(OneElementTerm<decltype(kind), decltype(element_law)>{});
                                     });
}

template <typename Real>
cudaError_t launch_contact_part(const ImplicitArguments<Real>& a, bool predicted, cudaStream_t stream) {
  if (a.vertex_count <= 0 || a.extra_blocks == nullptr) return cudaSuccess;
  contact_part_kernel<Real><<<blocks_for(a.vertex_count), kThreadsPerBlock, 0, stream>>>(a, predicted);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_implicit_finish(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  implicit_finish_kernel<Real><<<blocks_for(a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  return cudaGetLastError();
}

#define FMPC_IMPLICIT_STEP_LAUNCHERS(Real)                                                            \
  template cudaError_t launch_implicit_assemble<Real>(const ImplicitArguments<Real>&, bool, cudaStream_t); \
  template cudaError_t launch_cg_start<Real>(const ImplicitArguments<Real>&, bool, cudaStream_t);     \
  template cudaError_t launch_cg_iterations<Real>(const ImplicitArguments<Real>&, int, bool, cudaStream_t); \
  template cudaError_t launch_cg_persistent<Real>(const ImplicitArguments<Real>&, int, cudaStream_t); \
  template cudaError_t cg_persistent_block_limit<Real>(int&);                                         \
  template cudaError_t cg_block_shared_limit<Real>(long long&);                                       \
  template cudaError_t launch_cg_block<Real>(const ImplicitArguments<Real>&, const CgBlockLayout&, long long, bool, \
                                             cudaStream_t);                                           \
  template cudaError_t launch_contact_part<Real>(const ImplicitArguments<Real>&, bool, cudaStream_t); \
  template cudaError_t launch_implicit_finish<Real>(const ImplicitArguments<Real>&, cudaStream_t);
FMPC_IMPLICIT_STEP_LAUNCHERS(float)
FMPC_IMPLICIT_STEP_LAUNCHERS(double)

}  // namespace fmpc::gpu

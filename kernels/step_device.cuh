#pragma once
// Device functions every simulation kernel file shares (kernels/explicit_step.cu, persistent_step.cu,
// implicit_step.cu, reductions.cu): thread indexing, the force model of a thread, the Euler update of one vertex and
// the checks' per-vertex and per-element tests. Only CUDA translation units include it.
#include <type_traits>

#include "runtime/gpu/gpu_launch.h"

namespace fmpc::gpu {

constexpr int kThreadsPerBlock = 256;

inline int blocks_for(int count) { return (count + kThreadsPerBlock - 1) / kThreadsPerBlock; }

__device__ inline int vertex_index() {
  return static_cast<int>(blockIdx.x) * static_cast<int>(blockDim.x) + static_cast<int>(threadIdx.x);
}

// The vertex of thread `row` of a kernel with one thread per vertex (ForceModelView::vertex_order).
template <typename Real>
__device__ inline int vertex_of_row(const ForceModelView<Real>& m, int row) {
  return m.vertex_order != nullptr ? m.vertex_order[row] : row;
}

// The force model of thread `row` (a kernel with one thread per vertex, whose vertex is vertex_of_row(m, row)):
// with its sliced row of springs where the model has the sliced layout.
template <typename Real, GatherKind K>
__device__ auto forces_of(const ForceModelView<Real>& m, int row) {
  const kernels::SlicedRow sliced =
      m.springs.sliced.row != nullptr ? m.springs.sliced.row[row] : kernels::SlicedRow{0, -1};
  if constexpr (K == GatherKind::Springs) {
    return kernels::SpringForces<Real>{m.springs, sliced};
  } else if constexpr (K == GatherKind::Elements) {
    return kernels::ElementForces<Real>{m.corners};
  } else {
    return kernels::SpringAndElementForces<Real>{m.springs, m.corners, sliced};
  }
}

// Calls launch(std::integral_constant<GatherKind, K>{}) for the model's kind: the one place a kind becomes a
// template argument.
template <typename Launch>
inline cudaError_t with_kind(GatherKind kind, Launch&& launch) {
  switch (kind) {
    case GatherKind::Springs:
      return launch(std::integral_constant<GatherKind, GatherKind::Springs>{});
    case GatherKind::Elements:
      return launch(std::integral_constant<GatherKind, GatherKind::Elements>{});
    case GatherKind::SpringsAndElements:
      return launch(std::integral_constant<GatherKind, GatherKind::SpringsAndElements>{});
  }
  return cudaErrorInvalidValue;
}

template <typename Real>
__device__ Real step_of(const StepSize<Real>& step, int v) {
  return step.vertex_scene == nullptr ? step.h : step.scene_h[step.vertex_scene[v]];
}

template <typename Real>
__device__ void store_vertex_state(const MutableStateView<Real>& s, int v, const kernels::VertexState<Real>& x) {
  s.x[v] = x.x;
  s.y[v] = x.y;
  s.z[v] = x.z;
  s.vx[v] = x.vx;
  s.vy[v] = x.vy;
  s.vz[v] = x.vz;
}

// Forward or semi-implicit Euler on one vertex's state with acceleration a.
template <typename Real>
__device__ void euler_update(FusedScheme scheme, Real h, Real ax, Real ay, Real az, kernels::VertexState<Real>& x) {
  if (scheme == FusedScheme::ForwardEuler) {
    kernels::forward_euler_update(x.x, x.vx, ax, h);
    kernels::forward_euler_update(x.y, x.vy, ay, h);
    kernels::forward_euler_update(x.z, x.vz, az, h);
  } else {
    kernels::semi_implicit_euler_update(x.x, x.vx, ax, h);
    kernels::semi_implicit_euler_update(x.y, x.vy, ay, h);
    kernels::semi_implicit_euler_update(x.z, x.vz, az, h);
  }
}

// One vertex's forward or semi-implicit Euler step in registers: its acceleration from the internal force (fx, fy,
// fz) its caller gathered and its load values (kernels::loaded_acceleration; zero for a vertex held on every axis,
// whose force and load values are not read), then the update. Every explicit Euler kernel (per step, with lanes,
// persistent, in clusters) steps its vertices with it, so they give the same bits.
template <typename Real>
__device__ void explicit_vertex_step(FusedScheme scheme, Real h, unsigned char held,
                                     const kernels::VertexLoadValues<Real>& load,
                                     const kernels::VertexLoads<Real>& loads, Real fx, Real fy, Real fz,
                                     kernels::VertexState<Real>& self) {
  Real ax = Real(0), ay = Real(0), az = Real(0);
  if (held != kernels::kAllAxesFixed) kernels::loaded_acceleration(load, held, self, fx, fy, fz, loads, ax, ay, az);
  euler_update(scheme, h, ax, ay, az, self);
}

template <typename Real>
__device__ bool non_finite_vertex(const kernels::StateView<Real>& s, int v) {
  // Each value on its own: a sum of large finite values could overflow and be mistaken for one.
  return !(isfinite(s.x[v]) && isfinite(s.y[v]) && isfinite(s.z[v]) && isfinite(s.vx[v]) && isfinite(s.vy[v]) &&
           isfinite(s.vz[v]));
}

// Element e counted into its scene's inversion count and first inverted element where it is inverted at s.
template <typename Real>
__device__ void count_if_inverted(const int* nodes, int element_kind, int e, const int* element_scene,
                                  const kernels::StateView<Real>& s, unsigned int* count, int* first) {
  if (!kernels::element_inverted(element_kind, e, nodes, s.x, s.y, s.z)) return;
  const int scene = element_scene ? element_scene[e] : 0;
  atomicAdd(count + scene, 1u);
  atomicMin(first + scene, e);
}

// Six arrays of `stride` in shared memory (a persistent or cluster_euler_kernel block's state, a cluster block's
// window) as a state.
template <typename Real>
__device__ kernels::StateView<Real> shared_state(const Real* copy, int stride) {
  return {copy, copy + stride, copy + 2 * stride, copy + 3 * stride, copy + 4 * stride, copy + 5 * stride};
}
template <typename Real>
__device__ MutableStateView<Real> shared_state(Real* copy, int stride) {
  return {copy, copy + stride, copy + 2 * stride, copy + 3 * stride, copy + 4 * stride, copy + 5 * stride};
}

// The fixed tree of one block: thread t combines elements t, t + stride, ... in order, then pairs are combined
// halving the width. Deterministic because the shape depends only on the launch size, never on timing.
template <typename Combine>
__device__ double block_tree_reduce(double value, double* cache, Combine combine) {
  const int t = static_cast<int>(threadIdx.x);
  cache[t] = value;
  __syncthreads();
  for (int width = kEnergyThreads / 2; width > 0; width /= 2) {
    if (t < width) cache[t] = combine(cache[t], cache[t + width]);
    __syncthreads();
  }
  return cache[0];
}

__device__ inline double block_tree_sum(double value, double* cache) {
  return block_tree_reduce(value, cache, [](double a, double b) { return a + b; });
}

// A maximum that skips NaN as the host's std::max(largest, d) does (a NaN d never replaces largest).
__device__ inline double larger(double a, double b) { return a < b ? b : a; }

}  // namespace fmpc::gpu

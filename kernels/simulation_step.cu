// Thin CUDA kernels over the FMPC_HD functions of kernels/*_math.h: each per-vertex thread gathers its model's
// internal forces (springs in CSR order, elements' corner forces from the element pass; no float atomics) and writes
// only its own entries; each element thread writes only its own corners. A run gives the same bits every time and,
// compiled with --fmad=false, the same bits as the CPU loop. The per-vertex kernels are templates over the force
// model (GatherKind -> a struct of kernels/internal_force_math.h), dispatched once per launch.
#include <cooperative_groups.h>
#include <cuda/atomic>

#include <algorithm>
#include <limits>
#include <type_traits>

#include "runtime/gpu/gpu_launch.h"

namespace fmpc::gpu {

namespace {

constexpr int kThreadsPerBlock = 256;

__device__ int vertex_index() {
  return static_cast<int>(blockIdx.x) * static_cast<int>(blockDim.x) + static_cast<int>(threadIdx.x);
}

// The vertex of thread `row` of a kernel with one thread per vertex (ForceModelView::vertex_order).
template <typename Real>
__device__ int vertex_of_row(const ForceModelView<Real>& m, int row) {
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
cudaError_t with_kind(GatherKind kind, Launch&& launch) {
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

// The element's material in double, from the implicit copy of the field.
__device__ kernels::TetrahedronMaterial<double> implicit_material(const ImplicitElements& f, int e) {
  kernels::TetrahedronMaterial<double> m;
  m.law = f.law;
  m.rest_inverse = f.rest_inverse + 9 * e;
  m.rest_volume = f.rest_volume[e];
  m.youngs_modulus = f.youngs_modulus ? f.youngs_modulus[e] : 0.0;
  m.poisson_ratio = f.poisson_ratio ? f.poisson_ratio[e] : 0.0;
  m.bulk_modulus = f.bulk_modulus ? f.bulk_modulus[e] : 0.0;
  m.stiffness_damping = f.stiffness_damping ? f.stiffness_damping[e] : 0.0;
  m.strain_table = f.strain_table.strain ? &f.strain_table : nullptr;
  return m;
}

// The element pass needs 91 registers per thread in float unbounded (ptxas, sm_90), which leaves 2 blocks of 256 per
// SM; bounded to 3 blocks it gets 80 registers and spills 20 bytes (ncu: the spills' local stores became the pass's
// largest L2 traffic once the corner forces were written as vectors). ForceModelView::element_blocks picks the
// instance; double keeps its registers (1).
template <typename Real, int MinBlocks>
__global__ void __launch_bounds__(kThreadsPerBlock, MinBlocks)
    element_forces_kernel(ForceModelView<Real> m, kernels::StateView<Real> state) {
  const int e = vertex_index();
  if (e >= m.field.count) return;
  kernels::tetrahedron_corner_forces(e, m.field, state, m.corner_force);
}

template <typename Real>
__global__ void spring_incidence_kernel(kernels::SpringNetworkView<Real> net, int entries,
                                        kernels::SpringIncidence<Real>* incidence) {
  const int e = vertex_index();
  if (e >= entries) return;
  incidence[e] = kernels::incidence_from_arrays(net, e);
}

template <typename Real>
__global__ void sliced_springs_kernel(kernels::SpringNetworkView<Real> net, const int* vertex_order, int vertex_count,
                                      kernels::SpringIncidence<Real>* record) {
  const int row = vertex_index();
  if (row >= vertex_count) return;
  kernels::write_sliced_row(vertex_order[row], net, net.sliced.row[row], record);
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

// One vertex's forward or semi-implicit Euler step from `in` into `out`: the fused kernel's body, and the persistent
// kernel's for each vertex it owns (the same function, so the same bits).
template <typename Real, typename Forces>
__device__ void fused_vertex_step(const FusedStepArguments<Real>& a, const Forces& forces, int v,
                                  const kernels::StateView<Real>& in, const MutableStateView<Real>& out) {
  Real ax, ay, az;
  kernels::vertex_acceleration(v, forces, in, a.loads, ax, ay, az);
  kernels::VertexState<Real> x = kernels::vertex_state(in, v);
  euler_update(a.scheme, step_of(a.step, v), ax, ay, az, x);
  store_vertex_state(out, v, x);
}

// ProbeArguments' entry i as probe_entry_state reads it, for a chunk starting at step `step_base` (the per-step
// kernels read it from ProbeArguments::step_base, the persistent kernels have it by value).
template <typename Real>
__device__ ProbeEntry read_probe_entry(const ProbeArguments<Real>& a, int i, unsigned long long step_base) {
  ProbeEntry e;
  e.scene = a.scenes[a.entry_scene[i]];
  e.start_x = a.start_x[i];
  e.start_y = a.start_y[i];
  e.start_z = a.start_z[i];
  const bool based = e.scene.force_mode && e.scene.has_base_force;
  e.base_force_x = based ? a.base_force_x[i] : 0.0;
  e.base_force_y = based ? a.base_force_y[i] : 0.0;
  e.base_force_z = based ? a.base_force_z[i] : 0.0;
  e.step_base = step_base;
  e.vertex = a.vertices[i];
  return e;
}

// A force probe entry's force on its vertex, where probe_entry_state set one.
template <typename Real>
struct ProbeForce {
  bool set = false;
  Real x = Real(0), y = Real(0), z = Real(0);
};

// Probe entry e before or after the step at `offset` in the chunk: a force entry gives its vertex's external force
// (before the step) in `force`; a displacement entry prescribes its vertex's position and velocity into `state` and
// returns true.
template <typename Real>
__device__ bool probe_entry_state(const ProbeEntry& e, int offset, bool before_step, kernels::VertexState<Real>& state,
                                  ProbeForce<Real>& force) {
  const ProbeScene& p = e.scene;
  const double t =
      static_cast<double>(e.step_base + static_cast<unsigned long long>(offset + (before_step ? 0 : 1))) * p.h;
  if (p.force_mode) {
    if (!before_step) return false;
    const double share = kernels::probe_ramp_share(t, p.ramp_time);
    const double count = static_cast<double>(p.count);
    force = {true, static_cast<Real>(e.base_force_x + share * p.target_x / count),
             static_cast<Real>(e.base_force_y + share * p.target_y / count),
             static_cast<Real>(e.base_force_z + share * p.target_z / count)};
    return false;
  }
  kernels::probe_prescribed_state(e.start_x, p.target_x, t, p.ramp_time, before_step, state.x, state.vx);
  kernels::probe_prescribed_state(e.start_y, p.target_y, t, p.ramp_time, before_step, state.y, state.vy);
  kernels::probe_prescribed_state(e.start_z, p.target_z, t, p.ramp_time, before_step, state.z, state.vz);
  return true;
}

template <typename Real>
__device__ void store_probe_force(const MutableVector3View<Real>& to, int v, const ProbeForce<Real>& force) {
  if (!force.set) return;
  to.x[v] = force.x;
  to.y[v] = force.y;
  to.z[v] = force.z;
}

// Entry i of `a` (a chunk from step `step_base`) given to apply(entry, force), which returns whether it prescribed
// a state; a force it sets goes into a.force. The probe kernel's, the per-step fused kernels' and the cluster
// kernel's way to an entry.
template <typename Real, typename Apply>
__device__ bool apply_to_probe_entry(const ProbeArguments<Real>& a, int i, unsigned long long step_base, Apply apply) {
  const ProbeEntry e = read_probe_entry(a, i, step_base);
  ProbeForce<Real> force;
  const bool prescribed = apply(e, force);
  store_probe_force(a.force, e.vertex, force);
  return prescribed;
}

// probe_entry_state of entry i on `state`: the probe kernel's body.
template <typename Real>
__device__ void apply_probe_entry(const ProbeArguments<Real>& a, int i, int offset, bool before_step,
                                  const MutableStateView<Real>& state) {
  kernels::VertexState<Real> x{};
  const bool prescribed = apply_to_probe_entry(a, i, *a.step_base, [&](const ProbeEntry& e, ProbeForce<Real>& force) {
    return probe_entry_state(e, offset, before_step, x, force);
  });
  if (prescribed) store_vertex_state(state, a.vertices[i], x);
}

// Probe entry e after the step at `offset` and, where `next`, before the following one, on the state of its vertex
// `x`, by the thread that updated the vertex: the per-step fused kernels', the persistent kernels' order. Returns
// whether the entry prescribed `x` (a displacement entry; a force entry gives the vertex's external force in
// `force`).
template <typename Real>
__device__ bool probe_around_step(const ProbeEntry& e, int offset, bool next, kernels::VertexState<Real>& x,
                                  ProbeForce<Real>& force) {
  bool prescribed = probe_entry_state(e, offset, false, x, force);
  if (next) prescribed = probe_entry_state(e, offset + 1, true, x, force) || prescribed;
  return prescribed;
}

// probe_around_step for entry `entry` of `probe` (-1: none) in a chunk from step `step_base`, its force stored in
// probe.force.
template <typename Real>
__device__ bool probe_around_step(const ProbeArguments<Real>& probe, int entry, unsigned long long step_base,
                                  int offset, bool next, kernels::VertexState<Real>& x) {
  if (entry < 0) return false;
  return apply_to_probe_entry(probe, entry, step_base, [&](const ProbeEntry& e, ProbeForce<Real>& force) {
    return probe_around_step(e, offset, next, x, force);
  });
}

// probe_around_step on the state `out` (a displacement entry prescribes every value of its vertex's state, so
// nothing of `out` is read).
template <typename Real>
__device__ void apply_probe_after_step(const ProbeArguments<Real>& probe, int entry, int offset, bool next,
                                       const MutableStateView<Real>& out) {
  if (entry < 0) return;
  kernels::VertexState<Real> x{};
  if (probe_around_step(probe, entry, *probe.step_base, offset, next, x))
    store_vertex_state(out, probe.vertices[entry], x);
}

// Vertex v's probe entry around this step (FusedStepArguments::probe_entry).
template <typename Real>
__device__ void apply_own_probe(const FusedStepArguments<Real>& a, int v) {
  if (a.probe_entry != nullptr) apply_probe_after_step(a.probe, a.probe_entry[v], a.probe_offset, a.probe_next, a.out);
}

// Blocks per multiprocessor the fused step kernel is compiled for. The float springs gather reading four sliced
// entries ahead (kernels::kSlicedGatherBatch) takes 66 registers unbounded (3 blocks of 256 per SM); bounded to 4
// blocks it takes 64 with 4 bytes of spills, and the 240^3 box ran 601.1 steps/s against 581.4 (H100, 2,000 steps;
// 5 blocks: 48 registers, 80 bytes of spills, 414.6).
template <typename Real, GatherKind K>
constexpr int kFusedStepMinBlocks = std::is_same_v<Real, float>&& K == GatherKind::Springs ? 4 : 1;

template <typename Real, GatherKind K>
__global__ void __launch_bounds__(kThreadsPerBlock, (kFusedStepMinBlocks<Real, K>))
    fused_step_kernel(FusedStepArguments<Real> a) {
  const int row = vertex_index();
  if (row >= a.vertex_count) return;
  const int v = vertex_of_row(a.model, row);
  fused_vertex_step(a, forces_of<Real, K>(a.model, row), v, a.in, a.out);
  apply_own_probe(a, v);
}

template <typename Real, GatherKind K>
__global__ void acceleration_kernel(VerletArguments<Real> a) {
  const int row = vertex_index();
  if (row >= a.vertex_count) return;
  const int v = vertex_of_row(a.model, row);
  kernels::vertex_acceleration(v, forces_of<Real, K>(a.model, row), read_only(a.state), a.loads, a.acceleration.x[v],
                               a.acceleration.y[v], a.acceleration.z[v]);
}

template <typename Real, GatherKind>
__global__ void verlet_drift_kernel(VerletArguments<Real> a) {
  const int v = vertex_index();
  if (v >= a.vertex_count) return;
  const Real h = step_of(a.step, v);
  kernels::verlet_position_update(a.state.x[v], a.state.vx[v], a.acceleration.x[v], h, a.predicted.x[v]);
  kernels::verlet_position_update(a.state.y[v], a.state.vy[v], a.acceleration.y[v], h, a.predicted.y[v]);
  kernels::verlet_position_update(a.state.z[v], a.state.vz[v], a.acceleration.z[v], h, a.predicted.z[v]);
}

template <typename Real, GatherKind K>
__global__ void verlet_kick_kernel(VerletArguments<Real> a) {
  const int row = vertex_index();
  if (row >= a.vertex_count) return;
  const int v = vertex_of_row(a.model, row);
  const Real h = step_of(a.step, v);
  // Neighbours read x and the predictor only; v and a below are this vertex's own.
  const kernels::StateView<Real> drifted{a.state.x, a.state.y, a.state.z, a.predicted.x, a.predicted.y, a.predicted.z};
  Real ax, ay, az;
  kernels::vertex_acceleration(v, forces_of<Real, K>(a.model, row), drifted, a.loads, ax, ay, az);
  kernels::verlet_velocity_update(a.state.vx[v], a.acceleration.x[v], ax, h);
  kernels::verlet_velocity_update(a.state.vy[v], a.acceleration.y[v], ay, h);
  kernels::verlet_velocity_update(a.state.vz[v], a.acceleration.z[v], az, h);
  a.acceleration.x[v] = ax;
  a.acceleration.y[v] = ay;
  a.acceleration.z[v] = az;
}

template <typename Real, GatherKind K>
__global__ void runge_kutta4_stage_kernel(RungeKutta4Arguments<Real> a, int stage) {
  const int row = vertex_index();
  if (row >= a.vertex_count) return;
  const int v = vertex_of_row(a.model, row);
  const Real h = step_of(a.step, v);
  const kernels::StateView<Real> at =
      stage == 0 ? read_only(a.state) : kernels::StateView<Real>{a.stage_position[stage].x, a.stage_position[stage].y,
                                                                 a.stage_position[stage].z, a.stage_velocity[stage].x,
                                                                 a.stage_velocity[stage].y, a.stage_velocity[stage].z};
  Real ax, ay, az;
  kernels::vertex_acceleration(v, forces_of<Real, K>(a.model, row), at, a.loads, ax, ay, az);
  if (stage < 3) {
    a.stage_acceleration[stage].x[v] = ax;
    a.stage_acceleration[stage].y[v] = ay;
    a.stage_acceleration[stage].z[v] = az;
    // The offsets c of the next stage: h/2, h/2, h (the CPU loop's `offsets`).
    const Real c = stage == 2 ? h : h / Real(2);
    const int next = stage + 1;
    a.stage_position[next].x[v] = a.state.x[v] + c * at.vx[v];
    a.stage_position[next].y[v] = a.state.y[v] + c * at.vy[v];
    a.stage_position[next].z[v] = a.state.z[v] + c * at.vz[v];
    a.stage_velocity[next].x[v] = a.state.vx[v] + c * ax;
    a.stage_velocity[next].y[v] = a.state.vy[v] + c * ay;
    a.stage_velocity[next].z[v] = a.state.vz[v] + c * az;
    return;
  }
  if (a.loads.fixed[v] == kernels::kAllAxesFixed) return;
  const auto& kv = a.stage_velocity;
  const auto& ka = a.stage_acceleration;
  Real& x = a.state.x[v];
  Real& y = a.state.y[v];
  Real& z = a.state.z[v];
  Real& vx = a.state.vx[v];
  Real& vy = a.state.vy[v];
  Real& vz = a.state.vz[v];
  const Real vx0 = vx, vy0 = vy, vz0 = vz;
  x = kernels::runge_kutta4_combine(x, vx0, kv[1].x[v], kv[2].x[v], kv[3].x[v], h);
  y = kernels::runge_kutta4_combine(y, vy0, kv[1].y[v], kv[2].y[v], kv[3].y[v], h);
  z = kernels::runge_kutta4_combine(z, vz0, kv[1].z[v], kv[2].z[v], kv[3].z[v], h);
  vx = kernels::runge_kutta4_combine(vx0, ka[0].x[v], ka[1].x[v], ka[2].x[v], ax, h);
  vy = kernels::runge_kutta4_combine(vy0, ka[0].y[v], ka[1].y[v], ka[2].y[v], ay, h);
  vz = kernels::runge_kutta4_combine(vz0, ka[0].z[v], ka[1].z[v], ka[2].z[v], az, h);
}

template <typename Real>
__device__ bool non_finite_vertex(const kernels::StateView<Real>& s, int v) {
  // Each value on its own: a sum of large finite values could overflow and be mistaken for one.
  return !(isfinite(s.x[v]) && isfinite(s.y[v]) && isfinite(s.z[v]) && isfinite(s.vx[v]) && isfinite(s.vy[v]) &&
           isfinite(s.vz[v]));
}

template <typename Real>
__global__ void find_non_finite_kernel(kernels::StateView<Real> s, int vertex_count, int* first_vertex) {
  const int v = vertex_index();
  if (v >= vertex_count) return;
  if (non_finite_vertex(s, v)) atomicMin(first_vertex, v);
}

// Element e counted into its scene's inversion count and first inverted element where it is inverted at s.
template <typename Real>
__device__ void count_if_inverted(const int* corners, int e, const int* element_scene,
                                  const kernels::StateView<Real>& s, unsigned int* count, int* first) {
  if (!kernels::tetrahedron_inverted(e, corners, s.x, s.y, s.z)) return;
  const int scene = element_scene ? element_scene[e] : 0;
  atomicAdd(count + scene, 1u);
  atomicMin(first + scene, e);
}

template <typename Real>
__device__ double energy_term(const EnergyArguments<Real>& a, EnergyTerm term, int i) {
  const kernels::StateView<Real>& s = a.state;
  if (term == EnergyTerm::Kinetic) {
    const double vx = static_cast<double>(s.vx[i]), vy = static_cast<double>(s.vy[i]),
                 vz = static_cast<double>(s.vz[i]);
    return 0.5 * a.mass[i] * (vx * vx + vy * vy + vz * vz);
  }
  if (term == EnergyTerm::SpringPotential) {
    const int p = a.spring_first[i], q = a.spring_second[i];
    const double dx = static_cast<double>(s.x[q]) - static_cast<double>(s.x[p]);
    const double dy = static_cast<double>(s.y[q]) - static_cast<double>(s.y[p]);
    const double dz = static_cast<double>(s.z[q]) - static_cast<double>(s.z[p]);
    const double length = sqrt(dx * dx + dy * dy + dz * dz);
    const double k = a.table.strain != nullptr ? kernels::strain_table_stiffness(a.table, dx, dy, dz, a.rest_length[i],
                                                                                 a.stiffness_per_modulus[i])
                                               : a.stiffness[i];
    return kernels::spring_potential_energy(length, a.rest_length[i], k, a.law);
  }
  if (term == EnergyTerm::ElementPotential) {
    double corners[4][3];
    for (int c = 0; c < 4; ++c) {
      const int vertex = a.elements.corners[4 * i + c];
      corners[c][0] = static_cast<double>(s.x[vertex]);
      corners[c][1] = static_cast<double>(s.y[vertex]);
      corners[c][2] = static_cast<double>(s.z[vertex]);
    }
    return kernels::tetrahedron_elastic_energy(implicit_material(a.elements, i), corners);
  }
  const double x = static_cast<double>(s.x[i]), y = static_cast<double>(s.y[i]), z = static_cast<double>(s.z[i]);
  double energy = -(a.mass[i] * a.gravity_x * x) - a.mass[i] * a.gravity_y * y - a.mass[i] * a.gravity_z * z;
  if (a.force_x != nullptr) energy -= a.force_x[i] * x + a.force_y[i] * y + a.force_z[i] * z;
  return energy;
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

__device__ double block_tree_sum(double value, double* cache) {
  return block_tree_reduce(value, cache, [](double a, double b) { return a + b; });
}

// A maximum that skips NaN as the host's std::max(largest, d) does (a NaN d never replaces largest).
__device__ double larger(double a, double b) { return a < b ? b : a; }

// The largest |x - start| over vertices [begin, end), in double with mesh.cpp's distance() operations (compiled
// with --fmad=false: the host's bits); a maximum is exact in any order.
template <typename Real>
__global__ void largest_displacement_partial_kernel(kernels::StateView<Real> s, StartPositions start, int begin,
                                                    int end, double* partial) {
  __shared__ double cache[kEnergyThreads];
  double largest = 0.0;
  const long long stride = static_cast<long long>(kEnergyBlocks) * kEnergyThreads;
  for (long long i = begin + static_cast<long long>(blockIdx.x) * kEnergyThreads + threadIdx.x; i < end; i += stride) {
    const double dx = start.x[i] - static_cast<double>(s.x[i]);
    const double dy = start.y[i] - static_cast<double>(s.y[i]);
    const double dz = start.z[i] - static_cast<double>(s.z[i]);
    largest = larger(largest, sqrt(dx * dx + dy * dy + dz * dz));
  }
  const double block = block_tree_reduce(largest, cache, larger);
  if (threadIdx.x == 0) partial[blockIdx.x] = block;
}

__global__ void largest_displacement_final_kernel(const double* partial, double* result) {
  __shared__ double cache[kEnergyThreads];
  double largest = 0.0;
  for (int i = static_cast<int>(threadIdx.x); i < kEnergyBlocks; i += kEnergyThreads)
    largest = larger(largest, partial[i]);
  const double total = block_tree_reduce(largest, cache, larger);
  if (threadIdx.x == 0) *result = total;
}

template <typename Real>
__global__ void energy_partial_kernel(EnergyArguments<Real> a, EnergyTerm term, int begin, int end, double* partial) {
  __shared__ double cache[kEnergyThreads];
  double sum = 0.0;
  const long long stride = static_cast<long long>(kEnergyBlocks) * kEnergyThreads;
  for (long long i = begin + static_cast<long long>(blockIdx.x) * kEnergyThreads + threadIdx.x; i < end; i += stride) {
    sum += energy_term(a, term, static_cast<int>(i));
  }
  const double total = block_tree_sum(sum, cache);
  if (threadIdx.x == 0) partial[blockIdx.x] = total;
}

__global__ void energy_final_kernel(const double* partial, double* result) {
  __shared__ double cache[kEnergyThreads];
  double sum = 0.0;
  for (int i = static_cast<int>(threadIdx.x); i < kEnergyBlocks; i += kEnergyThreads) sum += partial[i];
  const double total = block_tree_sum(sum, cache);
  if (threadIdx.x == 0) *result = total;
}

template <typename Real>
__global__ void apply_probe_kernel(ProbeArguments<Real> a, int offset, bool before_step) {
  const int i = vertex_index();
  if (i >= a.count) return;
  apply_probe_entry(a, i, offset, before_step, a.state);
}

// A vertex's internal forces summed beforehand (by its lanes in fused_step_lanes_kernel): what vertex_acceleration
// reads through `gather`.
template <typename Real>
struct GatheredForces {
  Real fx, fy, fz;
  __device__ void gather(int, const kernels::StateView<Real>&, Real& x, Real& y, Real& z) const {
    x = fx;
    y = fy;
    z = fz;
  }
};

// `lanes` consecutive threads of a warp (mask) share a vertex: lane l computes the terms of entries begin + l,
// begin + l + lanes, ..., and every lane adds all terms in entry order from the lanes' shuffles. The sums have the
// sequential loop's order, hence its bits (kernels::sum_spring_forces, kernels::gather_corner_force), while a
// vertex's loads and square roots run side by side: one thread per vertex walks a chain of dependent L2 loads per
// entry, which bounds a small mesh's step, not the bandwidth.
template <typename Real, typename Term>
__device__ void lane_ordered_sum(unsigned mask, int lane, int lanes, int begin, int end, Term term, Real& fx, Real& fy,
                                 Real& fz) {
  Real sx = Real(0), sy = Real(0), sz = Real(0);
  for (int base = begin; base < end; base += lanes) {
    Real t0 = Real(0), t1 = Real(0), t2 = Real(0);
    if (base + lane < end) term(base + lane, t0, t1, t2);
    const int count = min(lanes, end - base);
    for (int j = 0; j < count; ++j) {
      sx += __shfl_sync(mask, t0, j, lanes);
      sy += __shfl_sync(mask, t1, j, lanes);
      sz += __shfl_sync(mask, t2, j, lanes);
    }
  }
  fx = sx;
  fy = sy;
  fz = sz;
}

// The shuffle mask of this thread's vertex: its `lanes` (valid_lanes) threads, an aligned part of the warp.
__device__ unsigned lane_mask(int lanes) {
  const int warp_lane = static_cast<int>(threadIdx.x) % 32;
  return lanes == 32 ? 0xffffffffu : ((1u << lanes) - 1u) << (warp_lane - warp_lane % lanes);
}

// What a vertex's lane reads before its gather: its vertex's spring and corner ranges and its own first spring
// record, so that its first neighbour's load waits on one load instead of two.
template <typename Real>
struct LaneCache {
  int spring_begin = 0, spring_end = 0;
  int corner_begin = 0, corner_end = 0;
  kernels::SpringIncidence<Real> first{};  // entry spring_begin + lane, where there is one
};

template <typename Real, GatherKind K>
__device__ LaneCache<Real> lane_cache(const ForceModelView<Real>& m, int v, int lane) {
  LaneCache<Real> c;
  if constexpr (K != GatherKind::Elements) {
    const kernels::SpringNetworkView<Real>& net = m.springs;
    c.spring_begin = net.adjacency_offset[v];
    c.spring_end = net.adjacency_offset[v + 1];
    const int e = c.spring_begin + lane;
    if (e < c.spring_end) c.first = kernels::spring_incidence(net, e);
  }
  if constexpr (K != GatherKind::Springs) {
    c.corner_begin = m.corners.offset[v];
    c.corner_end = m.corners.offset[v + 1];
  }
  return c;
}

// The model's internal forces on vertex v from its lanes, in the order of forces_of<Real, K>'s gather: springs,
// then corners (SpringAndElementForces adds the corner sum to the spring sum).
template <typename Real, GatherKind K>
__device__ GatheredForces<Real> lanes_gather(const ForceModelView<Real>& m, int v, const LaneCache<Real>& cache,
                                             const kernels::StateView<Real>& s, unsigned mask, int lane, int lanes) {
  GatheredForces<Real> f{Real(0), Real(0), Real(0)};
  if constexpr (K != GatherKind::Elements) {
    const kernels::SpringNetworkView<Real>& net = m.springs;
    const Real x = s.x[v], y = s.y[v], z = s.z[v], vx = s.vx[v], vy = s.vy[v], vz = s.vz[v];
    const int first = cache.spring_begin + lane;
    lane_ordered_sum(
        mask, lane, lanes, cache.spring_begin, cache.spring_end,
        [&](int e, Real& t0, Real& t1, Real& t2) {
          const kernels::SpringIncidence<Real> r = e == first ? cache.first : kernels::spring_incidence(net, e);
          kernels::entry_spring_force(net.law, r, kernels::vertex_state(s, r.neighbour), x, y, z, vx, vy, vz, t0, t1,
                                      t2);
        },
        f.fx, f.fy, f.fz);
  }
  if constexpr (K != GatherKind::Springs) {
    Real cx, cy, cz;
    lane_ordered_sum(
        mask, lane, lanes, cache.corner_begin, cache.corner_end,
        [&](int k, Real& t0, Real& t1, Real& t2) {
          const kernels::CornerForce<Real> corner = m.corners.force[k];
          t0 = corner.x;
          t1 = corner.y;
          t2 = corner.z;
        },
        cx, cy, cz);
    if constexpr (K == GatherKind::Elements) {
      f = {cx, cy, cz};
    } else {
      f.fx += cx;
      f.fy += cy;
      f.fz += cz;
    }
  }
  return f;
}

// State buffer 0 or 1 by selection: indexing the kernel parameter's array with a run-time index would copy it to
// local memory.
template <typename Real>
__device__ MutableStateView<Real> buffer(const PersistentEulerArguments<Real>& a, int parity) {
  return parity == 0 ? a.state[0] : a.state[1];
}

// The fused step with `lanes` threads per vertex (FusedStepArguments::lanes > 1).
template <typename Real, GatherKind K>
__global__ void fused_step_lanes_kernel(FusedStepArguments<Real> a) {
  const int thread = vertex_index();
  const int lanes = a.lanes;
  const int v = thread / lanes;
  if (v >= a.vertex_count) return;  // a vertex's lanes leave together
  const int lane = thread % lanes;
  const unsigned mask = lane_mask(lanes);
  const GatheredForces<Real> forces =
      lanes_gather<Real, K>(a.model, v, lane_cache<Real, K>(a.model, v, lane), a.in, mask, lane, lanes);
  if (lane == 0) {
    fused_vertex_step(a, forces, v, a.in, a.out);
    apply_own_probe(a, v);
  }
}

// The end-of-chunk checks' presets (PersistentChecks), written by a persistent kernel's threads before its first
// barrier, which publishes them.
__device__ void reset_chunk_checks(const PersistentChecks& c, int checks, int n, int thread, int stride) {
  if (c.first_non_finite == nullptr) return;
  for (int j = thread; j < checks; j += stride) c.first_non_finite[j * c.slot_stride] = n;
  for (int i = thread; i < checks * c.scene_count; i += stride) {
    const int j = i / c.scene_count, scene = i - j * c.scene_count;
    c.inverted_count[j * c.slot_stride + scene] = 0u;
    c.inverted_first[j * c.slot_stride + scene] = c.element_count;
  }
}

// Check j's results (PersistentChecks::slot_stride).
__device__ PersistentChecks check_slot(PersistentChecks c, int j) {
  const int offset = j * c.slot_stride;
  c.first_non_finite += offset;
  if (c.inverted_count != nullptr) {
    c.inverted_count += offset;
    c.inverted_first += offset;
  }
  return c;
}

// The end-of-chunk checks on the final state `end`, after a barrier that published it.
template <typename Real>
__device__ void run_chunk_checks(const PersistentChecks& c, const kernels::StateView<Real>& end, int n, int thread,
                                 int stride) {
  if (c.first_non_finite == nullptr) return;
  for (int v = thread; v < n; v += stride)
    if (non_finite_vertex(end, v)) atomicMin(c.first_non_finite, v);
  for (int e = thread; e < c.element_count; e += stride)
    count_if_inverted(c.corners, e, c.element_scene, end, c.inverted_count, c.inverted_first);
}

// Checkpoint slot k of a persistent launch (PersistentEulerArguments::checkpoints).
template <typename Real>
__device__ MutableStateView<Real> checkpoint_slot(const PersistentEulerArguments<Real>& a, int k) {
  return offset_state(a.checkpoints, k * a.checkpoint_stride);
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

// Blocks per multiprocessor the persistent kernel is compiled for (registers per thread <= 65536 / (256 x this)).
// Springs alone in float: bounded to 2 blocks it takes 112 registers and spills nothing, and the 20^3 box (36 rows
// per block, 258 blocks) ran 208,663-212,017 steps/s through fmpc simulate; bounded to 3 it takes 80 registers with
// 60 bytes of spills (24 rows, 386 blocks) and ran 195,931-200,902 (H100).
template <typename Real, GatherKind K>
struct PersistentOccupancy {
  static constexpr int min_blocks = std::is_same_v<Real, float> || K == GatherKind::Springs ? 2 : 1;
};

// Records per thread whose other ends block_spring_terms reads together: 4 for springs alone in float; 2 in double
// (4 spilled 162 bytes at the 128 registers of 2 blocks); 1 with elements, whose pass leaves no registers for more.
template <typename Real, GatherKind K>
constexpr int kPersistentTermBatch = K != GatherKind::Springs ? 1 : std::is_same_v<Real, float> ? 4 : 2;

// A block's step count, published once its threads have written the step (BlockNeighbours::steps_done): release
// by one thread after the block's barrier, the pattern of cooperative groups' grid barrier without its single counter
// that every block of the grid increments.
__device__ void publish_block_steps(unsigned* steps_done, unsigned steps) {
  __syncthreads();
  if (threadIdx.x == 0)
    cuda::atomic_ref<unsigned, cuda::thread_scope_device>(steps_done[kBlockStepsStride * blockIdx.x])
        .store(steps, cuda::memory_order_release);
}

// Waits until each of the `count` blocks `waited` (shared memory) has published `steps` steps: one thread per block
// polls with acquire loads, then the block's barrier passes what they saw on to every thread. (Relaxed polls and one
// acquire fence after them ran the 20^3 box at 168,343 steps/s against 180,091 with acquire polls; H100.)
__device__ void wait_for_blocks(const unsigned* steps_done, const int* waited, int count, unsigned steps) {
  for (int i = static_cast<int>(threadIdx.x); i < count; i += static_cast<int>(blockDim.x)) {
    cuda::atomic_ref<const unsigned, cuda::thread_scope_device> done(steps_done[kBlockStepsStride * waited[i]]);
    while (done.load(cuda::memory_order_acquire) < steps) {
    }
  }
  __syncthreads();
}

// A persistent block's shared memory (persistent_euler_shared_bytes' layout): its CSR records, their terms, its
// vertices' state at the step's start, which vertex of the block each record belongs to, and the blocks it waits for.
template <typename Real>
struct PersistentShared {
  kernels::SpringIncidence<Real>* record;
  ProbeEntry* probe;  // per row: its vertex's probe entry, where it has one
  Real* term;         // three arrays of a.block_records: x, y, z
  Real* own;          // six arrays of a.rows: the block's vertices' state
  int* owner;
  int* waited;
};

template <typename Real>
__device__ PersistentShared<Real> persistent_shared(unsigned char* base, int records, int rows) {
  PersistentShared<Real> p;
  p.record = reinterpret_cast<kernels::SpringIncidence<Real>*>(base);
  p.probe = reinterpret_cast<ProbeEntry*>(p.record + records);
  p.term = reinterpret_cast<Real*>(p.probe + rows);
  p.own = p.term + 3 * records;
  p.owner = reinterpret_cast<int*>(p.own + 6 * rows);
  p.waited = p.owner + records;
  return p;
}

// The terms of a block's `entries` CSR records (kernels::entry_spring_force at the step's start: the block's own
// vertices from shared memory, the other ends from `in`), spread over the block's threads regardless of which vertex
// each belongs to; `Batch` records per thread read their other ends before any term is computed.
template <int Batch, typename Real>
__device__ void block_spring_terms(const kernels::SpringLawParameters<Real>& law, int entries,
                                   const PersistentShared<Real>& p, int rows, const kernels::StateView<Real>& in) {
  const kernels::StateView<Real> own = shared_state(static_cast<const Real*>(p.own), rows);
  Real* const tx = p.term;
  Real* const ty = tx + entries;
  Real* const tz = ty + entries;
  constexpr int stride = kPersistentThreads;
  for (int first = static_cast<int>(threadIdx.x); first < entries; first += Batch * stride) {
    kernels::VertexState<Real> other[Batch];
    FMPC_UNROLL_ALL
    for (int k = 0; k < Batch; ++k)
      if (first + k * stride < entries) other[k] = kernels::vertex_state(in, p.record[first + k * stride].neighbour);
    FMPC_UNROLL_ALL
    for (int k = 0; k < Batch; ++k) {
      const int e = first + k * stride;
      if (e >= entries) break;
      const kernels::VertexState<Real> self = kernels::vertex_state(own, p.owner[e]);
      kernels::entry_spring_force(law, p.record[e], other[k], self.x, self.y, self.z, self.vx, self.vy, self.vz, tx[e],
                                  ty[e], tz[e]);
    }
  }
}

// launch_persistent_euler's kernel (gpu_launch.h): `steps` steps, block b on vertices [b rows, (b + 1) rows). Each
// step has two phases. First the block's threads compute the terms of all its vertices' springs side by side
// (block_spring_terms, into shared memory); then thread r adds vertex r's terms in CSR order (kernels::
// sum_spring_terms' order, so its bits), and its corner forces from the element pass, and updates the vertex in
// registers with the fused step's functions (loaded_acceleration, euler_update, the probe around the step), storing
// it for the neighbours and into the block's shared copy. A vertex's sum is one thread's chain of additions, so the
// lanes of a warp share no vertex: the sums cost a warp's instruction per term for 32 vertices at once, where lanes
// shuffling the terms of one vertex cost three per term for a few. Plain loads and stores of the state: the barriers
// (grid, or the neighbours' published steps) order them at device scope, and nothing here reads it through the
// non-coherent read-only path. At a check before the launch's last (check_count) each thread stores its vertex into
// the check's checkpoint slot and flags it there if non-finite; with elements, a grid barrier, then the grid counts
// the inverted ones in that slot. A launch thus takes many checks (a whole advance of a small mesh) instead of the
// launch, the end-of-chunk barrier and the download per check that cost the 20^3 box about 17 us each (H100).
template <typename Real, GatherKind K>
__global__ void __launch_bounds__(kPersistentThreads, (PersistentOccupancy<Real, K>::min_blocks))
    persistent_euler_kernel(PersistentEulerArguments<Real> a) {
  cooperative_groups::grid_group grid = cooperative_groups::this_grid();
  extern __shared__ __align__(16) unsigned char persistent_shared_memory[];
  constexpr bool springs = K != GatherKind::Elements;
  const int thread = vertex_index();
  const int stride = static_cast<int>(gridDim.x) * static_cast<int>(blockDim.x);
  const int local = static_cast<int>(threadIdx.x);
  const FusedStepArguments<Real>& step = a.step;
  const kernels::SpringNetworkView<Real>& net = step.model.springs;
  const int n = step.vertex_count;
  const int rows = a.rows;
  const ProbeArguments<Real>& probe = step.probe;
  const int* const probe_entry_of = step.probe_entry;
  const bool probed = probe_entry_of != nullptr;
  const int block_first = static_cast<int>(blockIdx.x) * rows, block_end = min(n, block_first + rows);
  const int v = block_first + local;
  const bool owner = local < rows && v < n;
  const PersistentShared<Real> p = persistent_shared<Real>(persistent_shared_memory, a.block_records, rows);
  // The block's records (its vertices' entries are contiguous) and their vertices.
  int entry_first = 0, entries = 0, begin = 0, end = 0;
  if constexpr (springs) {
    entry_first = net.adjacency_offset[block_first];
    entries = net.adjacency_offset[block_end] - entry_first;
    for (int e = local; e < entries; e += kPersistentThreads)
      p.record[e] = kernels::spring_incidence(net, entry_first + e);
    if (owner) {
      begin = net.adjacency_offset[v] - entry_first;
      end = net.adjacency_offset[v + 1] - entry_first;
      for (int e = begin; e < end; ++e) p.owner[e] = local;
    }
  }
  int waited_count = 0;
  const BlockNeighbours& neighbours = a.neighbours;
  if constexpr (K == GatherKind::Springs) {
    const int first = neighbours.offset[blockIdx.x];
    waited_count = neighbours.offset[blockIdx.x + 1] - first;
    for (int i = local; i < waited_count; i += kPersistentThreads) p.waited[i] = neighbours.block[first + i];
    if (local == 0) neighbours.steps_done[kBlockStepsStride * blockIdx.x] = 0u;
  }
  const unsigned char held = owner ? step.loads.fixed[v] : kernels::kAllAxesFixed;
  const Real h = owner ? step_of(step.step, v) : Real(0);
  const int probe_entry = owner && probed ? probe_entry_of[v] : -1;
  int parity = a.first_parity;
  const PersistentChecks& c = a.checks;
  reset_chunk_checks(c, a.check_count, n, thread, stride);
  int check = 0;                  // the next check's index
  int check_after = a.first_check;  // the steps after which it comes (before the last)
  const MutableStateView<Real> own = shared_state(p.own, rows);
  kernels::VertexState<Real> self{};
  // The vertex's load values for the launch (a force probe entry's force replaces its external force at each step).
  kernels::VertexLoadValues<Real> load{};
  if (owner) {
    self = kernels::vertex_state(read_only(buffer(a, parity)), v);
    if (a.store_start) store_vertex_state(checkpoint_slot(a, 0), v, self);
    if (probe_entry >= 0) {
      // Read once for the launch: after every step's barrier each of these loads would go to L2, and the probe
      // vertices' blocks hold their neighbours back. The 20^3 box ran 206,103-209,177 steps/s with the entry read per
      // step, 252,854-264,211 read once, 295,895-299,349 without its probe (H100).
      p.probe[local] = read_probe_entry(probe, probe_entry, a.step_base);
      ProbeForce<Real> force;
      if (probe_entry_state(p.probe[local], 0, true, self, force)) store_vertex_state(buffer(a, parity), v, self);
      store_probe_force(probe.force, v, force);
    }
    store_vertex_state(own, local, self);
    load = kernels::vertex_load_values(step.loads, v);
  }
  // Publishes the probe's state, the counters' reset, the checks' presets and the block's shared memory.
  grid.sync();
  for (int s = 0; s < a.steps; ++s) {
    const MutableStateView<Real> out = buffer(a, 1 - parity);
    const kernels::StateView<Real> in = read_only(buffer(a, parity));
    const bool checked = check + 1 < a.check_count && s + 1 == check_after;
    if constexpr (K != GatherKind::Springs) {
      for (int e = thread; e < step.model.field.count; e += stride)
        kernels::tetrahedron_corner_forces(e, step.model.field, in, step.model.corner_force);
      grid.sync();
    } else if (s > 0) {
      wait_for_blocks(neighbours.steps_done, p.waited, waited_count, static_cast<unsigned>(s));
    }
    if constexpr (springs) {
      block_spring_terms<kPersistentTermBatch<Real, K>>(net.law, entries, p, rows, in);
      __syncthreads();
    }
    if (owner) {
      // fused_vertex_step's arithmetic on the registers' state: vertex_acceleration's, then euler_update.
      Real ax = Real(0), ay = Real(0), az = Real(0);
      if (held != kernels::kAllAxesFixed) {
        Real fx = Real(0), fy = Real(0), fz = Real(0);
        // Unrolled so that the shared loads run ahead of the chain of additions.
        FMPC_UNROLL_GATHER
        for (int e = begin; e < end; ++e) {
          fx += p.term[e];
          fy += p.term[entries + e];
          fz += p.term[2 * entries + e];
        }
        if constexpr (K != GatherKind::Springs) {
          Real cx, cy, cz;
          kernels::gather_corner_force(v, step.model.corners, cx, cy, cz);
          if constexpr (springs) {
            fx += cx;
            fy += cy;
            fz += cz;
          } else {
            fx = cx;
            fy = cy;
            fz = cz;
          }
        }
        kernels::loaded_acceleration(load, held, self, fx, fy, fz, step.loads, ax, ay, az);
      }
      euler_update(step.scheme, h, ax, ay, az, self);
      // probe_around_step's two prescriptions, the check's state between them.
      ProbeForce<Real> force;
      if (probe_entry >= 0) probe_entry_state(p.probe[local], s, false, self, force);
      if (checked) {
        const MutableStateView<Real> checkpoint = checkpoint_slot(a, check + 1);
        store_vertex_state(checkpoint, v, self);
        if (non_finite_vertex(read_only(checkpoint), v)) atomicMin(check_slot(c, check).first_non_finite, v);
      }
      if (probe_entry >= 0) {
        if (s + 1 < a.steps) probe_entry_state(p.probe[local], s + 1, true, self, force);
        store_probe_force(probe.force, v, force);
        if (force.set) {
          load.force_x = force.x;
          load.force_y = force.y;
          load.force_z = force.z;
        }
      }
      store_vertex_state(out, v, self);
      store_vertex_state(own, local, self);
    }
    if constexpr (K == GatherKind::Springs) {
      publish_block_steps(neighbours.steps_done, static_cast<unsigned>(s + 1));
    } else {
      grid.sync();
    }
    if (checked) {
      if (c.element_count > 0) {
        if constexpr (K == GatherKind::Springs) grid.sync();  // the elements' corners are other blocks' vertices
        const PersistentChecks at = check_slot(c, check);
        const kernels::StateView<Real> checkpoint = read_only(checkpoint_slot(a, check + 1));
        for (int e = thread; e < c.element_count; e += stride)
          count_if_inverted(c.corners, e, c.element_scene, checkpoint, at.inverted_count, at.inverted_first);
      }
      ++check;
      check_after += a.check_every;
    }
    parity = 1 - parity;
  }
  if constexpr (K == GatherKind::Springs) grid.sync();  // the checks read every block's vertices
  run_chunk_checks(check_slot(c, a.check_count - 1), read_only(buffer(a, parity)), n, thread, stride);
}

// launch_cluster_euler's kernel (gpu_launch.h): clusters of a.cluster_blocks blocks of a.rows threads, thread r of
// a block on vertex first_vertex + r (ClusterBlock). Per step a block of a cluster of several copies its window (the
// vertices its gathers read, a contiguous range) from its cluster's published copies of the step's start,
// coalesced; a block alone in its cluster reads its own published copy. Then each thread gathers, updates its
// vertex in registers (fused_vertex_step's arithmetic: loaded_acceleration of sum_spring_terms, euler_update, then
// the probe after the step and before the next) and publishes it into the other copy; one cluster barrier per step.
// Clusters never wait on each other: a grid larger than the GPU runs in waves. The gather reads one entry at a time
// (sum_spring_terms' batches of 2, 4 and 8 entries measured slower here: 82,724, 78,967 and 73,224 steps/s on the
// 20^3 box against 94,019, the cohort 40.5 and 64.9 us per step against 36.1; H100).
template <typename Real>
__global__ void __launch_bounds__(kClusterRows, 1) cluster_euler_kernel(ClusterEulerArguments<Real> a) {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ < 900
  // Built for an architecture without clusters (CMAKE_CUDA_ARCHITECTURES below 90) and JIT-compiled on a newer GPU:
  // no silent empty step.
  __trap();
#else
  namespace cg = cooperative_groups;
  cg::cluster_group cluster = cg::this_cluster();
  extern __shared__ __align__(16) unsigned char cluster_shared[];
  const PersistentEulerArguments<Real>& chunk = a.chunk;
  const FusedStepArguments<Real>& step = chunk.step;
  const kernels::SpringNetworkView<Real>& net = step.model.springs;
  const int rows = a.rows;
  const bool alone = a.cluster_blocks == 1;
  const int rank = static_cast<int>(cluster.block_rank());
  const ClusterBlock me = a.block[blockIdx.x];
  const int cluster_first = a.block[static_cast<int>(blockIdx.x) - rank].first_vertex;
  const int local = static_cast<int>(threadIdx.x);
  const int v = me.first_vertex + local;
  const bool owner = v < me.end_vertex;
  Real* const published = reinterpret_cast<Real*>(cluster_shared);  // [2][6][rows]
  Real* const window = published + 12 * rows;                       // [6][window_capacity]
  // A block alone reads its own copy: its window is its own vertices.
  const int stride = alone ? rows : a.window_capacity;
  kernels::SpringIncidence<Real>* const record = reinterpret_cast<kernels::SpringIncidence<Real>*>(
      cluster_shared + cluster_euler_state_bytes<Real>(rows, a.window_capacity));
  // The block's records in CSR order, their neighbours as window indices.
  const int first_entry = net.adjacency_offset[me.first_vertex];
  const int entries = net.adjacency_offset[me.end_vertex] - first_entry;
  for (int e = local; e < entries; e += rows) {
    kernels::SpringIncidence<Real> r = net.incidence[first_entry + e];
    r.neighbour -= me.window_first;
    record[e] = r;
  }
  const int own_first = owner ? net.adjacency_offset[v] - first_entry : 0;
  const int own_count = owner ? net.adjacency_offset[v + 1] - net.adjacency_offset[v] : 0;
  const unsigned char held = owner ? step.loads.fixed[v] : kernels::kAllAxesFixed;
  const Real h = owner ? step_of(step.step, v) : Real(0);
  const int probe_entry = owner && step.probe_entry != nullptr ? step.probe_entry[v] : -1;
  int parity = chunk.first_parity;
  kernels::VertexState<Real> self{};
  if (owner) self = kernels::vertex_state(read_only(buffer(chunk, parity)), v);
  if (owner && chunk.store_start) store_vertex_state(checkpoint_slot(chunk, 0), v, self);
  if (probe_entry >= 0) {
    apply_to_probe_entry(step.probe, probe_entry, chunk.step_base, [&](const ProbeEntry& e, ProbeForce<Real>& force) {
      return probe_entry_state(e, 0, true, self, force);
    });
  }
  if (owner) store_vertex_state(shared_state(published, rows), local, self);
  cluster.sync();
  int current = 0;
  for (int s = 0; s < chunk.steps; ++s) {
    const Real* const start = published + current * 6 * rows;
    if (!alone) {
      for (int i = local; i < me.window_count; i += rows) {
        const int u = me.window_first + i - cluster_first, from = u / rows;
        const Real* const copy = from == rank ? start : cluster.map_shared_rank(start, from);
        store_vertex_state(shared_state(window, stride), i,
                           kernels::vertex_state(shared_state(copy, rows), u - from * rows));
      }
      __syncthreads();
    }
    const Real* const source = alone ? start : window;
    if (owner) {
      Real ax = Real(0), ay = Real(0), az = Real(0);
      if (held != kernels::kAllAxesFixed) {
        Real fx, fy, fz;
        kernels::sum_spring_terms(
            own_count, net.law, self, [&](int j) { return record[own_first + j]; },
            [&](const kernels::SpringIncidence<Real>& r) {
              return kernels::vertex_state(shared_state(source, stride), r.neighbour);
            },
            fx, fy, fz);
        kernels::loaded_acceleration(v, held, self, fx, fy, fz, step.loads, ax, ay, az);
      }
      euler_update(step.scheme, h, ax, ay, az, self);
      probe_around_step(step.probe, probe_entry, chunk.step_base, s, s + 1 < chunk.steps, self);
      store_vertex_state(shared_state(published + (1 - current) * 6 * rows, rows), local, self);
    }
    cluster.sync();
    current = 1 - current;
    parity = 1 - parity;
  }
  if (owner) {
    store_vertex_state(buffer(chunk, parity), v, self);
    store_vertex_state(
        buffer(chunk, 1 - parity), v,
        kernels::vertex_state(read_only(shared_state(published + (1 - current) * 6 * rows, rows)), local));
  }
  // The checks' presets come from reset_checks_kernel, launched before (clusters do not wait on each other).
  const PersistentChecks& c = chunk.checks;
  if (c.first_non_finite == nullptr) return;
  const kernels::StateView<Real> end = read_only(buffer(chunk, parity));
  if (owner && non_finite_vertex(end, v)) atomicMin(c.first_non_finite, v);
  if (me.element_first == me.element_end) return;
  cluster.sync();  // the elements' corners may be other blocks' vertices
  for (int e = me.element_first + local; e < me.element_end; e += rows)
    count_if_inverted(c.corners, e, c.element_scene, end, c.inverted_count, c.inverted_first);
#endif
}

// PersistentChecks' presets (reset_chunk_checks), for the kernels whose blocks do not all run at once.
__global__ void reset_checks_kernel(PersistentChecks c, int checks, int vertex_count) {
  reset_chunk_checks(c, checks, vertex_count, static_cast<int>(threadIdx.x), static_cast<int>(blockDim.x));
}

template <typename Real>
__global__ void strain_stiffness_kernel(StrainStiffnessArguments<Real> a) {
  const int s = vertex_index();
  if (s >= a.spring_count) return;
  const int p = a.first[s], q = a.second[s];
  const double dx = static_cast<double>(a.state.x[q]) - static_cast<double>(a.state.x[p]);
  const double dy = static_cast<double>(a.state.y[q]) - static_cast<double>(a.state.y[p]);
  const double dz = static_cast<double>(a.state.z[q]) - static_cast<double>(a.state.z[p]);
  a.stiffness[s] = static_cast<Real>(
      kernels::strain_table_stiffness(a.table, dx, dy, dz, a.rest_length[s], a.stiffness_per_modulus[s]));
}

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

// Element e's share of the implicit system, as the CPU backend's add_element_blocks: its linearisation at the
// step's start, h^2 K v0 for the right-hand side and the diagonal of (h^2 + h beta) K_aa for the preconditioner.
template <typename Real>
__global__ void implicit_element_kernel(ImplicitArguments<Real> a) {
  const int e = vertex_index();
  const ImplicitElements& f = a.elements;
  if (e >= f.count) return;
  double x[4][3], v[4][3], kv[4][3];
  for (int c = 0; c < 4; ++c) {
    const int vertex = f.corners[4 * e + c];
    x[c][0] = static_cast<double>(a.state.x[vertex]);
    x[c][1] = static_cast<double>(a.state.y[vertex]);
    x[c][2] = static_cast<double>(a.state.z[vertex]);
    v[c][0] = static_cast<double>(a.state.vx[vertex]);
    v[c][1] = static_cast<double>(a.state.vy[vertex]);
    v[c][2] = static_cast<double>(a.state.vz[vertex]);
  }
  const kernels::TetrahedronMaterial<double> m = implicit_material(f, e);
  kernels::TetrahedronLinearisation lin;
  kernels::linearise_tetrahedron(m, x, lin);
  f.linearisation[e] = lin;
  kernels::tetrahedron_stiffness_action(m, lin, v, kv);
  const double scale = a.h * a.h + a.h * m.stiffness_damping;
  for (int c = 0; c < 4; ++c) {
    double block[9];
    kernels::tetrahedron_stiffness_block(m, lin, c, c, block);
    for (int i = 0; i < 3; ++i) {
      f.rhs_part[12 * e + 3 * c + i] = a.h * a.h * kv[c][i];
      f.diagonal_part[12 * e + 3 * c + i] = scale * block[4 * i];
    }
  }
}

// (h^2 + h beta) K p of element e, with the corners at fixed vertices taken as zero (their rows are identity).
template <typename Real>
__global__ void implicit_element_apply_kernel(ImplicitArguments<Real> a) {
  const int e = vertex_index();
  const ImplicitElements& f = a.elements;
  if (e >= f.count) return;
  double p[4][3], kp[4][3];
  for (int c = 0; c < 4; ++c) {
    const int vertex = f.corners[4 * e + c];
    const unsigned char held = a.loads.fixed[vertex];
    for (int i = 0; i < 3; ++i) p[c][i] = kernels::axis_fixed(held, i) ? 0.0 : a.p[3 * vertex + i];
  }
  const kernels::TetrahedronMaterial<double> m = implicit_material(f, e);
  kernels::tetrahedron_stiffness_action(m, f.linearisation[e], p, kp);
  const double scale = a.h * a.h + a.h * m.stiffness_damping;
  for (int c = 0; c < 4; ++c)
    for (int i = 0; i < 3; ++i) f.product[12 * e + 3 * c + i] = scale * kp[c][i];
}

// Sum over the corners at v of an element-major array of 3 values per corner (double).
__device__ void gather_corner_values(int v, const kernels::CornerForceView<double>& corners, const double* values,
                                     double* out) {
  for (int k = corners.offset[v]; k < corners.offset[v + 1]; ++k) {
    const double* value = values + 3 * corners.corner[k];
    for (int i = 0; i < 3; ++i) out[i] += value[i];
  }
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
  const double diagonal = a.mass[v] + a.h * (static_cast<double>(a.loads.gamma0) +
                                             static_cast<double>(a.loads.gamma1) * sqrt(dx * dx + dy * dy + dz * dz) +
                                             static_cast<double>(a.loads.mass_damping) * a.mass[v]);
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
  if (a.elements.count > 0) {
    const kernels::CornerForceView<double> corners{a.model.corners.offset, a.model.corners.corner, nullptr};
    double kv[3] = {0.0, 0.0, 0.0}, element_diagonal[3] = {0.0, 0.0, 0.0};
    gather_corner_values(v, corners, a.elements.rhs_part, kv);
    gather_corner_values(v, corners, a.elements.diagonal_part, element_diagonal);
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
  if (v >= a.vertex_count) return;
  const double* own = a.p + 3 * v;
  double* out = a.ap + 3 * v;
  const unsigned char held = a.loads.fixed[v];
  if (held == kernels::kAllAxesFixed) {
    for (int c = 0; c < 3; ++c) out[c] = own[c];
    return;
  }
  double sum[3] = {a.diagonal[v] * own[0], a.diagonal[v] * own[1], a.diagonal[v] * own[2]};
  const kernels::SpringNetworkView<Real>& springs = a.model.springs;
  for (int e = springs.adjacency_offset[v]; e < springs.adjacency_offset[v + 1]; ++e) {
    const int s = springs.adjacency_spring[e], o = springs.adjacency_neighbour[e];
    const unsigned char other = a.loads.fixed[o];
    double relative[3];
    for (int c = 0; c < 3; ++c) relative[c] = own[c] - (kernels::axis_fixed(other, c) ? 0.0 : a.p[3 * o + c]);
    double product[3];
    kernels::symmetric_multiply(a.blocks + 12 * s + 6, relative, product);
    for (int c = 0; c < 3; ++c) sum[c] += product[c];
  }
  if (a.elements.count > 0) {
    const kernels::CornerForceView<double> corners{a.model.corners.offset, a.model.corners.corner, nullptr};
    gather_corner_values(v, corners, a.elements.product, sum);
  }
  for (int c = 0; c < 3; ++c) out[c] = kernels::axis_fixed(held, c) ? own[c] : sum[c];
}

template <typename Real>
__global__ void count_inverted_kernel(const int* corners, int element_count, const int* element_scene,
                                      kernels::StateView<Real> s, unsigned int* count, int* first) {
  const int e = vertex_index();
  if (e >= element_count) return;
  count_if_inverted(corners, e, element_scene, s, count, first);
}

// Partial sums of first . second (and of third . fourth when third is not null) over [0, count), in the fixed
// shape of the energy sums; block b writes partial[b] and partial[kEnergyBlocks + b].
__global__ void dot_partial_kernel(const double* first, const double* second, const double* third, const double* fourth,
                                   int count, double* partial) {
  __shared__ double cache[kEnergyThreads];
  double sum = 0.0, other = 0.0;
  const long long stride = static_cast<long long>(kEnergyBlocks) * kEnergyThreads;
  for (long long i = static_cast<long long>(blockIdx.x) * kEnergyThreads + threadIdx.x; i < count; i += stride) {
    sum += first[i] * second[i];
    if (third != nullptr) other += third[i] * fourth[i];
  }
  const double total = block_tree_sum(sum, cache);
  __syncthreads();  // every thread has read cache[0] before the second tree overwrites it
  const double other_total = block_tree_sum(other, cache);
  if (threadIdx.x == 0) {
    partial[blockIdx.x] = total;
    partial[kEnergyBlocks + blockIdx.x] = other_total;
  }
}

enum class CgStage : int { Start = 0, Alpha = 1, Residual = 2 };

__global__ void cg_scalars_kernel(const double* partial, ConjugateGradientScalars* scalars, CgStage stage) {
  __shared__ double cache[kEnergyThreads];
  double sum = 0.0, other = 0.0;
  for (int i = static_cast<int>(threadIdx.x); i < kEnergyBlocks; i += kEnergyThreads) {
    sum += partial[i];
    other += partial[kEnergyBlocks + i];
  }
  const double total = block_tree_sum(sum, cache);
  __syncthreads();
  const double other_total = block_tree_sum(other, cache);
  if (threadIdx.x != 0) return;
  switch (stage) {
    case CgStage::Start:
      scalars->rhs_norm2 = total;
      scalars->rz = other_total;
      break;
    case CgStage::Alpha:
      scalars->p_ap = total;
      scalars->alpha = scalars->rz / total;
      break;
    case CgStage::Residual:
      scalars->rr = total;
      scalars->rz_next = other_total;
      scalars->beta = other_total / scalars->rz;
      break;
  }
}

// Per degree of freedom: x = 0, r = b, z = p = M^-1 r.
template <typename Real>
__global__ void cg_start_kernel(ImplicitArguments<Real> a) {
  const int i = vertex_index();
  if (i >= 3 * a.vertex_count) return;
  a.x[i] = 0.0;
  a.r[i] = a.rhs[i];
  a.z[i] = a.inverse_jacobi[i] * a.r[i];
  a.p[i] = a.z[i];
}

template <typename Real>
__global__ void cg_update_kernel(ImplicitArguments<Real> a) {
  const int i = vertex_index();
  if (i >= 3 * a.vertex_count) return;
  const double alpha = a.scalars->alpha;
  a.x[i] += alpha * a.p[i];
  a.r[i] -= alpha * a.ap[i];
  a.z[i] = a.inverse_jacobi[i] * a.r[i];
}

template <typename Real>
__global__ void cg_direction_kernel(ImplicitArguments<Real> a) {
  const int i = vertex_index();
  if (i >= 3 * a.vertex_count) return;
  a.p[i] = a.z[i] + a.scalars->beta * a.p[i];
  // Nothing in this kernel reads rz: thread 0 may move rz_next into it.
  if (i == 0) a.scalars->rz = a.scalars->rz_next;
}

template <typename Real>
__global__ void implicit_finish_kernel(ImplicitArguments<Real> a) {
  const int v = vertex_index();
  if (v >= a.vertex_count || a.loads.fixed[v] == kernels::kAllAxesFixed) return;
  const Real h = static_cast<Real>(a.h);
  a.state.vx[v] += static_cast<Real>(a.x[3 * v]);
  a.state.vy[v] += static_cast<Real>(a.x[3 * v + 1]);
  a.state.vz[v] += static_cast<Real>(a.x[3 * v + 2]);
  a.state.x[v] += h * a.state.vx[v];
  a.state.y[v] += h * a.state.vy[v];
  a.state.z[v] += h * a.state.vz[v];
}

int blocks_for(int count) { return (count + kThreadsPerBlock - 1) / kThreadsPerBlock; }

template <typename Real>
cudaError_t launch_elements(const ForceModelView<Real>& model, const kernels::StateView<Real>& state,
                            cudaStream_t stream) {
  if (model.kind == GatherKind::Springs || model.field.count <= 0) return cudaSuccess;
  if constexpr (std::is_same_v<Real, float>) {
    if (model.element_blocks == 2) {
      element_forces_kernel<Real, 2><<<blocks_for(model.field.count), kThreadsPerBlock, 0, stream>>>(model, state);
      return cudaGetLastError();
    }
    element_forces_kernel<Real, 3><<<blocks_for(model.field.count), kThreadsPerBlock, 0, stream>>>(model, state);
  } else {
    element_forces_kernel<Real, 1><<<blocks_for(model.field.count), kThreadsPerBlock, 0, stream>>>(model, state);
  }
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_largest(const kernels::StateView<Real>& state, const StartPositions& start, int begin, int end,
                           double* partial, double* result, cudaStream_t stream) {
  largest_displacement_partial_kernel<Real>
      <<<kEnergyBlocks, kEnergyThreads, 0, stream>>>(state, start, begin, end, partial);
  cudaError_t status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  largest_displacement_final_kernel<<<1, kEnergyThreads, 0, stream>>>(partial, result);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_sliced(const kernels::SpringNetworkView<Real>& network, const int* vertex_order, int vertex_count,
                          kernels::SpringIncidence<Real>* record, cudaStream_t stream) {
  if (vertex_count <= 0) return cudaSuccess;
  sliced_springs_kernel<Real>
      <<<blocks_for(vertex_count), kThreadsPerBlock, 0, stream>>>(network, vertex_order, vertex_count, record);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_incidence(const kernels::SpringNetworkView<Real>& network, int entries,
                             kernels::SpringIncidence<Real>* incidence, cudaStream_t stream) {
  if (entries <= 0) return cudaSuccess;
  spring_incidence_kernel<Real><<<blocks_for(entries), kThreadsPerBlock, 0, stream>>>(network, entries, incidence);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_fused(const FusedStepArguments<Real>& arguments, cudaStream_t stream) {
  if (arguments.vertex_count <= 0) return cudaSuccess;
  const int lanes = arguments.lanes;
  if (lanes > 1) {
    if (!valid_lanes(lanes) ||
        static_cast<long long>(arguments.vertex_count) * lanes > std::numeric_limits<int>::max() - kThreadsPerBlock) {
      return cudaErrorInvalidValue;
    }
    return with_kind(arguments.model.kind, [&](auto kind) {
      fused_step_lanes_kernel<Real, decltype(kind)::value>
          <<<blocks_for(arguments.vertex_count * lanes), kThreadsPerBlock, 0, stream>>>(arguments);
      return cudaGetLastError();
    });
  }
  return with_kind(arguments.model.kind, [&](auto kind) {
    fused_step_kernel<Real, decltype(kind)::value>
        <<<blocks_for(arguments.vertex_count), kThreadsPerBlock, 0, stream>>>(arguments);
    return cudaGetLastError();
  });
}

// Raises persistent_euler_kernel's dynamic shared memory limit to `shared_bytes` where it is lower (beyond the default
// 48 KB), never lowers it: simulations alive side by side share the kernel, so their launches need not set it again.
template <typename Real, GatherKind K>
cudaError_t persistent_shared_limit(long long shared_bytes) {
  const void* kernel = reinterpret_cast<const void*>(persistent_euler_kernel<Real, K>);
  cudaFuncAttributes attributes{};
  const cudaError_t status = cudaFuncGetAttributes(&attributes, kernel);
  if (status != cudaSuccess || attributes.maxDynamicSharedSizeBytes >= shared_bytes) return status;
  return cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, static_cast<int>(shared_bytes));
}

template <typename Real>
cudaError_t persistent_block_limit(GatherKind kind, long long shared_bytes, int& blocks) {
  blocks = 0;
  int device = 0, cooperative = 0, multiprocessors = 0, shared_limit = 0;
  cudaError_t status = cudaGetDevice(&device);
  if (status == cudaSuccess) status = cudaDeviceGetAttribute(&cooperative, cudaDevAttrCooperativeLaunch, device);
  if (status == cudaSuccess) status = cudaDeviceGetAttribute(&multiprocessors, cudaDevAttrMultiProcessorCount, device);
  if (status == cudaSuccess)
    status = cudaDeviceGetAttribute(&shared_limit, cudaDevAttrMaxSharedMemoryPerBlockOptin, device);
  if (status != cudaSuccess || cooperative == 0 || shared_bytes < 0 || shared_bytes > shared_limit) return status;
  return with_kind(kind, [&](auto k) {
    constexpr GatherKind K = decltype(k)::value;
    int per_multiprocessor = 0;
    cudaError_t occupancy = persistent_shared_limit<Real, K>(shared_bytes);
    if (occupancy == cudaSuccess)
      occupancy = cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_multiprocessor, persistent_euler_kernel<Real, K>,
                                                                kPersistentThreads,
                                                                static_cast<std::size_t>(shared_bytes));
    blocks = per_multiprocessor * multiprocessors;
    return occupancy;
  });
}

// A launch's checks (PersistentEulerArguments::check_count): at least one, the last at the end and the others
// before it; more than one only with their results and checkpoint slots.
template <typename Real>
bool valid_checks(const PersistentEulerArguments<Real>& a) {
  if (a.check_count < 1) return false;
  if (a.check_count == 1) return true;
  const long long last_inner = a.first_check + static_cast<long long>(a.check_count - 2) * a.check_every;
  return a.first_check >= 1 && (a.check_count == 2 || a.check_every >= 1) && last_inner < a.steps &&
         a.checks.first_non_finite != nullptr &&
         a.checks.slot_stride >= 1 && a.checkpoints.x != nullptr &&
         a.checkpoint_stride >= static_cast<long long>(a.step.vertex_count);
}

template <typename Real>
cudaError_t launch_persistent(const PersistentEulerArguments<Real>& arguments, cudaStream_t stream) {
  if (arguments.step.vertex_count <= 0 || arguments.steps <= 0) return cudaSuccess;
  if (arguments.blocks <= 0 || arguments.rows <= 0 || arguments.rows > kPersistentThreads ||
      static_cast<long long>(arguments.blocks) * arguments.rows < arguments.step.vertex_count ||
      arguments.block_records < 0 || arguments.most_neighbour_blocks < 0 ||
      (arguments.step.model.kind == GatherKind::Springs && arguments.neighbours.steps_done == nullptr) ||
      !valid_checks(arguments)) {
    return cudaErrorInvalidValue;
  }
  const unsigned blocks = static_cast<unsigned>(arguments.blocks);
  const long long shared_bytes =
      persistent_euler_shared_bytes<Real>(arguments.rows, arguments.block_records, arguments.most_neighbour_blocks);
  return with_kind(arguments.step.model.kind, [&](auto kind) {
    constexpr GatherKind K = decltype(kind)::value;
    PersistentEulerArguments<Real> copy = arguments;
    void* parameters[] = {&copy};
    return cudaLaunchCooperativeKernel(reinterpret_cast<const void*>(persistent_euler_kernel<Real, K>), dim3(blocks),
                                       dim3(kPersistentThreads), parameters, static_cast<std::size_t>(shared_bytes),
                                       stream);
  });
}

// Sets cluster_euler_kernel's attributes for `shared_bytes` of dynamic shared memory and, beyond 8 blocks, Hopper's
// non-portable cluster sizes, and fills the launch configuration of `grid` blocks in clusters of `blocks`.
template <typename Real>
cudaError_t cluster_launch_config(int grid, int blocks, int rows, long long shared_bytes, cudaStream_t stream,
                                  cudaLaunchAttribute& attribute, cudaLaunchConfig_t& config) {
  const void* kernel = reinterpret_cast<const void*>(cluster_euler_kernel<Real>);
  cudaError_t status =
      cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, static_cast<int>(shared_bytes));
  if (status == cudaSuccess && blocks > 8)
    status = cudaFuncSetAttribute(kernel, cudaFuncAttributeNonPortableClusterSizeAllowed, 1);
  attribute.id = cudaLaunchAttributeClusterDimension;
  attribute.val.clusterDim.x = static_cast<unsigned>(blocks);
  attribute.val.clusterDim.y = 1;
  attribute.val.clusterDim.z = 1;
  config = {};
  config.gridDim = dim3(static_cast<unsigned>(grid));
  config.blockDim = dim3(static_cast<unsigned>(rows));
  config.dynamicSmemBytes = static_cast<std::size_t>(shared_bytes);
  config.stream = stream;
  config.attrs = &attribute;
  config.numAttrs = 1;
  return status;
}

template <typename Real>
cudaError_t cluster_fits(int blocks, int rows, long long shared_bytes, bool& fits) {
  fits = false;
  int device = 0, cluster_launch = 0, major = 0, shared_limit = 0;
  cudaError_t status = cudaGetDevice(&device);
  if (status == cudaSuccess) status = cudaDeviceGetAttribute(&cluster_launch, cudaDevAttrClusterLaunch, device);
  if (status == cudaSuccess) status = cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, device);
  if (status == cudaSuccess)
    status = cudaDeviceGetAttribute(&shared_limit, cudaDevAttrMaxSharedMemoryPerBlockOptin, device);
  if (status != cudaSuccess || cluster_launch == 0 || major < 9) return status;
  if (blocks < 1 || blocks > kClusterBlocks || rows < 32 || rows > kClusterRows || rows % 32 != 0 ||
      shared_bytes > shared_limit) {
    return cudaSuccess;
  }
  cudaLaunchAttribute attribute{};
  cudaLaunchConfig_t config{};
  status = cluster_launch_config<Real>(blocks, blocks, rows, shared_bytes, nullptr, attribute, config);
  // A device without non-portable sizes refuses the attribute: no fit, not an error.
  if (status == cudaErrorInvalidValue || status == cudaErrorNotSupported) {
    cudaGetLastError();
    return cudaSuccess;
  }
  if (status != cudaSuccess) return status;
  int clusters = 0;
  status =
      cudaOccupancyMaxActiveClusters(&clusters, reinterpret_cast<const void*>(cluster_euler_kernel<Real>), &config);
  if (status == cudaErrorInvalidValue || status == cudaErrorInvalidClusterSize) {
    cudaGetLastError();
    return cudaSuccess;
  }
  fits = status == cudaSuccess && clusters >= 1;
  return status;
}

template <typename Real>
cudaError_t launch_cluster(const ClusterEulerArguments<Real>& arguments, cudaStream_t stream) {
  const PersistentEulerArguments<Real>& chunk = arguments.chunk;
  if (chunk.step.vertex_count <= 0 || chunk.steps <= 0) return cudaSuccess;
  if (arguments.blocks < 1 || arguments.rows < 32 || arguments.rows > kClusterRows || arguments.rows % 32 != 0 ||
      arguments.cluster_blocks < 1 || arguments.cluster_blocks > kClusterBlocks ||
      arguments.blocks % arguments.cluster_blocks != 0 || chunk.step.model.kind != GatherKind::Springs ||
      chunk.step.model.springs.incidence == nullptr || arguments.window_capacity < 0 ||
      arguments.window_capacity % 4 != 0 || chunk.check_count != 1) {
    return cudaErrorInvalidValue;
  }
  if (chunk.checks.first_non_finite != nullptr) {
    reset_checks_kernel<<<1, kThreadsPerBlock, 0, stream>>>(chunk.checks, 1, chunk.step.vertex_count);
    const cudaError_t reset = cudaGetLastError();
    if (reset != cudaSuccess) return reset;
  }
  cudaLaunchAttribute attribute{};
  cudaLaunchConfig_t config{};
  const cudaError_t status = cluster_launch_config<Real>(arguments.blocks, arguments.cluster_blocks, arguments.rows,
                                                         arguments.shared_bytes, stream, attribute, config);
  if (status != cudaSuccess) return status;
  return cudaLaunchKernelEx(&config, cluster_euler_kernel<Real>, arguments);
}

enum class VerletKernel { Acceleration, Drift, Kick };

template <typename Real>
cudaError_t launch_verlet(VerletKernel which, const VerletArguments<Real>& arguments, cudaStream_t stream) {
  if (arguments.vertex_count <= 0) return cudaSuccess;
  return with_kind(arguments.model.kind, [&](auto kind) {
    constexpr GatherKind K = decltype(kind)::value;
    const int blocks = blocks_for(arguments.vertex_count);
    if (which == VerletKernel::Acceleration)
      acceleration_kernel<Real, K><<<blocks, kThreadsPerBlock, 0, stream>>>(arguments);
    if (which == VerletKernel::Drift) verlet_drift_kernel<Real, K><<<blocks, kThreadsPerBlock, 0, stream>>>(arguments);
    if (which == VerletKernel::Kick) verlet_kick_kernel<Real, K><<<blocks, kThreadsPerBlock, 0, stream>>>(arguments);
    return cudaGetLastError();
  });
}

template <typename Real>
cudaError_t launch_stage(const RungeKutta4Arguments<Real>& arguments, int stage, cudaStream_t stream) {
  if (arguments.vertex_count <= 0) return cudaSuccess;
  if (stage < 0 || stage > 3) return cudaErrorInvalidValue;
  return with_kind(arguments.model.kind, [&](auto kind) {
    runge_kutta4_stage_kernel<Real, decltype(kind)::value>
        <<<blocks_for(arguments.vertex_count), kThreadsPerBlock, 0, stream>>>(arguments, stage);
    return cudaGetLastError();
  });
}

template <typename Real>
cudaError_t launch_inverted(const int* corners, int element_count, const int* element_scene,
                            const kernels::StateView<Real>& state, unsigned int* count, int* first,
                            cudaStream_t stream) {
  if (element_count <= 0) return cudaSuccess;
  count_inverted_kernel<Real><<<blocks_for(element_count), kThreadsPerBlock, 0, stream>>>(
      corners, element_count, element_scene, state, count, first);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_non_finite(const kernels::StateView<Real>& state, int vertex_count, int* first_vertex,
                              cudaStream_t stream) {
  if (vertex_count <= 0) return cudaSuccess;
  find_non_finite_kernel<Real>
      <<<blocks_for(vertex_count), kThreadsPerBlock, 0, stream>>>(state, vertex_count, first_vertex);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_energy(const EnergyArguments<Real>& arguments, EnergyTerm term, int begin, int end, double* partial,
                          double* result, cudaStream_t stream) {
  energy_partial_kernel<Real><<<kEnergyBlocks, kEnergyThreads, 0, stream>>>(arguments, term, begin, end, partial);
  cudaError_t status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  energy_final_kernel<<<1, kEnergyThreads, 0, stream>>>(partial, result);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_probe(const ProbeArguments<Real>& arguments, int offset, bool before_step, cudaStream_t stream) {
  if (arguments.count <= 0) return cudaSuccess;
  apply_probe_kernel<Real>
      <<<blocks_for(arguments.count), kThreadsPerBlock, 0, stream>>>(arguments, offset, before_step);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_strain(const StrainStiffnessArguments<Real>& arguments, cudaStream_t stream) {
  if (arguments.spring_count <= 0) return cudaSuccess;
  strain_stiffness_kernel<Real><<<blocks_for(arguments.spring_count), kThreadsPerBlock, 0, stream>>>(arguments);
  return cudaGetLastError();
}

cudaError_t launch_dots(const double* first, const double* second, const double* third, const double* fourth, int count,
                        double* partial, ConjugateGradientScalars* scalars, CgStage stage, cudaStream_t stream) {
  dot_partial_kernel<<<kEnergyBlocks, kEnergyThreads, 0, stream>>>(first, second, third, fourth, count, partial);
  const cudaError_t status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  cg_scalars_kernel<<<1, kEnergyThreads, 0, stream>>>(partial, scalars, stage);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_assemble(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  if (a.spring_count > 0) {
    implicit_spring_blocks_kernel<Real><<<blocks_for(a.spring_count), kThreadsPerBlock, 0, stream>>>(a);
    const cudaError_t status = cudaGetLastError();
    if (status != cudaSuccess) return status;
  }
  if (a.elements.count > 0) {
    // The element pass at the state (f0 in b) and the elements' linearisation, before the per-vertex kernel.
    cudaError_t status = launch_elements(
        a.model, kernels::StateView<Real>{a.state.x, a.state.y, a.state.z, a.state.vx, a.state.vy, a.state.vz}, stream);
    if (status != cudaSuccess) return status;
    implicit_element_kernel<Real><<<blocks_for(a.elements.count), kThreadsPerBlock, 0, stream>>>(a);
    status = cudaGetLastError();
    if (status != cudaSuccess) return status;
  }
  if (a.vertex_count <= 0) return cudaSuccess;
  return with_kind(a.model.kind, [&](auto kind) {
    implicit_vertex_kernel<Real, decltype(kind)::value><<<blocks_for(a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
    return cudaGetLastError();
  });
}

template <typename Real>
cudaError_t launch_start(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  cg_start_kernel<Real><<<blocks_for(3 * a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  const cudaError_t status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  return launch_dots(a.rhs, a.rhs, a.r, a.z, 3 * a.vertex_count, a.partial, a.scalars, CgStage::Start, stream);
}

template <typename Real>
cudaError_t launch_iteration(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  if (a.elements.count > 0) {
    implicit_element_apply_kernel<Real><<<blocks_for(a.elements.count), kThreadsPerBlock, 0, stream>>>(a);
    const cudaError_t status = cudaGetLastError();
    if (status != cudaSuccess) return status;
  }
  implicit_apply_kernel<Real><<<blocks_for(a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  cudaError_t status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  status = launch_dots(a.p, a.ap, nullptr, nullptr, 3 * a.vertex_count, a.partial, a.scalars, CgStage::Alpha, stream);
  if (status != cudaSuccess) return status;
  cg_update_kernel<Real><<<blocks_for(3 * a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  return launch_dots(a.r, a.r, a.r, a.z, 3 * a.vertex_count, a.partial, a.scalars, CgStage::Residual, stream);
}

template <typename Real>
cudaError_t launch_direction(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  cg_direction_kernel<Real><<<blocks_for(3 * a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_finish(const ImplicitArguments<Real>& a, cudaStream_t stream) {
  if (a.vertex_count <= 0) return cudaSuccess;
  implicit_finish_kernel<Real><<<blocks_for(a.vertex_count), kThreadsPerBlock, 0, stream>>>(a);
  return cudaGetLastError();
}

}  // namespace

cudaError_t launch_element_forces(const ForceModelView<float>& model, const kernels::StateView<float>& state,
                                  cudaStream_t stream) {
  return launch_elements(model, state, stream);
}
cudaError_t launch_element_forces(const ForceModelView<double>& model, const kernels::StateView<double>& state,
                                  cudaStream_t stream) {
  return launch_elements(model, state, stream);
}
cudaError_t launch_largest_displacement(const kernels::StateView<float>& state, const StartPositions& start, int begin,
                                        int end, double* partial, double* result, cudaStream_t stream) {
  return launch_largest(state, start, begin, end, partial, result, stream);
}
cudaError_t launch_largest_displacement(const kernels::StateView<double>& state, const StartPositions& start, int begin,
                                        int end, double* partial, double* result, cudaStream_t stream) {
  return launch_largest(state, start, begin, end, partial, result, stream);
}
cudaError_t launch_sliced_springs(const kernels::SpringNetworkView<float>& network, const int* vertex_order,
                                  int vertex_count, kernels::SpringIncidence<float>* record, cudaStream_t stream) {
  return launch_sliced(network, vertex_order, vertex_count, record, stream);
}
cudaError_t launch_sliced_springs(const kernels::SpringNetworkView<double>& network, const int* vertex_order,
                                  int vertex_count, kernels::SpringIncidence<double>* record, cudaStream_t stream) {
  return launch_sliced(network, vertex_order, vertex_count, record, stream);
}
cudaError_t launch_spring_incidence(const kernels::SpringNetworkView<float>& network, int entries,
                                    kernels::SpringIncidence<float>* incidence, cudaStream_t stream) {
  return launch_incidence(network, entries, incidence, stream);
}
cudaError_t launch_spring_incidence(const kernels::SpringNetworkView<double>& network, int entries,
                                    kernels::SpringIncidence<double>* incidence, cudaStream_t stream) {
  return launch_incidence(network, entries, incidence, stream);
}
cudaError_t launch_count_inverted(const int* corners, int element_count, const int* element_scene,
                                  const kernels::StateView<float>& state, unsigned int* count, int* first,
                                  cudaStream_t stream) {
  return launch_inverted(corners, element_count, element_scene, state, count, first, stream);
}
cudaError_t launch_count_inverted(const int* corners, int element_count, const int* element_scene,
                                  const kernels::StateView<double>& state, unsigned int* count, int* first,
                                  cudaStream_t stream) {
  return launch_inverted(corners, element_count, element_scene, state, count, first, stream);
}
cudaError_t launch_fused_step(const FusedStepArguments<float>& arguments, cudaStream_t stream) {
  return launch_fused(arguments, stream);
}
cudaError_t launch_fused_step(const FusedStepArguments<double>& arguments, cudaStream_t stream) {
  return launch_fused(arguments, stream);
}
cudaError_t launch_acceleration(const VerletArguments<float>& arguments, cudaStream_t stream) {
  return launch_verlet(VerletKernel::Acceleration, arguments, stream);
}
cudaError_t launch_acceleration(const VerletArguments<double>& arguments, cudaStream_t stream) {
  return launch_verlet(VerletKernel::Acceleration, arguments, stream);
}
cudaError_t launch_verlet_drift(const VerletArguments<float>& arguments, cudaStream_t stream) {
  return launch_verlet(VerletKernel::Drift, arguments, stream);
}
cudaError_t launch_verlet_drift(const VerletArguments<double>& arguments, cudaStream_t stream) {
  return launch_verlet(VerletKernel::Drift, arguments, stream);
}
cudaError_t launch_verlet_kick(const VerletArguments<float>& arguments, cudaStream_t stream) {
  return launch_verlet(VerletKernel::Kick, arguments, stream);
}
cudaError_t launch_verlet_kick(const VerletArguments<double>& arguments, cudaStream_t stream) {
  return launch_verlet(VerletKernel::Kick, arguments, stream);
}
cudaError_t launch_runge_kutta4_stage(const RungeKutta4Arguments<float>& arguments, int stage, cudaStream_t stream) {
  return launch_stage(arguments, stage, stream);
}
cudaError_t launch_runge_kutta4_stage(const RungeKutta4Arguments<double>& arguments, int stage, cudaStream_t stream) {
  return launch_stage(arguments, stage, stream);
}
cudaError_t launch_find_non_finite(const kernels::StateView<float>& state, int vertex_count, int* first_vertex,
                                   cudaStream_t stream) {
  return launch_non_finite(state, vertex_count, first_vertex, stream);
}
cudaError_t launch_find_non_finite(const kernels::StateView<double>& state, int vertex_count, int* first_vertex,
                                   cudaStream_t stream) {
  return launch_non_finite(state, vertex_count, first_vertex, stream);
}
cudaError_t launch_energy_sum(const EnergyArguments<float>& arguments, EnergyTerm term, int begin, int end,
                              double* partial, double* result, cudaStream_t stream) {
  return launch_energy(arguments, term, begin, end, partial, result, stream);
}
cudaError_t launch_energy_sum(const EnergyArguments<double>& arguments, EnergyTerm term, int begin, int end,
                              double* partial, double* result, cudaStream_t stream) {
  return launch_energy(arguments, term, begin, end, partial, result, stream);
}

cudaError_t launch_apply_probe(const ProbeArguments<float>& arguments, int offset, bool before_step,
                               cudaStream_t stream) {
  return launch_probe(arguments, offset, before_step, stream);
}
cudaError_t launch_apply_probe(const ProbeArguments<double>& arguments, int offset, bool before_step,
                               cudaStream_t stream) {
  return launch_probe(arguments, offset, before_step, stream);
}
cudaError_t launch_strain_stiffness(const StrainStiffnessArguments<float>& arguments, cudaStream_t stream) {
  return launch_strain(arguments, stream);
}
cudaError_t launch_strain_stiffness(const StrainStiffnessArguments<double>& arguments, cudaStream_t stream) {
  return launch_strain(arguments, stream);
}
cudaError_t launch_implicit_assemble(const ImplicitArguments<float>& arguments, cudaStream_t stream) {
  return launch_assemble(arguments, stream);
}
cudaError_t launch_implicit_assemble(const ImplicitArguments<double>& arguments, cudaStream_t stream) {
  return launch_assemble(arguments, stream);
}
cudaError_t launch_cg_start(const ImplicitArguments<float>& arguments, cudaStream_t stream) {
  return launch_start(arguments, stream);
}
cudaError_t launch_cg_start(const ImplicitArguments<double>& arguments, cudaStream_t stream) {
  return launch_start(arguments, stream);
}
cudaError_t launch_cg_iteration(const ImplicitArguments<float>& arguments, cudaStream_t stream) {
  return launch_iteration(arguments, stream);
}
cudaError_t launch_cg_iteration(const ImplicitArguments<double>& arguments, cudaStream_t stream) {
  return launch_iteration(arguments, stream);
}
cudaError_t launch_cg_direction(const ImplicitArguments<float>& arguments, cudaStream_t stream) {
  return launch_direction(arguments, stream);
}
cudaError_t launch_cg_direction(const ImplicitArguments<double>& arguments, cudaStream_t stream) {
  return launch_direction(arguments, stream);
}
cudaError_t persistent_euler_block_limit(GatherKind kind, bool double_precision, long long shared_bytes, int& blocks) {
  return double_precision ? persistent_block_limit<double>(kind, shared_bytes, blocks)
                          : persistent_block_limit<float>(kind, shared_bytes, blocks);
}
cudaError_t cluster_euler_fits(bool double_precision, int blocks, int rows, long long shared_bytes, bool& fits) {
  return double_precision ? cluster_fits<double>(blocks, rows, shared_bytes, fits)
                          : cluster_fits<float>(blocks, rows, shared_bytes, fits);
}
cudaError_t launch_cluster_euler(const ClusterEulerArguments<float>& arguments, cudaStream_t stream) {
  return launch_cluster(arguments, stream);
}
cudaError_t launch_cluster_euler(const ClusterEulerArguments<double>& arguments, cudaStream_t stream) {
  return launch_cluster(arguments, stream);
}
cudaError_t launch_persistent_euler(const PersistentEulerArguments<float>& arguments, cudaStream_t stream) {
  return launch_persistent(arguments, stream);
}
cudaError_t launch_persistent_euler(const PersistentEulerArguments<double>& arguments, cudaStream_t stream) {
  return launch_persistent(arguments, stream);
}
cudaError_t launch_implicit_finish(const ImplicitArguments<float>& arguments, cudaStream_t stream) {
  return launch_finish(arguments, stream);
}
cudaError_t launch_implicit_finish(const ImplicitArguments<double>& arguments, cudaStream_t stream) {
  return launch_finish(arguments, stream);
}

}  // namespace fmpc::gpu

// The explicit schemes' kernels (forward and semi-implicit Euler one fused kernel per step, velocity Verlet, RK4),
// the element pass every per-vertex kernel gathers from, the springs' record layouts and the probe and strain-table
// kernels around each step: thin kernels over the FMPC_HD functions of kernels/*_math.h. Each per-vertex thread
// gathers its model's internal forces (springs in CSR order, elements' corner forces from the element pass; no float
// atomics) and writes only its own entries; each element thread writes only its own corners. A run gives the same
// bits every time and, compiled with --fmad=false, the same bits as the CPU loop. The per-vertex kernels are
// templates over the force model (GatherKind -> a struct of kernels/internal_force_math.h), dispatched once per
// launch.
#include <limits>
#include <type_traits>

#include "kernels/probe_schedule.cuh"
#include "kernels/step_device.cuh"

namespace fmpc::gpu {

namespace {

// The element pass needs 91 registers per thread in float unbounded (ptxas, sm_90), which leaves 2 blocks of 256 per
// SM; bounded to 3 blocks it gets 80 registers and spills 20 bytes (ncu: the spills' local stores became the pass's
// largest L2 traffic once the corner forces were written as vectors). ForceModelView::element_blocks picks the
// instance (0: the element kind's kFloatElementBlocks); double keeps its registers (1).
template <typename Real, typename Element, typename Law, bool Accumulate, int MinBlocks>
__global__ void __launch_bounds__(kThreadsPerBlock, MinBlocks)
    element_forces_kernel(kernels::ElementTermView<Real> term, kernels::StateView<Real> state,
                          kernels::CornerForce<Real>* force) {
  const int e = vertex_index();
  if (e >= term.count) return;
  kernels::element_node_forces<Element, Law, Accumulate>(e, term, state, force);
}

// One term's element pass with its element kind, law and whether it adds to the node forces as template arguments.
template <typename Real, typename Element, typename Law, bool Accumulate>
cudaError_t launch_term_forces(const ForceModelView<Real>& model, const kernels::ElementTermView<Real>& term,
                               const kernels::StateView<Real>& state, cudaStream_t stream) {
  const int blocks = blocks_for(term.count);
  if constexpr (std::is_same_v<Real, float>) {
    if ((model.element_blocks == 0 ? Element::kFloatElementBlocks : model.element_blocks) == 2) {
      element_forces_kernel<Real, Element, Law, Accumulate, 2>
          <<<blocks, kThreadsPerBlock, 0, stream>>>(term, state, model.corner_force);
      return cudaGetLastError();
    }
    element_forces_kernel<Real, Element, Law, Accumulate, 3>
        <<<blocks, kThreadsPerBlock, 0, stream>>>(term, state, model.corner_force);
  } else {
    element_forces_kernel<Real, Element, Law, Accumulate, 1>
        <<<blocks, kThreadsPerBlock, 0, stream>>>(term, state, model.corner_force);
  }
  return cudaGetLastError();
}

// The nodal pass's two kernels (launch_nodal_pass): one thread per element, then one per vertex.
template <typename Real, typename StateReal, typename Element, typename Law>
__global__ void nodal_shares_kernel(NodalPassArguments<Real> a, kernels::StateView<StateReal> state) {
  const int e = vertex_index();
  if (e >= a.term.count) return;
  kernels::element_nodal_shares<Element, Law>(e, a.term, state, a.shares);
}

template <typename Real>
__global__ void nodal_pressure_kernel(NodalPassArguments<Real> a) {
  const int v = vertex_index();
  if (v >= a.vertex_count) return;
  const kernels::CornerForceView<Real> shares{a.corner_offset, a.corner_index, a.shares};
  kernels::nodal_pressure_at(v, shares, a.pressure[v], a.dilatation[v]);
}

template <typename Real, typename Element, typename Law>
__global__ void point_state_kernel(kernels::ElementTermView<Real> term, kernels::StateView<Real> state) {
  const int e = vertex_index();
  if (e >= term.count) return;
  kernels::element_state_update<Element, Law>(e, term, state);
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

// One vertex's forward or semi-implicit Euler step from `in` into `out`: the fused kernels' body.
template <typename Real, typename Forces>
__device__ void fused_vertex_step(const FusedStepArguments<Real>& a, const Forces& forces, int v,
                                  const kernels::StateView<Real>& in, const MutableStateView<Real>& out) {
  const unsigned char held = a.loads.fixed[v];
  Real fx = Real(0), fy = Real(0), fz = Real(0);
  kernels::VertexLoadValues<Real> load{};
  if (held != kernels::kAllAxesFixed) {
    forces.gather(v, in, fx, fy, fz);
    load = kernels::vertex_load_values(a.loads, v);
  }
  kernels::VertexState<Real> x = kernels::vertex_state(in, v);
  explicit_vertex_step(a.scheme, step_of(a.step, v), held, load, a.loads, fx, fy, fz, x);
  store_vertex_state(out, v, x);
}

// Vertex v's probe entry (FusedStepArguments::probe_entry) after this step and, where probe_next, before the next,
// applied by the thread that updated the vertex.
template <typename Real>
__device__ void apply_own_probe(const FusedStepArguments<Real>& a, int v) {
  if (a.probe_entry == nullptr) return;
  const int entry = a.probe_entry[v];
  if (entry < 0) return;
  const ProbeEntry e = probe_entry(a.probe, entry, *a.probe.step_base);
  kernels::VertexState<Real> x{};
  ProbeForce<Real> force;
  if (probe_between_steps(e, a.probe_offset, a.probe_next, x, force, [](const kernels::VertexState<Real>&) {}))
    store_vertex_state(a.out, v, x);
  store_probe_force(a.probe.force, v, force);
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
__global__ void apply_probe_kernel(ProbeArguments<Real> a, int offset, bool before_step) {
  const int i = vertex_index();
  if (i >= a.count) return;
  const ProbeEntry e = probe_entry(a, i, *a.step_base);
  kernels::VertexState<Real> x{};
  ProbeForce<Real> force;
  if (probe_prescribe(e, offset, before_step, x, force)) store_vertex_state(a.state, e.vertex, x);
  store_probe_force(a.force, e.vertex, force);
}

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

}  // namespace

template <typename Real, typename StateReal>
cudaError_t launch_nodal_pass(const NodalPassArguments<Real>& arguments, const kernels::StateView<StateReal>& state,
                              cudaStream_t stream) {
  if (arguments.term.count <= 0 || arguments.vertex_count <= 0) return cudaSuccess;
  const cudaError_t status =
      kernels::visit_element_term(arguments.term.element, arguments.term.law, [&](auto kind, auto element_law) {
        using Element = decltype(kind);
        // Instantiated for the kinds with a nodal pass only; a view of another kind is a caller's error.
        if constexpr (Element::kNodalPressure) {
          nodal_shares_kernel<Real, StateReal, Element, decltype(element_law)>
              <<<blocks_for(arguments.term.count), kThreadsPerBlock, 0, stream>>>(arguments, state);
          return cudaGetLastError();
        } else {
          return cudaErrorInvalidValue;
        }
      });
  if (status != cudaSuccess) return status;
  nodal_pressure_kernel<Real><<<blocks_for(arguments.vertex_count), kThreadsPerBlock, 0, stream>>>(arguments);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_element_forces(const ForceModelView<Real>& model, const kernels::StateView<Real>& state,
                                  cudaStream_t stream) {
  if (model.kind == GatherKind::Springs || model.element_count <= 0) return cudaSuccess;
  // Every term's nodal field before any term's element pass: the shares use the corner slots those passes write.
  for (int t = 0; t < model.term_count; ++t) {
    if (model.nodal_pressure[t] == nullptr) continue;
    const NodalPassArguments<Real> nodal{model.terms[t],         model.corner_force,      model.corners.offset,
                                         model.corners.corner,   model.nodal_pressure[t], model.nodal_dilatation[t],
                                         model.vertex_count};
    const cudaError_t status = launch_nodal_pass(nodal, state, stream);
    if (status != cudaSuccess) return status;
  }
  for (int t = 0; t < model.term_count; ++t) {
    const kernels::ElementTermView<Real>& term = model.terms[t];
    const cudaError_t status = kernels::visit_element_term(term.element, term.law, [&](auto kind, auto element_law) {
      using Element = decltype(kind);
      using Law = decltype(element_law);
      return t == 0 ? launch_term_forces<Real, Element, Law, false>(model, term, state, stream)
                    : launch_term_forces<Real, Element, Law, true>(model, term, state, stream);
    });
    if (status != cudaSuccess) return status;
  }
  return cudaSuccess;
}

template <typename Real>
cudaError_t launch_point_state_update(const ForceModelView<Real>& model, const kernels::StateView<Real>& state,
                                      cudaStream_t stream) {
  if (model.kind == GatherKind::Springs || model.element_count <= 0) return cudaSuccess;
  for (int t = 0; t < model.term_count; ++t) {
    const kernels::ElementTermView<Real>& term = model.terms[t];
    if (term.prony.count == 0) continue;
    const cudaError_t status = kernels::visit_element_term(term.element, term.law, [&](auto kind, auto element_law) {
      point_state_kernel<Real, decltype(kind), decltype(element_law)>
          <<<blocks_for(term.count), kThreadsPerBlock, 0, stream>>>(term, state);
      return cudaGetLastError();
    });
    if (status != cudaSuccess) return status;
  }
  return cudaSuccess;
}

template <typename Real>
cudaError_t launch_sliced_springs(const kernels::SpringNetworkView<Real>& network, const int* vertex_order,
                                  int vertex_count, kernels::SpringIncidence<Real>* record, cudaStream_t stream) {
  if (vertex_count <= 0) return cudaSuccess;
  sliced_springs_kernel<Real>
      <<<blocks_for(vertex_count), kThreadsPerBlock, 0, stream>>>(network, vertex_order, vertex_count, record);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_spring_incidence(const kernels::SpringNetworkView<Real>& network, int entries,
                                    kernels::SpringIncidence<Real>* incidence, cudaStream_t stream) {
  if (entries <= 0) return cudaSuccess;
  spring_incidence_kernel<Real><<<blocks_for(entries), kThreadsPerBlock, 0, stream>>>(network, entries, incidence);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_fused_step(const FusedStepArguments<Real>& arguments, cudaStream_t stream) {
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

template <typename Real>
cudaError_t launch_acceleration(const VerletArguments<Real>& arguments, cudaStream_t stream) {
  return launch_verlet(VerletKernel::Acceleration, arguments, stream);
}
template <typename Real>
cudaError_t launch_verlet_drift(const VerletArguments<Real>& arguments, cudaStream_t stream) {
  return launch_verlet(VerletKernel::Drift, arguments, stream);
}
template <typename Real>
cudaError_t launch_verlet_kick(const VerletArguments<Real>& arguments, cudaStream_t stream) {
  return launch_verlet(VerletKernel::Kick, arguments, stream);
}

template <typename Real>
cudaError_t launch_runge_kutta4_stage(const RungeKutta4Arguments<Real>& arguments, int stage, cudaStream_t stream) {
  if (arguments.vertex_count <= 0) return cudaSuccess;
  if (stage < 0 || stage > 3) return cudaErrorInvalidValue;
  return with_kind(arguments.model.kind, [&](auto kind) {
    runge_kutta4_stage_kernel<Real, decltype(kind)::value>
        <<<blocks_for(arguments.vertex_count), kThreadsPerBlock, 0, stream>>>(arguments, stage);
    return cudaGetLastError();
  });
}

template <typename Real>
cudaError_t launch_apply_probe(const ProbeArguments<Real>& arguments, int offset, bool before_step,
                               cudaStream_t stream) {
  if (arguments.count <= 0) return cudaSuccess;
  apply_probe_kernel<Real>
      <<<blocks_for(arguments.count), kThreadsPerBlock, 0, stream>>>(arguments, offset, before_step);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_strain_stiffness(const StrainStiffnessArguments<Real>& arguments, cudaStream_t stream) {
  if (arguments.spring_count <= 0) return cudaSuccess;
  strain_stiffness_kernel<Real><<<blocks_for(arguments.spring_count), kThreadsPerBlock, 0, stream>>>(arguments);
  return cudaGetLastError();
}

#define FMPC_EXPLICIT_STEP_LAUNCHERS(Real)                                                                       \
  template cudaError_t launch_element_forces<Real>(const ForceModelView<Real>&, const kernels::StateView<Real>&, \
                                                   cudaStream_t);                                                \
  template cudaError_t launch_point_state_update<Real>(const ForceModelView<Real>&,                                \
                                                       const kernels::StateView<Real>&, cudaStream_t);           \
  template cudaError_t launch_sliced_springs<Real>(const kernels::SpringNetworkView<Real>&, const int*, int,     \
                                                   kernels::SpringIncidence<Real>*, cudaStream_t);               \
  template cudaError_t launch_spring_incidence<Real>(const kernels::SpringNetworkView<Real>&, int,               \
                                                     kernels::SpringIncidence<Real>*, cudaStream_t);             \
  template cudaError_t launch_fused_step<Real>(const FusedStepArguments<Real>&, cudaStream_t);                   \
  template cudaError_t launch_acceleration<Real>(const VerletArguments<Real>&, cudaStream_t);                    \
  template cudaError_t launch_verlet_drift<Real>(const VerletArguments<Real>&, cudaStream_t);                    \
  template cudaError_t launch_verlet_kick<Real>(const VerletArguments<Real>&, cudaStream_t);                     \
  template cudaError_t launch_runge_kutta4_stage<Real>(const RungeKutta4Arguments<Real>&, int, cudaStream_t);    \
  template cudaError_t launch_apply_probe<Real>(const ProbeArguments<Real>&, int, bool, cudaStream_t);           \
  template cudaError_t launch_strain_stiffness<Real>(const StrainStiffnessArguments<Real>&, cudaStream_t);
FMPC_EXPLICIT_STEP_LAUNCHERS(float)
FMPC_EXPLICIT_STEP_LAUNCHERS(double)
template cudaError_t launch_nodal_pass<float, float>(const NodalPassArguments<float>&, const kernels::StateView<float>&,
                                                     cudaStream_t);
template cudaError_t launch_nodal_pass<double, double>(const NodalPassArguments<double>&,
                                                       const kernels::StateView<double>&, cudaStream_t);
template cudaError_t launch_nodal_pass<double, float>(const NodalPassArguments<double>&,
                                                      const kernels::StateView<float>&, cudaStream_t);

}  // namespace fmpc::gpu

// Thin CUDA kernels over the FMPC_HD functions in spring_math.h and integrator_math.h: each thread owns one
// vertex, gathers its springs in CSR order (no float atomics) and writes only its own entries, so a run gives the
// same bits every time and, compiled with --fmad=false, the same bits as the CPU loop.
#include "runtime/gpu/gpu_launch.h"

namespace fmpc::gpu {

namespace {

constexpr int kThreadsPerBlock = 256;

__device__ int vertex_index() {
  return static_cast<int>(blockIdx.x) * static_cast<int>(blockDim.x) + static_cast<int>(threadIdx.x);
}

template <typename Real>
__device__ Real step_of(const StepSize<Real>& step, int v) {
  return step.vertex_scene == nullptr ? step.h : step.scene_h[step.vertex_scene[v]];
}

template <typename Real>
__device__ kernels::StateView<Real> read_only(const MutableStateView<Real>& s) {
  return {s.x, s.y, s.z, s.vx, s.vy, s.vz};
}

template <typename Real>
__global__ void fused_step_kernel(FusedStepArguments<Real> a) {
  const int v = vertex_index();
  if (v >= a.vertex_count) return;
  const Real h = step_of(a.step, v);
  Real ax, ay, az;
  kernels::vertex_acceleration(v, a.network, a.in, a.loads, ax, ay, az);
  Real x = a.in.x[v], y = a.in.y[v], z = a.in.z[v];
  Real vx = a.in.vx[v], vy = a.in.vy[v], vz = a.in.vz[v];
  if (a.scheme == FusedScheme::ForwardEuler) {
    kernels::forward_euler_update(x, vx, ax, h);
    kernels::forward_euler_update(y, vy, ay, h);
    kernels::forward_euler_update(z, vz, az, h);
  } else {
    kernels::semi_implicit_euler_update(x, vx, ax, h);
    kernels::semi_implicit_euler_update(y, vy, ay, h);
    kernels::semi_implicit_euler_update(z, vz, az, h);
  }
  a.out.x[v] = x;
  a.out.y[v] = y;
  a.out.z[v] = z;
  a.out.vx[v] = vx;
  a.out.vy[v] = vy;
  a.out.vz[v] = vz;
}

template <typename Real>
__global__ void acceleration_kernel(VerletArguments<Real> a) {
  const int v = vertex_index();
  if (v >= a.vertex_count) return;
  kernels::vertex_acceleration(v, a.network, read_only(a.state), a.loads, a.acceleration.x[v], a.acceleration.y[v],
                               a.acceleration.z[v]);
}

template <typename Real>
__global__ void verlet_drift_kernel(VerletArguments<Real> a) {
  const int v = vertex_index();
  if (v >= a.vertex_count) return;
  const Real h = step_of(a.step, v);
  kernels::verlet_position_update(a.state.x[v], a.state.vx[v], a.acceleration.x[v], h, a.predicted.x[v]);
  kernels::verlet_position_update(a.state.y[v], a.state.vy[v], a.acceleration.y[v], h, a.predicted.y[v]);
  kernels::verlet_position_update(a.state.z[v], a.state.vz[v], a.acceleration.z[v], h, a.predicted.z[v]);
}

template <typename Real>
__global__ void verlet_kick_kernel(VerletArguments<Real> a) {
  const int v = vertex_index();
  if (v >= a.vertex_count) return;
  const Real h = step_of(a.step, v);
  // Neighbours read x and the predictor only; v and a below are this vertex's own.
  const kernels::StateView<Real> drifted{a.state.x, a.state.y, a.state.z, a.predicted.x, a.predicted.y, a.predicted.z};
  Real ax, ay, az;
  kernels::vertex_acceleration(v, a.network, drifted, a.loads, ax, ay, az);
  kernels::verlet_velocity_update(a.state.vx[v], a.acceleration.x[v], ax, h);
  kernels::verlet_velocity_update(a.state.vy[v], a.acceleration.y[v], ay, h);
  kernels::verlet_velocity_update(a.state.vz[v], a.acceleration.z[v], az, h);
  a.acceleration.x[v] = ax;
  a.acceleration.y[v] = ay;
  a.acceleration.z[v] = az;
}

template <typename Real>
__global__ void runge_kutta4_stage_kernel(RungeKutta4Arguments<Real> a, int stage) {
  const int v = vertex_index();
  if (v >= a.vertex_count) return;
  const Real h = step_of(a.step, v);
  const kernels::StateView<Real> at =
      stage == 0 ? read_only(a.state) : kernels::StateView<Real>{a.stage_position[stage].x, a.stage_position[stage].y,
                                                                 a.stage_position[stage].z, a.stage_velocity[stage].x,
                                                                 a.stage_velocity[stage].y, a.stage_velocity[stage].z};
  Real ax, ay, az;
  kernels::vertex_acceleration(v, a.network, at, a.loads, ax, ay, az);
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
  if (a.loads.fixed[v]) return;
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
__global__ void find_non_finite_kernel(kernels::StateView<Real> s, int vertex_count, int* first_vertex) {
  const int v = vertex_index();
  if (v >= vertex_count) return;
  // Each value on its own: a sum of large finite values could overflow and be mistaken for one.
  if (!(isfinite(s.x[v]) && isfinite(s.y[v]) && isfinite(s.z[v]) && isfinite(s.vx[v]) && isfinite(s.vy[v]) &&
        isfinite(s.vz[v]))) {
    atomicMin(first_vertex, v);
  }
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
    return kernels::spring_potential_energy(length, a.rest_length[i], a.stiffness[i], a.law);
  }
  const double x = static_cast<double>(s.x[i]), y = static_cast<double>(s.y[i]), z = static_cast<double>(s.z[i]);
  double energy = -(a.mass[i] * a.gravity_x * x) - a.mass[i] * a.gravity_y * y - a.mass[i] * a.gravity_z * z;
  if (a.force_x != nullptr) energy -= a.force_x[i] * x + a.force_y[i] * y + a.force_z[i] * z;
  return energy;
}

// The fixed tree of one block: thread t adds elements t, t + stride, ... in order, then pairs are summed halving
// the width. Deterministic because the shape depends only on the launch size, never on timing.
__device__ double block_tree_sum(double value, double* cache) {
  const int t = static_cast<int>(threadIdx.x);
  cache[t] = value;
  __syncthreads();
  for (int width = kEnergyThreads / 2; width > 0; width /= 2) {
    if (t < width) cache[t] += cache[t + width];
    __syncthreads();
  }
  return cache[0];
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

int blocks_for(int count) { return (count + kThreadsPerBlock - 1) / kThreadsPerBlock; }

template <typename Real>
cudaError_t launch_fused(const FusedStepArguments<Real>& arguments, cudaStream_t stream) {
  if (arguments.vertex_count <= 0) return cudaSuccess;
  fused_step_kernel<Real><<<blocks_for(arguments.vertex_count), kThreadsPerBlock, 0, stream>>>(arguments);
  return cudaGetLastError();
}

template <typename Real, typename Kernel>
cudaError_t launch_per_vertex(Kernel kernel, const VerletArguments<Real>& arguments, cudaStream_t stream) {
  if (arguments.vertex_count <= 0) return cudaSuccess;
  kernel<<<blocks_for(arguments.vertex_count), kThreadsPerBlock, 0, stream>>>(arguments);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_stage(const RungeKutta4Arguments<Real>& arguments, int stage, cudaStream_t stream) {
  if (arguments.vertex_count <= 0) return cudaSuccess;
  if (stage < 0 || stage > 3) return cudaErrorInvalidValue;
  runge_kutta4_stage_kernel<Real>
      <<<blocks_for(arguments.vertex_count), kThreadsPerBlock, 0, stream>>>(arguments, stage);
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

}  // namespace

cudaError_t launch_fused_step(const FusedStepArguments<float>& arguments, cudaStream_t stream) {
  return launch_fused(arguments, stream);
}
cudaError_t launch_fused_step(const FusedStepArguments<double>& arguments, cudaStream_t stream) {
  return launch_fused(arguments, stream);
}
cudaError_t launch_acceleration(const VerletArguments<float>& arguments, cudaStream_t stream) {
  return launch_per_vertex(acceleration_kernel<float>, arguments, stream);
}
cudaError_t launch_acceleration(const VerletArguments<double>& arguments, cudaStream_t stream) {
  return launch_per_vertex(acceleration_kernel<double>, arguments, stream);
}
cudaError_t launch_verlet_drift(const VerletArguments<float>& arguments, cudaStream_t stream) {
  return launch_per_vertex(verlet_drift_kernel<float>, arguments, stream);
}
cudaError_t launch_verlet_drift(const VerletArguments<double>& arguments, cudaStream_t stream) {
  return launch_per_vertex(verlet_drift_kernel<double>, arguments, stream);
}
cudaError_t launch_verlet_kick(const VerletArguments<float>& arguments, cudaStream_t stream) {
  return launch_per_vertex(verlet_kick_kernel<float>, arguments, stream);
}
cudaError_t launch_verlet_kick(const VerletArguments<double>& arguments, cudaStream_t stream) {
  return launch_per_vertex(verlet_kick_kernel<double>, arguments, stream);
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

}  // namespace fmpc::gpu

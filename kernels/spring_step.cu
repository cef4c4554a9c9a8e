// Thin CUDA kernels over the FMPC_HD functions in spring_math.h and integrator_math.h: each thread owns one
// vertex, gathers its springs in CSR order (no float atomics) and writes only its own entries.
#include "runtime/gpu/gpu_launch.h"

namespace fmpc::gpu {

namespace {

constexpr int kThreadsPerBlock = 256;

template <typename Real>
__global__ void fused_step_kernel(FusedStepArguments<Real> a) {
  const int v = static_cast<int>(blockIdx.x) * static_cast<int>(blockDim.x) + static_cast<int>(threadIdx.x);
  if (v >= a.vertex_count) return;
  Real ax, ay, az;
  kernels::vertex_acceleration(v, a.network, a.in, a.loads, ax, ay, az);
  Real x = a.in.x[v], y = a.in.y[v], z = a.in.z[v];
  Real vx = a.in.vx[v], vy = a.in.vy[v], vz = a.in.vz[v];
  if (a.scheme == FusedScheme::ForwardEuler) {
    kernels::forward_euler_update(x, vx, ax, a.h);
    kernels::forward_euler_update(y, vy, ay, a.h);
    kernels::forward_euler_update(z, vz, az, a.h);
  } else {
    kernels::semi_implicit_euler_update(x, vx, ax, a.h);
    kernels::semi_implicit_euler_update(y, vy, ay, a.h);
    kernels::semi_implicit_euler_update(z, vz, az, a.h);
  }
  a.out.x[v] = x;
  a.out.y[v] = y;
  a.out.z[v] = z;
  a.out.vx[v] = vx;
  a.out.vy[v] = vy;
  a.out.vz[v] = vz;
}

template <typename Real>
__global__ void find_non_finite_kernel(kernels::StateView<Real> s, int vertex_count, int* first_vertex) {
  const int v = static_cast<int>(blockIdx.x) * static_cast<int>(blockDim.x) + static_cast<int>(threadIdx.x);
  if (v >= vertex_count) return;
  const Real sum = s.x[v] + s.y[v] + s.z[v] + s.vx[v] + s.vy[v] + s.vz[v];
  // NaN or +-Inf in any term makes the sum non-finite (Inf - Inf is NaN).
  if (!isfinite(sum)) atomicMin(first_vertex, v);
}

int blocks_for(int count) { return (count + kThreadsPerBlock - 1) / kThreadsPerBlock; }

template <typename Real>
cudaError_t launch_fused(const FusedStepArguments<Real>& arguments, cudaStream_t stream) {
  if (arguments.vertex_count <= 0) return cudaSuccess;
  fused_step_kernel<Real><<<blocks_for(arguments.vertex_count), kThreadsPerBlock, 0, stream>>>(arguments);
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

}  // namespace

cudaError_t launch_fused_step(const FusedStepArguments<float>& arguments, cudaStream_t stream) {
  return launch_fused(arguments, stream);
}
cudaError_t launch_fused_step(const FusedStepArguments<double>& arguments, cudaStream_t stream) {
  return launch_fused(arguments, stream);
}
cudaError_t launch_find_non_finite(const kernels::StateView<float>& state, int vertex_count, int* first_vertex,
                                   cudaStream_t stream) {
  return launch_non_finite(state, vertex_count, first_vertex, stream);
}
cudaError_t launch_find_non_finite(const kernels::StateView<double>& state, int vertex_count, int* first_vertex,
                                   cudaStream_t stream) {
  return launch_non_finite(state, vertex_count, first_vertex, stream);
}

}  // namespace fmpc::gpu

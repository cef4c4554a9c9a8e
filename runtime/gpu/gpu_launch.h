#pragma once
// Host-side declarations of the kernel launches in kernels/spring_step.cu. Every launcher returns the launch's
// cudaError_t (cudaGetLastError after <<<>>>), never exits; runtime/gpu/gpu_simulation.cpp turns it into a Diagnostic.
#include <cuda_runtime_api.h>

#include "kernels/integrator_math.h"
#include "kernels/spring_math.h"

namespace fmpc::gpu {

template <typename Real>
struct MutableStateView {
  Real* x;
  Real* y;
  Real* z;
  Real* vx;
  Real* vy;
  Real* vz;
};

enum class FusedScheme : int { ForwardEuler = 0, SemiImplicitEuler = 1 };

template <typename Real>
struct FusedStepArguments {
  kernels::SpringNetworkView<Real> network;
  kernels::VertexLoads<Real> loads;
  kernels::StateView<Real> in;  // state at t
  MutableStateView<Real> out;   // state at t + h (a different buffer: neighbours read `in` while `out` is written)
  int vertex_count;
  FusedScheme scheme;
  Real h;
};

// One fused kernel per step: gather the spring forces over the CSR adjacency, add the loads, update the vertex.
cudaError_t launch_fused_step(const FusedStepArguments<float>& arguments, cudaStream_t stream);
cudaError_t launch_fused_step(const FusedStepArguments<double>& arguments, cudaStream_t stream);

// Writes into *first_vertex (device memory, preset to vertex_count) the smallest vertex index whose position or
// velocity is NaN or infinite (integer atomicMin: the answer does not depend on scheduling).
cudaError_t launch_find_non_finite(const kernels::StateView<float>& state, int vertex_count, int* first_vertex,
                                   cudaStream_t stream);
cudaError_t launch_find_non_finite(const kernels::StateView<double>& state, int vertex_count, int* first_vertex,
                                   cudaStream_t stream);

}  // namespace fmpc::gpu

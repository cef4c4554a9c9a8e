// The reductions and checks over a state (gpu_launch.h): the first non-finite vertex, inverted elements per scene,
// energies and the largest displacement, each summed or maximised by a fixed-shape tree so that a run gives the same
// bits every time.
#include "kernels/step_device.cuh"

namespace fmpc::gpu {

namespace {

template <typename Real>
__global__ void find_non_finite_kernel(kernels::StateView<Real> s, int vertex_count, int* first_vertex) {
  const int v = vertex_index();
  if (v >= vertex_count) return;
  if (non_finite_vertex(s, v)) atomicMin(first_vertex, v);
}

template <typename Real>
__global__ void copy_state_kernel(MutableStateView<Real> to, kernels::StateView<Real> from, int vertex_count) {
  const int v = vertex_index();
  if (v >= vertex_count) return;
  to.x[v] = from.x[v];
  to.y[v] = from.y[v];
  to.z[v] = from.z[v];
  to.vx[v] = from.vx[v];
  to.vy[v] = from.vy[v];
  to.vz[v] = from.vz[v];
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
    const kernels::ElementTermView<double>& term = a.element_term;
    return kernels::visit_element_term_on_device(term.element, term.law, [&](auto kind, auto element_law) {
      using Element = decltype(kind);
      constexpr int N = Element::kNodes;
      double x[N][3];
      for (int c = 0; c < N; ++c) {
        const int vertex = term.corners[N * i + c];
        x[c][0] = static_cast<double>(s.x[vertex]);
        x[c][1] = static_cast<double>(s.y[vertex]);
        x[c][2] = static_cast<double>(s.z[vertex]);
      }
      return Element::template energy<decltype(element_law)>(term, i, x);
    });
  }
  const double x = static_cast<double>(s.x[i]), y = static_cast<double>(s.y[i]), z = static_cast<double>(s.z[i]);
  double energy = -(a.mass[i] * a.gravity_x * x) - a.mass[i] * a.gravity_y * y - a.mass[i] * a.gravity_z * z;
  if (a.force_x != nullptr) energy -= a.force_x[i] * x + a.force_y[i] * y + a.force_z[i] * z;
  return energy;
}

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
__global__ void count_inverted_kernel(const int* nodes, int element_kind, int element_count, const int* element_scene,
                                      kernels::StateView<Real> s, unsigned int* count, int* first) {
  const int e = vertex_index();
  if (e >= element_count) return;
  count_if_inverted(nodes, element_kind, e, element_scene, s, count, first);
}

}  // namespace

template <typename Real>
cudaError_t launch_largest_displacement(const kernels::StateView<Real>& state, const StartPositions& start, int begin,
                                        int end, double* partial, double* result, cudaStream_t stream) {
  largest_displacement_partial_kernel<Real>
      <<<kEnergyBlocks, kEnergyThreads, 0, stream>>>(state, start, begin, end, partial);
  cudaError_t status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  largest_displacement_final_kernel<<<1, kEnergyThreads, 0, stream>>>(partial, result);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_count_inverted(const int* nodes, int element_kind, int element_count, const int* element_scene,
                                  const kernels::StateView<Real>& state, unsigned int* count, int* first,
                                  cudaStream_t stream) {
  if (element_count <= 0) return cudaSuccess;
  count_inverted_kernel<Real><<<blocks_for(element_count), kThreadsPerBlock, 0, stream>>>(
      nodes, element_kind, element_count, element_scene, state, count, first);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_find_non_finite(const kernels::StateView<Real>& state, int vertex_count, int* first_vertex,
                                   cudaStream_t stream) {
  if (vertex_count <= 0) return cudaSuccess;
  find_non_finite_kernel<Real>
      <<<blocks_for(vertex_count), kThreadsPerBlock, 0, stream>>>(state, vertex_count, first_vertex);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_copy_state(const MutableStateView<Real>& to, const kernels::StateView<Real>& from, int vertex_count,
                              cudaStream_t stream) {
  if (vertex_count <= 0) return cudaSuccess;
  copy_state_kernel<Real><<<blocks_for(vertex_count), kThreadsPerBlock, 0, stream>>>(to, from, vertex_count);
  return cudaGetLastError();
}

template <typename Real>
cudaError_t launch_energy_sum(const EnergyArguments<Real>& arguments, EnergyTerm term, int begin, int end,
                              double* partial, double* result, cudaStream_t stream) {
  energy_partial_kernel<Real><<<kEnergyBlocks, kEnergyThreads, 0, stream>>>(arguments, term, begin, end, partial);
  cudaError_t status = cudaGetLastError();
  if (status != cudaSuccess) return status;
  energy_final_kernel<<<1, kEnergyThreads, 0, stream>>>(partial, result);
  return cudaGetLastError();
}

#define FMPC_REDUCTION_LAUNCHERS(Real)                                                                                \
  template cudaError_t launch_largest_displacement<Real>(const kernels::StateView<Real>&, const StartPositions&, int, \
                                                         int, double*, double*, cudaStream_t);                        \
  template cudaError_t launch_count_inverted<Real>(const int*, int, int, const int*, const kernels::StateView<Real>&, \
                                                   unsigned int*, int*, cudaStream_t);                                \
  template cudaError_t launch_find_non_finite<Real>(const kernels::StateView<Real>&, int, int*, cudaStream_t);        \
  template cudaError_t launch_copy_state<Real>(const MutableStateView<Real>&, const kernels::StateView<Real>&, int,     \
                                               cudaStream_t);                                                          \
  template cudaError_t launch_energy_sum<Real>(const EnergyArguments<Real>&, EnergyTerm, int, int, double*, double*,  \
                                               cudaStream_t);
FMPC_REDUCTION_LAUNCHERS(float)
FMPC_REDUCTION_LAUNCHERS(double)

}  // namespace fmpc::gpu

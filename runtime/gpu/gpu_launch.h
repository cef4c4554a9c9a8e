#pragma once
// Host-side declarations of the kernel launches in kernels/spring_step.cu. Every launcher returns the launch's
// cudaError_t (cudaGetLastError after <<<>>>), never exits; runtime/gpu/gpu_simulation.cpp turns it into a Diagnostic.
//
// A batch of scenes is one concatenated network: scene s owns a contiguous range of vertices and springs, its CSR
// entries point at its own vertices only, so one thread per vertex serves every scene in one launch. Per-scene time
// steps are read through vertex_scene (null for a single scene, which then uses `h`).
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

template <typename Real>
struct MutableVector3View {
  Real* x;
  Real* y;
  Real* z;
};

// The step size of each vertex: scene_h[vertex_scene[v]] in a batch, h otherwise.
template <typename Real>
struct StepSize {
  const int* vertex_scene;  // null: every vertex uses h
  const Real* scene_h;
  Real h;
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
  StepSize<Real> step;
};

// One fused kernel per step: gather the spring forces over the CSR adjacency, add the loads, update the vertex.
cudaError_t launch_fused_step(const FusedStepArguments<float>& arguments, cudaStream_t stream);
cudaError_t launch_fused_step(const FusedStepArguments<double>& arguments, cudaStream_t stream);

// Velocity Verlet, two kernels per step (the second gathers at positions the first one wrote):
//   drift: x += h v + h^2/2 a, predicted = v + h a            (own vertex only)
//   kick:  a1 = a(x, predicted), v += h/2 (a + a1), a = a1     (gathers x and predicted of the neighbours)
// `acceleration` alone computes a = a(x, v), for the first step.
template <typename Real>
struct VerletArguments {
  kernels::SpringNetworkView<Real> network;
  kernels::VertexLoads<Real> loads;
  MutableStateView<Real> state;           // x and v, updated in place
  MutableVector3View<Real> acceleration;  // a at the current positions
  MutableVector3View<Real> predicted;     // the velocity predictor v + h a
  int vertex_count;
  StepSize<Real> step;
};
cudaError_t launch_acceleration(const VerletArguments<float>& arguments, cudaStream_t stream);
cudaError_t launch_acceleration(const VerletArguments<double>& arguments, cudaStream_t stream);
cudaError_t launch_verlet_drift(const VerletArguments<float>& arguments, cudaStream_t stream);
cudaError_t launch_verlet_drift(const VerletArguments<double>& arguments, cudaStream_t stream);
cudaError_t launch_verlet_kick(const VerletArguments<float>& arguments, cudaStream_t stream);
cudaError_t launch_verlet_kick(const VerletArguments<double>& arguments, cudaStream_t stream);

// Classical RK4 as four gather kernels per step. Stage s (0..3) gathers the acceleration at the stage state
// (stage_position[s], stage_velocity[s]) (stage 0: the state itself), stores it, and writes the next stage's state
// of its own vertex: position + c_{s+1} k_v, velocity + c_{s+1} k_a (c = h/2, h/2, h). Stage 3 combines the four
// slopes with runge_kutta4_combine into the state. Stage positions alternate between two buffers so that no kernel
// writes what its neighbours read.
template <typename Real>
struct RungeKutta4Arguments {
  kernels::SpringNetworkView<Real> network;
  kernels::VertexLoads<Real> loads;
  MutableStateView<Real> state;                    // y0, combined in place by stage 3
  MutableVector3View<Real> stage_position[4];      // [0] unused (the state); [1] and [3] share a buffer
  MutableVector3View<Real> stage_velocity[4];      // k_v of each stage; [0] unused (the state's velocity)
  MutableVector3View<Real> stage_acceleration[3];  // k_a of stages 0..2 (stage 3's stays in registers)
  int vertex_count;
  StepSize<Real> step;
};
cudaError_t launch_runge_kutta4_stage(const RungeKutta4Arguments<float>& arguments, int stage, cudaStream_t stream);
cudaError_t launch_runge_kutta4_stage(const RungeKutta4Arguments<double>& arguments, int stage, cudaStream_t stream);

// Writes into *first_vertex (device memory, preset to vertex_count) the smallest vertex index whose position or
// velocity is NaN or infinite (integer atomicMin: the answer does not depend on scheduling).
cudaError_t launch_find_non_finite(const kernels::StateView<float>& state, int vertex_count, int* first_vertex,
                                   cudaStream_t stream);
cudaError_t launch_find_non_finite(const kernels::StateView<double>& state, int vertex_count, int* first_vertex,
                                   cudaStream_t stream);

// Energies of one scene, summed in double by a fixed-shape tree (kEnergyBlocks partial sums of kEnergyThreads
// threads each, then one block): the same bits on every run, whatever the scheduling.
constexpr int kEnergyBlocks = 128;
constexpr int kEnergyThreads = 256;

template <typename Real>
struct EnergyArguments {
  kernels::StateView<Real> state;
  const double* mass;  // kg, as given (not rounded to Real)
  const int* spring_first;
  const int* spring_second;
  const double* rest_length;
  const double* stiffness;
  kernels::SpringLawParameters<double> law;
  double gravity_x, gravity_y, gravity_z;
  const double* force_x;  // null: no external forces
  const double* force_y;
  const double* force_z;
};

enum class EnergyTerm : int {
  Kinetic = 0,          // sum over vertices of m |v|^2 / 2
  SpringPotential = 1,  // sum over springs of spring_potential_energy
  LoadPotential = 2,    // sum over vertices of -(m g + f) . x
};

// Sums the term over [begin, end) into *result (device memory); `partial` holds kEnergyBlocks doubles.
cudaError_t launch_energy_sum(const EnergyArguments<float>& arguments, EnergyTerm term, int begin, int end,
                              double* partial, double* result, cudaStream_t stream);
cudaError_t launch_energy_sum(const EnergyArguments<double>& arguments, EnergyTerm term, int begin, int end,
                              double* partial, double* result, cudaStream_t stream);

}  // namespace fmpc::gpu

// One stepper per explicit integrator family, each enqueueing one step on the engine's stream: forward and
// semi-implicit Euler (one fused kernel), velocity Verlet (drift and kick), RK4 (four stages), with their launch
// arguments. Implicit Euler's is gpu_engine_implicit.cpp; the schedule around them, gpu_engine_steps.cpp.
#include "runtime/gpu/cuda_check.h"
#include "runtime/gpu/gpu_engine.h"

namespace fmpc::gpu {

template <typename Real>
bool GpuEngine<Real>::enqueue_euler_step(int offset, bool probe_next, bool fused_probes, int& parity,
                                         DiagnosticList& diagnostics) {
  FMPC_CUDA_CHECK(launch_element_forces(model_, state_[parity].view(), stream_), diagnostics, false);
  FusedStepArguments<Real> a = fused_arguments();
  a.in = state_[parity].view();
  a.out = state_[1 - parity].mutable_view();
  a.lanes = plan_.gather_lanes;
  if (fused_probes) {
    a.probe = probe_arguments(state_[1 - parity]);
    a.probe_entry = probe_entry_.data();
    a.probe_offset = offset;
    a.probe_next = probe_next;
  }
  FMPC_CUDA_CHECK(launch_fused_step(a, stream_), diagnostics, false);
  parity = 1 - parity;
  return true;
}

template <typename Real>
bool GpuEngine<Real>::enqueue_verlet_step(DiagnosticList& diagnostics) {
  // a(x0, v0) once, after the first step's probe and lookup (run_steps keeps that step out of graphs).
  if (!have_acceleration_) {
    FMPC_CUDA_CHECK(launch_element_forces(model_, state_[0].view(), stream_), diagnostics, false);
    FMPC_CUDA_CHECK(launch_acceleration(verlet_arguments(), stream_), diagnostics, false);
    have_acceleration_ = true;
  }
  FMPC_CUDA_CHECK(launch_verlet_drift(verlet_arguments(), stream_), diagnostics, false);
  {
    // The kick gathers at the drifted positions with the velocity predictor.
    const DeviceState<Real>& state = state_[0];
    const kernels::StateView<Real> drifted{state.x.data(),      state.y.data(),      state.z.data(),
                                           predicted_.x.data(), predicted_.y.data(), predicted_.z.data()};
    FMPC_CUDA_CHECK(launch_element_forces(model_, drifted, stream_), diagnostics, false);
  }
  FMPC_CUDA_CHECK(launch_verlet_kick(verlet_arguments(), stream_), diagnostics, false);
  return true;
}

template <typename Real>
bool GpuEngine<Real>::enqueue_runge_kutta4_step(DiagnosticList& diagnostics) {
  const RungeKutta4Arguments<Real> a = runge_kutta4_arguments();
  for (int stage = 0; stage < 4; ++stage) {
    const kernels::StateView<Real> at =
        stage == 0 ? state_[0].view() : kernels::StateView<Real>{a.stage_position[stage].x, a.stage_position[stage].y,
                                                                 a.stage_position[stage].z, a.stage_velocity[stage].x,
                                                                 a.stage_velocity[stage].y, a.stage_velocity[stage].z};
    FMPC_CUDA_CHECK(launch_element_forces(model_, at, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(launch_runge_kutta4_stage(a, stage, stream_), diagnostics, false);
  }
  return true;
}

template <typename Real>
FusedStepArguments<Real> GpuEngine<Real>::fused_arguments() const {
  FusedStepArguments<Real> a{};
  a.model = model_;
  a.loads = loads_;
  a.vertex_count = n_;
  a.scheme = scheme() == sim::Integrator::ForwardEuler ? FusedScheme::ForwardEuler : FusedScheme::SemiImplicitEuler;
  a.step = step_;
  return a;
}

template <typename Real>
VerletArguments<Real> GpuEngine<Real>::verlet_arguments() const {
  return {model_, loads_, state_[0].mutable_view(), acceleration_.view(), predicted_.view(), n_, step_};
}

template <typename Real>
RungeKutta4Arguments<Real> GpuEngine<Real>::runge_kutta4_arguments() const {
  RungeKutta4Arguments<Real> a{};
  a.model = model_;
  a.loads = loads_;
  a.state = state_[0].mutable_view();
  a.stage_position[1] = stage_position_a_.view();
  a.stage_position[2] = stage_position_b_.view();
  a.stage_position[3] = stage_position_a_.view();
  for (std::size_t s = 1; s < 4; ++s) a.stage_velocity[s] = stage_velocity_[s - 1].view();
  for (std::size_t s = 0; s < 3; ++s) a.stage_acceleration[s] = stage_acceleration_[s].view();
  a.vertex_count = n_;
  a.step = step_;
  return a;
}

#define FMPC_GPU_ENGINE_STEPPERS_MEMBERS(Real)                                                                   \
  template bool GpuEngine<Real>::enqueue_euler_step(int offset, bool probe_next, bool fused_probes, int& parity, \
                                                    DiagnosticList& diagnostics);                                \
  template bool GpuEngine<Real>::enqueue_verlet_step(DiagnosticList& diagnostics);                               \
  template bool GpuEngine<Real>::enqueue_runge_kutta4_step(DiagnosticList& diagnostics);                         \
  template FusedStepArguments<Real> GpuEngine<Real>::fused_arguments() const;                                    \
  template VerletArguments<Real> GpuEngine<Real>::verlet_arguments() const;                                      \
  template RungeKutta4Arguments<Real> GpuEngine<Real>::runge_kutta4_arguments() const;
FMPC_GPU_ENGINE_STEPPERS_MEMBERS(float)
FMPC_GPU_ENGINE_STEPPERS_MEMBERS(double)
#undef FMPC_GPU_ENGINE_STEPPERS_MEMBERS

}  // namespace fmpc::gpu

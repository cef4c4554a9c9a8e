// Implicit Euler on the device: assembly and the Jacobi-preconditioned conjugate gradient (kernels/implicit_math.h),
// stopped and warned about as on the CPU.
#include <algorithm>
#include <cmath>
#include <limits>

#include "runtime/gpu/cuda_check.h"
#include "runtime/gpu/gpu_engine.h"

namespace fmpc::gpu {

template <typename Real>
ImplicitArguments<Real> GpuEngine<Real>::implicit_arguments() {
  ImplicitArguments<Real> a{};
  a.model = model_;
  a.elements = elements_;
  a.loads = loads_;
  a.state = state_[0].mutable_view();
  a.first = first_.data();
  a.second = second_.data();
  a.rest_length = energy_rest_length_.data();
  a.mass = energy_mass_.data();
  a.rest_position = implicit_rest_.data();
  // The CPU backend steps with h rounded to Real and widened again; so does this.
  a.h = static_cast<double>(static_cast<Real>(stability_.front().time_step));
  a.vertex_count = n_;
  a.spring_count = spring_begin_.back();
  a.blocks = implicit_blocks_.data();
  a.diagonal = implicit_diagonal_.data();
  a.inverse_jacobi = implicit_jacobi_.data();
  a.rhs = implicit_rhs_.data();
  a.x = cg_x_.data();
  a.r = cg_r_.data();
  a.z = cg_z_.data();
  a.p = cg_p_.data();
  a.ap = cg_ap_.data();
  a.scalars = cg_scalars_.data();
  a.partial = cg_partial_.data();
  return a;
}

template <typename Real>
bool GpuEngine<Real>::read_cg_scalars(ConjugateGradientScalars& scalars, DiagnosticList& diagnostics) {
  FMPC_CUDA_CHECK(cudaMemcpyAsync(&scalars, cg_scalars_.data(), sizeof scalars, cudaMemcpyDeviceToHost, stream_),
                  diagnostics, false);
  return synchronize(diagnostics);
}

template <typename Real>
bool GpuEngine<Real>::implicit_solve(DiagnosticList& diagnostics) {
  const ImplicitArguments<Real> a = implicit_arguments();
  FMPC_CUDA_CHECK(launch_implicit_assemble(a, stream_), diagnostics, false);
  FMPC_CUDA_CHECK(launch_cg_start(a, stream_), diagnostics, false);
  ConjugateGradientScalars scalars{};
  if (!read_cg_scalars(scalars, diagnostics)) return false;
  const sim::ImplicitSolverOptions& options = scenes_.front().implicit;
  // As the CPU backend: a right-hand side this small means the system is at rest to double precision; dv = 0 (the
  // start's x) and the positions still move with their velocities.
  if (std::sqrt(scalars.rhs_norm2) < 1e-150) {
    implicit_log_.record({steps_taken_ + 1, 0, 0.0, false});
    FMPC_CUDA_CHECK(launch_implicit_finish(a, stream_), diagnostics, false);
    return true;
  }
  const double threshold =
      std::max(options.tolerance * options.tolerance * scalars.rhs_norm2, std::numeric_limits<double>::min());
  double residual = scalars.rhs_norm2;
  // Iterations count the matrix products, the converging one included (the CPU's count).
  int iterations = 0;
  const int limit = sim::implicit_iteration_limit(scenes_.front());
  while (residual >= threshold && iterations < limit) {
    FMPC_CUDA_CHECK(launch_cg_iteration(a, stream_), diagnostics, false);
    if (!read_cg_scalars(scalars, diagnostics)) return false;
    residual = scalars.rr;
    ++iterations;
    if (residual < threshold) break;
    FMPC_CUDA_CHECK(launch_cg_direction(a, stream_), diagnostics, false);
  }
  const double error = std::sqrt(residual / scalars.rhs_norm2);
  const sim::ImplicitStepRecord record{steps_taken_ + 1, iterations, error, !(residual < threshold)};
  if (implicit_log_.record(record))
    diagnostics.warning(scenes_.front().source_range, "cg-not-converged",
                        sim::cg_stopped_message(sim::ImplicitMethod::ConjugateGradient, record.step, iterations,
                                                error, options.tolerance));
  FMPC_CUDA_CHECK(launch_implicit_finish(a, stream_), diagnostics, false);
  return true;
}

#define FMPC_GPU_ENGINE_IMPLICIT_MEMBERS(Real)                                                                    \
  template ImplicitArguments<Real> GpuEngine<Real>::implicit_arguments();                                         \
  template bool GpuEngine<Real>::read_cg_scalars(ConjugateGradientScalars& scalars, DiagnosticList& diagnostics); \
  template bool GpuEngine<Real>::implicit_solve(DiagnosticList& diagnostics);
FMPC_GPU_ENGINE_IMPLICIT_MEMBERS(float)
FMPC_GPU_ENGINE_IMPLICIT_MEMBERS(double)
#undef FMPC_GPU_ENGINE_IMPLICIT_MEMBERS

}  // namespace fmpc::gpu

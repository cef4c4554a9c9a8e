// Implicit Euler on the device: assembly and the Jacobi-preconditioned conjugate gradient (kernels/implicit_math.h),
// stopped and warned about as on the CPU.
#include <cmath>

#include "runtime/gpu/cuda_check.h"
#include "runtime/gpu/gpu_engine.h"
#include "runtime/gpu/launch_plan.h"

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
  const bool contact = loads_.contact.tool_count > 0;
  a.extra_blocks = contact ? contact_blocks_.data() : nullptr;
  a.extra_rhs = contact ? contact_rhs_.data() : nullptr;
  a.contact_active = contact ? contact_active_.data() : nullptr;
  a.contact_changes = contact ? contact_changes_.data() : nullptr;
  a.diagonal = implicit_diagonal_.data();
  a.inverse_jacobi = implicit_jacobi_.data();
  a.rhs = implicit_rhs_.data();
  a.x = cg_x_.data();
  a.r = cg_r_.data();
  a.z = cg_z_.data();
  a.p = cg_p_.data();
  a.ap = cg_ap_.data();
  a.scalars = cg_scalars_.data() + deferred_solves_;
  a.partial = cg_partial_.data();
  a.tolerance = scenes_.front().implicit.tolerance;
  a.iteration_limit = sim::implicit_iteration_limit(scenes_.front());
  return a;
}

template <typename Real>
bool GpuEngine<Real>::read_cg_scalars(const ImplicitArguments<Real>& a, ConjugateGradientScalars& scalars,
                                      DiagnosticList& diagnostics) {
  FMPC_CUDA_CHECK(cudaMemcpyAsync(&scalars, a.scalars, sizeof scalars, cudaMemcpyDeviceToHost, stream_), diagnostics,
                  false);
  return synchronize(diagnostics);
}

template <typename Real>
bool GpuEngine<Real>::implicit_solve(DiagnosticList& diagnostics) {
  const ImplicitArguments<Real> a = implicit_arguments();
  const bool contact = a.extra_blocks != nullptr;
  // The tools' contact as the system's linear part (launch_contact_part): the pairs inside at the step's start,
  // then those the solution predicts inside, solved again until the set stays, at most contact_rounds solves, as on
  // the CPU (a later round's CG starts from zero where the CPU's starts from the last round's dv: the two agree to
  // the solver's tolerance). The last solve's prediction still runs, to count a set that changed after it.
  if (!contact && (plan_.cg_block_bytes > 0 || plan_.cg_grid_blocks > 0)) {
    FMPC_CUDA_CHECK(launch_implicit_assemble(a, true, stream_), diagnostics, false);
    if (plan_.cg_block_bytes > 0) {
      FMPC_CUDA_CHECK(launch_cg_block(a, plan_.cg_block, plan_.cg_block_bytes, true, stream_), diagnostics, false);
    } else {
      FMPC_CUDA_CHECK(launch_cg_start(a, plan_.cg_fused_stages, stream_), diagnostics, false);
      FMPC_CUDA_CHECK(launch_cg_persistent(a, plan_.cg_grid_blocks, stream_), diagnostics, false);
      FMPC_CUDA_CHECK(launch_implicit_finish(a, stream_), diagnostics, false);
    }
    if (deferred_solves_ == 0) deferred_first_step_ = steps_taken_ + 1;
    return ++deferred_solves_ < kDeferredSolves || record_deferred_solves(diagnostics);
  }
  FMPC_CUDA_CHECK(launch_contact_part(a, false, stream_), diagnostics, false);
  const int most_rounds = scenes_.front().implicit.contact_rounds;
  ConjugateGradientScalars scalars{};
  int iterations = 0;
  bool settled = true;
  for (int round = 1;; ++round) {
    if (!conjugate_gradient(a, round == 1, scalars, diagnostics)) return false;
    iterations += scalars.iterations;
    if (!contact || scalars.at_rest) break;
    unsigned int changes = 0;
    FMPC_CUDA_CHECK(cudaMemsetAsync(a.contact_changes, 0, sizeof changes, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(launch_contact_part(a, true, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(cudaMemcpyAsync(&changes, a.contact_changes, sizeof changes, cudaMemcpyDeviceToHost, stream_),
                    diagnostics, false);
    if (!synchronize(diagnostics)) return false;
    if (changes == 0) break;
    if (round >= most_rounds) {
      settled = false;
      break;
    }
  }
  record_solve(steps_taken_ + 1, iterations, scalars, diagnostics);
  if (!settled)
    implicit_log_.contact_unsettled(steps_taken_ + 1, most_rounds, scenes_.front().source_range, diagnostics);
  FMPC_CUDA_CHECK(launch_implicit_finish(a, stream_), diagnostics, false);
  return true;
}

template <typename Real>
void GpuEngine<Real>::record_solve(std::size_t step, int iterations, const ConjugateGradientScalars& scalars,
                                   DiagnosticList& diagnostics) {
  if (scalars.at_rest) {
    implicit_log_.record({step, 0, 0.0, false});
    return;
  }
  const double error = std::sqrt(scalars.rr / scalars.rhs_norm2);
  const sim::ImplicitStepRecord record{step, iterations, error, !(scalars.rr < scalars.threshold)};
  if (implicit_log_.record(record))
    diagnostics.warning(scenes_.front().source_range, "cg-not-converged",
                        sim::cg_stopped_message(sim::ImplicitMethod::ConjugateGradient, record.step, iterations, error,
                                                scenes_.front().implicit.tolerance));
}

template <typename Real>
bool GpuEngine<Real>::record_deferred_solves(DiagnosticList& diagnostics) {
  if (deferred_solves_ == 0) return true;
  const int count = deferred_solves_;
  deferred_solves_ = 0;
  FMPC_CUDA_CHECK(cudaMemcpyAsync(cg_scalars_host_.data(), cg_scalars_.data(), count * sizeof(ConjugateGradientScalars),
                                  cudaMemcpyDeviceToHost, stream_),
                  diagnostics, false);
  if (!synchronize(diagnostics)) return false;
  for (int k = 0; k < count; ++k) {
    const ConjugateGradientScalars& scalars = cg_scalars_host_.data()[k];
    record_solve(deferred_first_step_ + static_cast<std::size_t>(k), scalars.iterations, scalars, diagnostics);
  }
  return true;
}

template <typename Real>
bool GpuEngine<Real>::conjugate_gradient(const ImplicitArguments<Real>& a, bool linearise,
                                         ConjugateGradientScalars& scalars, DiagnosticList& diagnostics) {
  FMPC_CUDA_CHECK(launch_implicit_assemble(a, linearise, stream_), diagnostics, false);
  // The solve stops on the device (ConjugateGradientScalars::done); the host reads the scalars once after the
  // one-block or cooperative launch, or after each chunk of per-iteration launches (cg_iterations_before_read).
  if (plan_.cg_block_bytes > 0) {
    FMPC_CUDA_CHECK(launch_cg_block(a, plan_.cg_block, plan_.cg_block_bytes, false, stream_), diagnostics, false);
    if (!read_cg_scalars(a, scalars, diagnostics)) return false;
  } else if (plan_.cg_grid_blocks > 0) {
    FMPC_CUDA_CHECK(launch_cg_start(a, plan_.cg_fused_stages, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(launch_cg_persistent(a, plan_.cg_grid_blocks, stream_), diagnostics, false);
    if (!read_cg_scalars(a, scalars, diagnostics)) return false;
  } else {
    FMPC_CUDA_CHECK(launch_cg_start(a, plan_.cg_fused_stages, stream_), diagnostics, false);
    int enqueued = 0;
    for (;;) {
      const int chunk = cg_iterations_before_read(cg_previous_iterations_, enqueued, a.iteration_limit);
      FMPC_CUDA_CHECK(launch_cg_iterations(a, chunk, plan_.cg_fused_stages, stream_), diagnostics, false);
      enqueued += chunk;
      if (!read_cg_scalars(a, scalars, diagnostics)) return false;
      if (scalars.done || chunk == 0) break;
    }
  }
  cg_previous_iterations_ = scalars.iterations;
  return true;
}

#define FMPC_GPU_ENGINE_IMPLICIT_MEMBERS(Real)                                                                    \
  template ImplicitArguments<Real> GpuEngine<Real>::implicit_arguments();                                         \
  template bool GpuEngine<Real>::read_cg_scalars(const ImplicitArguments<Real>& a, ConjugateGradientScalars& scalars, \
                                                 DiagnosticList& diagnostics);                                      \
  template bool GpuEngine<Real>::implicit_solve(DiagnosticList& diagnostics);                                     \
  template void GpuEngine<Real>::record_solve(std::size_t step, int iterations,                                   \
                                              const ConjugateGradientScalars& scalars, DiagnosticList& diagnostics); \
  template bool GpuEngine<Real>::record_deferred_solves(DiagnosticList& diagnostics);                             \
  template bool GpuEngine<Real>::conjugate_gradient(const ImplicitArguments<Real>& a, bool linearise,             \
                                                    ConjugateGradientScalars& scalars, DiagnosticList& diagnostics);
FMPC_GPU_ENGINE_IMPLICIT_MEMBERS(float)
FMPC_GPU_ENGINE_IMPLICIT_MEMBERS(double)
#undef FMPC_GPU_ENGINE_IMPLICIT_MEMBERS

}  // namespace fmpc::gpu

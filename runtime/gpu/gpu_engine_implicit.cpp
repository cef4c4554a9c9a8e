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
  const bool contact = loads_.contact.tool_count > 0;
  a.contact_blocks = contact ? contact_blocks_.data() : nullptr;
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
  const bool contact = a.contact_blocks != nullptr;
  // The tools' contact as an active set (kernels/contact_math.h): the pairs inside at the step's start, then those
  // the solution predicts inside, solved again until the set stays, as on the CPU (each round's CG starts from zero
  // where the CPU's starts from the last round's dv: the two agree to the solver's tolerance).
  FMPC_CUDA_CHECK(launch_contact_set(a, false, stream_), diagnostics, false);
  for (int round = 1;; ++round) {
    FMPC_CUDA_CHECK(launch_implicit_assemble(a, stream_), diagnostics, false);
    bool at_rest = false;
    if (!conjugate_gradient(a, at_rest, diagnostics)) return false;
    if (at_rest) return true;  // as the CPU backend: the step changes nothing
    if (!contact) break;
    unsigned int changes = 0;
    FMPC_CUDA_CHECK(cudaMemsetAsync(a.contact_changes, 0, sizeof changes, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(launch_contact_set(a, true, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(cudaMemcpyAsync(&changes, a.contact_changes, sizeof changes, cudaMemcpyDeviceToHost, stream_),
                    diagnostics, false);
    if (!synchronize(diagnostics)) return false;
    if (changes == 0) break;
    if (round == kernels::kMostContactRounds) {
      if (!contact_warning_given_) {
        contact_warning_given_ = true;
        diagnostics.warning(scenes_.front().source_range, "contact-not-settled",
                            sim::contact_unsettled_message(steps_taken_ + 1, kernels::kMostContactRounds));
      }
      break;
    }
  }
  FMPC_CUDA_CHECK(launch_implicit_finish(a, stream_), diagnostics, false);
  return true;
}

template <typename Real>
bool GpuEngine<Real>::conjugate_gradient(const ImplicitArguments<Real>& a, bool& at_rest, DiagnosticList& diagnostics) {
  FMPC_CUDA_CHECK(launch_cg_start(a, stream_), diagnostics, false);
  ConjugateGradientScalars scalars{};
  if (!read_cg_scalars(scalars, diagnostics)) return false;
  // As the CPU backend: a right-hand side this small means the system is at rest to double precision.
  at_rest = std::sqrt(scalars.rhs_norm2) < 1e-150;
  if (at_rest) return true;
  const sim::ImplicitSolverOptions& options = scenes_.front().implicit;
  const double threshold =
      std::max(options.tolerance * options.tolerance * scalars.rhs_norm2, std::numeric_limits<double>::min());
  double residual = scalars.rhs_norm2;
  int iterations = 0;
  if (residual >= threshold) {
    const int limit = sim::implicit_iteration_limit(scenes_.front());
    while (iterations < limit) {
      FMPC_CUDA_CHECK(launch_cg_iteration(a, stream_), diagnostics, false);
      if (!read_cg_scalars(scalars, diagnostics)) return false;
      residual = scalars.rr;
      if (residual < threshold) break;
      FMPC_CUDA_CHECK(launch_cg_direction(a, stream_), diagnostics, false);
      ++iterations;
    }
  }
  implicit_iterations_max_ = std::max(implicit_iterations_max_, iterations);
  const double error = std::sqrt(residual / scalars.rhs_norm2);
  if (!(error <= options.tolerance) && !cg_warning_given_) {
    cg_warning_given_ = true;
    diagnostics.warning(scenes_.front().source_range, "cg-not-converged",
                        sim::cg_stopped_message(steps_taken_ + 1, iterations, error, options.tolerance));
  }
  return true;
}

#define FMPC_GPU_ENGINE_IMPLICIT_MEMBERS(Real)                                                                    \
  template ImplicitArguments<Real> GpuEngine<Real>::implicit_arguments();                                         \
  template bool GpuEngine<Real>::read_cg_scalars(ConjugateGradientScalars& scalars, DiagnosticList& diagnostics); \
  template bool GpuEngine<Real>::implicit_solve(DiagnosticList& diagnostics);                                     \
  template bool GpuEngine<Real>::conjugate_gradient(const ImplicitArguments<Real>& a, bool& at_rest,              \
                                                    DiagnosticList& diagnostics);
FMPC_GPU_ENGINE_IMPLICIT_MEMBERS(float)
FMPC_GPU_ENGINE_IMPLICIT_MEMBERS(double)
#undef FMPC_GPU_ENGINE_IMPLICIT_MEMBERS

}  // namespace fmpc::gpu

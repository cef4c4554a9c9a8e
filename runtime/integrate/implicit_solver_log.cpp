// Implicit Euler's per-step records and their sums, shared by the CPU and CUDA engines (stepping_engine.h).
#include <algorithm>
#include <sstream>

#include "runtime/integrate/stepping_engine.h"

namespace fmpc::sim {

const char* to_string(ImplicitMethod method) {
  switch (method) {
    case ImplicitMethod::Automatic:
      return "auto";
    case ImplicitMethod::Direct:
      return "direct";
    case ImplicitMethod::ConjugateGradient:
      return "cg";
  }
  return "cg";
}

std::string cg_stopped_message(ImplicitMethod method, std::size_t step, int iterations, double relative_residual,
                               double tolerance) {
  std::ostringstream message;
  if (method == ImplicitMethod::Direct) {
    message << "implicit Euler: the direct solver stopped at step " << step << " after " << iterations
            << " solves (refinements) with relative residual " << relative_residual << " (tolerance " << tolerance
            << "); raise solver.max_iterations or the tolerance, or use a smaller dt";
  } else {
    message << "implicit Euler: conjugate gradient stopped at step " << step << " after " << iterations
            << " iterations with relative residual " << relative_residual << " (tolerance " << tolerance
            << "); raise max_iterations or use a smaller dt";
  }
  return message.str();
}

std::string contact_unsettled_message(std::size_t step, int rounds) {
  std::string message = "implicit Euler: the vertices the tools push still changed after " + std::to_string(rounds) +
                        " solves (solver.contact_rounds) at step " + std::to_string(step) +
                        "; the step went on with the last set (a tool moving further than its contact's depth in "
                        "one step): move it less per step or use a smaller dt";
  if (rounds < kernels::kMostContactRounds)
    message += ", or raise solver.contact_rounds (at most " + std::to_string(kernels::kMostContactRounds) + ")";
  return message;
}

ImplicitSolverLog::ImplicitSolverLog(ImplicitMethod method, double tolerance, int max_iterations) {
  report_.method = method;
  report_.tolerance = tolerance;
  report_.max_iterations = max_iterations;
  saved_ = report_;
}

bool ImplicitSolverLog::record(const ImplicitStepRecord& step) {
  ImplicitSolverReport& r = report_;
  r.iterations_min = r.steps == 0 ? step.iterations : std::min(r.iterations_min, step.iterations);
  r.iterations_max = std::max(r.iterations_max, step.iterations);
  r.iterations_total += static_cast<std::uint64_t>(step.iterations);
  ++r.steps;
  if (r.residual_max_step == 0 || step.relative_residual > r.residual_max) {
    r.residual_max = step.relative_residual;
    r.residual_max_step = step.step;
  }
  r.last = step;
  bool first_capped = false;
  if (step.capped) {
    ++r.capped_steps;
    if (r.first_capped_step == 0) {
      r.first_capped_step = step.step;
      r.first_capped_residual = step.relative_residual;
    }
    first_capped = !warned_;
    warned_ = true;
  }
  if (pending_.size() < kMostPendingImplicitSteps) pending_.push_back(step);
  else ++r.unlogged_steps;
  return first_capped;
}

void ImplicitSolverLog::contact_unsettled(std::size_t step, int rounds, const SourceRange& where,
                                          DiagnosticList& diagnostics) {
  ++report_.contact_unsettled_steps;
  if (report_.first_contact_unsettled_step == 0) report_.first_contact_unsettled_step = step;
  const bool first = !contact_warned_;
  contact_warned_ = true;
  if (first && rounds > 1)
    diagnostics.warning(where, "contact-not-settled", contact_unsettled_message(step, rounds));
}

std::vector<ImplicitStepRecord> ImplicitSolverLog::take() {
  std::vector<ImplicitStepRecord> out;
  out.swap(pending_);
  return out;
}

void ImplicitSolverLog::save(std::size_t step) {
  saved_ = report_;
  saved_step_ = step;
}

// The records after the checkpoint's step go (the replay records them again); the warning stays given.
void ImplicitSolverLog::restore() {
  const std::size_t step = saved_step_;
  report_ = saved_;
  pending_.erase(std::remove_if(pending_.begin(), pending_.end(),
                                [step](const ImplicitStepRecord& record) { return record.step > step; }),
                 pending_.end());
}

}  // namespace fmpc::sim

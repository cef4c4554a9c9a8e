#pragma once
// Implicit Euler's rigid-tool contact per vertex (kernels/contact_math.h's linear model in kernels/implicit_math.h's
// step), shared by the CPU's contact part of the system (runtime/integrate/implicit_contact.h) and the CUDA kernel
// that fills the same part on the device (kernels/implicit_step.cu): one implementation for both backends.
#include "kernels/contact_math.h"
#include "kernels/fmpc_hd.h"
#include "kernels/implicit_math.h"
#include "kernels/integrator_math.h"

namespace fmpc::kernels {

// The contact set a vertex at x0 (3 values) is predicted to have after an implicit step's solution dv: moved by
// h (v0 + dv) on its free axes (`held`: kernels::axis_fixed's bits).
template <typename Real>
FMPC_HD unsigned predicted_contact_set(const ContactView<Real>& contact, unsigned char held, double h, const double* x0,
                                       const double* v0, const double* dv) {
  double moved[3];
  for (int c = 0; c < 3; ++c) moved[c] = axis_fixed(held, c) ? 0.0 : h * (v0[c] + dv[c]);
  return contact_set(contact, x0[0], x0[1], x0[2], moved);
}

// One vertex's contact in implicit Euler's system (kernels/implicit_math.h's step with contact_linear_model's force
// for the set `active`): h^2 K_c into `block` (6 values) and h change - h^2 K_c v0 into `rhs` (3 values), v0 the
// vertex's velocity with its held axes zeroed (a held axis is an identity row and column of the system).
template <typename Real>
FMPC_HD void contact_system_part(const ContactView<Real>& contact, unsigned active, double k, double h, const double* x0,
                                 const double* v0, unsigned char held, double* block, double* rhs) {
  double change[3];
  contact_linear_model(contact, active, k, x0[0], x0[1], x0[2], block, change);
  for (int i = 0; i < 6; ++i) block[i] *= h * h;
  double free_velocity[3], kv[3];
  for (int c = 0; c < 3; ++c) free_velocity[c] = axis_fixed(held, c) ? 0.0 : v0[c];
  symmetric_multiply(block, free_velocity, kv);
  for (int c = 0; c < 3; ++c) rhs[c] = h * change[c] - kv[c];
}

}  // namespace fmpc::kernels

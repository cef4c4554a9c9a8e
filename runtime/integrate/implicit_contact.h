#pragma once
// The rigid tools' contact in implicit Euler's system on the CPU, as ImplicitSolver's linear part (implicit_solver.h):
// an active set of (vertex, tool) pairs, first those inside at the step's start, then those the last solution
// predicts inside, each set's system part from kernels/implicit_contact_math.h (the CUDA backend's kernel uses the
// same functions). Internal to runtime/integrate (cpu_engine.cpp's implicit step).
#include <cstddef>
#include <vector>

#include "kernels/implicit_contact_math.h"
#include "runtime/integrate/implicit_solver.h"

namespace fmpc::sim {

template <typename Real>
class ImplicitContact final : public ImplicitLinearPart {
 public:
  // `contact` and `held` (per vertex, kernels::axis_fixed's bits) are read at each call.
  ImplicitContact(const kernels::ContactView<Real>& contact, const std::vector<unsigned char>& held)
      : contact_(contact), held_(held) {}

  // The step's state (positions and velocities, interleaved as the solver's, read until the step's solve ends) and
  // its first set: the pairs inside at x0.
  void start(const std::vector<double>& x0, const std::vector<double>& v0, double h) {
    x0_ = &x0;
    v0_ = &v0;
    h_ = h;
    active_.assign(held_.size(), 0u);
    for (std::size_t i = 0; i < active_.size(); ++i)
      if (touches(i)) active_[i] = kernels::contact_set(contact_, x0[3 * i], x0[3 * i + 1], x0[3 * i + 2], nullptr);
  }

  void linearise(std::vector<double>& blocks, std::vector<double>& rhs) override {
    for (std::size_t i = 0; i < active_.size(); ++i)
      if (touches(i))
        kernels::contact_system_part(contact_, active_[i], static_cast<double>(contact_.stiffness[i]), h_,
                                     &(*x0_)[3 * i], &(*v0_)[3 * i], held_[i], &blocks[6 * i], &rhs[3 * i]);
  }

  bool changed_by(const std::vector<double>& dv) override {
    bool changed = false;
    for (std::size_t i = 0; i < active_.size(); ++i) {
      if (!touches(i)) continue;
      const unsigned set =
          kernels::predicted_contact_set(contact_, held_[i], h_, &(*x0_)[3 * i], &(*v0_)[3 * i], &dv[3 * i]);
      changed = changed || set != active_[i];
      active_[i] = set;
    }
    return changed;
  }

 private:
  bool touches(std::size_t i) const { return contact_.stiffness[i] > Real(0); }

  const kernels::ContactView<Real>& contact_;
  const std::vector<unsigned char>& held_;
  const std::vector<double>* x0_ = nullptr;
  const std::vector<double>* v0_ = nullptr;
  double h_ = 0.0;
  std::vector<unsigned> active_;  // per vertex: bit t, tool t pushes it
};

}  // namespace fmpc::sim

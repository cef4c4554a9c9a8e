#pragma once
// The internal forces of a force model at one vertex, for the integrators (kernels/integrator_math.h): each model is
// a plain struct with an FMPC_HD `gather`, and the integrators, the CPU loops and the CUDA kernels are templates over
// it (static dispatch: no virtual call per vertex or element). As SOFA keeps ForceField apart from the ODE solver, a
// new force model is a new struct here and plugs into every integrator on both backends.
//
// - SpringForces: springs gathered over the CSR adjacency (kernels/spring_math.h);
// - ElementForces: per-tetrahedron forces computed beforehand, one pass per element term (kernels/element_term.h,
//   element_corner_forces; the laws in kernels/laws/), then gathered per vertex over the corner CSR;
// - SpringAndElementForces: both (springs with an element term beside them, e.g. the volume term).
// Each vertex adds its terms in one fixed order (springs first, then corners), so the sums do not depend on threads
// or scheduling and the CUDA kernels add the same terms in the same order as the CPU loop.
#include "kernels/fmpc_hd.h"
#include "kernels/spring_math.h"
#include "kernels/element_term.h"

namespace fmpc::kernels {

// `row`: the thread's sliced row on the GPU (kernels/spring_math.h, SlicedSpringsView), loaded with its vertex;
// count -1 (the default) reads the CSR order (the CPU, the lane kernels).
template <typename Real>
struct SpringForces {
  SpringNetworkView<Real> springs;
  SlicedRow row{0, -1};
  FMPC_HD void gather(int v, const StateView<Real>& s, Real& fx, Real& fy, Real& fz) const {
    gather_spring_force(v, row, springs, s, fx, fy, fz);
  }
};

template <typename Real>
struct ElementForces {
  CornerForceView<Real> corners;
  FMPC_HD void gather(int v, const StateView<Real>&, Real& fx, Real& fy, Real& fz) const {
    gather_corner_force(v, corners, fx, fy, fz);
  }
};

template <typename Real>
struct SpringAndElementForces {
  SpringNetworkView<Real> springs;
  CornerForceView<Real> corners;
  SlicedRow row{0, -1};
  FMPC_HD void gather(int v, const StateView<Real>& s, Real& fx, Real& fy, Real& fz) const {
    gather_spring_force(v, row, springs, s, fx, fy, fz);
    Real cx, cy, cz;
    gather_corner_force(v, corners, cx, cy, cz);
    fx += cx;
    fy += cy;
    fz += cz;
  }
};

}  // namespace fmpc::kernels

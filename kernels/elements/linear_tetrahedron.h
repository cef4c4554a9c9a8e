#pragma once
// The linear (4-node) tetrahedron as an element kind: one material point, F = sum_a x_a g_a^T and corner forces
// f_a = -V0 P(F) g_a (kernels/elements/corner_tetrahedron.h), the law's own material at the point. Every function is
// generic over the constitutive law (kernels/laws/: first_piola, energy_density, linearise and stress_differential,
// rest_lame, stress_output); the element kinds are listed in kernels/element_laws.h.
#include "kernels/elements/corner_tetrahedron.h"

namespace fmpc::kernels {

struct LinearTetrahedron : CornerTetrahedron<LinearTetrahedron> {
  // Whether the element pass reads a nodal pass's pressure (kernels/elements/linear_nodal_pressure.h): no.
  static constexpr bool kNodalPressure = false;

  // The material each point integrates (the Prony series' elastic stress reads it): the law's own.
  template <typename Law, typename Real>
  static FMPC_HD typename Law::template Material<Real> point_material(const ElementTermView<Real>& t, int e) {
    return Law::material(t, e);
  }

  // Nothing beyond the law's stress and energy.
  template <typename Real>
  static FMPC_HD void add_volumetric_stress(const ElementTermView<Real>&, int, const Real*, Real*) {}
  static FMPC_HD double volumetric_energy_density(const ElementTermView<double>&, int) { return 0.0; }
};

}  // namespace fmpc::kernels

#pragma once
// What the laws given by Young's modulus and Poisson's ratio read per element (corotational_linear.h,
// stable_neo_hookean.h derive from it): the two moduli, the stiffness damping and the strain table, whose E(strain)
// replaces the Young's modulus during the run.
#include "kernels/element_term.h"

namespace fmpc::kernels {

struct IsotropicModuli {
  static constexpr int kParameterCount = 2;
  static constexpr int kYoungsModulus = 0;  // Pa
  static constexpr int kPoissonRatio = 1;
  static constexpr bool kStrainTableModulus = true;

  template <typename Real>
  struct Material {
    Real youngs_modulus;
    Real poisson_ratio;
    Real stiffness_damping;  // beta (s)
    // By value: a pointer into the kernel's parameter would copy the whole ElementTermView to local memory in every
    // thread (ptxas: a 128-byte stack frame, the float element pass 24% slower). strain == null: youngs_modulus.
    StrainTableView strain_table;
  };

  template <typename Real>
  static FMPC_HD Material<Real> material(const ElementTermView<Real>& t, int e) {
    Material<Real> m;
    m.youngs_modulus = t.parameter[kYoungsModulus][e];
    m.poisson_ratio = t.parameter[kPoissonRatio][e];
    m.stiffness_damping = t.stiffness_damping[e];
    m.strain_table = t.strain_table;
    return m;
  }

  // The split of the average nodal pressure element (kernels/elements/linear_nodal_pressure.h): the material at the
  // same shear modulus with lambda = 0 (E / (1 + nu) and nu = 0: mu = E / (2 (1 + nu)) is kept), and lambda. A
  // strain table's E would lose the 1 / (1 + nu): runtime/fem refuses tables on that element.
  template <typename Real>
  static FMPC_HD Material<Real> shear_part(Material<Real> m) {
    m.youngs_modulus = m.youngs_modulus / (Real(1) + m.poisson_ratio);
    m.poisson_ratio = Real(0);
    return m;
  }
  template <typename Real>
  static FMPC_HD Real volumetric_modulus(const Material<Real>& m) {
    Real mu, lambda;
    lame_parameters(m.youngs_modulus, m.poisson_ratio, mu, lambda);
    return lambda;
  }
};

}  // namespace fmpc::kernels

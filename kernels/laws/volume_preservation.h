#pragma once
// The volume term that keeps a spring network from turning inside out: the volume constraint C = V - V0 of Teschner,
// Heidelberger, Mueller & Gross 2004 ("A versatile and robust model for geometrically complex deformable solids",
// CGI), with stiffness k_V = kappa / V0 so that kappa is a modulus (Pa) and the term does not depend on the element
// size. As a constitutive law with J = det F = V / V0: energy density kappa (J - 1)^2 / 2 (kappa (V - V0)^2 / (2 V0)
// per element), P = kappa (J - 1) cof(F) (on a linear tetrahedron the corner force -V0 P g_a is -kappa (V - V0) / V0
// dV/dx_a, since dV/dx_a = V0 cof(F) g_a). At small strain J - 1 = tr(eps), so the term adds kappa to Lame's lambda of
// the springs beside it (docs/simulator.md calibrates it to a Poisson ratio). Unlike a spring it tells a tetrahedron
// from its mirror image: an inverted element (J < 0) is pushed back. Damping: P gains beta kappa (dJ/dt) cof(F).
#include "kernels/element_term.h"

namespace fmpc::kernels {

struct VolumePreservation {
  // Per element: the bulk modulus kappa (Pa).
  static constexpr int kParameterCount = 1;
  static constexpr int kBulkModulus = 0;
  static constexpr bool kStrainTableModulus = false;

  template <typename Real>
  struct Material {
    Real bulk_modulus;
    Real stiffness_damping;  // beta (s)
  };

  template <typename Real>
  static FMPC_HD Material<Real> material(const ElementTermView<Real>& t, int e) {
    Material<Real> m;
    m.bulk_modulus = t.parameter[kBulkModulus][e];
    m.stiffness_damping = t.stiffness_damping[e];
    return m;
  }

  // The average nodal pressure element's split (kernels/elements/linear_nodal_pressure.h): the term is volumetric
  // alone, kappa (J - 1)^2 / 2, so its shear part is zero and its modulus kappa.
  template <typename Real>
  static FMPC_HD Material<Real> shear_part(Material<Real> m) {
    m.bulk_modulus = Real(0);
    return m;
  }
  template <typename Real>
  static FMPC_HD Real volumetric_modulus(const Material<Real>& m) {
    return m.bulk_modulus;
  }

  template <typename Real>
  static FMPC_HD void first_piola(const Material<Real>& m, const Real* F, const Real* F_rate, Real* P) {
    Real C[9];
    cofactor3(F, C);
    const Real rate = F_rate && m.stiffness_damping != Real(0) ? m.stiffness_damping * contract3(C, F_rate) : Real(0);
    const Real scale = m.bulk_modulus * (determinant_minus_one(F) + rate);
    for (int i = 0; i < 9; ++i) P[i] = scale * C[i];
  }

  // Implicit Euler's Gauss-Newton tangent kappa cof(F) (x) cof(F) (its positive semi-definite part, which keeps
  // conjugate gradients applicable; kappa / V0 dV dV^T on a linear tetrahedron) at the step's start.
  struct Linearisation {
    double cofactor[9];
  };

  static FMPC_HD void linearise(const Material<double>&, const double* F, Linearisation& lin) {
    cofactor3(F, lin.cofactor);
  }

  static FMPC_HD void stress_differential(const Material<double>& m, const Linearisation& lin, const double* dF,
                                          double* dP) {
    const double scale = m.bulk_modulus * contract3(lin.cofactor, dF);
    for (int i = 0; i < 9; ++i) dP[i] = scale * lin.cofactor[i];
  }

  // stress_differential's dP/dF in closed form: A[(i k), (j l)] = kappa cof_ik cof_jl.
  static FMPC_HD void tangent_modulus(const Material<double>& m, const Linearisation& lin, double* A) {
    for (int row = 0; row < 9; ++row)
      for (int column = 0; column < 9; ++column)
        A[9 * row + column] = m.bulk_modulus * lin.cofactor[row] * lin.cofactor[column];
  }

  // At rest the term is a pure lambda = kappa.
  static FMPC_HD void rest_lame(const Material<double>& m, double& mu, double& lambda) {
    mu = 0.0;
    lambda = m.bulk_modulus;
  }

  // Frames' cell data: a pure pressure has no deviatoric part (its von Mises stress is zero); the pressure's
  // magnitude |kappa (J - 1)| is what the term adds to the springs' (unrepresented) stress, so that is written.
  static constexpr const char* kStressOutput = "volume_term_pressure_Pa";
  static FMPC_HD double stress_output(const Material<double>& m, const double* F) {
    const double pressure = m.bulk_modulus * determinant_minus_one(F);
    return pressure < 0.0 ? -pressure : pressure;
  }

  static FMPC_HD double energy_density(const Material<double>& m, const double* F) {
    const double change = determinant_minus_one(F);
    return 0.5 * m.bulk_modulus * change * change;
  }
};

}  // namespace fmpc::kernels

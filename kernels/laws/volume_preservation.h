#pragma once
// The volume term that keeps a spring network from turning inside out: the volume constraint C = V - V0 of Teschner,
// Heidelberger, Mueller & Gross 2004 ("A versatile and robust model for geometrically complex deformable solids",
// CGI), with stiffness k_V = kappa / V0 so that kappa is a modulus (Pa) and the term does not depend on the element
// size: energy kappa (V - V0)^2 / (2 V0), force f_a = -kappa (V - V0) / V0 dV/dx_a. At small strain V - V0 =
// V0 tr(eps), so the term adds kappa to Lame's lambda of the springs beside it (docs/simulator.md calibrates it to a
// Poisson ratio). Unlike a spring it tells a tetrahedron from its mirror image: an inverted element (V < 0) is pushed
// back. Damping: beta kappa (dV/dt) / V0 dV/dx_a.
#include "kernels/element_term.h"

namespace fmpc::kernels {

struct VolumePreservation {
  // Per element: the bulk modulus kappa (Pa).
  static constexpr int kParameterCount = 1;
  static constexpr int kBulkModulus = 0;
  static constexpr bool kStrainTableModulus = false;

  template <typename Real>
  struct Material {
    const Real* rest_inverse;  // Dm^-1, 9 values (for the stiffness bound only)
    Real rest_volume;
    Real bulk_modulus;
    Real stiffness_damping;  // beta (s)
  };

  template <typename Real>
  static FMPC_HD Material<Real> material(const ElementTermView<Real>& t, int e) {
    Material<Real> m;
    m.rest_inverse = t.rest_inverse + 9 * e;
    m.rest_volume = t.rest_volume[e];
    m.bulk_modulus = t.parameter[kBulkModulus][e];
    m.stiffness_damping = t.stiffness_damping ? t.stiffness_damping[e] : Real(0);
    return m;
  }

  // dV/dx_a = (x_b - x_0) x (x_c - x_0) / 6 for (a, b, c) = (1, 2, 3) cyclic, dV/dx_0 = -(sum).
  template <typename Real>
  static FMPC_HD void volume_gradient(const Real x[4][3], Real gradient[4][3]) {
    Real e[3][3];
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) e[k][i] = x[k + 1][i] - x[0][i];
    cross3(e[1], e[2], gradient[1]);
    cross3(e[2], e[0], gradient[2]);
    cross3(e[0], e[1], gradient[3]);
    for (int i = 0; i < 3; ++i) {
      for (int a = 1; a < 4; ++a) gradient[a][i] /= Real(6);
      gradient[0][i] = -(gradient[1][i] + gradient[2][i] + gradient[3][i]);
    }
  }

  template <typename Real>
  static FMPC_HD void forces(const Material<Real>& m, const Real x[4][3], const Real v[4][3], Real force[4][3]) {
    const Real volume = tetrahedron_volume(x);
    Real gradient[4][3];
    volume_gradient(x, gradient);
    Real rate = Real(0);
    for (int a = 0; a < 4; ++a) rate += dot3(gradient[a], v[a]);
    const Real scale = -m.bulk_modulus * ((volume - m.rest_volume) + m.stiffness_damping * rate) / m.rest_volume;
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) force[a][i] = scale * gradient[a][i];
  }

  // Implicit Euler's Gauss-Newton tangent kappa / V0 dV dV^T (its positive semi-definite part, which keeps conjugate
  // gradients applicable) at the step's start.
  struct Linearisation {
    double gradient[4][3];  // dV/dx_a
  };

  static FMPC_HD void linearise(const Material<double>&, const double x[4][3], Linearisation& lin) {
    volume_gradient(x, lin.gradient);
  }

  static FMPC_HD void stiffness_action(const Material<double>& m, const Linearisation& lin, const double p[4][3],
                                       double out[4][3]) {
    double along = 0.0;
    for (int a = 0; a < 4; ++a) along += dot3(lin.gradient[a], p[a]);
    const double scale = m.bulk_modulus / m.rest_volume * along;
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) out[a][i] = scale * lin.gradient[a][i];
  }

  static FMPC_HD void stiffness_block(const Material<double>& m, const Linearisation& lin, int a, int b,
                                      double* block) {
    const double scale = m.bulk_modulus / m.rest_volume;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) block[3 * i + j] = scale * lin.gradient[a][i] * lin.gradient[b][j];
  }

  static FMPC_HD void stiffness_matrix(const Material<double>& m, const Linearisation& lin, double* K) {
    const double scale = m.bulk_modulus / m.rest_volume;
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) K[12 * (3 * a + i) + 3 * b + j] = scale * lin.gradient[a][i] * lin.gradient[b][j];
  }

  // Frames' cell data: a pure pressure has no deviatoric part (its von Mises stress is zero); the pressure's
  // magnitude |kappa (V - V0) / V0| is what the term adds to the springs' (unrepresented) stress, so that is written.
  static constexpr const char* kStressOutput = "volume_term_pressure_Pa";
  static FMPC_HD double stress_output(const Material<double>& m, const double x[4][3]) {
    const double pressure = m.bulk_modulus * (tetrahedron_volume(x) - m.rest_volume) / m.rest_volume;
    return pressure < 0.0 ? -pressure : pressure;
  }

  static FMPC_HD double energy(const Material<double>& m, const double x[4][3]) {
    const double change = tetrahedron_volume(x) - m.rest_volume;
    return m.bulk_modulus * change * change / (2.0 * m.rest_volume);
  }

  // The only non-zero eigenvalue of kappa / V0 dV dV^T is kappa / V0 |dV|^2, and at rest dV/dx_a = V0 g_a.
  static FMPC_HD double stiffness_bound(const Material<double>& m) {
    double g[4][3], squared = 0.0;
    shape_gradients(m.rest_inverse, g);
    for (int a = 0; a < 4; ++a) squared += dot3(g[a], g[a]);
    return m.bulk_modulus * m.rest_volume * squared;
  }
};

}  // namespace fmpc::kernels

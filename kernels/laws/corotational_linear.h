#pragma once
// Co-rotational linear elasticity (Mueller & Gross 2004, "Interactive virtual materials", GI; Nesme, Payan & Faure
// 2005, "Efficient, physically plausible finite elements", Eurographics; SOFA's TetrahedronFEMForceField with method
// "large" uses a QR rotation instead), as a constitutive law at a material point: the rotation R is the rotation of
// the polar decomposition F = R S (kernels/tetrahedron_math.h: polar_rotation, with the sign of the smallest singular
// value flipped for an inverted element after Irving, Teran & Fedkiw 2004, so that R is always a proper rotation and an
// inverted element is pushed back towards its rest orientation). Strain eps = sym(R^T F) - I, stress sigma =
// lambda tr(eps) I + 2 mu eps, first Piola-Kirchhoff stress P = R sigma; on a linear tetrahedron the corner forces
// -V0 P g_a are -R K0 (R^T x - X). Damping: sigma uses eps + beta d(eps)/dt with d(eps)/dt = sym(R^T dF/dt):
// stiffness-proportional (Rayleigh) damping beta R K0 R^T v per element. A strain table replaces Young's modulus with
// E at the point's principal strain of largest magnitude.
#include "kernels/element_term.h"
#include "kernels/laws/isotropic_moduli.h"

namespace fmpc::kernels {

struct CorotationalLinear : IsotropicModuli {
  // R of F and the modulus at F (a strain table's value at the point's strain; the principal stretches cost an
  // eigen-decomposition, so only a strain table computes them).
  template <typename Real>
  static FMPC_HD Real rotation_and_modulus(const Material<Real>& m, const Real* F, Real* R) {
    if (m.strain_table.strain) {
      Real stretch[3];
      rotation_and_stretches(F, R, stretch);
      const Real strain = principal_strain_of_largest_magnitude(stretch);
      return static_cast<Real>(strain_table_modulus(m.strain_table, static_cast<double>(strain)));
    }
    polar_rotation(F, R);
    return m.youngs_modulus;
  }

  // P(F), with the rate dF/dt where the element is damped (null otherwise).
  template <typename Real>
  static FMPC_HD void first_piola(const Material<Real>& m, const Real* F, const Real* F_rate, Real* P) {
    Real R[9];
    const Real modulus = rotation_and_modulus(m, F, R);
    rotated_first_piola(m, R, modulus, F, F_rate, P);
  }

  // P(F) from R and the modulus that rotation_and_modulus gives at F: first_piola after its decomposition.
  template <typename Real>
  static FMPC_HD void rotated_first_piola(const Material<Real>& m, const Real* R, Real modulus, const Real* F,
                                          const Real* F_rate, Real* P) {
    Real mu, lambda;
    lame_parameters(modulus, m.poisson_ratio, mu, lambda);
    Real e[9];
    corotated_symmetric_part(R, F, true, e);
    if (F_rate && m.stiffness_damping != Real(0)) {
      Real rate[9];
      corotated_symmetric_part(R, F_rate, false, rate);
      for (int i = 0; i < 9; ++i) e[i] += m.stiffness_damping * rate[i];
    }
    Real sigma[9];
    linear_stress(e, mu, lambda, sigma);
    multiply3(R, sigma, P);
  }

  // What implicit Euler keeps between the conjugate gradient's iterations: R and the modulus at the step's start (the
  // rotation held fixed over the step, as in Mueller & Gross 2004).
  struct Linearisation {
    double rotation[9];
    double modulus;     // a strain table's value at the step's start
    double mu, lambda;  // the Lame parameters of modulus and nu: computed once, not in every product (two divisions)
  };

  static FMPC_HD void linearise(const Material<double>& m, const double* F, Linearisation& lin) {
    lin.modulus = rotation_and_modulus(m, F, lin.rotation);
    lame_parameters(lin.modulus, m.poisson_ratio, lin.mu, lin.lambda);
  }

  // first_piola at the F that `lin` was linearised at, from its rotation and modulus: first_piola's bits without a
  // second polar decomposition (implicit Euler's force pass, which keeps lin for the step's tangent).
  static FMPC_HD void first_piola_linearised(const Material<double>& m, const Linearisation& lin, const double* F,
                                             const double* F_rate, double* P) {
    rotated_first_piola(m, lin.rotation, lin.modulus, F, F_rate, P);
  }

  // dP = R sigma(sym(R^T dF)) with R held: the tangent of the co-rotated law (R K0 R^T on a linear tetrahedron).
  static FMPC_HD void stress_differential(const Material<double>&, const Linearisation& lin, const double* dF,
                                          double* dP) {
    double e[9], sigma[9];
    corotated_symmetric_part(lin.rotation, dF, false, e);
    linear_stress(e, lin.mu, lin.lambda, sigma);
    multiply3(lin.rotation, sigma, dP);
  }

  // stress_differential's dP/dF in closed form: A[(i k), (j l)] = lambda R_ik R_jl + mu (R R^T)_ij delta_kl +
  // mu R_il R_jk (dF = e_j e_l^T in the formula above; R R^T is the identity up to round-off and kept as computed).
  static FMPC_HD void tangent_modulus(const Material<double>&, const Linearisation& lin, double* A) {
    double RRt[9];
    const double* R = lin.rotation;
    const double mu = lin.mu, lambda = lin.lambda;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) RRt[3 * i + j] = R[3 * i] * R[3 * j] + R[3 * i + 1] * R[3 * j + 1] + R[3 * i + 2] * R[3 * j + 2];
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j)
          for (int l = 0; l < 3; ++l)
            A[9 * (3 * i + k) + 3 * j + l] = lambda * R[3 * i + k] * R[3 * j + l] +
                                             (k == l ? mu * RRt[3 * i + j] : 0.0) + mu * R[3 * i + l] * R[3 * j + k];
  }

  // The small-strain Lame parameters at the largest modulus the run can give the point (a strain table's largest):
  // the stable step and the element damping use the element's rest stiffness with these.
  static FMPC_HD void rest_lame(const Material<double>& m, double& mu, double& lambda) {
    const double modulus = m.strain_table.strain ? strain_table_largest_modulus(m.strain_table) : m.youngs_modulus;
    lame_parameters(modulus, m.poisson_ratio, mu, lambda);
  }

  // The co-rotated stress sigma at F (its rotation R sigma R^T is the Cauchy stress of the small-strain law).
  // The frames take Higham's rotation also where a strain table's modulus needed the stretches.
  static FMPC_HD void stress(const Material<double>& m, const double* F, double* sigma) {
    double R[9], e[9], mu, lambda;
    const double modulus = rotation_and_modulus(m, F, R);
    if (m.strain_table.strain) polar_rotation(F, R);
    corotated_symmetric_part(R, F, true, e);
    lame_parameters(modulus, m.poisson_ratio, mu, lambda);
    linear_stress(e, mu, lambda, sigma);
  }

  // Frames' cell data: the von Mises stress (Pa), invariant under rotation.
  static constexpr const char* kStressOutput = "von_mises_stress_Pa";
  static FMPC_HD double stress_output(const Material<double>& m, const double* F) {
    double sigma[9];
    stress(m, F, sigma);
    return von_mises_stress(sigma);
  }

  // Energy density (J/m^3): mu eps:eps + lambda/2 tr(eps)^2 with the co-rotated strain (and a strain table's modulus
  // at the point's strain: its value there, the integral of the varying modulus not taken).
  static FMPC_HD double energy_density(const Material<double>& m, const double* F) {
    double R[9], strain[9], mu, lambda;
    const double modulus = rotation_and_modulus(m, F, R);
    corotated_symmetric_part(R, F, true, strain);
    lame_parameters(modulus, m.poisson_ratio, mu, lambda);
    double contraction = 0.0;
    for (int i = 0; i < 9; ++i) contraction += strain[i] * strain[i];
    const double trace = strain[0] + strain[4] + strain[8];
    return mu * contraction + 0.5 * lambda * trace * trace;
  }
};

}  // namespace fmpc::kernels

#pragma once
// Co-rotational linear elasticity on a linear tetrahedron (Mueller & Gross 2004, "Interactive virtual materials", GI;
// Nesme, Payan & Faure 2005, "Efficient, physically plausible finite elements", Eurographics; SOFA's
// TetrahedronFEMForceField with method "large" uses a QR rotation instead). The rotation R is the rotation of the
// polar decomposition F = R S (kernels/tetrahedron_math.h: polar_rotation, with the sign of the smallest singular
// value flipped for an inverted element after Irving, Teran & Fedkiw 2004, so that R is always a proper rotation and
// an inverted element is pushed back towards its rest orientation). Strain eps = sym(R^T F) - I, stress sigma =
// lambda tr(eps) I + 2 mu eps, and the force on corner a is f_a = -V0 R sigma g_a (g_a the rest shape-function
// gradient); i.e. -R K0 (R^T x - X). Damping: sigma uses eps + beta d(eps)/dt with d(eps)/dt = sym(R^T L), L the
// velocity gradient: stiffness-proportional (Rayleigh) damping beta R K0 R^T v per element. A strain table replaces
// Young's modulus with E at the element's principal strain of largest magnitude.
#include "kernels/element_term.h"

namespace fmpc::kernels {

struct CorotationalLinear {
  // Per element: Young's modulus (Pa) and Poisson's ratio.
  static constexpr int kParameterCount = 2;
  static constexpr int kYoungsModulus = 0;
  static constexpr int kPoissonRatio = 1;
  // A strain table's E(strain) replaces the Young's modulus during the run.
  static constexpr bool kStrainTableModulus = true;

  template <typename Real>
  struct Material {
    const Real* rest_inverse;  // Dm^-1, 9 values
    Real rest_volume;
    Real youngs_modulus;
    Real poisson_ratio;
    Real stiffness_damping;               // beta (s)
    const StrainTableView* strain_table;  // null: youngs_modulus
  };

  template <typename Real>
  static FMPC_HD Material<Real> material(const ElementTermView<Real>& t, int e) {
    Material<Real> m;
    m.rest_inverse = t.rest_inverse + 9 * e;
    m.rest_volume = t.rest_volume[e];
    m.youngs_modulus = t.parameter[kYoungsModulus][e];
    m.poisson_ratio = t.parameter[kPoissonRatio][e];
    m.stiffness_damping = t.stiffness_damping ? t.stiffness_damping[e] : Real(0);
    m.strain_table = t.strain_table.strain ? &t.strain_table : nullptr;
    return m;
  }

  // The force on each corner; x and v the corners' positions and velocities [corner][axis].
  template <typename Real>
  static FMPC_HD void forces(const Material<Real>& m, const Real x[4][3], const Real v[4][3], Real force[4][3]) {
    Real g[4][3], F[9], R[9];
    shape_gradients(m.rest_inverse, g);
    corner_gradient(x, m.rest_inverse, F);
    // The principal stretches cost an eigen-decomposition: only a strain table needs them.
    Real modulus = m.youngs_modulus;
    if (m.strain_table) {
      Real stretch[3];
      rotation_and_stretches(F, R, stretch);
      const Real strain = principal_strain_of_largest_magnitude(stretch);
      modulus = static_cast<Real>(strain_table_modulus(*m.strain_table, static_cast<double>(strain)));
    } else {
      polar_rotation(F, R);
    }
    Real mu, lambda;
    lame_parameters(modulus, m.poisson_ratio, mu, lambda);
    Real e[9];
    corotated_symmetric_part(R, F, true, e);
    if (m.stiffness_damping != Real(0)) {
      Real L[9], rate[9];
      corner_gradient(v, m.rest_inverse, L);
      corotated_symmetric_part(R, L, false, rate);
      for (int i = 0; i < 9; ++i) e[i] += m.stiffness_damping * rate[i];
    }
    Real sigma[9], P[9];
    linear_stress(e, mu, lambda, sigma);
    multiply3(R, sigma, P);
    corner_forces_from_stress(P, g, m.rest_volume, force);
  }

  // What implicit Euler keeps between the conjugate gradient's iterations: R and the modulus at the step's start (the
  // rotation held fixed over the step, as in Mueller & Gross 2004).
  struct Linearisation {
    double rotation[9];
    double modulus;  // a strain table's value at the step's start
  };

  static FMPC_HD void linearise(const Material<double>& m, const double x[4][3], Linearisation& lin) {
    double F[9];
    corner_gradient(x, m.rest_inverse, F);
    lin.modulus = m.youngs_modulus;
    if (m.strain_table) {
      double stretch[3];
      rotation_and_stretches(F, lin.rotation, stretch);
      lin.modulus = strain_table_modulus(*m.strain_table, principal_strain_of_largest_magnitude(stretch));
    } else {
      polar_rotation(F, lin.rotation);
    }
  }

  // The tangent stiffness R K0 R^T applied to a corner field p [corner][axis]: out_a = sum_b K_ab p_b.
  static FMPC_HD void stiffness_action(const Material<double>& m, const Linearisation& lin, const double p[4][3],
                                       double out[4][3]) {
    double g[4][3];
    shape_gradients(m.rest_inverse, g);
    // p' = R^T p, strain sym(sum_b p'_b g_b^T), stress, then f'_a = V0 sigma g_a and out_a = R f'_a.
    double rotated[4][3];
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i)
        rotated[a][i] = lin.rotation[i] * p[a][0] + lin.rotation[3 + i] * p[a][1] + lin.rotation[6 + i] * p[a][2];
    double H[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) H[3 * i + j] += rotated[a][i] * g[a][j];
    double e[9];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) e[3 * i + j] = 0.5 * (H[3 * i + j] + H[3 * j + i]);
    double mu, lambda, sigma[9], P[9];
    lame_parameters(lin.modulus, m.poisson_ratio, mu, lambda);
    linear_stress(e, mu, lambda, sigma);
    multiply3(lin.rotation, sigma, P);
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i)
        out[a][i] = m.rest_volume * (P[3 * i] * g[a][0] + P[3 * i + 1] * g[a][1] + P[3 * i + 2] * g[a][2]);
  }

  // The 3 x 3 block K_ab (row-major): V0 R (lambda g_a g_b^T + mu g_b g_a^T + mu (g_a . g_b) I) R^T.
  static FMPC_HD void stiffness_block(const Material<double>& m, const Linearisation& lin, int a, int b,
                                      double* block) {
    double g[4][3];
    shape_gradients(m.rest_inverse, g);
    double mu, lambda;
    lame_parameters(lin.modulus, m.poisson_ratio, mu, lambda);
    const double gg = dot3(g[a], g[b]);
    double k0[9];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        k0[3 * i + j] =
            m.rest_volume * (lambda * g[a][i] * g[b][j] + mu * g[b][i] * g[a][j] + (i == j ? mu * gg : 0.0));
    double rk[9];
    multiply3(lin.rotation, k0, rk);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        block[3 * i + j] = rk[3 * i] * lin.rotation[3 * j] + rk[3 * i + 1] * lin.rotation[3 * j + 1] +
                           rk[3 * i + 2] * lin.rotation[3 * j + 2];
  }

  // All 16 blocks at once (row-major 12 x 12: K[3a + i][3b + j]), the shape gradients and Lame's parameters computed
  // once: what assembling a matrix wants. R K0_ab R^T = V0 (lambda (R g_a)(R g_b)^T + mu (R g_b)(R g_a)^T +
  // mu (g_a . g_b) I).
  static FMPC_HD void stiffness_matrix(const Material<double>& m, const Linearisation& lin, double* K) {
    double g[4][3], rg[4][3], mu, lambda;
    shape_gradients(m.rest_inverse, g);
    lame_parameters(lin.modulus, m.poisson_ratio, mu, lambda);
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i)
        rg[a][i] =
            lin.rotation[3 * i] * g[a][0] + lin.rotation[3 * i + 1] * g[a][1] + lin.rotation[3 * i + 2] * g[a][2];
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const double gg = dot3(g[a], g[b]);
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            K[12 * (3 * a + i) + 3 * b + j] =
                m.rest_volume * (lambda * rg[a][i] * rg[b][j] + mu * rg[b][i] * rg[a][j] + (i == j ? mu * gg : 0.0));
      }
  }

  // The element's stress at positions x in its rotated frame (a strain table's modulus at its strain).
  static FMPC_HD void stress(const Material<double>& m, const double x[4][3], double* sigma) {
    double F[9], R[9], e[9], mu, lambda;
    corner_gradient(x, m.rest_inverse, F);
    double modulus = m.youngs_modulus;
    if (m.strain_table) {
      double stretch[3];
      rotation_and_stretches(F, R, stretch);
      modulus = strain_table_modulus(*m.strain_table, principal_strain_of_largest_magnitude(stretch));
    }
    polar_rotation(F, R);
    corotated_symmetric_part(R, F, true, e);
    lame_parameters(modulus, m.poisson_ratio, mu, lambda);
    linear_stress(e, mu, lambda, sigma);
  }

  // Frames' cell data: the von Mises stress (Pa), invariant under rotation, so the co-rotated stress gives the value
  // of R sigma R^T.
  static constexpr const char* kStressOutput = "von_mises_stress_Pa";
  static FMPC_HD double stress_output(const Material<double>& m, const double x[4][3]) {
    double sigma[9];
    stress(m, x, sigma);
    return von_mises_stress(sigma);
  }

  // Elastic energy at positions x (J): V0 (mu eps:eps + lambda/2 tr(eps)^2) with the co-rotated strain (and a strain
  // table's modulus at the element's strain: its value there, the integral of the varying modulus not taken).
  static FMPC_HD double energy(const Material<double>& m, const double x[4][3]) {
    double F[9], R[9], strain[9], mu, lambda;
    corner_gradient(x, m.rest_inverse, F);
    double modulus = m.youngs_modulus;
    if (m.strain_table) {
      double stretch[3];
      rotation_and_stretches(F, R, stretch);
      modulus = strain_table_modulus(*m.strain_table, principal_strain_of_largest_magnitude(stretch));
    } else {
      polar_rotation(F, R);
    }
    corotated_symmetric_part(R, F, true, strain);
    lame_parameters(modulus, m.poisson_ratio, mu, lambda);
    double contraction = 0.0;
    for (int i = 0; i < 9; ++i) contraction += strain[i] * strain[i];
    const double trace = strain[0] + strain[4] + strain[8];
    return m.rest_volume * (mu * contraction + 0.5 * lambda * trace * trace);
  }

  // An upper bound of the largest eigenvalue of the element's stiffness (N/m) for the critical time step, at the
  // largest modulus the run can give it (a strain table's largest, else its own): the smaller of the Frobenius norm
  // and the largest absolute row sum (Gershgorin) of the 12 x 12 matrix at rest, both of which bound the spectral
  // radius of a symmetric matrix. The rotation does not change the eigenvalues.
  static FMPC_HD double stiffness_bound(const Material<double>& m) {
    Linearisation lin{};
    for (int i = 0; i < 9; ++i) lin.rotation[i] = (i % 4 == 0) ? 1.0 : 0.0;
    lin.modulus = m.strain_table ? strain_table_largest_modulus(*m.strain_table) : m.youngs_modulus;
    double frobenius = 0.0, row_max = 0.0;
    double rows[12] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        double block[9];
        stiffness_block(m, lin, a, b, block);
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) {
            const double entry = block[3 * i + j];
            frobenius += entry * entry;
            rows[3 * a + i] += entry < 0.0 ? -entry : entry;
          }
        }
      }
    }
    for (int r = 0; r < 12; ++r) row_max = rows[r] > row_max ? rows[r] : row_max;
    frobenius = square_root(frobenius);
    return frobenius < row_max ? frobenius : row_max;
  }
};

}  // namespace fmpc::kernels

#pragma once
// Stable neo-Hookean hyperelasticity (B. Smith, F. de Goes, T. Kim, "Stable Neo-Hookean Flesh Simulation", ACM TOG
// 37(2), article 12, 2018), as a constitutive law at a material point. With I_C = |F|^2 and J = det F, the energy
// density is (eq. 14 of the paper)
//   Psi(F) = mu'/2 (I_C - 3) + lambda'/2 (J - alpha)^2 - mu'/2 log(I_C + 1),   alpha = 1 + 3 mu' / (4 lambda'),
// stress-free at rest, and with the paper's re-parameterisation (section 3.4) mu' = 4/3 mu, lambda' = lambda + 5/6 mu
// from the Lame parameters of E and nu, its small-strain limit is linear elasticity with those mu and lambda (the
// co-rotational law's). P = mu' (1 - 1/(I_C + 1)) F + lambda' (J - alpha) cof(F): rational in F, finite for every F
// (inverted, flat or collapsed), and an inverted element (J < 0 < alpha) is pushed back towards J > 0. No
// eigen-decomposition in P: the explicit path costs a cofactor matrix and a few products.
// Energies are reported relative to rest (Psi(F) - Psi(I)), with log(1 + x) computed from +, -, *, / alone
// (log_one_plus below), so that CPU and CUDA energies agree bit for bit.
// Implicit Euler's tangent is the energy's Hessian projected to its positive semi-definite part by the analytic
// eigen-system of an isotropic energy (Teran, Sifakis, Irving & Fedkiw 2005, "Robust quasistatic finite elements and
// flesh simulation", SCA; Smith et al. 2018 section 4): with the inversion-aware SVD F = U diag(s) V^T, the Hessian in
// U, V's frame is a 3 x 3 block on the diagonal entries (d^2 Psi / ds_i ds_j, projected by its eigen-decomposition)
// and, for each pair (i, j) with third index k, a "twist" mode (antisymmetric) with eigenvalue
// mu' I_C/(I_C + 1) + lambda' (J - alpha) s_k and a "flip" mode (symmetric) with mu' I_C/(I_C + 1) -
// lambda' (J - alpha) s_k, each clamped at zero. At rest nothing is clamped: it is the small-strain tangent.
// Damping: a Kelvin-Voigt stress on the Green strain rate, P_d = F beta (2 mu dE + lambda tr(dE) I) with
// dE = sym(F^T dF/dt) and the small-strain mu, lambda: zero for rigid motion, dissipative for every F, and the
// co-rotational law's damping at small strain. A strain table replaces Young's modulus with E at the point's
// principal strain (stretch - 1) of largest magnitude, as for the co-rotational law (its stretches cost an
// eigen-decomposition, paid only with a table).
#include "kernels/element_term.h"

namespace fmpc::kernels {

struct StableNeoHookean {
  // Per element: Young's modulus (Pa) and Poisson's ratio (the small-strain moduli the law reproduces).
  static constexpr int kParameterCount = 2;
  static constexpr int kYoungsModulus = 0;
  static constexpr int kPoissonRatio = 1;
  static constexpr bool kStrainTableModulus = true;

  template <typename Real>
  struct Material {
    Real youngs_modulus;
    Real poisson_ratio;
    Real stiffness_damping;  // beta (s)
    // By value, as the co-rotational law's: a pointer into the kernel's parameter would copy the whole
    // ElementTermView to local memory in every thread. strain == null: youngs_modulus.
    StrainTableView strain_table;
  };

  template <typename Real>
  static FMPC_HD Material<Real> material(const ElementTermView<Real>& t, int e) {
    Material<Real> m;
    m.youngs_modulus = t.parameter[kYoungsModulus][e];
    m.poisson_ratio = t.parameter[kPoissonRatio][e];
    m.stiffness_damping = t.stiffness_damping ? t.stiffness_damping[e] : Real(0);
    m.strain_table = t.strain_table;
    return m;
  }

  // The paper's parameters at the point: mu' = 4/3 mu, lambda' = lambda + 5/6 mu, and alpha - 1 = 3 mu' / (4 lambda')
  // = mu / lambda'; also the small-strain mu and lambda (damping).
  template <typename Real>
  struct Parameters {
    Real mu, lambda;      // small-strain Lame parameters
    Real mu_s, lambda_s;  // mu', lambda'
    Real alpha_minus_one;
  };

  template <typename Real>
  static FMPC_HD Parameters<Real> parameters(const Material<Real>& m, const Real* F) {
    Real modulus = m.youngs_modulus;
    if (m.strain_table.strain) {
      Real R[9], stretch[3];
      rotation_and_stretches(F, R, stretch);
      const Real strain = principal_strain_of_largest_magnitude(stretch);
      modulus = static_cast<Real>(strain_table_modulus(m.strain_table, static_cast<double>(strain)));
    }
    Parameters<Real> p;
    lame_parameters(modulus, m.poisson_ratio, p.mu, p.lambda);
    p.mu_s = Real(4) / Real(3) * p.mu;
    p.lambda_s = p.lambda + Real(5) / Real(6) * p.mu;
    p.alpha_minus_one = p.mu / p.lambda_s;
    return p;
  }

  // log(1 + x) for x > -1 from +, -, * and / (no library call, so both backends give the same bits): with
  // 1 + x = m 2^k, m in [sqrt(1/2), sqrt(2)), log m = 2 atanh(s), s = (m - 1)/(m + 1), |s| <= 0.1716, by its series
  // to s^21 (the next term is below 2.3e-17 relative), plus k log 2 in two parts. Near 1, s = x / (2 + x) keeps x's
  // relative precision.
  static FMPC_HD double log_one_plus(double x) {
    const double y = 1.0 + x;
    double s = 0.0;
    int k = 0;
    if (y >= 0.7071067811865476 && y < 1.4142135623730951) {
      s = x / (2.0 + x);
    } else {
      double m = fraction_and_exponent(y, k);  // m in [0.5, 1)
      if (m < 0.7071067811865476) {
        m *= 2.0;
        k -= 1;
      }
      s = (m - 1.0) / (m + 1.0);
    }
    const double s2 = s * s;
    double series = 1.0 / 21.0;
    for (int n = 9; n >= 0; --n) series = series * s2 + 1.0 / (2 * n + 1);
    const double kd = static_cast<double>(k);
    return kd * 6.93147180369123816490e-01 + (kd * 1.90821492927058770002e-10 + 2.0 * s * series);
  }

  // P(F), with the rate dF/dt where the element is damped (null otherwise).
  template <typename Real>
  static FMPC_HD void first_piola(const Material<Real>& m, const Real* F, const Real* F_rate, Real* P) {
    const Parameters<Real> p = parameters(m, F);
    Real C[9];
    cofactor3(F, C);
    Real invariant = Real(0);
    for (int i = 0; i < 9; ++i) invariant += F[i] * F[i];
    const Real shear = p.mu_s * invariant / (invariant + Real(1));
    const Real volume = p.lambda_s * (determinant_minus_one(F) - p.alpha_minus_one);
    for (int i = 0; i < 9; ++i) P[i] = shear * F[i] + volume * C[i];
    if (F_rate && m.stiffness_damping != Real(0)) {
      Real rate[9], S[9], damping[9];
      multiply3_transposed_left(F, F_rate, rate);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) S[3 * i + j] = m.stiffness_damping * (rate[3 * i + j] + rate[3 * j + i]) / Real(2);
      linear_stress(S, p.mu, p.lambda, damping);
      multiply3(F, damping, S);
      for (int i = 0; i < 9; ++i) P[i] += S[i];
    }
  }

  // What implicit Euler keeps between the conjugate gradient's iterations: the SVD frames at the step's start and
  // the projected Hessian's parts in them.
  struct Linearisation {
    double left[9];     // U (row-major; columns u_i)
    double right[9];    // V
    double scaling[9];  // the projected 3 x 3 block on the diagonal entries of U^T dF V
    double twist[3];    // clamped eigenvalue of pair k's antisymmetric mode (pair k: the two indices other than k)
    double flip[3];     // clamped eigenvalue of pair k's symmetric mode
  };

  static FMPC_HD void linearise(const Material<double>& m, const double* F, Linearisation& lin) {
    const Parameters<double> p = parameters(m, F);
    double R[9], s[3];
    rotation_and_stretches(F, R, s, lin.right);
    multiply3(R, lin.right, lin.left);
    const double invariant = s[0] * s[0] + s[1] * s[1] + s[2] * s[2];
    const double shear = p.mu_s * invariant / (invariant + 1.0);
    const double curvature = 2.0 * p.mu_s / ((invariant + 1.0) * (invariant + 1.0));
    const double volume = p.lambda_s * (determinant_minus_one(F) - p.alpha_minus_one);
    double block[9];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const int k = 3 - i - j;
        // d^2 Psi / ds_i ds_j: dJ/ds_i = J / s_i is the product of the other two stretches.
        const double ji = s[(i + 1) % 3] * s[(i + 2) % 3], jj = s[(j + 1) % 3] * s[(j + 2) % 3];
        block[3 * i + j] = curvature * s[i] * s[j] + p.lambda_s * ji * jj + (i == j ? shear : volume * s[k]);
      }
    double eigenvalues[3], vectors[9];
    symmetric_eigen3(block, eigenvalues, vectors);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        double sum = 0.0;
        for (int n = 0; n < 3; ++n)
          sum += vectors[3 * i + n] * (eigenvalues[n] > 0.0 ? eigenvalues[n] : 0.0) * vectors[3 * j + n];
        lin.scaling[3 * i + j] = sum;
      }
    for (int k = 0; k < 3; ++k) {
      const double twist = shear + volume * s[k], flip = shear - volume * s[k];
      lin.twist[k] = twist > 0.0 ? twist : 0.0;
      lin.flip[k] = flip > 0.0 ? flip : 0.0;
    }
  }

  // dP = U dP^ V^T with dP^ the projected Hessian applied to dF^ = U^T dF V.
  static FMPC_HD void stress_differential(const Material<double>&, const Linearisation& lin, const double* dF,
                                          double* dP) {
    double t[9], d[9], q[9];
    multiply3_transposed_left(lin.left, dF, t);
    multiply3(t, lin.right, d);
    for (int i = 0; i < 3; ++i)
      q[4 * i] = lin.scaling[3 * i] * d[0] + lin.scaling[3 * i + 1] * d[4] + lin.scaling[3 * i + 2] * d[8];
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      const double symmetric = (d[3 * i + j] + d[3 * j + i]) / 2.0, antisymmetric = (d[3 * i + j] - d[3 * j + i]) / 2.0;
      q[3 * i + j] = lin.flip[k] * symmetric + lin.twist[k] * antisymmetric;
      q[3 * j + i] = lin.flip[k] * symmetric - lin.twist[k] * antisymmetric;
    }
    multiply3(lin.left, q, t);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        dP[3 * i + j] =
            t[3 * i] * lin.right[3 * j] + t[3 * i + 1] * lin.right[3 * j + 1] + t[3 * i + 2] * lin.right[3 * j + 2];
  }

  // The small-strain Lame parameters (those of E and nu: the re-parameterisation makes the law's rest tangent
  // theirs) at the largest modulus the run can give the point. Under large compression the tangent stiffens beyond
  // them (docs/simulator.md, "Stable neo-Hookean").
  static FMPC_HD void rest_lame(const Material<double>& m, double& mu, double& lambda) {
    const double modulus = m.strain_table.strain ? strain_table_largest_modulus(m.strain_table) : m.youngs_modulus;
    lame_parameters(modulus, m.poisson_ratio, mu, lambda);
  }

  // Frames' cell data: the von Mises stress of the Cauchy stress sigma = P F^T / J (Pa); a flat or inverted element
  // (J <= 0, where no Cauchy stress exists) writes that of P F^T, the Kirchhoff stress.
  static constexpr const char* kStressOutput = "von_mises_stress_Pa";
  static FMPC_HD double stress_output(const Material<double>& m, const double* F) {
    double P[9], sigma[9];
    first_piola(m, F, static_cast<const double*>(nullptr), P);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        sigma[3 * i + j] = P[3 * i] * F[3 * j] + P[3 * i + 1] * F[3 * j + 1] + P[3 * i + 2] * F[3 * j + 2];
    const double J = determinant3(F);
    if (J > 0.0)
      for (double& entry : sigma) entry /= J;
    return von_mises_stress(sigma);
  }

  // Psi(F) - Psi(I) (J/m^3), written without the cancellations near rest: I_C - 3 = 2 tr H + |H|^2 with H = F - I,
  // (J - alpha)^2 - (1 - alpha)^2 = (J - 1)(J - 1 - 2 (alpha - 1)), log((I_C + 1) / 4) = log(1 + (I_C - 3) / 4).
  static FMPC_HD double energy_density(const Material<double>& m, const double* F) {
    const Parameters<double> p = parameters(m, F);
    double excess = 0.0;
    for (int i = 0; i < 9; ++i) {
      const double h = F[i] - (i % 4 == 0 ? 1.0 : 0.0);
      excess += h * h + (i % 4 == 0 ? 2.0 * h : 0.0);
    }
    const double change = determinant_minus_one(F);
    return 0.5 * p.mu_s * (excess - log_one_plus(excess / 4.0)) +
           0.5 * p.lambda_s * change * (change - 2.0 * p.alpha_minus_one);
  }
};

}  // namespace fmpc::kernels

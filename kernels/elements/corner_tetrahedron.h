#pragma once
// What the element kinds on a tetrahedron's four corners share (the linear tetrahedron and the nodal pressure one,
// kernels/elements/): constant shape-function gradients g_a (rows of Dm^-1, g_0 = -(g_1 + g_2 + g_3)), one material
// point, F = sum_a x_a g_a^T and corner forces f_a = -V0 P(F) g_a (Bonet & Wood, "Nonlinear Continuum Mechanics for
// Finite Element Analysis", 2nd ed., 9.4), quarter masses, the signed volume's inversion test and the rest stiffness
// bound. A kind derives from CornerTetrahedron<Kind> (the curiously recurring template pattern) and gives
// point_material<Law> (the material its point integrates), add_volumetric_stress (what it adds to the point's P) and
// volumetric_energy_density (what it adds to the energy density); every function is generic over the law.
#include "kernels/element_term.h"
#include "kernels/elements/element_kind_tangent.h"

namespace fmpc::kernels {

// An upper bound of the largest eigenvalue of a 4-node tetrahedron's rest stiffness (N/m) from its Dm^-1, volume V0
// and Lame parameters: the smaller of the Frobenius norm and the largest absolute row sum (Gershgorin) of the 12 x 12
// matrix K_ab = V0 (lambda g_a g_b^T + mu g_b g_a^T + mu (g_a . g_b) I), both of which bound the spectral radius of
// a symmetric matrix. The kinds on four corners share it.
FMPC_HD double corner_stiffness_bound(const double* rest_inverse, double volume, double mu, double lambda) {
  double g[4][3];
  shape_gradients(rest_inverse, g);
  double frobenius = 0.0, row_max = 0.0;
  double rows[12] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) {
      const double gg = dot3(g[a], g[b]);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const double entry =
              volume * (lambda * g[a][i] * g[b][j] + mu * g[b][i] * g[a][j] + (i == j ? mu * gg : 0.0));
          frobenius += entry * entry;
          rows[3 * a + i] += entry < 0.0 ? -entry : entry;
        }
    }
  for (int r = 0; r < 12; ++r) row_max = rows[r] > row_max ? rows[r] : row_max;
  frobenius = square_root(frobenius);
  return frobenius < row_max ? frobenius : row_max;
}

template <typename Kind>
struct CornerTetrahedron : ElementKindTangent<Kind> {
  static constexpr int kNodes = 4;
  static constexpr int kEdgeNodes = 0;  // nodes beyond the corners, one per edge (kernels/element_term.h)
  // Each corner's lumped mass as a fraction of the element's (rho V0): a quarter (the consistent mass's row sums).
  static constexpr double kMassFraction[kNodes] = {0.25, 0.25, 0.25, 0.25};
  static constexpr int kPoints = 1;  // material points (per-point state: kernels/prony_viscoelasticity.h)

  // F at each material point from node positions x.
  template <typename Real>
  static FMPC_HD void deformation_gradients(const ElementTermView<Real>& t, int e, const Real x[kNodes][3],
                                            Real F[kPoints][9]) {
    corner_gradient(x, rest_inverse_of(t, e), F[0]);
  }

  // The element's forces on its nodes at positions x and, where the term is damped (v non-null), velocities v.
  template <typename Law, typename Real>
  static FMPC_HD void forces(const ElementTermView<Real>& t, int e, const Real x[kNodes][3], const Real (*v)[3],
                             Real out[kNodes][3]) {
    const Real* rest_inverse = rest_inverse_of(t, e);
    const typename Law::template Material<Real> material = Kind::template point_material<Law>(t, e);
    Real g[4][3], F[9], P[9];
    shape_gradients(rest_inverse, g);
    corner_gradient(x, rest_inverse, F);
    // Two calls, not one with `v ? F_rate : nullptr`: a pointer chosen at run time keeps F_rate, and the velocities
    // behind v, in local memory on the GPU (ptxas: a 208-byte stack frame in float, the element pass 24% slower).
    if (v) {
      Real F_rate[9];
      corner_gradient(v, rest_inverse, F_rate);
      point_first_piola_of<Law>(material, t, e, kPoints * e, F, F_rate, P);
    } else {
      point_first_piola_of<Law>(material, t, e, kPoints * e, F, static_cast<const Real*>(nullptr), P);
    }
    Kind::add_volumetric_stress(t, e, F, P);
    corner_forces_from_stress(P, g, t.rest_volume[e], out);
  }

  // What implicit Euler holds over a step: the law's linearisation at the element's point.
  template <typename Law>
  struct Linearisation {
    typename Law::Linearisation point;
  };

  template <typename Law>
  static FMPC_HD void linearise(const ElementTermView<double>& t, int e, const double x[kNodes][3],
                                Linearisation<Law>& lin) {
    double F[9];
    corner_gradient(x, rest_inverse_of(t, e), F);
    Law::linearise(Kind::template point_material<Law>(t, e), F, lin.point);
  }

  // forces() and linearise() at the same x in one: the linearisation into lin, and the forces with the law's stress
  // from it (point_first_piola_linearised: forces()'s bits, the law's decomposition taken once).
  template <typename Law>
  static FMPC_HD void forces_and_linearisation(const ElementTermView<double>& t, int e, const double x[kNodes][3],
                                               const double (*v)[3], Linearisation<Law>& lin,
                                               double out[kNodes][3]) {
    const double* rest_inverse = rest_inverse_of(t, e);
    const typename Law::template Material<double> material = Kind::template point_material<Law>(t, e);
    double g[4][3], F[9], F_rate[9], P[9];
    shape_gradients(rest_inverse, g);
    corner_gradient(x, rest_inverse, F);
    Law::linearise(material, F, lin.point);
    if (v) corner_gradient(v, rest_inverse, F_rate);
    point_first_piola_linearised<Law>(material, t, e, kPoints * e, lin.point, F, v ? F_rate : nullptr, P);
    Kind::add_volumetric_stress(t, e, F, P);
    corner_forces_from_stress(P, g, t.rest_volume[e], out);
  }

  // The tangent stiffness applied to a nodal field p [node][axis]: out_a = sum_b K_ab p_b = V0 dP(dF) g_a with
  // dF = sum_b p_b g_b^T (the element's own part: a kind's nodal coupling is its assembler's).
  template <typename Law>
  static FMPC_HD void stiffness_action(const ElementTermView<double>& t, int e, const Linearisation<Law>& lin,
                                       const double p[kNodes][3], double out[kNodes][3]) {
    const double* rest_inverse = rest_inverse_of(t, e);
    double g[4][3], dF[9], dP[9];
    shape_gradients(rest_inverse, g);
    corner_gradient(p, rest_inverse, dF);
    Law::stress_differential(Kind::template point_material<Law>(t, e), lin.point, dF, dP);
    for (int a = 0; a < kNodes; ++a)
      for (int i = 0; i < 3; ++i)
        out[a][i] = t.rest_volume[e] * (dP[3 * i] * g[a][0] + dP[3 * i + 1] * g[a][1] + dP[3 * i + 2] * g[a][2]);
  }

  // The whole 12 x 12 tangent in closed form, row-major as ElementKindTangent::stiffness_matrix (which builds it
  // from 12 stiffness actions): K_ab,ij = V0 sum_kl g_a[k] A[(i k), (j l)] g_b[l] with A the law's tangent modulus
  // dP/dF (law_tangent_modulus; R K0 R^T for the co-rotational law), for a, b = 1..3; node 0's rows and columns are
  // minus the sums of the others' (g_0 = -(g_1 + g_2 + g_3)). The same matrix as stiffness_action's columns up to
  // round-off (the sums are taken in another order), for about a third of their cost.
  template <typename Law>
  static FMPC_HD void stiffness_matrix(const ElementTermView<double>& t, int e, const Linearisation<Law>& lin,
                                       double* K) {
    constexpr int S = 3 * kNodes;
    double g[4][3], A[81];
    shape_gradients(rest_inverse_of(t, e), g);
    law_tangent_modulus<Law>(Kind::template point_material<Law>(t, e), lin.point, A);
    const double volume = t.rest_volume[e];
    for (int b = 1; b < kNodes; ++b) {
      // H[(i k), j] = V0 sum_l A[(i k), (j l)] g_b[l].
      double H[27];
      for (int row = 0; row < 9; ++row)
        for (int j = 0; j < 3; ++j)
          H[3 * row + j] = volume * (A[9 * row + 3 * j] * g[b][0] + A[9 * row + 3 * j + 1] * g[b][1] +
                                     A[9 * row + 3 * j + 2] * g[b][2]);
      for (int a = 1; a < kNodes; ++a)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            K[S * (3 * a + i) + 3 * b + j] =
                g[a][0] * H[3 * (3 * i) + j] + g[a][1] * H[3 * (3 * i + 1) + j] + g[a][2] * H[3 * (3 * i + 2) + j];
    }
    for (int r = 3; r < S; ++r)
      for (int j = 0; j < 3; ++j) K[S * r + j] = -(K[S * r + 3 + j] + K[S * r + 6 + j] + K[S * r + 9 + j]);
    for (int c = 0; c < S; ++c)
      for (int i = 0; i < 3; ++i) K[S * i + c] = -(K[S * (3 + i) + c] + K[S * (6 + i) + c] + K[S * (9 + i) + c]);
  }

  // Elastic energy at positions x (J).
  template <typename Law>
  static FMPC_HD double energy(const ElementTermView<double>& t, int e, const double x[kNodes][3]) {
    double F[9];
    corner_gradient(x, rest_inverse_of(t, e), F);
    return t.rest_volume[e] *
           (Law::energy_density(Kind::template point_material<Law>(t, e), F) + Kind::volumetric_energy_density(t, e));
  }

  // The law's stress output (its kStressOutput) at positions x, of the material the point integrates.
  template <typename Law>
  static FMPC_HD double stress_output(const ElementTermView<double>& t, int e, const double x[kNodes][3]) {
    double F[9];
    corner_gradient(x, rest_inverse_of(t, e), F);
    return Law::stress_output(Kind::template point_material<Law>(t, e), F);
  }

  // Whether the element is inverted or flat at x (signed volume <= 0).
  template <typename Real>
  static FMPC_HD bool inverted(const Real x[kNodes][3]) {
    return !(tetrahedron_volume(x) > Real(0));
  }

  // An upper bound of the largest eigenvalue of the element's rest stiffness (N/m), for the critical time step and the
  // element damping, at the law's rest Lame parameters (corner_stiffness_bound).
  template <typename Law>
  static FMPC_HD double stiffness_bound(const ElementTermView<double>& t, int e) {
    double mu, lambda;
    Law::rest_lame(Law::material(t, e), mu, lambda);
    return corner_stiffness_bound(rest_inverse_of(t, e), t.rest_volume[e], mu, lambda);
  }
};

}  // namespace fmpc::kernels

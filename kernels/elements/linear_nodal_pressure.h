#pragma once
// The average nodal pressure tetrahedron (Bonet & Burton 1998, "A simple average nodal pressure tetrahedral element
// for incompressible and nearly incompressible dynamic explicit applications", Commun. Numer. Meth. Eng. 14:437-449)
// as an element kind: the linear tetrahedron's nodes, F and corner forces, with the law split into its shear part
// (the law at the same mu and lambda = 0: Law::shear_part), integrated per element, and a volumetric energy
// lambda/2 (J - 1)^2 whose J is averaged over each node's patch. With theta_a = (V_a - V0_a) / V0_a at node a
// (V_a = sum over its elements of V_e / 4) and K_a the patch's volume-weighted lambda, the energy is
//   W = sum_e V0_e Psi_shear(F_e) + sum_a V0_a K_a theta_a^2 / 2,
// whose gradient gives each element the pressure p_e = mean over its corners of p_a = K_a theta_a, acting as
// P_vol = p_e cof(F) (the element's corner forces -p_e dV_e/dx_b). A tetrahedron has one volume constraint per
// element, a mesh about six elements per node: averaging the constraint over the node's patch leaves one per node,
// which a linear displacement field can meet without locking (Bonet & Burton section 3).
//
// The variant: Bonet & Burton's, with lambda (not the bulk modulus) as the averaged modulus, so that the split is
// exact: stable neo-Hookean with lambda = 0 plus lambda/2 (J - 1)^2 is the law itself (its lambda' (alpha - 1) = mu
// for every lambda), and the co-rotational law's lambda/2 tr(eps)^2 equals lambda/2 (J - 1)^2 to second order in the
// strain. K_a averages lambda over the patch by rest volume: Joldes, Wittek & Miller 2009 ("Improved linear
// tetrahedral element for surgical simulation", Computational Biomechanics for Medicine) average the Jacobian
// instead (F-bar: the law evaluated at (J_avg / J)^(1/3) F), which is generic over the law but not the gradient of
// an energy, so its forces are not conservative and its tangent not symmetric; their 2010 paper (Commun. Numer.
// Meth. Eng. 26) extends Bonet & Burton to several materials, which the volume weighting here approximates.
//
// What is not element-local: theta_a and K_a. Each evaluation runs a nodal pass first (kernels/element_term.h,
// element_nodal_shares and nodal_pressure_at: each element writes its shares (V - V0)/4, V0/4, lambda V0/4 at its
// corner slots, each vertex sums its own), then the element pass reads the nodal pressure through
// ElementTermView::nodal_pressure (and the energy nodal_dilatation). Kinds with kNodalPressure are the only ones the
// engines run that pass for. The Prony series (viscoelasticity) and the stiffness damping act on the shear part.
#include "kernels/elements/corner_tetrahedron.h"

namespace fmpc::kernels {

struct LinearNodalPressure : CornerTetrahedron<LinearNodalPressure> {
  static constexpr bool kNodalPressure = true;

  // What the element integrates per point (the Prony series' elastic stress, the damping, the tangent's element part,
  // the stress output: the pressure is hydrostatic in the Cauchy stress, p cof(F) F^T / J = p I, so the von Mises
  // stress the laws write is the shear part's alone): the law's shear part.
  template <typename Law, typename Real>
  static FMPC_HD typename Law::template Material<Real> point_material(const ElementTermView<Real>& t, int e) {
    return Law::shear_part(Law::material(t, e));
  }

  // Element e's share of each corner's sums, the same at every corner: (V - V0) / 4, V0 / 4 and lambda V0 / 4.
  // V - V0 is V0 (det F - 1), without the cancellation of V - V0 near rest.
  template <typename Law, typename Real>
  static FMPC_HD void nodal_shares(const ElementTermView<Real>& t, int e, const Real x[kNodes][3], Real share[3]) {
    Real F[9];
    corner_gradient(x, rest_inverse_of(t, e), F);
    const Real quarter = t.rest_volume[e] / Real(4);
    share[0] = quarter * determinant_minus_one(F);
    share[1] = quarter;
    share[2] = quarter * Law::volumetric_modulus(Law::material(t, e));
  }

  // The mean of a nodal field over element e's corners, summed in one order on both backends.
  template <typename Real>
  static FMPC_HD Real corner_mean(const ElementTermView<Real>& t, int e, const Real* field) {
    const int* node = t.corners + kNodes * e;
    return ((field[node[0]] + field[node[1]]) + (field[node[2]] + field[node[3]])) / Real(4);
  }

  // P += p_e cof(F), p_e the mean nodal pressure: the corner forces -p_e dV_e/dx_b.
  template <typename Real>
  static FMPC_HD void add_volumetric_stress(const ElementTermView<Real>& t, int e, const Real* F, Real* P) {
    const Real pressure = corner_mean(t, e, t.nodal_pressure);
    Real C[9];
    cofactor3(F, C);
    for (int i = 0; i < 9; ++i) P[i] += pressure * C[i];
  }

  // The element's share of the nodal energy per rest volume: V0_a = sum_e V0_e / 4, so sum_a V0_a K_a theta_a^2 / 2 =
  // sum_e V0_e times the mean over e's corners of p_a theta_a / 2.
  static FMPC_HD double volumetric_energy_density(const ElementTermView<double>& t, int e) {
    const int* node = t.corners + kNodes * e;
    double nodal = 0.0;
    for (int a = 0; a < kNodes; ++a) nodal += t.nodal_pressure[node[a]] * t.nodal_dilatation[node[a]];
    return nodal / 8.0;
  }

  // dV_e/dx_b = V0 cof(F) g_b at positions x: the element's row of the nodal pass's volume gradient (the static
  // solver's B^T D B, runtime/integrate/model_tangent.cpp; the element's own tangent, stiffness_action, is the shear
  // part's). The stable step's bound is the linear tetrahedron's at the law's rest mu and lambda: by Cauchy-Schwarz,
  // V0_a theta_a^2 <= sum over a's elements of V0_e (dV_e / V0_e)^2 / 4, so the averaged volumetric energy never
  // exceeds the linear element's lambda/2 sum_e V0_e (dV_e / V0_e)^2, and neither does the largest eigenvalue.
  static FMPC_HD void volume_gradient(const ElementTermView<double>& t, int e, const double x[kNodes][3],
                                      double out[kNodes][3]) {
    const double* rest_inverse = rest_inverse_of(t, e);
    double g[4][3], F[9], C[9];
    shape_gradients(rest_inverse, g);
    corner_gradient(x, rest_inverse, F);
    cofactor3(F, C);
    corner_forces_from_stress(C, g, -t.rest_volume[e], out);
  }
};

}  // namespace fmpc::kernels

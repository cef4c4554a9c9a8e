#pragma once
// The quadratic (10-node) tetrahedron as an element kind: the corners, then one node on each edge in Abaqus / CalculiX
// C3D10 and VTK_QUADRATIC_TETRA order (edges 0-1, 1-2, 2-0, 0-3, 1-3, 2-3). Shape functions in the barycentric
// coordinates L_k: N_a = L_a (2 L_a - 1) at corner a, N_ij = 4 L_i L_j on edge ij (Zienkiewicz, Taylor & Zhu, "The
// Finite Element Method", 7th ed., 8.8). The rest element is straight-sided (its edge nodes are the edges' midpoints:
// runtime/fem builds them so), so grad L_k are the linear tetrahedron's g_k and the rest Jacobian is constant:
// grad N_a = (4 L_a - 1) g_a, grad N_ij = 4 (L_j g_i + L_i g_j), and each of the four points of the degree-2 rule
// (L = (a, b, b, b) and its permutations, a = (5 + 3 sqrt 5) / 20, b = (5 - sqrt 5) / 20, weight V0 / 4) needs only
// Dm^-1 and V0: no more rest data than the linear kind. At a point, F = sum_k y_k g_k^T with y_k = sum_a x_a dN_a/dL_k,
// which is the linear tetrahedron's corner_gradient of the four y_k; the forces f_a = -sum_q V0/4 P_q grad N_a(q) are
// the linear tetrahedron's corner forces c_k = -V0/4 P_q g_k spread back by the same dN_a/dL_k. Every function is
// generic over the law, as LinearTetrahedron's.
#include "kernels/element_term.h"
#include "kernels/elements/element_kind_tangent.h"

namespace fmpc::kernels {

struct QuadraticTetrahedron : ElementKindTangent<QuadraticTetrahedron> {
  static constexpr int kNodes = 10;
  static constexpr int kEdgeNodes = 6;
  static constexpr int kPoints = 4;
  // Whether the element pass reads a nodal pass's pressure (kernels/elements/linear_nodal_pressure.h): no.
  static constexpr bool kNodalPressure = false;

  // The material each point integrates (the Prony series' elastic stress reads it): the law's own.
  template <typename Law, typename Real>
  static FMPC_HD typename Law::template Material<Real> point_material(const ElementTermView<Real>& t, int e) {
    return Law::material(t, e);
  }

  // The float element pass's register bound by default (blocks of 256 threads per SM; kernels/explicit_step.cu): two
  // (no spills) measured 2.32e9 element-steps/s against 1.77e9 at three on 10M elements (docs/performance.md,
  // fifteenth run).
  static constexpr int kFloatElementBlocks = 2;
  // Edge node 4 + m lies between corners edge_end(m, 0) and edge_end(m, 1): edges 0-1, 1-2, 2-0, then k-3 for k = 0,
  // 1, 2 (arithmetic rather than a table: a constant array indexed at run time is not addressable in device code).
  static FMPC_HD constexpr int edge_end(int m, int end) {
    return m < 3 ? (end == 0 ? m : (m + 1) % 3) : (end == 0 ? m - 3 : 3);
  }
  // The lumped mass of each node as a fraction of the element's (rho V0): Hinton, Rock & Zienkiewicz (1976)'s
  // diagonal scaling of the consistent mass (whose diagonal is 6/420 at a corner and 32/420 on an edge): 1/36 at each
  // corner, 4/27 on each edge. The row-sum lumping would give the corners -1/20 (a negative mass); HRZ keeps every
  // mass positive and the total exact, and is the lumping that reproduces the element's lowest modes best among the
  // positive ones (Cook, Malkus, Plesha & Witt, "Concepts and Applications of FEA", 4th ed., 11.3).
  static constexpr double kMassFraction[kNodes] = {1.0 / 36, 1.0 / 36, 1.0 / 36, 1.0 / 36, 4.0 / 27,
                                                   4.0 / 27, 4.0 / 27, 4.0 / 27, 4.0 / 27, 4.0 / 27};

  // Barycentric coordinate k of quadrature point q, and 4 L_k - 1 there.
  template <typename Real>
  static FMPC_HD Real coordinate(int q, int k) {
    return q == k ? Real(0.58541019662496845446) : Real(0.13819660112501051518);
  }

  // y_k = sum_a d_a dN_a/dL_k at point q for a nodal field d [node][axis].
  template <typename Real>
  static FMPC_HD void barycentric_derivatives(const Real d[kNodes][3], int q, Real y[4][3]) {
    for (int k = 0; k < 4; ++k) {
      const Real corner = Real(4) * coordinate<Real>(q, k) - Real(1);
      for (int i = 0; i < 3; ++i) y[k][i] = corner * d[k][i];
    }
    for (int m = 0; m < 6; ++m) {
      const int i = edge_end(m, 0), j = edge_end(m, 1);
      const Real to_i = Real(4) * coordinate<Real>(q, j), to_j = Real(4) * coordinate<Real>(q, i);
      for (int axis = 0; axis < 3; ++axis) {
        y[i][axis] += to_i * d[4 + m][axis];
        y[j][axis] += to_j * d[4 + m][axis];
      }
    }
  }

  // The field's gradient sum_a d_a grad N_a(q)^T at point q. Positions are taken relative to node 0 first (the
  // gradient of a constant is zero): y_k sums three times the positions, and differences of such sums far from the
  // origin would lose the element's size in float.
  template <typename Real>
  static FMPC_HD void point_gradient(const Real x[kNodes][3], int q, const Real* rest_inverse, Real* out) {
    Real d[kNodes][3], y[4][3];
    for (int a = 0; a < kNodes; ++a)
      for (int i = 0; i < 3; ++i) d[a][i] = x[a][i] - x[0][i];
    barycentric_derivatives(d, q, y);
    corner_gradient(y, rest_inverse, out);
  }

  // out_a += sum_k c_k dN_a/dL_k at point q: corner forces c_k of the linear tetrahedron spread to the ten nodes.
  template <typename Real>
  static FMPC_HD void spread(const Real c[4][3], int q, Real out[kNodes][3]) {
    for (int k = 0; k < 4; ++k) {
      const Real corner = Real(4) * coordinate<Real>(q, k) - Real(1);
      for (int i = 0; i < 3; ++i) out[k][i] += corner * c[k][i];
    }
    for (int m = 0; m < 6; ++m) {
      const int i = edge_end(m, 0), j = edge_end(m, 1);
      const Real from_i = Real(4) * coordinate<Real>(q, j), from_j = Real(4) * coordinate<Real>(q, i);
      for (int axis = 0; axis < 3; ++axis) out[4 + m][axis] += from_i * c[i][axis] + from_j * c[j][axis];
    }
  }

  // F at each of the four points from node positions x.
  template <typename Real>
  static FMPC_HD void deformation_gradients(const ElementTermView<Real>& t, int e, const Real x[kNodes][3],
                                            Real F[kPoints][9]) {
    for (int q = 0; q < kPoints; ++q) point_gradient(x, q, rest_inverse_of(t, e), F[q]);
  }

  // Each point's stress through point_first_piola (point kPoints e + q), so that a term's per-point state (the Prony
  // series) acts on every point.
  template <typename Law, typename Real>
  static FMPC_HD void forces(const ElementTermView<Real>& t, int e, const Real x[kNodes][3], const Real (*v)[3],
                             Real out[kNodes][3]) {
    const Real* rest_inverse = rest_inverse_of(t, e);
    const Real weight = t.rest_volume[e] / Real(kPoints);
    Real g[4][3];
    shape_gradients(rest_inverse, g);
    for (int a = 0; a < kNodes; ++a)
      for (int i = 0; i < 3; ++i) out[a][i] = Real(0);
    for (int q = 0; q < kPoints; ++q) {
      Real F[9], P[9], c[4][3];
      point_gradient(x, q, rest_inverse, F);
      // Two calls with a constant pointer each, as LinearTetrahedron::forces says why.
      if (v) {
        Real F_rate[9];
        point_gradient(v, q, rest_inverse, F_rate);
        point_first_piola<Law>(t, e, kPoints * e + q, F, F_rate, P);
      } else {
        point_first_piola<Law>(t, e, kPoints * e + q, F, static_cast<const Real*>(nullptr), P);
      }
      corner_forces_from_stress(P, g, weight, c);
      spread(c, q, out);
    }
  }

  template <typename Law>
  struct Linearisation {
    typename Law::Linearisation point[kPoints];
  };

  template <typename Law>
  static FMPC_HD void linearise(const ElementTermView<double>& t, int e, const double x[kNodes][3],
                                Linearisation<Law>& lin) {
    const typename Law::template Material<double> material = Law::material(t, e);
    for (int q = 0; q < kPoints; ++q) {
      double F[9];
      point_gradient(x, q, rest_inverse_of(t, e), F);
      Law::linearise(material, F, lin.point[q]);
    }
  }

  // out_a = sum_b K_ab p_b = sum_q V0/4 dP_q(dF_q) grad N_a(q), dF_q = sum_b p_b grad N_b(q)^T.
  template <typename Law>
  static FMPC_HD void stiffness_action(const ElementTermView<double>& t, int e, const Linearisation<Law>& lin,
                                       const double p[kNodes][3], double out[kNodes][3]) {
    const double* rest_inverse = rest_inverse_of(t, e);
    const typename Law::template Material<double> material = Law::material(t, e);
    double g[4][3];
    shape_gradients(rest_inverse, g);
    for (int a = 0; a < kNodes; ++a)
      for (int i = 0; i < 3; ++i) out[a][i] = 0.0;
    for (int q = 0; q < kPoints; ++q) {
      double dF[9], dP[9], c[4][3];
      point_gradient(p, q, rest_inverse, dF);
      Law::stress_differential(material, lin.point[q], dF, dP);
      // corner_forces_from_stress gives -V dP g_k: the action is its negative.
      corner_forces_from_stress(dP, g, -t.rest_volume[e] / kPoints, c);
      spread(c, q, out);
    }
  }

  // The mean over the four points of value(material, F_q): each point carries a quarter of the volume.
  template <typename Law, typename Value>
  static FMPC_HD double point_mean(const ElementTermView<double>& t, int e, const double x[kNodes][3], Value value) {
    const typename Law::template Material<double> material = Law::material(t, e);
    double sum = 0.0;
    for (int q = 0; q < kPoints; ++q) {
      double F[9];
      point_gradient(x, q, rest_inverse_of(t, e), F);
      sum += value(material, F);
    }
    return sum / kPoints;
  }

  template <typename Law>
  static FMPC_HD double energy(const ElementTermView<double>& t, int e, const double x[kNodes][3]) {
    return t.rest_volume[e] *
           point_mean<Law>(t, e, x, [](const typename Law::template Material<double>& material, const double* F) {
             return Law::energy_density(material, F);
           });
  }

  // The law's stress output averaged over the four points.
  template <typename Law>
  static FMPC_HD double stress_output(const ElementTermView<double>& t, int e, const double x[kNodes][3]) {
    return point_mean<Law>(t, e, x, [](const typename Law::template Material<double>& material, const double* F) {
      return Law::stress_output(material, F);
    });
  }

  // Whether the element is inverted or flat at x: the Jacobian det(dx/dL) <= 0 at one of its quadrature points
  // (where its forces are evaluated). With L_1..L_3 independent (L_0 = 1 - L_1 - L_2 - L_3), dx/dL_k = y_k - y_0, so
  // the determinant is 6 times the signed volume of the four y_k: the corner tetrahedron's volume for a straight
  // element, and det F times the rest's 6 V0 > 0 in general (the sign of det F, with no rest data read). A curved
  // element can fold between its corners while its corner tetrahedron keeps a positive volume; this catches it.
  template <typename Real>
  static FMPC_HD bool inverted(const Real x[kNodes][3]) {
    Real d[kNodes][3];
    for (int a = 0; a < kNodes; ++a)
      for (int i = 0; i < 3; ++i) d[a][i] = x[a][i] - x[0][i];
    for (int q = 0; q < kPoints; ++q) {
      Real y[4][3];
      barycentric_derivatives(d, q, y);
      if (!(tetrahedron_volume(y) > Real(0))) return true;
    }
    return false;
  }

  // Shape-function gradients grad N_a at point q from the linear tetrahedron's g_k.
  static FMPC_HD void node_gradients(const double g[4][3], int q, double out[kNodes][3]) {
    for (int k = 0; k < 4; ++k) {
      const double corner = 4.0 * coordinate<double>(q, k) - 1.0;
      for (int i = 0; i < 3; ++i) out[k][i] = corner * g[k][i];
    }
    for (int m = 0; m < 6; ++m) {
      const int i = edge_end(m, 0), j = edge_end(m, 1);
      for (int axis = 0; axis < 3; ++axis)
        out[4 + m][axis] = 4.0 * (coordinate<double>(q, j) * g[i][axis] + coordinate<double>(q, i) * g[j][axis]);
    }
  }

  // The bound of LinearTetrahedron::stiffness_bound (the smaller of the Frobenius norm and the largest absolute row
  // sum) for the 30 x 30 rest stiffness sum_q V0/4 (lambda G_a G_b^T + mu G_b G_a^T + mu (G_a . G_b) I), G = grad N(q).
  template <typename Law>
  static FMPC_HD double stiffness_bound(const ElementTermView<double>& t, int e) {
    double g[4][3], G[kPoints][kNodes][3], mu, lambda;
    shape_gradients(rest_inverse_of(t, e), g);
    for (int q = 0; q < kPoints; ++q) node_gradients(g, q, G[q]);
    Law::rest_lame(Law::material(t, e), mu, lambda);
    const double weight = t.rest_volume[e] / kPoints;
    double frobenius = 0.0, rows[3 * kNodes] = {}, row_max = 0.0;
    for (int a = 0; a < kNodes; ++a)
      for (int b = 0; b < kNodes; ++b) {
        double block[3][3] = {};
        for (int q = 0; q < kPoints; ++q) {
          const double gg = dot3(G[q][a], G[q][b]);
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
              block[i][j] +=
                  weight * (lambda * G[q][a][i] * G[q][b][j] + mu * G[q][b][i] * G[q][a][j] + (i == j ? mu * gg : 0.0));
        }
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) {
            frobenius += block[i][j] * block[i][j];
            rows[3 * a + i] += block[i][j] < 0.0 ? -block[i][j] : block[i][j];
          }
      }
    for (int r = 0; r < 3 * kNodes; ++r) row_max = rows[r] > row_max ? rows[r] : row_max;
    frobenius = square_root(frobenius);
    return frobenius < row_max ? frobenius : row_max;
  }
};

}  // namespace fmpc::kernels

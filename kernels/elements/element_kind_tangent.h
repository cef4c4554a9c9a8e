#pragma once
// What every element kind derives from its stiffness_action alone (Element::stiffness_action<Law>(view, e, lin, p,
// out)): a column of the tangent, its diagonal (Jacobi's preconditioner) and the whole matrix (tests, small direct
// solves). A kind derives from ElementKindTangent<Kind> (the curiously recurring template pattern).
#include "kernels/fmpc_hd.h"
#include "kernels/tetrahedron_math.h"

namespace fmpc::kernels {

template <typename Kind>
struct ElementKindTangent {
  // Column (3 b + j) of the 3N x 3N tangent: its action on the unit displacement of node b along axis j.
  template <typename Law, typename View, typename Linearisation, int N>
  static FMPC_HD void stiffness_column(const View& t, int e, const Linearisation& lin, int b, int j,
                                       double (&out)[N][3]) {
    double p[N][3] = {};
    p[b][j] = 1.0;
    Kind::template stiffness_action<Law>(t, e, lin, p, out);
  }

  // The diagonal entries K_(3a+i),(3a+i), as [node][axis].
  template <typename Law, typename View, typename Linearisation, int N>
  static FMPC_HD void stiffness_diagonal(const View& t, int e, const Linearisation& lin, double (&diagonal)[N][3]) {
    for (int a = 0; a < N; ++a)
      for (int i = 0; i < 3; ++i) {
        double column[N][3];
        stiffness_column<Law>(t, e, lin, a, i, column);
        diagonal[a][i] = column[a][i];
      }
  }

  // The whole 3N x 3N tangent, row-major: K[3 N (3 a + i) + 3 b + j].
  template <typename Law, typename View, typename Linearisation>
  static FMPC_HD void stiffness_matrix(const View& t, int e, const Linearisation& lin, double* K) {
    constexpr int N = Kind::kNodes;
    for (int b = 0; b < N; ++b)
      for (int j = 0; j < 3; ++j) {
        double column[N][3];
        stiffness_column<Law>(t, e, lin, b, j, column);
        for (int a = 0; a < N; ++a)
          for (int i = 0; i < 3; ++i) K[3 * N * (3 * a + i) + 3 * b + j] = column[a][i];
      }
  }
};

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
          const double entry = volume * (lambda * g[a][i] * g[b][j] + mu * g[b][i] * g[a][j] + (i == j ? mu * gg : 0.0));
          frobenius += entry * entry;
          rows[3 * a + i] += entry < 0.0 ? -entry : entry;
        }
    }
  for (int r = 0; r < 12; ++r) row_max = rows[r] > row_max ? rows[r] : row_max;
  frobenius = square_root(frobenius);
  return frobenius < row_max ? frobenius : row_max;
}

}  // namespace fmpc::kernels

#pragma once
// What every element kind derives from its stiffness_action alone (Element::stiffness_action<Law>(view, e, lin, p,
// out)): a column of the tangent, its diagonal (Jacobi's preconditioner) and the whole matrix (tests, small direct
// solves). A kind derives from ElementKindTangent<Kind> (the curiously recurring template pattern).
#include "kernels/fmpc_hd.h"

namespace fmpc::kernels {

template <typename Kind>
struct ElementKindTangent {
  // The float element pass's register bound by default, in blocks of 256 threads per SM (kernels/explicit_step.cu):
  // three unless a kind declares its own.
  static constexpr int kFloatElementBlocks = 3;
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

}  // namespace fmpc::kernels

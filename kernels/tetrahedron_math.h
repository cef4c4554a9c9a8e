#pragma once
// Linear tetrahedra's geometry and the small-matrix algebra the element laws (kernels/laws/) are written in, shared by
// the CPU loops (runtime/), the CUDA kernels (kernels/*.cu) and the host's energy, stress and probe sums: every
// function is FMPC_HD and templated on the real type, and uses only +, -, *, / and sqrt (correctly rounded on both
// sides; no transcendental functions), so a kernel compiled with --fmad=false gives the CPU loop's bits. Also the
// corner forces' layout (CornerForce, CornerForceView) that an element pass writes and a vertex's gather reads.
#include "kernels/fmpc_hd.h"
#include "kernels/spring_math.h"
#include "kernels/strain_table_math.h"

namespace fmpc::kernels {

template <typename Real>
struct RealLimits;
template <>
struct RealLimits<float> {
  static constexpr float epsilon = 1.1920929e-7f;
  static constexpr float largest = 3.4028235e38f;
};
template <>
struct RealLimits<double> {
  static constexpr double epsilon = 2.220446049250313e-16;
  static constexpr double largest = 1.7976931348623157e308;
};

// ---- 3 x 3 matrices (row-major arrays of 9) ---------------------------------------------------------------------

template <typename Real>
FMPC_HD Real dot3(const Real* a, const Real* b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

template <typename Real>
FMPC_HD void cross3(const Real* a, const Real* b, Real* out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

// out = a b (row-major 3 x 3).
template <typename Real>
FMPC_HD void multiply3(const Real* a, const Real* b, Real* out) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

// out = a^T b.
template <typename Real>
FMPC_HD void multiply3_transposed_left(const Real* a, const Real* b, Real* out) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out[3 * i + j] = a[i] * b[j] + a[3 + i] * b[3 + j] + a[6 + i] * b[6 + j];
}

template <typename Real>
FMPC_HD Real determinant3(const Real* m) {
  return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

// The cofactor matrix cof(F) = det(F) F^-T (row-major), defined for every F: dJ = cof(F) : dF.
template <typename Real>
FMPC_HD void cofactor3(const Real* F, Real* C) {
  C[0] = F[4] * F[8] - F[5] * F[7];
  C[1] = F[5] * F[6] - F[3] * F[8];
  C[2] = F[3] * F[7] - F[4] * F[6];
  C[3] = F[2] * F[7] - F[1] * F[8];
  C[4] = F[0] * F[8] - F[2] * F[6];
  C[5] = F[1] * F[6] - F[0] * F[7];
  C[6] = F[1] * F[5] - F[2] * F[4];
  C[7] = F[2] * F[3] - F[0] * F[5];
  C[8] = F[0] * F[4] - F[1] * F[3];
}

// det(F) - 1 without the cancellation of det(F) near 1: with H = F - I (exact for entries in [0.5, 2]),
// det(I + H) - 1 = tr H + (tr(H)^2 - tr(H^2)) / 2 + det H. A volume change of 1e-6 keeps its relative precision.
template <typename Real>
FMPC_HD Real determinant_minus_one(const Real* F) {
  const Real h0 = F[0] - Real(1), h4 = F[4] - Real(1), h8 = F[8] - Real(1);
  const Real first = h0 + h4 + h8;
  const Real second = h0 * h4 + h4 * h8 + h0 * h8 - F[1] * F[3] - F[5] * F[7] - F[2] * F[6];
  const Real third = h0 * (h4 * h8 - F[5] * F[7]) - F[1] * (F[3] * h8 - F[5] * F[6]) + F[2] * (F[3] * F[7] - h4 * F[6]);
  return first + second + third;
}

// A : B, the sum of the entries' products.
template <typename Real>
FMPC_HD Real contract3(const Real* A, const Real* B) {
  Real sum = Real(0);
  for (int i = 0; i < 9; ++i) sum += A[i] * B[i];
  return sum;
}

// Signed volume (b - a) x (c - a) . (d - a) / 6 of four corners given as [corner][axis].
template <typename Real>
FMPC_HD Real tetrahedron_volume(const Real x[4][3]) {
  Real e1[3], e2[3], e3[3], n[3];
  for (int i = 0; i < 3; ++i) {
    e1[i] = x[1][i] - x[0][i];
    e2[i] = x[2][i] - x[0][i];
    e3[i] = x[3][i] - x[0][i];
  }
  cross3(e1, e2, n);
  return dot3(n, e3) / Real(6);
}

// Shape-function gradients of a linear tetrahedron from the inverse rest edge matrix Dm^-1 (Dm's columns are
// X_1 - X_0, X_2 - X_0, X_3 - X_0): g_a is row a - 1 of Dm^-1 for a = 1..3 and g_0 = -(g_1 + g_2 + g_3).
template <typename Real>
FMPC_HD void shape_gradients(const Real* rest_inverse, Real g[4][3]) {
  for (int i = 0; i < 3; ++i) {
    g[1][i] = rest_inverse[i];
    g[2][i] = rest_inverse[3 + i];
    g[3][i] = rest_inverse[6 + i];
    g[0][i] = -(g[1][i] + g[2][i] + g[3][i]);
  }
}

// A gradient sum_a y_a g_a^T written as D Dm^-1 with D's columns y_a - y_0 (edge differences first: for positions
// this keeps the precision of nearby points far from the origin). Gives the deformation gradient F from positions and
// the velocity gradient L from velocities.
template <typename Real>
FMPC_HD void corner_gradient(const Real y[4][3], const Real* rest_inverse, Real* out) {
  Real d[9];
  for (int i = 0; i < 3; ++i)
    for (int a = 0; a < 3; ++a) d[3 * i + a] = y[a + 1][i] - y[0][i];
  multiply3(d, rest_inverse, out);
}

// Eigen-decomposition of a symmetric 3 x 3 matrix by cyclic Jacobi rotations (Golub & Van Loan, "Matrix
// Computations", section 8.5; the rotation formula of Numerical Recipes 11.1, which needs only sqrt and division).
// `a` is overwritten; eigenvalues in descending order, eigenvectors as the columns of `vectors`. At most 12 sweeps;
// the iteration converges quadratically and stops when the off-diagonal part is zero to the precision of Real.
template <typename Real>
FMPC_HD void symmetric_eigen3(Real* a, Real* eigenvalues, Real* vectors) {
  for (int i = 0; i < 9; ++i) vectors[i] = (i % 4 == 0) ? Real(1) : Real(0);
  for (int sweep = 0; sweep < 12; ++sweep) {
    const Real off = a[1] * a[1] + a[2] * a[2] + a[5] * a[5];
    const Real diagonal = a[0] * a[0] + a[4] * a[4] + a[8] * a[8];
    if (!(off > RealLimits<Real>::epsilon * RealLimits<Real>::epsilon * diagonal)) break;
    for (int pair = 0; pair < 3; ++pair) {
      const int p = pair == 2 ? 1 : 0, q = pair == 0 ? 1 : 2;
      const Real apq = a[3 * p + q];
      if (apq == Real(0)) continue;
      const Real theta = (a[3 * q + q] - a[3 * p + p]) / (Real(2) * apq);
      const Real magnitude = theta < Real(0) ? -theta : theta;
      // For |theta| beyond 1e18, theta^2 + 1 is theta^2 to every precision and would overflow in float.
      Real t = magnitude > Real(1e18) ? Real(0.5) / magnitude
                                      : Real(1) / (magnitude + square_root(magnitude * magnitude + Real(1)));
      if (theta < Real(0)) t = -t;
      const Real c = Real(1) / square_root(t * t + Real(1));
      const Real s = t * c;
      a[3 * p + p] -= t * apq;
      a[3 * q + q] += t * apq;
      a[3 * p + q] = a[3 * q + p] = Real(0);
      const int r = 3 - p - q;
      const Real arp = a[3 * r + p], arq = a[3 * r + q];
      a[3 * r + p] = a[3 * p + r] = c * arp - s * arq;
      a[3 * r + q] = a[3 * q + r] = s * arp + c * arq;
      for (int k = 0; k < 3; ++k) {
        const Real vkp = vectors[3 * k + p], vkq = vectors[3 * k + q];
        vectors[3 * k + p] = c * vkp - s * vkq;
        vectors[3 * k + q] = s * vkp + c * vkq;
      }
    }
  }
  for (int i = 0; i < 3; ++i) eigenvalues[i] = a[4 * i];
  // Descending order (three compare-and-swap steps, columns moved with their values).
  const int order[3][2] = {{0, 1}, {1, 2}, {0, 1}};
  for (const auto& pair : order) {
    const int i = pair[0], j = pair[1];
    if (eigenvalues[i] < eigenvalues[j]) {
      const Real value = eigenvalues[i];
      eigenvalues[i] = eigenvalues[j];
      eigenvalues[j] = value;
      for (int k = 0; k < 3; ++k) {
        const Real v = vectors[3 * k + i];
        vectors[3 * k + i] = vectors[3 * k + j];
        vectors[3 * k + j] = v;
      }
    }
  }
}

// The rotation R of F = R S, a proper rotation for every F (also inverted, flat or collapsed elements), and the
// principal stretches as R^T F sees them: stretch[0] >= stretch[1] >= |stretch[2]|, stretch[2] negative for an
// inverted element. From the right singular vectors v_i (eigenvectors of F^T F): u_1 = F v_1 / |F v_1|, u_2 the part
// of F v_2 orthogonal to u_1, normalised, u_3 = u_1 x u_2 and v_3 = v_1 x v_2, R = sum u_i v_i^T. A collapsed
// element (F v_1 = 0) gets R = I; a flat one (F v_2 parallel to u_1 within rounding) gets u_2 perpendicular to u_1
// along the coordinate axis u_1 is least aligned with.
// F scaled by an exact power of two so that its largest entry lies in [0.5, 1): F^T F neither underflows nor
// overflows whatever the element's scale, and the rotation (scale-invariant) is unchanged. Returns the exponent
// that undoes the scaling (0 for a zero or non-finite F, copied as it is).
template <typename Real>
FMPC_HD int normalised_copy(const Real* F, Real* out) {
  Real largest = Real(0);
  for (int i = 0; i < 9; ++i) {
    const Real magnitude = F[i] < Real(0) ? -F[i] : F[i];
    largest = magnitude > largest ? magnitude : largest;
  }
  int exponent = 0;
  if (largest > Real(0) && largest <= RealLimits<Real>::largest) fraction_and_exponent(largest, exponent);
  for (int i = 0; i < 9; ++i) out[i] = scale_by_power_of_two(F[i], -exponent);
  return exponent;
}

// Where `right` is non-null, the right singular vectors v_i are written as its columns (v_3 = v_1 x v_2, a proper
// rotation): F = U diag(stretch) V^T with U = R V, the inversion-aware SVD of Irving, Teran & Fedkiw 2004.
template <typename Real>
FMPC_HD void rotation_and_stretches_of_normalised(const Real* F, Real* R, Real* stretch, Real* right = nullptr);

template <typename Real>
FMPC_HD void rotation_and_stretches(const Real* unscaled, Real* R, Real* stretch, Real* right = nullptr) {
  Real F[9];
  const int exponent = normalised_copy(unscaled, F);
  rotation_and_stretches_of_normalised(F, R, stretch, right);
  for (int k = 0; k < 3; ++k) stretch[k] = scale_by_power_of_two(stretch[k], exponent);
}

// rotation_and_stretches for an F whose largest entry is about 1.
template <typename Real>
FMPC_HD void rotation_and_stretches_of_normalised(const Real* F, Real* R, Real* stretch, Real* right) {
  Real c[9], eigenvalues[3], v[9];
  multiply3_transposed_left(F, F, c);
  symmetric_eigen3(c, eigenvalues, v);
  const Real v1[3] = {v[0], v[3], v[6]}, v2[3] = {v[1], v[4], v[7]};
  Real v3[3];
  cross3(v1, v2, v3);
  if (right) {
    for (int i = 0; i < 3; ++i) {
      right[3 * i] = v1[i];
      right[3 * i + 1] = v2[i];
      right[3 * i + 2] = v3[i];
    }
  }
  Real u1[3], u2[3], u3[3];
  for (int i = 0; i < 3; ++i) {
    u1[i] = F[3 * i] * v1[0] + F[3 * i + 1] * v1[1] + F[3 * i + 2] * v1[2];
    u2[i] = F[3 * i] * v2[0] + F[3 * i + 1] * v2[1] + F[3 * i + 2] * v2[2];
  }
  const Real n1 = square_root(dot3(u1, u1));
  if (!(n1 > Real(0))) {
    for (int i = 0; i < 9; ++i) R[i] = (i % 4 == 0) ? Real(1) : Real(0);
    stretch[0] = stretch[1] = stretch[2] = Real(0);
    return;
  }
  for (int i = 0; i < 3; ++i) u1[i] /= n1;
  const Real along = dot3(u1, u2);
  for (int i = 0; i < 3; ++i) u2[i] -= along * u1[i];
  const Real n2 = square_root(dot3(u2, u2));
  if (n2 > Real(64) * RealLimits<Real>::epsilon * n1) {
    for (int i = 0; i < 3; ++i) u2[i] /= n2;
  } else {
    const Real m0 = u1[0] < Real(0) ? -u1[0] : u1[0], m1 = u1[1] < Real(0) ? -u1[1] : u1[1],
               m2 = u1[2] < Real(0) ? -u1[2] : u1[2];
    Real axis[3] = {Real(0), Real(0), Real(0)};
    axis[m0 <= m1 && m0 <= m2 ? 0 : m1 <= m2 ? 1 : 2] = Real(1);
    cross3(axis, u1, u2);
    const Real n = square_root(dot3(u2, u2));
    for (int i = 0; i < 3; ++i) u2[i] /= n;
  }
  cross3(u1, u2, u3);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R[3 * i + j] = u1[i] * v1[j] + u2[i] * v2[j] + u3[i] * v3[j];
  // R^T F v_i = stretch_i v_i: the stretches are u_i . F v_i.
  Real fv[3];
  for (int k = 0; k < 3; ++k) {
    const Real* vk = k == 0 ? v1 : k == 1 ? v2 : v3;
    const Real* uk = k == 0 ? u1 : k == 1 ? u2 : u3;
    for (int i = 0; i < 3; ++i) fv[i] = F[3 * i] * vk[0] + F[3 * i + 1] * vk[1] + F[3 * i + 2] * vk[2];
    stretch[k] = dot3(uk, fv);
  }
}

// The rotation R of the polar decomposition F = R S, as rotation_and_stretches gives it, by Higham's Newton
// iteration X <- (gamma X + X^-T / gamma) / 2 with Frobenius-norm scaling gamma = sqrt(|X^-1|_F / |X|_F) (N. J.
// Higham, "Computing the polar decomposition -- with applications", SIAM J. Sci. Stat. Comput. 7(4), 1986): about
// 3 iterations near the identity, against 3 to 4 Jacobi sweeps of divisions and square roots for the eigenvectors.
// It converges quadratically to the rotation for det F > 0; an inverted or nearly flat element (det F <= 1e-3 |F|^3
// / 3^(3/2), i.e. a singular value below about 1e-3 of the largest), or one that has not converged after 24
// iterations, takes rotation_and_stretches, which also handles them. Scaling stops once an iteration changes X by
// less than 1e-2 (it would only slow the final quadratic steps); the iteration stops when the change is below
// 64 epsilon |X|.
template <typename Real>
FMPC_HD void polar_rotation(const Real* unscaled, Real* R) {
  Real F[9];
  normalised_copy(unscaled, F);
  Real norm_squared = Real(0);
  for (int i = 0; i < 9; ++i) norm_squared += F[i] * F[i];
  const Real det = determinant3(F);
  // |F|_F^3 / 3^(3/2) >= |det F| for every F: the test is relative to the element's own scale.
  if (det > Real(1e-3) * norm_squared * square_root(norm_squared) / Real(5.196152422706632)) {
    Real X[9];
    for (int i = 0; i < 9; ++i) X[i] = F[i];
    bool scaled = true;
    for (int iteration = 0; iteration < 24; ++iteration) {
      // X^-T = cofactor(X) / det X.
      Real cofactor[9];
      cofactor3(X, cofactor);
      const Real detX = X[0] * cofactor[0] + X[1] * cofactor[1] + X[2] * cofactor[2];
      Real gamma = Real(1);
      if (scaled) {
        Real x2 = Real(0), c2 = Real(0);
        for (int i = 0; i < 9; ++i) {
          x2 += X[i] * X[i];
          c2 += cofactor[i] * cofactor[i];
        }
        // |X^-1|_F = |cofactor|_F / |det X|.
        gamma = square_root(square_root(c2 / x2) / detX);
      }
      const Real a = Real(0.5) * gamma, b = Real(0.5) / (gamma * detX);
      Real change = Real(0), size = Real(0);
      for (int i = 0; i < 9; ++i) {
        const Real next = a * X[i] + b * cofactor[i];
        change += (next - X[i]) * (next - X[i]);
        size += next * next;
        X[i] = next;
      }
      if (change < Real(1e-4) * size) scaled = false;
      if (change <= Real(64) * Real(64) * RealLimits<Real>::epsilon * RealLimits<Real>::epsilon * size) {
        for (int i = 0; i < 9; ++i) R[i] = X[i];
        return;
      }
    }
  }
  Real stretch[3];
  rotation_and_stretches_of_normalised(F, R, stretch);
}

// The strain a strain table looks up for an element: its principal strain (stretch - 1) of largest magnitude,
// with its sign (compression negative); ties go to the larger stretch.
template <typename Real>
FMPC_HD Real principal_strain_of_largest_magnitude(const Real* stretch) {
  Real best = stretch[0] - Real(1);
  for (int i = 1; i < 3; ++i) {
    const Real strain = stretch[i] - Real(1);
    if ((strain < Real(0) ? -strain : strain) > (best < Real(0) ? -best : best)) best = strain;
  }
  return best;
}

// Lame's parameters of an isotropic material: mu = E / (2 (1 + nu)), lambda = E nu / ((1 + nu)(1 - 2 nu)).
template <typename Real>
FMPC_HD void lame_parameters(Real youngs_modulus, Real poisson_ratio, Real& mu, Real& lambda) {
  mu = youngs_modulus / (Real(2) * (Real(1) + poisson_ratio));
  lambda = youngs_modulus * poisson_ratio / ((Real(1) + poisson_ratio) * (Real(1) - Real(2) * poisson_ratio));
}

// sigma = lambda tr(e) I + 2 mu e for a symmetric e (row-major 9).
template <typename Real>
FMPC_HD void linear_stress(const Real* e, Real mu, Real lambda, Real* sigma) {
  const Real trace = e[0] + e[4] + e[8];
  for (int i = 0; i < 9; ++i) sigma[i] = Real(2) * mu * e[i];
  sigma[0] += lambda * trace;
  sigma[4] += lambda * trace;
  sigma[8] += lambda * trace;
}

// sym(R^T G) - (identity ? I : 0).
template <typename Real>
FMPC_HD void corotated_symmetric_part(const Real* R, const Real* G, bool subtract_identity, Real* out) {
  Real m[9];
  multiply3_transposed_left(R, G, m);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out[3 * i + j] = Real(0.5) * (m[3 * i + j] + m[3 * j + i]);
  if (subtract_identity) {
    out[0] -= Real(1);
    out[4] -= Real(1);
    out[8] -= Real(1);
  }
}

// f_a = -V0 P g_a for a = 1..3 and f_0 = -(f_1 + f_2 + f_3) (the forces of one element sum to zero).
template <typename Real>
FMPC_HD void corner_forces_from_stress(const Real* P, const Real g[4][3], Real volume, Real force[4][3]) {
  for (int i = 0; i < 3; ++i) force[0][i] = Real(0);
  for (int a = 1; a < 4; ++a) {
    for (int i = 0; i < 3; ++i) {
      force[a][i] = -volume * (P[3 * i] * g[a][0] + P[3 * i + 1] * g[a][1] + P[3 * i + 2] * g[a][2]);
      force[0][i] -= force[a][i];
    }
  }
}

// ---- the gather: corner forces summed per vertex ------------------------------------------------------------------

// One corner's force, padded to four values: the element pass writes it with one aligned vector store and the gather
// reads it with one aligned load. With three scalar stores per corner (12 per element, each to its own 32-byte
// sector) the element pass was bound by L2 throughput (94% of it at 120^3 on an H100, ncu; docs/performance.md).
template <typename Real>
struct alignas(4 * sizeof(Real)) CornerForce {
  Real x, y, z, unused;
};

// The corners of the elements at each vertex, as CSR: entries corner[offset[v] .. offset[v+1]) are 4 e + c (element
// e's corner c), increasing; force holds one CornerForce per entry in the same order (vertex-major: force[k] is entry
// k's, written by the element pass through ElementTermView::corner_slot), so a vertex reads one contiguous run.
template <typename Real>
struct CornerForceView {
  const int* offset;
  const int* corner;
  const CornerForce<Real>* force;
};

// Sum of the corner forces at vertex v, in CSR order (deterministic; no atomics).
template <typename Real>
FMPC_HD void gather_corner_force(int v, const CornerForceView<Real>& view, Real& fx, Real& fy, Real& fz) {
  Real sx = Real(0), sy = Real(0), sz = Real(0);
  FMPC_UNROLL_GATHER
  for (int k = view.offset[v]; k < view.offset[v + 1]; ++k) {
    const CornerForce<Real> f = view.force[k];
    sx += f.x;
    sy += f.y;
    sz += f.z;
  }
  fx = sx;
  fy = sy;
  fz = sz;
}

// ---- outputs -----------------------------------------------------------------------------------------------------

// Von Mises equivalent stress of a symmetric stress (Pa): sqrt(((s11 - s22)^2 + (s22 - s33)^2 + (s33 - s11)^2) / 2
// + 3 (s12^2 + s23^2 + s13^2)). Invariant under rotation, so the co-rotated stress gives the value of R sigma R^T.
FMPC_HD double von_mises_stress(const double* s) {
  const double a = s[0] - s[4], b = s[4] - s[8], c = s[8] - s[0];
  return square_root(0.5 * (a * a + b * b + c * c) + 3.0 * (s[1] * s[1] + s[5] * s[5] + s[2] * s[2]));
}

}  // namespace fmpc::kernels

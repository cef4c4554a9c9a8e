#pragma once
// Membership functions, t-norms, s-norms and hedges: the one definition shared by the reference interpreter, the
// CPU loops, the CUDA kernels and generated code. Formulas are MATLAB's (Fuzzy Logic Toolbox trimf.m ... pimf.m
// and its C core fis.c, which MATLAB's evalfis runs); docs/numerics.md lists every edge case and where Octave's
// fuzzy-logic-toolkit or fuzzylite differ.
//
// Conventions every function keeps:
// - NaN in, NaN out: a NaN input (or grade) never becomes a silent number (comparisons alone would turn it into 0).
// - x = +-inf gives the limit of the MF (e.g. sigmf [0 c] stays 0.5, gbellmf with b > 0 goes to 0).
// - Only functions that exist on the device: the fmpc_* wrappers below pick expf/exp etc. by type, so float code
//   never promotes to double and double code never truncates.
#include <math.h>

#include "kernels/fmpc_hd.h"
#include "kernels/fuzzy_kinds.h"

namespace fmpc {

FMPC_HD float fmpc_exp(float x) { return ::expf(x); }
FMPC_HD double fmpc_exp(double x) { return ::exp(x); }
FMPC_HD float fmpc_pow(float x, float y) { return ::powf(x, y); }
FMPC_HD double fmpc_pow(double x, double y) { return ::pow(x, y); }
FMPC_HD float fmpc_fabs(float x) { return ::fabsf(x); }
FMPC_HD double fmpc_fabs(double x) { return ::fabs(x); }

// x != x is the NaN test that works for float and double on host and device alike (no -ffast-math in fmpc).
template <typename T>
FMPC_HD bool fmpc_is_nan(T x) {
  return x != x;  // NOLINT(misc-redundant-expression)
}

template <typename T>
FMPC_HD T fmpc_quiet_nan() {
  return T(0) / T(0);
}

namespace mf {

// trimf [a b c] (MATLAB trimf.m / fisTriangleMf): 0 outside (a, c), 1 at x == b even when a == b or b == c.
template <typename T>
FMPC_HD T triangle(T x, T a, T b, T c) {
  if (x == b) return T(1);
  if (x <= a || x >= c) return T(0);
  if (x < b) return (x - a) / (b - a);  // a < x < b, so a != b
  return (c - x) / (c - b);             // b < x < c, so b != c
}

// trapmf [a b c d] (MATLAB trapmf.m): min of a rising edge (1 from b on) and a falling edge (1 up to c). With
// b > c the two edges overlap and the top is below 1, as in MATLAB.
template <typename T>
FMPC_HD T trapezoid(T x, T a, T b, T c, T d) {
  T rising;
  if (x >= b) rising = T(1);
  else if (x < a) rising = T(0);
  else rising = (x - a) / (b - a);  // a <= x < b, so a != b
  T falling;
  if (x <= c) falling = T(1);
  else if (x > d) falling = T(0);
  else falling = (d - x) / (d - c);  // c < x <= d, so c != d
  return rising < falling ? rising : falling;
}

// gaussmf [sigma c]: exp(-(x - c)^2 / (2 sigma^2)).
template <typename T>
FMPC_HD T gaussian(T x, T sigma, T c) {
  const T t = (x - c) / sigma;
  return fmpc_exp(-t * t / T(2));
}

// gauss2mf [sigma1 c1 sigma2 c2]: left Gaussian below c1, right Gaussian above c2, 1 between (MATLAB gauss2mf.m:
// the two factors multiply, so with c1 > c2 the top is below 1).
template <typename T>
FMPC_HD T gaussian2(T x, T sigma1, T c1, T sigma2, T c2) {
  const T left = x <= c1 ? gaussian(x, sigma1, c1) : T(1);
  const T right = x >= c2 ? gaussian(x, sigma2, c2) : T(1);
  return left * right;
}

// gbellmf [a b c]: 1 / (1 + ((x - c)/a)^(2b)), computed as MATLAB does, ((x-c)/a)^2 raised to b, which gives
// MATLAB's 0.5 at x == c for b == 0 and 0 there for b < 0 (pow(0, 0) == 1, pow(0, negative) == inf).
template <typename T>
FMPC_HD T generalized_bell(T x, T a, T b, T c) {
  const T t = (x - c) / a;
  return T(1) / (T(1) + fmpc_pow(t * t, b));
}

// sigmf [a c]: 1 / (1 + exp(-a (x - c))). a == 0 is the constant 0.5, also at x = +-inf where a (x - c) is NaN.
template <typename T>
FMPC_HD T sigmoid(T x, T a, T c) {
  if (a == T(0)) return T(0.5);
  return T(1) / (T(1) + fmpc_exp(-a * (x - c)));
}

// dsigmf [a1 c1 a2 c2]: |sigmf(a1, c1) - sigmf(a2, c2)| (MATLAB dsigmf.m and fis.c take the absolute value).
template <typename T>
FMPC_HD T difference_sigmoid(T x, T a1, T c1, T a2, T c2) {
  return fmpc_fabs(sigmoid(x, a1, c1) - sigmoid(x, a2, c2));
}

// psigmf [a1 c1 a2 c2]: sigmf(a1, c1) * sigmf(a2, c2).
template <typename T>
FMPC_HD T product_sigmoid(T x, T a1, T c1, T a2, T c2) {
  return sigmoid(x, a1, c1) * sigmoid(x, a2, c2);
}

// smf [a b]: quadratic spline from 0 at a to 1 at b, 0.5 at (a+b)/2. a >= b is MATLAB's step x >= (a+b)/2.
template <typename T>
FMPC_HD T s_shape(T x, T a, T b) {
  const T middle = (a + b) / T(2);
  if (a >= b) return x >= middle ? T(1) : T(0);
  if (x <= a) return T(0);
  if (x <= middle) {
    const T t = (x - a) / (b - a);
    return T(2) * t * t;
  }
  if (x <= b) {
    const T t = (b - x) / (b - a);
    return T(1) - T(2) * t * t;
  }
  return T(1);
}

// zmf [a b]: mirror of smf, 1 at a to 0 at b. a >= b is MATLAB's step x <= (a+b)/2.
template <typename T>
FMPC_HD T z_shape(T x, T a, T b) {
  const T middle = (a + b) / T(2);
  if (a >= b) return x <= middle ? T(1) : T(0);
  if (x <= a) return T(1);
  if (x <= middle) {
    const T t = (x - a) / (b - a);
    return T(1) - T(2) * t * t;
  }
  if (x <= b) {
    const T t = (b - x) / (b - a);
    return T(2) * t * t;
  }
  return T(0);
}

// pimf [a b c d]: smf(a, b) * zmf(c, d).
template <typename T>
FMPC_HD T pi_shape(T x, T a, T b, T c, T d) {
  return s_shape(x, a, b) * z_shape(x, c, d);
}

// linsmf [a b] (MATLAB R2022a): 0 below a, linear to 1 at b; a == b is the step 0 for x < a, 1 for x >= a.
template <typename T>
FMPC_HD T linear_s(T x, T a, T b) {
  if (a == b) return x < a ? T(0) : T(1);
  if (x < a) return T(0);
  if (x > b) return T(1);
  return (x - a) / (b - a);
}

// linzmf [a b] (MATLAB R2022a): 1 below a, linear to 0 at b; a == b is the step 1 for x < a, 0 for x >= a.
template <typename T>
FMPC_HD T linear_z(T x, T a, T b) {
  if (a == b) return x < a ? T(1) : T(0);
  if (x < a) return T(1);
  if (x > b) return T(0);
  return (b - x) / (b - a);
}

}  // namespace mf

// Grade of x in a type-1 input MF. `params` in MATLAB order (kernels/fuzzy_kinds.h). Constant and Linear are
// Sugeno output functions, not grades of x: they give NaN here (see sugeno_output_value in the interpreter).
template <typename T>
FMPC_HD T membership(MfKind kind, const T* params, T x) {
  if (fmpc_is_nan(x)) return x;
  const T* p = params;
  switch (kind) {
    case MfKind::Triangle: return mf::triangle(x, p[0], p[1], p[2]);
    case MfKind::Trapezoid: return mf::trapezoid(x, p[0], p[1], p[2], p[3]);
    case MfKind::Gaussian: return mf::gaussian(x, p[0], p[1]);
    case MfKind::Gaussian2: return mf::gaussian2(x, p[0], p[1], p[2], p[3]);
    case MfKind::GeneralizedBell: return mf::generalized_bell(x, p[0], p[1], p[2]);
    case MfKind::Sigmoid: return mf::sigmoid(x, p[0], p[1]);
    case MfKind::DifferenceSigmoid: return mf::difference_sigmoid(x, p[0], p[1], p[2], p[3]);
    case MfKind::ProductSigmoid: return mf::product_sigmoid(x, p[0], p[1], p[2], p[3]);
    case MfKind::ZShape: return mf::z_shape(x, p[0], p[1]);
    case MfKind::SShape: return mf::s_shape(x, p[0], p[1]);
    case MfKind::PiShape: return mf::pi_shape(x, p[0], p[1], p[2], p[3]);
    case MfKind::LinearS: return mf::linear_s(x, p[0], p[1]);
    case MfKind::LinearZ: return mf::linear_z(x, p[0], p[1]);
    case MfKind::Constant:
    case MfKind::Linear: return fmpc_quiet_nan<T>();
  }
  return fmpc_quiet_nan<T>();
}

// Hedges are powers of the grade (Zadeh 1972; Octave evalmf: y .^ hedge). Exponent 1 returns mu unchanged.
template <typename T>
FMPC_HD T apply_hedge(T mu, T exponent) {
  if (exponent == T(1)) return mu;
  return fmpc_pow(mu, exponent);
}

// Standard fuzzy complement, applied after the hedge (MATLAB, Octave).
template <typename T>
FMPC_HD T fuzzy_not(T mu) {
  return T(1) - mu;
}

// min / max that propagate NaN (fmin, fmax and a plain comparison would drop it).
template <typename T>
FMPC_HD T nan_min(T a, T b) {
  if (fmpc_is_nan(a)) return a;
  if (fmpc_is_nan(b)) return b;
  return a < b ? a : b;
}
template <typename T>
FMPC_HD T nan_max(T a, T b) {
  if (fmpc_is_nan(a)) return a;
  if (fmpc_is_nan(b)) return b;
  return a > b ? a : b;
}

// AND, implication. Einstein product x y / (2 - (x + y - x y)) (Octave einstein_product.m).
template <typename T>
FMPC_HD T tnorm(TNorm norm, T a, T b) {
  switch (norm) {
    case TNorm::Minimum: return nan_min(a, b);
    case TNorm::Product: return a * b;
    case TNorm::EinsteinProduct: return (a * b) / (T(2) - (a + b - a * b));
  }
  return fmpc_quiet_nan<T>();
}

// OR, aggregation. MATLAB's `sum` is the plain sum (fis.c fisSum), not clipped to 1; probor x + y - x y;
// Einstein sum (x + y) / (1 + x y) (Octave einstein_sum.m).
template <typename T>
FMPC_HD T snorm(SNorm norm, T a, T b) {
  switch (norm) {
    case SNorm::Maximum: return nan_max(a, b);
    case SNorm::ProbabilisticSum: return a + b - a * b;
    case SNorm::Sum: return a + b;
    case SNorm::EinsteinSum: return (a + b) / (T(1) + a * b);
  }
  return fmpc_quiet_nan<T>();
}

// Identity elements: folding a rule's clauses or an output's rules starts here (MATLAB's don't-care inputs are 1
// under AND and 0 under OR, which are these identities).
template <typename T>
FMPC_HD T tnorm_identity() {
  return T(1);
}
template <typename T>
FMPC_HD T snorm_identity() {
  return T(0);
}

}  // namespace fmpc

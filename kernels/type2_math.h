#pragma once
// Interval type-2 membership: the [lower, upper] grade of x in a term with a footprint of uncertainty, and the
// t-norms, s-norms, hedges and complement on such intervals. Shared by the reference interpreter, the CUDA
// kernels and generated code (FMPC_HD); docs/numerics.md ("Interval type-2") gives the sources.
//
// Footprints (Mendel, "Uncertain Rule-Based Fuzzy Systems", 2nd ed. 2017, ch. 6; MATLAB fismftype2):
//   UncertainMean  gauss, mean in [m1, m2], sd s:   upper = N(m1,s) left of m1, 1 on [m1, m2], N(m2,s) right of m2;
//                                                   lower = N(m2,s) up to (m1+m2)/2, N(m1,s) beyond.
//   UncertainSd    gauss, mean m, sd in [s1, s2]:   upper = N(m,s2), lower = N(m,s1).
//   ExplicitLower  any upper MF, any lower MF:      [min(l, u), max(l, u)] (lint warns where l > u).
//   ScaleLag       MATLAB LowerScale s, LowerLag g: upper = mf(x); lower = s * max(0, (mf(x) - g) / (1 - g)), so
//                  the lower MF starts rising where the upper one reaches g and peaks at s (for the piecewise
//                  linear families this is a triangle/trapezoid with the feet moved in, as MATLAB draws them).
//   IntervalValue  a Sugeno consequent constant in [c1, c2]: not a grade of x (NaN here).
// Every interval operation below is the type-1 operation applied to each end: all of fmpc's t-norms, s-norms and
// hedges are nondecreasing in each argument on [0, 1], so the ends map to the ends; the complement swaps them.
#include "kernels/fmpc_hd.h"
#include "kernels/fuzzy_kinds.h"
#include "kernels/fuzzy_math.h"

namespace fmpc {

// Numeric values are part of the compiled-artefact format: append, never renumber.
enum class FootprintKind : int {
  None = 0,  // zero width: upper == lower == the type-1 MF
  UncertainMean = 1,
  UncertainSd = 2,
  ExplicitLower = 3,
  ScaleLag = 4,
  IntervalValue = 5,
};

template <typename T>
struct GradeInterval {
  T lower;
  T upper;
};

// [lower, upper] grade of x. `params` are the term's MF in MATLAB order (for UncertainMean params[0] is the sd,
// for UncertainSd params[1] the mean); `first`/`second` the footprint's numbers (m1 m2 | sd1 sd2 | scale lag);
// `lower_kind`/`lower_params` the explicit lower MF (ExplicitLower only; may be null otherwise).
template <typename T>
FMPC_HD GradeInterval<T> footprint_membership(MfKind kind, const T* params, FootprintKind footprint, T first,
                                              T second, MfKind lower_kind, const T* lower_params, T x) {
  if (fmpc_is_nan(x)) return GradeInterval<T>{x, x};
  switch (footprint) {
    case FootprintKind::None: {
      const T mu = membership(kind, params, x);
      return GradeInterval<T>{mu, mu};
    }
    case FootprintKind::UncertainMean: {
      const T sd = params[0];
      T upper = T(1);
      if (x < first) upper = mf::gaussian(x, sd, first);
      else if (x > second) upper = mf::gaussian(x, sd, second);
      const T lower = x <= (first + second) / T(2) ? mf::gaussian(x, sd, second) : mf::gaussian(x, sd, first);
      return GradeInterval<T>{lower, upper};
    }
    case FootprintKind::UncertainSd: {
      const T mean = params[1];
      return GradeInterval<T>{mf::gaussian(x, first, mean), mf::gaussian(x, second, mean)};
    }
    case FootprintKind::ExplicitLower: {
      const T upper = membership(kind, params, x);
      const T lower = membership(lower_kind, lower_params, x);
      return GradeInterval<T>{nan_min(lower, upper), nan_max(lower, upper)};
    }
    case FootprintKind::ScaleLag: {
      const T upper = membership(kind, params, x);
      T raised = (upper - second) / (T(1) - second);
      if (raised < T(0)) raised = T(0);
      return GradeInterval<T>{first * raised, upper};
    }
    case FootprintKind::IntervalValue: break;
  }
  return GradeInterval<T>{fmpc_quiet_nan<T>(), fmpc_quiet_nan<T>()};
}

template <typename T>
FMPC_HD GradeInterval<T> interval_tnorm(TNorm norm, GradeInterval<T> a, GradeInterval<T> b) {
  return GradeInterval<T>{tnorm(norm, a.lower, b.lower), tnorm(norm, a.upper, b.upper)};
}

template <typename T>
FMPC_HD GradeInterval<T> interval_snorm(SNorm norm, GradeInterval<T> a, GradeInterval<T> b) {
  return GradeInterval<T>{snorm(norm, a.lower, b.lower), snorm(norm, a.upper, b.upper)};
}

template <typename T>
FMPC_HD GradeInterval<T> interval_hedge(GradeInterval<T> mu, T exponent) {
  return GradeInterval<T>{apply_hedge(mu.lower, exponent), apply_hedge(mu.upper, exponent)};
}

// not [l, u] = [1 - u, 1 - l].
template <typename T>
FMPC_HD GradeInterval<T> interval_not(GradeInterval<T> mu) {
  return GradeInterval<T>{fuzzy_not(mu.upper), fuzzy_not(mu.lower)};
}

}  // namespace fmpc

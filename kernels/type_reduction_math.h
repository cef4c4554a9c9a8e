#pragma once
// Type reduction of interval type-2 fuzzy sets: from points x_1 <= ... <= x_N with interval weights
// [lower_i, upper_i] (rule firing intervals for Sugeno/centre-of-sets, or sampled membership intervals for a
// Mamdani centroid) to the interval [yl, yr] of centroids of all embedded type-1 sets.
//
//   yl = min_k ( sum_{i<=k} x_i upper_i + sum_{i>k} x_i lower_i ) / ( sum_{i<=k} upper_i + sum_{i>k} lower_i )
//   yr = max_k ( sum_{i<=k} x_i lower_i + sum_{i>k} x_i upper_i ) / ( sum_{i<=k} lower_i + sum_{i>k} upper_i )
//
// (Karnik & Mendel 2001, "Centroid of a type-2 fuzzy set", Inf. Sci. 132; Mendel, "Uncertain Rule-Based Fuzzy
// Systems", 2nd ed. 2017, ch. 7.) k is the switch point: the number of points that take the upper weight on the
// left (yl) or the lower weight on the left (yr). Every algorithm here returns the same interval as
// exhaustive_switch_search to rounding; they differ in cost. Nie-Tan is a closed-form approximation of the crisp
// midpoint, not of the interval.
//
// Preconditions for all: x sorted ascending, 0 <= lower_i <= upper_i. When every weight is zero the result is
// NaN with fired == false: the caller applies its no-rule-fired policy.
#include "kernels/fmpc_hd.h"

namespace fmpc {

enum class TypeReduction : int { KarnikMendel = 0, EnhancedKarnikMendel = 1, Eiasc = 2, NieTan = 3 };

template <typename T>
struct TypeReducedInterval {
  T left;   // yl
  T right;  // yr
  int left_switch;   // k for yl: points 1..k take upper weights (0 <= k <= N)
  int right_switch;  // k for yr: points 1..k take lower weights
  int left_iterations;
  int right_iterations;
  bool fired;  // false when all weights are zero (left = right = NaN)
};

namespace type_reduction_detail {

template <typename T>
FMPC_HD T quiet_nan() {
  return T(0) / T(0);
}

// Centroid with points 1..k weighted by `first` and the rest by `second`.
template <typename T>
FMPC_HD T switched_centroid(const T* x, const T* first, const T* second, int n, int k) {
  T numerator = T(0), denominator = T(0);
  for (int i = 0; i < n; ++i) {
    const T w = i < k ? first[i] : second[i];
    numerator += x[i] * w;
    denominator += w;
  }
  return numerator / denominator;
}

// Like switched_centroid, but when every weight is zero at k (0/0) moves k by `step` until one is not: for yl
// (step +1) more points take the upper weight, for yr (step -1) fewer take the lower one. Terminates because at
// the far end every point has its upper weight and some upper weight is positive (checked by the caller).
template <typename T>
FMPC_HD T switched_centroid_defined(const T* x, const T* first, const T* second, int n, int& k, int step) {
  for (;;) {
    T numerator = T(0), denominator = T(0);
    for (int i = 0; i < n; ++i) {
      const T w = i < k ? first[i] : second[i];
      numerator += x[i] * w;
      denominator += w;
    }
    if (denominator > T(0) || k + step < 0 || k + step > n) return numerator / denominator;
    k += step;
  }
}

template <typename T>
FMPC_HD bool any_weight(const T* upper, int n) {
  for (int i = 0; i < n; ++i)
    if (upper[i] > T(0)) return true;
  return false;
}

// The switch point for `y`: the number of points with x_i <= y (KM step 2).
template <typename T>
FMPC_HD int switch_point(const T* x, int n, T y) {
  int k = 0;
  while (k < n && x[k] <= y) ++k;
  return k;
}

// The centroid with weights lower_i + upper_i: the Nie-Tan output and the Karnik-Mendel starting point (the
// centroid of the mid weights; halving every weight leaves a centroid unchanged, so it is the same number).
template <typename T>
FMPC_HD T summed_weight_centroid(const T* x, const T* lower, const T* upper, int n) {
  T numerator = T(0), denominator = T(0);
  for (int i = 0; i < n; ++i) {
    numerator += x[i] * (lower[i] + upper[i]);
    denominator += lower[i] + upper[i];
  }
  return numerator / denominator;
}

// Records one endpoint: side 0 is yl, side 1 is yr.
template <typename T>
FMPC_HD void store_endpoint(TypeReducedInterval<T>& r, int side, T y, int switch_point, int iterations) {
  if (side == 0) {
    r.left = y;
    r.left_switch = switch_point;
    r.left_iterations = iterations;
  } else {
    r.right = y;
    r.right_switch = switch_point;
    r.right_iterations = iterations;
  }
}

}  // namespace type_reduction_detail

// Reference: tries every switch point, O(N^2). Used by the tests and for tiny N.
template <typename T>
FMPC_HD TypeReducedInterval<T> exhaustive_switch_search(const T* x, const T* lower, const T* upper, int n) {
  using namespace type_reduction_detail;
  TypeReducedInterval<T> r{quiet_nan<T>(), quiet_nan<T>(), 0, 0, n + 1, n + 1, false};
  if (!any_weight(upper, n)) return r;
  r.fired = true;
  for (int k = 0; k <= n; ++k) {
    const T yl = switched_centroid(x, upper, lower, n, k);
    const T yr = switched_centroid(x, lower, upper, n, k);
    // A switch point whose weights are all zero gives 0/0; it cannot be the extremum.
    if (yl == yl && !(r.left <= yl)) {
      r.left = yl;
      r.left_switch = k;
    }
    if (yr == yr && !(r.right >= yr)) {
      r.right = yr;
      r.right_switch = k;
    }
  }
  return r;
}

// Karnik-Mendel iterations (Karnik & Mendel 2001): start from the centroid of the mid weights, switch at the
// current estimate, repeat until the switch point stops moving. Converges in at most N iterations.
template <typename T>
FMPC_HD TypeReducedInterval<T> karnik_mendel(const T* x, const T* lower, const T* upper, int n) {
  using namespace type_reduction_detail;
  TypeReducedInterval<T> r{quiet_nan<T>(), quiet_nan<T>(), 0, 0, 0, 0, false};
  if (!any_weight(upper, n)) return r;
  r.fired = true;
  const T start = summed_weight_centroid(x, lower, upper, n);
  for (int side = 0; side < 2; ++side) {
    const T* first = side == 0 ? upper : lower;
    const T* second = side == 0 ? lower : upper;
    T y = start;
    int k = switch_point(x, n, y);
    int iterations = 0;
    for (;;) {
      ++iterations;
      y = switched_centroid_defined(x, first, second, n, k, side == 0 ? 1 : -1);
      const int next = switch_point(x, n, y);
      if (next == k || iterations > n + 1) break;
      k = next;
    }
    store_endpoint(r, side, y, k, iterations);
  }
  return r;
}

// Enhanced Karnik-Mendel (Wu & Mendel 2009, "Enhanced Karnik-Mendel algorithms", IEEE TFS 17(4)): better start
// (k = round(N/2.4) for yl, round(N/1.7) for yr) and sums updated incrementally over the points between the old and
// new switch points.
template <typename T>
FMPC_HD TypeReducedInterval<T> enhanced_karnik_mendel(const T* x, const T* lower, const T* upper, int n) {
  using namespace type_reduction_detail;
  TypeReducedInterval<T> r{quiet_nan<T>(), quiet_nan<T>(), 0, 0, 0, 0, false};
  if (!any_weight(upper, n)) return r;
  r.fired = true;
  for (int side = 0; side < 2; ++side) {
    const T* first = side == 0 ? upper : lower;
    const T* second = side == 0 ? lower : upper;
    int k = static_cast<int>(static_cast<double>(n) / (side == 0 ? 2.4 : 1.7) + 0.5);
    T a = T(0), b = T(0);
    for (int i = 0; i < n; ++i) {
      const T w = i < k ? first[i] : second[i];
      a += x[i] * w;
      b += w;
    }
    T total = T(0);
    for (int i = 0; i < n; ++i) total += upper[i];
    int iterations = 0;
    // All weights on one side of k may be zero (0/0): fall back to the plain KM step from a valid start.
    if (!(b > T(0))) {
      const TypeReducedInterval<T> km = karnik_mendel(x, lower, upper, n);
      if (side == 0)
        store_endpoint(r, 0, km.left, km.left_switch, km.left_iterations);
      else
        store_endpoint(r, 1, km.right, km.right_switch, km.right_iterations);
      continue;
    }
    T y = a / b;
    for (;;) {
      ++iterations;
      const int next = switch_point(x, n, y);
      if (next == k || iterations > n + 1) break;
      // Points moving across the switch change weight from `second` to `first` (or back).
      const T s = next > k ? T(1) : T(-1);
      const int lo = next > k ? k : next, hi = next > k ? next : k;
      for (int i = lo; i < hi; ++i) {
        a += s * x[i] * (first[i] - second[i]);
        b += s * (first[i] - second[i]);
      }
      k = next;
      // Incremental sums lose everything to cancellation when almost no weight remains: recompute them, and if
      // no weight is left at all, let plain KM settle the switch point.
      if (!(b > T(1e-6) * total)) {
        a = T(0), b = T(0);
        for (int i = 0; i < n; ++i) {
          const T w = i < k ? first[i] : second[i];
          a += x[i] * w;
          b += w;
        }
      }
      if (!(b > T(0))) {
        const TypeReducedInterval<T> km = karnik_mendel(x, lower, upper, n);
        y = side == 0 ? km.left : km.right;
        k = side == 0 ? km.left_switch : km.right_switch;
        break;
      }
      y = a / b;
    }
    store_endpoint(r, side, y, k, iterations);
  }
  return r;
}

// Enhanced Iterative Algorithm with Stop Condition (Wu & Nie 2011, "Comparison and practical implementation of
// type-reduction algorithms for type-2 fuzzy sets and systems", FUZZ-IEEE): start with every point at its lower
// (yl) weight and move points to the upper weight one at a time from the left until the centroid stops passing
// them; mirror for yr from the right.
template <typename T>
FMPC_HD TypeReducedInterval<T> eiasc(const T* x, const T* lower, const T* upper, int n) {
  using namespace type_reduction_detail;
  TypeReducedInterval<T> r{quiet_nan<T>(), quiet_nan<T>(), 0, 0, 0, 0, false};
  if (!any_weight(upper, n)) return r;
  r.fired = true;
  T a0 = T(0), b0 = T(0);
  for (int i = 0; i < n; ++i) {
    a0 += x[i] * lower[i];
    b0 += lower[i];
  }
  {
    T a = a0, b = b0, y = T(0);
    int k = 0, iterations = 0;
    while (k < n) {
      a += x[k] * (upper[k] - lower[k]);
      b += upper[k] - lower[k];
      ++k;
      ++iterations;
      if (!(b > T(0))) continue;  // nothing weighs yet: keep moving right
      y = a / b;
      if (k == n || y <= x[k]) break;
    }
    r.left = y;
    r.left_switch = k;
    r.left_iterations = iterations;
  }
  {
    T a = a0, b = b0, y = T(0);
    int k = n, iterations = 0;
    while (k > 0) {
      a += x[k - 1] * (upper[k - 1] - lower[k - 1]);
      b += upper[k - 1] - lower[k - 1];
      --k;
      ++iterations;
      if (!(b > T(0))) continue;
      y = a / b;
      if (k == 0 || y >= x[k - 1]) break;
    }
    r.right = y;
    r.right_switch = k;
    r.right_iterations = iterations;
  }
  return r;
}

// Nie & Tan 2008 ("Towards an efficient type-reduction method for interval type-2 fuzzy logic systems",
// FUZZ-IEEE): the centroid of the average of the upper and lower weights. Closed form; an approximation of the
// KM midpoint (the tests measure how close). Returned as a degenerate interval [y, y].
template <typename T>
FMPC_HD TypeReducedInterval<T> nie_tan(const T* x, const T* lower, const T* upper, int n) {
  using namespace type_reduction_detail;
  TypeReducedInterval<T> r{quiet_nan<T>(), quiet_nan<T>(), 0, 0, 1, 1, false};
  if (!any_weight(upper, n)) return r;
  r.fired = true;
  r.left = r.right = summed_weight_centroid(x, lower, upper, n);
  return r;
}

template <typename T>
FMPC_HD TypeReducedInterval<T> reduce_type(TypeReduction method, const T* x, const T* lower, const T* upper, int n) {
  switch (method) {
    case TypeReduction::KarnikMendel: return karnik_mendel(x, lower, upper, n);
    case TypeReduction::EnhancedKarnikMendel: return enhanced_karnik_mendel(x, lower, upper, n);
    case TypeReduction::Eiasc: return eiasc(x, lower, upper, n);
    case TypeReduction::NieTan: return nie_tan(x, lower, upper, n);
  }
  return karnik_mendel(x, lower, upper, n);
}

}  // namespace fmpc

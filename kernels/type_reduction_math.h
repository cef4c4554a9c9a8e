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
// left (yl) or the lower weight on the left (yr). KM, EKM and EIASC return the interval of
// exhaustive_switch_search to rounding (tests/unit/type_reduction_test.cpp holds them to 1e-12 of the range
// against an exhaustive search in long double); they differ in cost. Nie-Tan is a closed-form approximation of the
// crisp midpoint, not of the interval.
//
// Rounding. KM's step "k = the number of points left of the centroid y" is taken with y rounded. Where a point
// lies within the rounding error of y (a computed y can equal a sample exactly, e.g. when almost all the weight
// sits on the last sample and the other weights are 1e-25), comparing x_i with the rounded y can put the point
// on the wrong side; the next centroid then jumps far away and the iteration cycles. Here a point within the
// rounding bound of y is placed by the sign of sum_j (x_i - x_j) w_j, which is the sign of x_i - y for the exact
// centroid y of the current weights w (no cancellation between x_i and y), and a point exactly at y keeps its
// side. Besides, each accepted step must improve the endpoint strictly (y decreases for yl, increases for yr, as
// it does in exact arithmetic: Mendel 2017, sec. 7.3), so no switch point is visited twice and the iteration ends
// within N + 1 steps; a step that would not improve it only moves the end by rounding and is not taken.
// Reaching the cap of N + 2 steps is therefore a bug: the result is NaN with iteration_cap_hit set, never a
// number. Weights below the normal range (subnormal sums) are scaled by a power of two, which is exact, so that
// products with x keep their precision.
//
// Preconditions for all: x sorted ascending and finite, 0 <= lower_i <= upper_i finite. When every weight is
// zero the result is NaN with fired == false: the caller applies its no-rule-fired policy.
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
  // KM or EKM reached its iteration cap (an fmpc bug, see above): left = right = NaN. Callers report an internal
  // error (the interpreter throws; generated code sets kFlagInternalError).
  bool iteration_cap_hit;
};

namespace type_reduction_detail {

template <typename T>
FMPC_HD T quiet_nan() {
  return T(0) / T(0);
}

// Per-type constants: the machine epsilon, the sum below which products x * w may have lost bits to the subnormal
// range (2^(mantissa bits + 1) times the smallest normal number), and the power of two that lifts such weights.
template <typename T>
struct Limits;
template <>
struct Limits<double> {
  static FMPC_HD double epsilon() { return 0x1p-52; }
  static FMPC_HD double tiny_sum() { return 0x1p-968; }
  static FMPC_HD double lift() { return 0x1p600; }
};
template <>
struct Limits<float> {
  static FMPC_HD float epsilon() { return 0x1p-23f; }
  static FMPC_HD float tiny_sum() { return 0x1p-101f; }
  static FMPC_HD float lift() { return 0x1p64f; }
};

template <typename T>
FMPC_HD T magnitude(T v) {
  return v < T(0) ? -v : v;
}

// The weights of one embedded set: points 0..k-1 weighted by `first`, the rest by `second`, all times `scale`
// (1, or Limits::lift() where the weights are subnormal).
template <typename T>
struct EmbeddedSet {
  const T* x;
  const T* first;
  const T* second;
  int n;
  int k;
  T scale;
  FMPC_HD T weight(int i) const { return (i < k ? first[i] : second[i]) * scale; }
};

// The middle of the points: centroids are summed as origin + sum (x_i - origin) w_i / sum w_i, so that their
// rounding error is relative to the points' spread, not to their distance from zero (points at 1e6 +- 1e-3).
template <typename T>
FMPC_HD T points_origin(const T* x, int n) {
  return n > 0 ? x[0] + (x[n - 1] - x[0]) / T(2) : T(0);
}

// The centroid of the embedded set at switch point `k` (NaN when its weights are all zero), and the scale used.
template <typename T>
FMPC_HD T embedded_centroid(EmbeddedSet<T>& set) {
  const T origin = points_origin(set.x, set.n);
  for (int pass = 0; pass < 2; ++pass) {
    T numerator = T(0), denominator = T(0);
    for (int i = 0; i < set.n; ++i) {
      const T w = set.weight(i);
      numerator += (set.x[i] - origin) * w;
      denominator += w;
    }
    // The weights in the set are all below the sum, so lifting them cannot overflow.
    if (pass == 1 || !(denominator < Limits<T>::tiny_sum()) || !(denominator > T(0)))
      return origin + numerator / denominator;
    set.scale = Limits<T>::lift();
  }
  return quiet_nan<T>();
}

// Points whose weights are zero in every embedded set carry nothing: an embedded set whose weights are all zero
// (0/0) is moved by `step` until one is not. For yl (step +1) more points take the upper weight, for yr (step -1)
// fewer take the lower one; at the far end every point has its upper weight, and some upper weight is positive
// (checked by the caller), so this ends.
template <typename T>
FMPC_HD T defined_centroid(EmbeddedSet<T>& set, int step) {
  for (;;) {
    set.scale = T(1);
    const T y = embedded_centroid(set);
    if (y == y || set.k + step < 0 || set.k + step > set.n) return y;
    set.k += step;
  }
}

// sign(x_i - y) for the exact centroid y of `set`: the sign of sum_j (x_i - x_j) w_j, in which x_i is never
// compared with a rounded y.
template <typename T>
FMPC_HD int side_of_exact_centroid(const EmbeddedSet<T>& set, T xi) {
  T sum = T(0);
  for (int j = 0; j < set.n; ++j) sum += (xi - set.x[j]) * set.weight(j);
  return sum > T(0) ? 1 : (sum < T(0) ? -1 : 0);
}

// The first index with x[i] >= value (strict == false) or x[i] > value (strict == true), by bisection.
template <typename T>
FMPC_HD int first_index_beyond(const T* x, int n, T value, bool strict) {
  int lo = 0, hi = n;
  while (lo < hi) {
    const int mid = lo + (hi - lo) / 2;
    if (strict ? !(x[mid] > value) : x[mid] < value) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

// KM step 2 with exact sides: the switch point for the centroid y (computed) of `set`. Points left of the exact
// centroid come first, points right of it after; a point exactly at it keeps its side (either side gives the same
// centroid), so the result is set.k clamped to [points left of y, points left of or at y].
template <typename T>
FMPC_HD int next_switch_point(const EmbeddedSet<T>& set, T y) {
  const T* x = set.x;
  const int n = set.n;
  // |computed y - exact y| <= (2n + 4) eps (half the spread) for the sums in embedded_centroid (Higham, "Accuracy
  // and Stability of Numerical Algorithms", 2nd ed., sec. 4.2: recursive summation, one product per term, one
  // division), plus the rounding of origin + quotient, eps |y|.
  const T band = T(2 * n + 4) * Limits<T>::epsilon() * (x[n - 1] - x[0]) + Limits<T>::epsilon() * magnitude(y);
  const int sure_left = first_index_beyond(x, n, y - band, false);  // x < y - band: left of the exact centroid
  const int sure_right = first_index_beyond(x, n, y + band, true);  // x > y + band: right of it
  int left = sure_left, left_or_at = sure_left;
  int side = -1;
  for (int i = sure_left; i < sure_right; ++i) {
    if (i == sure_left || x[i] != x[i - 1]) side = side_of_exact_centroid(set, x[i]);
    if (side < 0) ++left;
    if (side <= 0) ++left_or_at;
  }
  return set.k < left ? left : (set.k > left_or_at ? left_or_at : set.k);
}

template <typename T>
FMPC_HD bool any_weight(const T* upper, int n) {
  for (int i = 0; i < n; ++i)
    if (upper[i] > T(0)) return true;
  return false;
}

// The centroid with weights lower_i + upper_i: the Nie-Tan output and the Karnik-Mendel starting point (the
// centroid of the mid weights; halving every weight leaves a centroid unchanged, so it is the same number).
template <typename T>
FMPC_HD T summed_weight_centroid(const T* x, const T* lower, const T* upper, int n) {
  const T origin = points_origin(x, n);
  T scale = T(1);
  for (int pass = 0; pass < 2; ++pass) {
    T numerator = T(0), denominator = T(0);
    for (int i = 0; i < n; ++i) {
      const T w = lower[i] * scale + upper[i] * scale;
      numerator += (x[i] - origin) * w;
      denominator += w;
    }
    if (pass == 1 || !(denominator < Limits<T>::tiny_sum()) || !(denominator > T(0)))
      return origin + numerator / denominator;
    scale = Limits<T>::lift();
  }
  return quiet_nan<T>();
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

// The iteration both KM and the end of EKM run for one endpoint (side 0: yl, 1: yr), from switch point k: exact
// KM steps, each taken only where it improves the endpoint. `iterations` counts on from what the caller spent.
template <typename T>
FMPC_HD void karnik_mendel_endpoint(const T* x, const T* lower, const T* upper, int n, int side, int k,
                                    int iterations, TypeReducedInterval<T>& r) {
  const int step = side == 0 ? 1 : -1;
  EmbeddedSet<T> set{x, side == 0 ? upper : lower, side == 0 ? lower : upper, n, k, T(1)};
  T y = defined_centroid(set, step);
  const int cap = iterations + n + 2;
  for (;;) {
    if (++iterations > cap) {
      r.iteration_cap_hit = true;
      store_endpoint(r, side, quiet_nan<T>(), set.k, iterations);
      return;
    }
    EmbeddedSet<T> next = set;
    next.k = next_switch_point(set, y);
    if (next.k == set.k) break;
    const T candidate = defined_centroid(next, step);
    if (!(side == 0 ? candidate < y : candidate > y)) break;
    set = next;
    y = candidate;
  }
  store_endpoint(r, side, y, set.k, iterations);
}

}  // namespace type_reduction_detail

// Reference: tries every switch point, O(N^2). Used by the tests and for tiny N.
template <typename T>
FMPC_HD TypeReducedInterval<T> exhaustive_switch_search(const T* x, const T* lower, const T* upper, int n) {
  using namespace type_reduction_detail;
  TypeReducedInterval<T> r{quiet_nan<T>(), quiet_nan<T>(), 0, 0, n + 1, n + 1, false, false};
  if (!any_weight(upper, n)) return r;
  r.fired = true;
  for (int k = 0; k <= n; ++k) {
    EmbeddedSet<T> left_set{x, upper, lower, n, k, T(1)}, right_set{x, lower, upper, n, k, T(1)};
    const T yl = embedded_centroid(left_set);
    const T yr = embedded_centroid(right_set);
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
// current estimate, repeat until the switch point stops moving (with the exact sides and strict improvement
// described at the top).
template <typename T>
FMPC_HD TypeReducedInterval<T> karnik_mendel(const T* x, const T* lower, const T* upper, int n) {
  using namespace type_reduction_detail;
  TypeReducedInterval<T> r{quiet_nan<T>(), quiet_nan<T>(), 0, 0, 0, 0, false, false};
  if (!any_weight(upper, n)) return r;
  r.fired = true;
  const T start = summed_weight_centroid(x, lower, upper, n);
  const int k = first_index_beyond(x, n, start, true);  // the points with x_i <= start
  for (int side = 0; side < 2; ++side) karnik_mendel_endpoint(x, lower, upper, n, side, k, 0, r);
  if (r.iteration_cap_hit) r.left = r.right = quiet_nan<T>();
  return r;
}

// Enhanced Karnik-Mendel (Wu & Mendel 2009, "Enhanced Karnik-Mendel algorithms", IEEE TFS 17(4)): better start
// (k = round(N/2.4) for yl, round(N/1.7) for yr) and sums updated incrementally over the points between the old and
// new switch points. Incremental sums drift by rounding, so where they settle, the exact KM step above confirms
// the switch point from freshly summed weights (one more pass over the points; it moves on where they disagree).
template <typename T>
FMPC_HD TypeReducedInterval<T> enhanced_karnik_mendel(const T* x, const T* lower, const T* upper, int n) {
  using namespace type_reduction_detail;
  TypeReducedInterval<T> r{quiet_nan<T>(), quiet_nan<T>(), 0, 0, 0, 0, false, false};
  if (!any_weight(upper, n)) return r;
  r.fired = true;
  for (int side = 0; side < 2; ++side) {
    const int step = side == 0 ? 1 : -1;
    EmbeddedSet<T> set{x, side == 0 ? upper : lower, side == 0 ? lower : upper, n,
                       static_cast<int>(static_cast<double>(n) / (side == 0 ? 2.4 : 1.7) + 0.5), T(1)};
    T y = defined_centroid(set, step);
    // a, b: numerator and denominator at set.k in the scale of `set`; `fresh` is b when last summed directly and
    // `moved` the weight moved since, which bound the cancellation in b.
    const T origin = points_origin(x, n);
    T a = T(0), b = T(0);
    for (int i = 0; i < n; ++i) {
      const T w = set.weight(i);
      a += (x[i] - origin) * w;
      b += w;
    }
    T fresh = b, moved = T(0);
    int iterations = 0;
    while (iterations <= n) {
      ++iterations;
      // EKM step: the switch point of the incrementally computed y (a point at y keeps its side).
      const int left = first_index_beyond(x, n, y, false), left_or_at = first_index_beyond(x, n, y, true);
      const int next = set.k < left ? left : (set.k > left_or_at ? left_or_at : set.k);
      if (next == set.k) break;
      const int previous = set.k;
      const T s = next > set.k ? T(1) : T(-1);
      const int lo = next > set.k ? set.k : next, hi = next > set.k ? next : set.k;
      for (int i = lo; i < hi; ++i) {
        const T change = (set.first[i] - set.second[i]) * set.scale;
        a += s * (x[i] - origin) * change;
        b += s * change;
        moved += magnitude(change);
      }
      set.k = next;
      T candidate;
      if (b > T(1024) * Limits<T>::epsilon() * (fresh + moved)) {
        candidate = origin + a / b;
      } else {
        // Most of the weight has been moved out and b has lost its digits to cancellation: sum afresh.
        candidate = defined_centroid(set, step);
        a = T(0), b = T(0);
        for (int i = 0; i < n; ++i) {
          const T w = set.weight(i);
          a += (x[i] - origin) * w;
          b += w;
        }
        fresh = b, moved = T(0);
      }
      // In exact arithmetic each step improves the endpoint; where rounding says otherwise (where the plain
      // comparisons would start to cycle), the exact steps below take over from the last improvement.
      if (!(side == 0 ? candidate < y : candidate > y)) {
        set.k = previous;
        break;
      }
      y = candidate;
    }
    karnik_mendel_endpoint(x, lower, upper, n, side, set.k, iterations, r);
  }
  if (r.iteration_cap_hit) r.left = r.right = quiet_nan<T>();
  return r;
}

// Enhanced Iterative Algorithm with Stop Condition (Wu & Nie 2011, "Comparison and practical implementation of
// type-reduction algorithms for type-2 fuzzy sets and systems", FUZZ-IEEE): start with every point at its lower
// (yl) weight and move points to the upper weight one at a time from the left until the centroid stops passing
// them; mirror for yr from the right. The sums only grow, so they do not cancel; a point within rounding of the
// centroid moves it by no more than that distance, whichever side it is put on. Weights are lifted by a power of
// two where the sums are subnormal (never past 2^-368 times the lift for double, so nothing overflows).
template <typename T>
FMPC_HD TypeReducedInterval<T> eiasc(const T* x, const T* lower, const T* upper, int n) {
  using namespace type_reduction_detail;
  TypeReducedInterval<T> r{quiet_nan<T>(), quiet_nan<T>(), 0, 0, 0, 0, false, false};
  if (!any_weight(upper, n)) return r;
  r.fired = true;
  const T origin = points_origin(x, n);
  for (int side = 0; side < 2; ++side) {
    // The set before any point moved: every weight at its lower end. k counts the points moved (from the left for
    // yl, from the right for yr); `first` holds the moved points' weights, `second` the others'.
    EmbeddedSet<T> set{x, side == 0 ? upper : lower, side == 0 ? lower : upper, n, side == 0 ? 0 : n, T(1)};
    T a = T(0), b = T(0), y = T(0);
    const auto sum_afresh = [&]() {
      a = T(0), b = T(0);
      for (int i = 0; i < n; ++i) {
        const T w = set.weight(i);
        a += (x[i] - origin) * w;
        b += w;
      }
    };
    sum_afresh();
    int iterations = 0;
    for (;;) {
      if (side == 0 ? set.k == n : set.k == 0) break;
      const int i = side == 0 ? set.k : set.k - 1;
      const T change = (upper[i] - lower[i]) * set.scale;
      a += (x[i] - origin) * change;
      b += change;
      set.k += side == 0 ? 1 : -1;
      ++iterations;
      if (!(b > T(0))) continue;  // nothing weighs yet: keep moving
      if (b < Limits<T>::tiny_sum() && set.scale == T(1)) {
        set.scale = Limits<T>::lift();
        sum_afresh();
      }
      y = origin + a / b;
      if (side == 0 ? (set.k == n || y <= x[set.k]) : (set.k == 0 || y >= x[set.k - 1])) break;
    }
    store_endpoint(r, side, y, set.k, iterations);
  }
  return r;
}

// Nie & Tan 2008 ("Towards an efficient type-reduction method for interval type-2 fuzzy logic systems",
// FUZZ-IEEE): the centroid of the average of the upper and lower weights. Closed form; an approximation of the
// KM midpoint (the tests measure how close). Returned as a degenerate interval [y, y].
template <typename T>
FMPC_HD TypeReducedInterval<T> nie_tan(const T* x, const T* lower, const T* upper, int n) {
  using namespace type_reduction_detail;
  TypeReducedInterval<T> r{quiet_nan<T>(), quiet_nan<T>(), 0, 0, 1, 1, false, false};
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

#pragma once
// How alike two time curves are (a displacement or a velocity against time), as one number in [0, 1]: the measure
// the thesis's "graph similarity" (Tan Sing Yee 2014, section 4.5.2, Table 4-1) never defined, made precise.
//
// Each curve is the piecewise-linear function through its samples (t_i, y_i). They are compared over their common
// interval I = [max(a.t_0, b.t_0), min(a.t_last, b.t_last)], on the union of both sample times inside I, so curves
// of different lengths and sample times compare without resampling error. With ||f|| = sqrt(integral over I of
// f(t)^2 dt), integrated exactly for the piecewise-linear interpolants (h (p^2 + p q + q^2) / 3 per segment of
// length h with end values p, q):
//
//   similarity S(a, b) = 1 - ||a - b|| / (||a|| + ||b||)        (S = 1 when both are zero on I)
//
// Properties (tests/unit/curve_similarity_test.cpp checks each):
// - bounded: 0 <= S <= 1 (triangle inequality, ||a - b|| <= ||a|| + ||b||);
// - S = 1 exactly when a = b on I; S = 0 exactly when one curve is a non-negative multiple of minus the other
//   (opposite curves, or one zero and the other not);
// - symmetric: S(a, b) = S(b, a);
// - invariant to the unit of y (S(c a, c b) = S(a, b) for c > 0), to a shift of time, to the length of I (no
//   dependence on |I| beyond what the curves do inside it) and to resampling (a sample inserted on a straight
//   segment changes nothing);
// - sensitive to amplitude (b = lambda a gives S = 2 min(1, lambda) / (1 + lambda): 2/3 for a factor of 2), to a
//   delay, to an offset and to sign; in particular two step responses that rise alike but settle at different
//   values are told apart, which a correlation coefficient does not do.
//
// The Pearson correlation of the two interpolants over I (continuous form, integrals exact as above) is reported
// beside it as the shape-only measure the thesis's numbers may have been (Excel's CORREL is its sampled form): it
// ignores scale and offset, so every rising step response correlates well with every other.
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"

namespace fmpc::sim {

struct Curve {
  std::string name;           // names the curve in error messages
  std::vector<double> time;   // s, strictly increasing, finite
  std::vector<double> value;  // one per time, finite
};

struct CurveComparison {
  double similarity = 0.0;        // S above, in [0, 1]
  double difference_norm = 0.0;   // ||a - b|| (unit of y x sqrt(s))
  double norm_a = 0.0;            // ||a||
  double norm_b = 0.0;            // ||b||
  // Pearson correlation of a and b over I, in [-1, 1]; nullopt when either curve is constant on I (its variance is
  // at most (1e-12 x its largest |y|)^2, so rounding in the mean cannot pass for a shape).
  std::optional<double> correlation;
  double interval_start = 0.0;    // s, I
  double interval_end = 0.0;      // s
  std::size_t points = 0;         // the merged sample times in I
};

// Compares a and b; appends an error naming the curve and the sample and returns nullopt when a curve has fewer
// than 2 samples or more than kCurveSamplesMax, times and values of different counts, a NaN or infinite time or
// value, times that do not strictly increase, or when the curves share no interval of positive length.
std::optional<CurveComparison> compare_curves(const Curve& a, const Curve& b, DiagnosticList& diagnostics);

// The most samples a curve may have (2^27: two curves of doubles, 4 GiB in all, plus the merged grid).
constexpr std::size_t kCurveSamplesMax = std::size_t(1) << 27;

}  // namespace fmpc::sim

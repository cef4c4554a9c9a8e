#pragma once
// How well predicted values agree with measured ones (`fmpc validate`, the studio's validation panel): the error
// measures MATLAB's System Validation reports (MAE, RMSE), the mean difference (bias) and the Bland-Altman limits
// of agreement (Bland & Altman, "Statistical methods for assessing agreement between two methods of clinical
// measurement", Lancet 1986; 327:307-310, with the 1.96 of "Measuring agreement in method comparison studies",
// Stat Methods Med Res 1999; 8:135-160), and a histogram for distributions of differences (`fmpc diff`).
#include <cstddef>
#include <vector>

namespace fmpc {

// Differences are predicted - measured throughout: a positive bias means the rules predict too high.
struct Agreement {
  std::size_t count = 0;
  double mean_absolute_error = 0.0;      // mean |d|
  double root_mean_square_error = 0.0;   // sqrt(mean d^2)
  double bias = 0.0;                     // mean d
  // Sample standard deviation of d (divisor count - 1) and the 95% limits of agreement bias -/+ 1.96 sd (Bland and
  // Altman's normal approximation). NaN for a single pair, where no spread can be estimated.
  double difference_sd = 0.0;
  double lower_limit = 0.0;
  double upper_limit = 0.0;
  double largest_absolute_error = 0.0;  // max |d|
  std::size_t largest_error_index = 0;  // the first pair reaching it
  // Pearson's r between predicted and measured; NaN when either is constant (r is undefined there).
  double correlation = 0.0;
};

// Precondition (std::invalid_argument otherwise): the vectors have the same, non-zero length and every value is
// finite. Sums are taken over values scaled by a power of two near the largest magnitude (an exact scaling), so
// neither large values (1e300) overflow a sum of squares nor subnormal differences vanish in one; a difference that
// itself exceeds DBL_MAX (predicted 1e308, measured -1e308) is infinite and makes the measures infinite (the bias
// NaN when differences overflow both ways): never a finite wrong number.
Agreement measure_agreement(const std::vector<double>& predicted, const std::vector<double>& measured);

// Counts of `values` in `bins` equal-width bins over [lo, hi]: lo the smallest value, hi the largest (a value on
// hi falls in the last bin; a value on an inner edge falls on either side of it, to rounding). When every value is
// the same, v, the bins span [v - 0.5, v + 0.5] (wider where 0.5 is below v's precision). Precondition (std::invalid_argument): values not empty, all finite, bins > 0.
struct Histogram {
  double lo = 0.0;
  double hi = 0.0;
  std::vector<std::size_t> counts;
  double bin_width() const { return (hi - lo) / static_cast<double>(counts.size()); }
};
Histogram histogram(const std::vector<double>& values, std::size_t bins);

// Sturges' rule, ceil(log2 n) + 1, at most 50 (the bin count `fmpc diff` and the studio use).
std::size_t sturges_bins(std::size_t count);

}  // namespace fmpc

#include "compiler/eval/agreement.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace fmpc {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A power of two at least as large as the largest |v| (1 when all are 0): dividing by it is exact (barring
// underflow of values 2^-1074 times smaller than the largest, which cannot move a sum), and so is multiplying back.
double power_of_two_scale(const std::vector<double>& values) {
  double largest = 0.0;
  for (double v : values) largest = std::max(largest, std::fabs(v));
  if (largest == 0.0 || !std::isfinite(largest)) return 1.0;
  int exponent = 0;
  std::frexp(largest, &exponent);  // largest = f * 2^exponent, f in [0.5, 1)
  return std::ldexp(1.0, exponent);
}

double scaled_mean(const std::vector<double>& values) {
  const double scale = power_of_two_scale(values);
  double sum = 0.0;
  for (double v : values) sum += v / scale;
  return sum / static_cast<double>(values.size()) * scale;
}

// sqrt(sum v^2 / divisor), without overflow or underflow of the squares.
double scaled_root_mean_square(const std::vector<double>& values, double divisor) {
  const double scale = power_of_two_scale(values);
  double sum = 0.0;
  for (double v : values) {
    const double s = v / scale;
    sum += s * s;
  }
  return std::sqrt(sum / divisor) * scale;
}

std::vector<double> deviations(const std::vector<double>& values, double mean) {
  std::vector<double> result(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) result[i] = values[i] - mean;
  return result;
}

// Pearson's r from the deviations of each series from its mean; NaN when either series is constant.
double pearson_correlation(const std::vector<double>& x, const std::vector<double>& y) {
  const std::vector<double> dx = deviations(x, scaled_mean(x));
  const std::vector<double> dy = deviations(y, scaled_mean(y));
  const double sx = power_of_two_scale(dx), sy = power_of_two_scale(dy);
  double sxy = 0.0, sxx = 0.0, syy = 0.0;
  for (std::size_t i = 0; i < dx.size(); ++i) {
    const double a = dx[i] / sx, b = dy[i] / sy;
    sxy += a * b;
    sxx += a * a;
    syy += b * b;
  }
  if (!(sxx > 0.0) || !(syy > 0.0)) return kNaN;
  return std::clamp(sxy / std::sqrt(sxx * syy), -1.0, 1.0);
}

void require_finite(const std::vector<double>& values, const char* what) {
  for (double v : values)
    if (!std::isfinite(v)) throw std::invalid_argument(std::string(what) + " holds a value that is not finite");
}

}  // namespace

Agreement measure_agreement(const std::vector<double>& predicted, const std::vector<double>& measured) {
  if (predicted.size() != measured.size())
    throw std::invalid_argument("measure_agreement: predicted and measured differ in length");
  if (predicted.empty()) throw std::invalid_argument("measure_agreement: no pairs");
  require_finite(predicted, "measure_agreement: predicted");
  require_finite(measured, "measure_agreement: measured");
  const std::size_t n = predicted.size();
  std::vector<double> difference(n), magnitude(n);
  Agreement result;
  result.count = n;
  for (std::size_t i = 0; i < n; ++i) {
    difference[i] = predicted[i] - measured[i];
    magnitude[i] = std::fabs(difference[i]);
    if (magnitude[i] > result.largest_absolute_error || i == 0) {
      result.largest_absolute_error = magnitude[i];
      result.largest_error_index = i;
    }
  }
  result.mean_absolute_error = scaled_mean(magnitude);
  result.root_mean_square_error = scaled_root_mean_square(difference, static_cast<double>(n));
  result.bias = scaled_mean(difference);
  if (n >= 2) {
    result.difference_sd = scaled_root_mean_square(deviations(difference, result.bias), static_cast<double>(n - 1));
    result.lower_limit = result.bias - 1.96 * result.difference_sd;
    result.upper_limit = result.bias + 1.96 * result.difference_sd;
  } else {
    result.difference_sd = result.lower_limit = result.upper_limit = kNaN;
  }
  result.correlation = pearson_correlation(predicted, measured);
  return result;
}

Histogram histogram(const std::vector<double>& values, std::size_t bins) {
  if (values.empty()) throw std::invalid_argument("histogram: no values");
  if (bins == 0) throw std::invalid_argument("histogram: no bins");
  require_finite(values, "histogram: values");
  Histogram result;
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  result.lo = *lo;
  result.hi = *hi;
  if (result.lo == result.hi) {
    // v -/+ 0.5, or wider where 0.5 is below v's precision (v = 1e300 would otherwise give an empty span).
    const double widen = std::max(0.5, std::fabs(result.lo) * 0x1p-40);
    result.lo -= widen;
    result.hi += widen;
  }
  result.counts.assign(bins, 0);
  // Bin edges lo + k (hi - lo) / bins; the index is computed from the value's fraction of the span, scaled so that a
  // span near DBL_MAX (lo -1e308, hi 1e308) does not overflow.
  const double half_span = result.hi / 2 - result.lo / 2;
  for (double v : values) {
    const double fraction = (v / 2 - result.lo / 2) / half_span;
    const auto index = static_cast<std::size_t>(std::clamp(fraction * static_cast<double>(bins), 0.0,
                                                           static_cast<double>(bins - 1)));
    ++result.counts[index];
  }
  return result;
}

std::size_t sturges_bins(std::size_t count) {
  if (count <= 1) return 1;
  const auto bins = static_cast<std::size_t>(std::ceil(std::log2(static_cast<double>(count)))) + 1;
  return std::min<std::size_t>(bins, 50);
}

}  // namespace fmpc

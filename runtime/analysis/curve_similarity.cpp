#include "runtime/analysis/curve_similarity.h"

#include <algorithm>
#include <cmath>

#include "diagnostics/number_format.h"

namespace fmpc::sim {

namespace {

bool check_curve(const Curve& curve, DiagnosticList& diagnostics) {
  const std::string name = "curve '" + curve.name + "'";
  if (curve.time.size() != curve.value.size()) {
    diagnostics.error(SourceRange{}, name + " has " + std::to_string(curve.time.size()) + " times and " +
                                         std::to_string(curve.value.size()) + " values; give one value per time");
    return false;
  }
  if (curve.time.size() < 2) {
    diagnostics.error(SourceRange{}, name + " has " + std::to_string(curve.time.size()) +
                                         " sample(s); a curve needs at least 2 to span an interval");
    return false;
  }
  if (curve.time.size() > kCurveSamplesMax) {
    diagnostics.error(SourceRange{}, name + " has " + std::to_string(curve.time.size()) +
                                         " samples, more than the limit " + std::to_string(kCurveSamplesMax) +
                                         "; resample it more coarsely");
    return false;
  }
  for (std::size_t i = 0; i < curve.time.size(); ++i) {
    if (!std::isfinite(curve.time[i]) || !std::isfinite(curve.value[i])) {
      diagnostics.error(SourceRange{}, name + " sample " + std::to_string(i) + " (t = " +
                                           format_number(curve.time[i]) + ", y = " + format_number(curve.value[i]) +
                                           ") is not finite; a NaN or infinite sample has no similarity");
      return false;
    }
    if (i > 0 && !(curve.time[i] > curve.time[i - 1])) {
      diagnostics.error(SourceRange{}, name + " sample " + std::to_string(i) + ": time " +
                                           format_number(curve.time[i]) + " does not increase past " +
                                           format_number(curve.time[i - 1]) + "; times must strictly increase");
      return false;
    }
  }
  return true;
}

// The curve's piecewise-linear value at each of the increasing times `at` (all inside its span).
std::vector<double> interpolate(const Curve& curve, const std::vector<double>& at) {
  std::vector<double> values(at.size());
  std::size_t segment = 0;
  for (std::size_t i = 0; i < at.size(); ++i) {
    const double t = at[i];
    while (segment + 2 < curve.time.size() && curve.time[segment + 1] <= t) ++segment;
    const double t0 = curve.time[segment], t1 = curve.time[segment + 1];
    const double y0 = curve.value[segment], y1 = curve.value[segment + 1];
    if (t == t0) values[i] = y0;
    else if (t == t1) values[i] = y1;
    else values[i] = y0 + (y1 - y0) * ((t - t0) / (t1 - t0));
  }
  return values;
}

// Integral over the grid of f g, f and g linear on each segment: h (2 (f0 g0 + f1 g1) + (f0 g1 + f1 g0)) / 6,
// grouped so that swapping f and g adds the same numbers in the same order (the measure is exactly symmetric).
double integral_of_product(const std::vector<double>& t, const std::vector<double>& f, const std::vector<double>& g) {
  double sum = 0.0;
  for (std::size_t i = 0; i + 1 < t.size(); ++i)
    sum += (t[i + 1] - t[i]) * (2.0 * (f[i] * g[i] + f[i + 1] * g[i + 1]) + (f[i] * g[i + 1] + f[i + 1] * g[i])) / 6.0;
  return sum;
}

double integral(const std::vector<double>& t, const std::vector<double>& f) {
  double sum = 0.0;
  for (std::size_t i = 0; i + 1 < t.size(); ++i) sum += (t[i + 1] - t[i]) * (f[i] + f[i + 1]) / 2.0;
  return sum;
}

double largest_magnitude(const std::vector<double>& f) {
  double largest = 0.0;
  for (const double y : f) largest = std::max(largest, std::abs(y));
  return largest;
}

}  // namespace

std::optional<CurveComparison> compare_curves(const Curve& a, const Curve& b, DiagnosticList& diagnostics) {
  if (!check_curve(a, diagnostics) || !check_curve(b, diagnostics)) return std::nullopt;
  const double start = std::max(a.time.front(), b.time.front());
  const double end = std::min(a.time.back(), b.time.back());
  if (!(end > start)) {
    diagnostics.error(SourceRange{}, "curves '" + a.name + "' [" + format_number(a.time.front()) + ", " +
                                         format_number(a.time.back()) + "] s and '" + b.name + "' [" +
                                         format_number(b.time.front()) + ", " + format_number(b.time.back()) +
                                         "] s share no interval of positive length; compare curves that overlap");
    return std::nullopt;
  }

  std::vector<double> grid;
  grid.reserve(a.time.size() + b.time.size() + 2);
  grid.push_back(start);
  std::size_t i = 0, j = 0;
  while (i < a.time.size() || j < b.time.size()) {
    double t;
    if (j == b.time.size() || (i < a.time.size() && a.time[i] <= b.time[j])) t = a.time[i++];
    else t = b.time[j++];
    if (t > grid.back() && t < end) grid.push_back(t);
  }
  grid.push_back(end);

  std::vector<double> ya = interpolate(a, grid), yb = interpolate(b, grid);
  for (std::size_t k = 0; k < grid.size(); ++k)
    if (!std::isfinite(ya[k]) || !std::isfinite(yb[k])) {
      diagnostics.error(SourceRange{}, "curves '" + a.name + "' and '" + b.name + "': interpolating at t = " +
                                           format_number(grid[k]) +
                                           " s overflows (values near the largest double); rescale the curves");
      return std::nullopt;
    }
  // S and the correlation do not depend on a common factor: scale both by the power of two that brings the largest
  // |y| into [0.5, 1) (exact), so that squares of tiny (subnormal) or huge values neither underflow nor overflow.
  int exponent = 0;
  std::frexp(std::max(largest_magnitude(ya), largest_magnitude(yb)), &exponent);
  for (std::size_t k = 0; k < grid.size(); ++k) {
    ya[k] = std::ldexp(ya[k], -exponent);
    yb[k] = std::ldexp(yb[k], -exponent);
  }
  std::vector<double> difference(grid.size());
  for (std::size_t k = 0; k < grid.size(); ++k) difference[k] = ya[k] - yb[k];

  CurveComparison result;
  result.interval_start = start;
  result.interval_end = end;
  result.points = grid.size();
  const double norm_a = std::sqrt(integral_of_product(grid, ya, ya));
  const double norm_b = std::sqrt(integral_of_product(grid, yb, yb));
  const double difference_norm = std::sqrt(integral_of_product(grid, difference, difference));
  result.norm_a = std::ldexp(norm_a, exponent);
  result.norm_b = std::ldexp(norm_b, exponent);
  result.difference_norm = std::ldexp(difference_norm, exponent);
  const double scale = norm_a + norm_b;
  // Rounding can carry the exact value, which lies in [0, 1], out by a few ulps (opposite curves): clamp.
  result.similarity = scale > 0.0 ? std::clamp(1.0 - difference_norm / scale, 0.0, 1.0) : 1.0;

  const double length = end - start;
  const double mean_a = integral(grid, ya) / length, mean_b = integral(grid, yb) / length;
  std::vector<double> da(grid.size()), db(grid.size());
  for (std::size_t k = 0; k < grid.size(); ++k) {
    da[k] = ya[k] - mean_a;
    db[k] = yb[k] - mean_b;
  }
  const double variance_a = integral_of_product(grid, da, da) / length;
  const double variance_b = integral_of_product(grid, db, db) / length;
  const double floor_a = 1e-12 * largest_magnitude(ya), floor_b = 1e-12 * largest_magnitude(yb);
  if (variance_a > floor_a * floor_a && variance_b > floor_b * floor_b) {
    const double covariance = integral_of_product(grid, da, db) / length;
    result.correlation = std::clamp(covariance / std::sqrt(variance_a * variance_b), -1.0, 1.0);
  }
  return result;
}

}  // namespace fmpc::sim

#include "compiler/eval/nelder_mead.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace fmpc {

namespace {

// Non-finite values (infeasible points) rank last.
double ranked(double value) { return std::isfinite(value) ? value : std::numeric_limits<double>::infinity(); }

}  // namespace

NelderMeadResult minimise_nelder_mead(const std::function<double(const std::vector<double>&)>& objective,
                                      const std::vector<double>& start, const std::vector<double>& lower,
                                      const std::vector<double>& upper, const NelderMeadOptions& options) {
  const std::size_t n = start.size();
  NelderMeadResult result;
  const int cap = options.max_evaluations > 0 ? options.max_evaluations : 200 * static_cast<int>(std::max<std::size_t>(n, 1));
  const auto clamp = [&](std::vector<double> x) {
    for (std::size_t i = 0; i < n; ++i) x[i] = std::clamp(x[i], lower[i], upper[i]);
    return x;
  };
  const auto evaluate = [&](const std::vector<double>& x) {
    ++result.evaluations;
    return ranked(objective(x));
  };
  std::vector<std::vector<double>> simplex{clamp(start)};
  std::vector<double> values{evaluate(simplex[0])};
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<double> vertex = simplex[0];
    const double width = upper[i] - lower[i];
    const double step = options.initial_step * width;
    // Towards the side with more room, so that the vertex differs from the start even at a bound.
    vertex[i] += upper[i] - vertex[i] >= vertex[i] - lower[i] ? step : -step;
    vertex = clamp(vertex);
    simplex.push_back(vertex);
    values.push_back(evaluate(vertex));
  }
  std::vector<std::size_t> order(n + 1);
  const auto sort_simplex = [&] {
    std::iota(order.begin(), order.end(), 0);
    // Ties keep their index order: the search is the same run to run.
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
    std::vector<std::vector<double>> sorted_simplex;
    std::vector<double> sorted_values;
    for (std::size_t i : order) {
      sorted_simplex.push_back(simplex[i]);
      sorted_values.push_back(values[i]);
    }
    simplex.swap(sorted_simplex);
    values.swap(sorted_values);
  };
  const auto converged = [&] {
    const double spread = values[n] - values[0];
    if (!(spread <= options.value_tolerance * (1.0 + std::fabs(values[0])))) return false;
    for (std::size_t v = 1; v <= n; ++v)
      for (std::size_t i = 0; i < n; ++i) {
        const double width = upper[i] - lower[i];
        if (std::fabs(simplex[v][i] - simplex[0][i]) > options.point_tolerance * (width > 0 ? width : 1.0)) return false;
      }
    return true;
  };
  sort_simplex();
  while (n > 0 && !(result.converged = converged()) && result.evaluations < cap) {
    ++result.iterations;
    std::vector<double> centroid(n, 0.0);
    for (std::size_t v = 0; v < n; ++v)
      for (std::size_t i = 0; i < n; ++i) centroid[i] += simplex[v][i] / static_cast<double>(n);
    const auto along = [&](double t) {  // centroid + t (centroid - worst)
      std::vector<double> x(n);
      for (std::size_t i = 0; i < n; ++i) x[i] = centroid[i] + t * (centroid[i] - simplex[n][i]);
      return clamp(x);
    };
    const std::vector<double> reflected = along(1.0);
    const double reflected_value = evaluate(reflected);
    if (reflected_value < values[0]) {
      const std::vector<double> expanded = along(2.0);
      const double expanded_value = evaluate(expanded);
      if (expanded_value < reflected_value) {
        simplex[n] = expanded;
        values[n] = expanded_value;
      } else {
        simplex[n] = reflected;
        values[n] = reflected_value;
      }
    } else if (reflected_value < values[n - 1]) {
      simplex[n] = reflected;
      values[n] = reflected_value;
    } else {
      const bool outside = reflected_value < values[n];
      const std::vector<double> contracted = along(outside ? 0.5 : -0.5);
      const double contracted_value = evaluate(contracted);
      if (contracted_value < (outside ? reflected_value : values[n])) {
        simplex[n] = contracted;
        values[n] = contracted_value;
      } else {
        for (std::size_t v = 1; v <= n; ++v) {
          for (std::size_t i = 0; i < n; ++i) simplex[v][i] = simplex[0][i] + 0.5 * (simplex[v][i] - simplex[0][i]);
          simplex[v] = clamp(simplex[v]);
          values[v] = evaluate(simplex[v]);
        }
      }
    }
    sort_simplex();
  }
  if (n == 0) result.converged = true;
  result.point = simplex[0];
  result.value = values[0];
  result.value_spread = values[n] - values[0];
  return result;
}

}  // namespace fmpc

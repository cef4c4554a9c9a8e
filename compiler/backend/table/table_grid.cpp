#include "compiler/backend/table/table_grid.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <set>

namespace fmpc::table_build {

namespace {

constexpr std::size_t kWorstPointsPerRound = 64;

double stored(double value, TableValueType type) {
  return type == TableValueType::Float32 ? static_cast<double>(static_cast<float>(value)) : value;
}

}  // namespace

std::string counts_text(const std::vector<std::vector<double>>& axes) {
  std::string text;
  std::uint64_t total = 1;
  for (const auto& axis : axes) {
    text += (text.empty() ? "" : " x ") + std::to_string(axis.size());
    total *= axis.size();
  }
  return text + " = " + std::to_string(total) + " points";
}

std::uint64_t grid_size(const std::vector<std::vector<double>>& axes) {
  std::uint64_t total = 1;
  for (const auto& axis : axes) {
    total *= axis.size();
    if (total > (1ULL << 62)) return total;
  }
  return total;
}

std::vector<double> uniform_axis(double lo, double hi, int count) {
  std::vector<double> axis(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) axis[static_cast<std::size_t>(k)] = lo + (hi - lo) * k / (count - 1);
  axis.back() = hi;
  return axis;
}

std::vector<double> feature_axis(const Variable& input) {
  std::vector<double> points = {input.min, input.max};
  for (const Term& term : input.terms) {
    const std::vector<double>& p = term.mf.params;
    std::vector<double> features;
    switch (term.mf.kind) {
      case MfKind::Triangle: features = {p[0], p[1], p[2]}; break;
      case MfKind::Trapezoid:
      case MfKind::PiShape: features = {p[0], p[1], p[2], p[3]}; break;
      case MfKind::Gaussian: features = {p[1] - p[0], p[1], p[1] + p[0]}; break;
      case MfKind::Gaussian2: features = {p[1], p[3]}; break;
      case MfKind::GeneralizedBell: features = {p[2] - p[0], p[2], p[2] + p[0]}; break;
      case MfKind::Sigmoid: features = {p[1]}; break;
      case MfKind::DifferenceSigmoid:
      case MfKind::ProductSigmoid: features = {p[1], p[3]}; break;
      case MfKind::ZShape:
      case MfKind::SShape:
      case MfKind::LinearS:
      case MfKind::LinearZ: features = {p[0], p[1]}; break;
      case MfKind::Constant:
      case MfKind::Linear: break;
    }
    for (double x : features)
      if (x > input.min && x < input.max) points.push_back(x);
  }
  std::sort(points.begin(), points.end());
  const double tolerance = (input.max - input.min) * 1e-6;
  std::vector<double> axis;
  for (double x : points)
    if (axis.empty() || x - axis.back() > tolerance) axis.push_back(x);
  axis.back() = input.max;
  if (axis.size() < 3) axis = uniform_axis(input.min, input.max, 3);
  return axis;
}

bool GridBuilder::set_axes(const std::vector<std::vector<double>>& axes, DiagnosticList& diagnostics) {
  const std::size_t dimensions = axes.size(), outputs = table_.output_names.size();
  std::vector<std::vector<long long>> old_index(dimensions);
  std::vector<long long> old_counts(dimensions, 0);
  const bool had_values = !table_.values.empty();
  for (std::size_t a = 0; a < dimensions; ++a) {
    const std::vector<double>& previous = table_.axes[a].breakpoints;
    old_counts[a] = static_cast<long long>(previous.size());
    for (double x : axes[a]) {
      const auto found = std::lower_bound(previous.begin(), previous.end(), x);
      old_index[a].push_back(had_values && found != previous.end() && *found == x ? found - previous.begin() : -1);
    }
  }
  const std::uint64_t total = grid_size(axes);
  // While the grid grows, the old and the new grids' values and rounding (8 bytes each per output) and the points
  // left to evaluate (8 bytes) are held at once.
  const double bytes = static_cast<double>(total) * (16.0 * static_cast<double>(outputs) + 8.0) +
                       16.0 * static_cast<double>(table_.values.size());
  if (options_.memory_limit_bytes > 0 && bytes > static_cast<double>(options_.memory_limit_bytes)) {
    char needed[64], limit[64];
    std::snprintf(needed, sizeof needed, "%.3g GiB", bytes / 1073741824.0);
    std::snprintf(limit, sizeof limit, "%.3g GiB", static_cast<double>(options_.memory_limit_bytes) / 1073741824.0);
    diagnostics.error(SourceRange{table_.source_path, 0, 0, 0, 0},
                      "the grid of " + std::to_string(total) + " points needs an estimated " + needed +
                          " while it is built; the limit is " + options_.memory_limit_source + ", " + limit,
                      {"lower --max-grid-points, raise --max-error, or fix more inputs"});
    return false;
  }
  std::vector<double> values(static_cast<std::size_t>(total) * outputs, 0.0);
  std::vector<double> rounding(values.size(), 0.0);
  std::vector<std::size_t> missing;
  std::vector<std::size_t> multi(dimensions, 0);
  for (std::uint64_t flat = 0; flat < total; ++flat) {
    long long previous_flat = 0;
    bool present = had_values;
    for (std::size_t a = 0; a < dimensions && present; ++a) {
      const long long i = old_index[a][multi[a]];
      present = i >= 0;
      previous_flat = previous_flat * old_counts[a] + i;
    }
    if (present) {
      std::copy_n(table_.values.begin() + previous_flat * static_cast<long long>(outputs), outputs,
                  values.begin() + static_cast<std::ptrdiff_t>(flat * outputs));
      std::copy_n(rounding_.begin() + previous_flat * static_cast<long long>(outputs), outputs,
                  rounding.begin() + static_cast<std::ptrdiff_t>(flat * outputs));
    } else
      missing.push_back(static_cast<std::size_t>(flat));
    for (std::size_t a = dimensions; a-- > 0;) {
      if (++multi[a] < axes[a].size()) break;
      multi[a] = 0;
    }
  }
  std::atomic<bool> not_finite{false};
  std::vector<std::size_t> counts(dimensions);
  for (std::size_t a = 0; a < dimensions; ++a) counts[a] = axes[a].size();
  run_parallel(missing.size(), options_.threads, [&](int thread, std::size_t m) {
    std::size_t flat = missing[m];
    std::vector<double> point(dimensions);
    for (std::size_t a = dimensions; a-- > 0;) {
      point[a] = axes[a][flat % counts[a]];
      flat /= counts[a];
    }
    const std::vector<double> out = evaluators_.grid(thread, point.data());
    for (std::size_t o = 0; o < outputs; ++o) {
      if (!std::isfinite(out[o])) not_finite = true;
      values[missing[m] * outputs + o] = stored(out[o], options_.value_type);
      rounding[missing[m] * outputs + o] = std::fabs(values[missing[m] * outputs + o] - out[o]);
    }
  });
  stats_.grid_evaluations += missing.size();
  if (not_finite) {
    diagnostics.error(SourceRange{options_.source_path, 0, 0, 0, 0},
                      "an output is not finite at a grid point (no rule fires there and the policy is 'error')",
                      {"a table needs a value everywhere: choose another 'when no rule fires' policy, or narrow "
                       "the inputs' ranges"});
    return false;
  }
  for (std::size_t a = 0; a < dimensions; ++a) table_.axes[a].breakpoints = axes[a];
  table_.values = std::move(values);
  rounding_ = std::move(rounding);
  return true;
}

std::vector<Refinement> worst_axes(const LookupTable& table, const PointSet& training, const Measurement& measured,
                                   const std::vector<bool>& refinable, double threshold, Evaluators& evaluators,
                                   const TableBuildOptions& options, TableBuildStatistics& stats) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < measured.errors.size(); ++i)
    if (measured.errors[i] > threshold) order.push_back(i);
  const std::size_t take = std::min(order.size(), kWorstPointsPerRound);
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(take), order.end(),
                    [&](std::size_t a, std::size_t b) {
                      return measured.errors[a] != measured.errors[b] ? measured.errors[a] > measured.errors[b] : a < b;
                    });
  order.resize(take);
  const std::size_t dimensions = table.axes.size(), outputs = table.output_names.size();
  std::vector<Refinement> result(take);
  std::vector<char> valid(take, 0);
  run_parallel(take, options.threads, [&](int thread, std::size_t k) {
    const double* p = training.point(order[k]);
    const double* reference = training.reference.data() + order[k] * outputs;
    Refinement best;
    bool found = false;
    for (std::size_t a = 0; a < dimensions; ++a) {
      const std::vector<double>& axis = table.axes[a].breakpoints;
      int cell = 0;
      double fraction = 0.0;
      locate_on_axis(axis.data(), static_cast<int>(axis.size()), p[a], cell, fraction);
      const double lo = axis[static_cast<std::size_t>(cell)], hi = axis[static_cast<std::size_t>(cell) + 1];
      if (hi - lo <= (axis.back() - axis.front()) * 1e-9) continue;
      std::vector<double> q(p, p + dimensions);
      q[a] = lo;
      const std::vector<double> at_lo = evaluators.grid(thread, q.data());
      q[a] = hi;
      const std::vector<double> at_hi = evaluators.grid(thread, q.data());
      double miss = 0.0;
      for (std::size_t o = 0; o < outputs; ++o)
        miss = std::max(miss, std::fabs(reference[o] - (at_lo[o] + fraction * (at_hi[o] - at_lo[o]))));
      if (!found || miss > best.error) best = Refinement{a, static_cast<std::size_t>(cell), miss};
      found = true;
    }
    // A point whose worst axis has a fixed count (--vary NAME:points) is left alone: refining another axis
    // would not help it.
    if (found && refinable[best.axis]) {
      result[k] = best;
      valid[k] = 1;
    }
  });
  stats.probe_evaluations += take * 2 * dimensions;
  std::vector<Refinement> chosen;
  for (std::size_t k = 0; k < take; ++k)
    if (valid[k]) chosen.push_back(result[k]);
  return chosen;
}

void refine_axes(const std::vector<std::vector<double>>& axes,
                 const std::vector<std::pair<std::size_t, std::size_t>>& splits, const std::vector<double>& weights,
                 const TableBuildOptions& options, std::vector<std::vector<double>>& next) {
  if (splits.empty()) return;
  if (options.spacing == BreakpointSpacing::Uniform) {
    std::vector<double> total(axes.size(), 0.0);
    for (std::size_t k = 0; k < splits.size(); ++k) total[splits[k].first] = std::max(total[splits[k].first], weights[k]);
    const auto axis = static_cast<std::size_t>(std::max_element(total.begin(), total.end()) - total.begin());
    const std::vector<double>& current = axes[axis];
    next[axis] = uniform_axis(current.front(), current.back(), static_cast<int>(2 * current.size() - 1));
    // Nested doubling: the old breakpoints are exactly the even ones (set them so, not recomputed).
    for (std::size_t k = 0; k < current.size(); ++k) next[axis][2 * k] = current[k];
    return;
  }
  std::set<std::pair<std::size_t, std::size_t>> done;
  for (const auto& [axis_index, cell] : splits) {
    if (!done.insert({axis_index, cell}).second) continue;
    // The grid with one more breakpoint on this axis, against the budget (without building it).
    std::uint64_t size = 1;
    for (std::size_t a = 0; a < next.size() && size <= options.max_grid_points; ++a)
      size *= next[a].size() + (a == axis_index ? 1 : 0);
    if (size > options.max_grid_points) continue;
    const double mid = 0.5 * (axes[axis_index][cell] + axes[axis_index][cell + 1]);
    auto& axis = next[axis_index];
    axis.insert(std::upper_bound(axis.begin(), axis.end(), mid), mid);
  }
}

}  // namespace fmpc::table_build

#include "compiler/backend/table/table_builder.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <thread>

#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

constexpr double kTrainingMargin = 0.8;  // train below 0.8 of the target before measuring held-out points
constexpr std::size_t kWorstPointsPerRound = 64;
constexpr int kMaxHeldOutSets = 6;

// Runs work(thread, index) for index in [0, count) on `threads` std::threads, in chunks taken in turn.
template <typename Work>
void run_parallel(std::size_t count, int threads, const Work& work) {
  const std::size_t workers = std::max<std::size_t>(1, std::min<std::size_t>(static_cast<std::size_t>(threads), count));
  constexpr std::size_t kChunk = 64;
  std::atomic<std::size_t> next{0};
  const auto worker = [&](int thread) {
    for (;;) {
      const std::size_t begin = next.fetch_add(kChunk);
      if (begin >= count) return;
      const std::size_t end = std::min(count, begin + kChunk);
      for (std::size_t i = begin; i < end; ++i) work(thread, i);
    }
  };
  if (workers == 1) {
    worker(0);
    return;
  }
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < workers; ++t) pool.emplace_back(worker, static_cast<int>(t));
  worker(0);
  for (std::thread& thread : pool) thread.join();
}

// One interpreter per thread for the specialised system (grid values) and for the source (the reference).
class Evaluators {
 public:
  Evaluators(const FuzzySystem& source, const CompileResult& compiled, const EvaluationOptions& options, int threads)
      : compiled_(compiled), source_inputs_(source.inputs.size(), 0.0) {
    for (int t = 0; t < std::max(1, threads); ++t) {
      specialised_.emplace_back(compiled.system, options);
      reference_.emplace_back(source, options);
    }
    for (const auto& [index, value] : compiled.fixed) source_inputs_[static_cast<std::size_t>(index)] = value;
  }

  std::vector<double> grid(int thread, const double* point) {
    const std::vector<double> inputs(point, point + compiled_.system.inputs.size());
    return specialised_[static_cast<std::size_t>(thread)].evaluate(inputs).outputs;
  }

  std::vector<double> reference(int thread, const double* point) {
    std::vector<double> inputs = source_inputs_;
    for (std::size_t a = 0; a < compiled_.source_inputs.size(); ++a)
      inputs[static_cast<std::size_t>(compiled_.source_inputs[a])] = point[a];
    return reference_[static_cast<std::size_t>(thread)].evaluate(inputs).outputs;
  }

 private:
  const CompileResult& compiled_;
  std::vector<double> source_inputs_;
  std::vector<Interpreter> specialised_;
  std::vector<Interpreter> reference_;
};

// Points uniform over the axes' ranges with their reference outputs, row-major (point, coordinate / output).
struct PointSet {
  std::size_t dimensions = 0;
  std::size_t outputs = 0;
  std::vector<double> points;
  std::vector<double> reference;
  std::size_t size() const { return dimensions == 0 ? 0 : points.size() / dimensions; }
  const double* point(std::size_t i) const { return points.data() + i * dimensions; }
};

// Draws from std::mt19937_64 and maps the bits itself, so a seed gives the same points on every platform.
PointSet draw_points(const LookupTable& table, std::uint64_t seed, std::size_t count, Evaluators& evaluators,
                     int threads) {
  PointSet set;
  set.dimensions = table.axes.size();
  set.outputs = table.output_names.size();
  std::mt19937_64 generator(seed);
  set.points.resize(count * set.dimensions);
  for (std::size_t i = 0; i < count; ++i)
    for (std::size_t a = 0; a < set.dimensions; ++a) {
      const double unit = static_cast<double>(generator() >> 11) * 0x1.0p-53;
      const double lo = table.axes[a].breakpoints.front(), hi = table.axes[a].breakpoints.back();
      set.points[i * set.dimensions + a] = lo + unit * (hi - lo);
    }
  set.reference.resize(count * set.outputs);
  run_parallel(count, threads, [&](int thread, std::size_t i) {
    const std::vector<double> outputs = evaluators.reference(thread, set.point(i));
    std::copy(outputs.begin(), outputs.end(), set.reference.begin() + static_cast<std::ptrdiff_t>(i * set.outputs));
  });
  return set;
}

struct Measurement {
  std::vector<double> errors;  // per point: the largest |table - reference| over the outputs
  double max_error = 0.0;
  std::size_t worst = 0;  // the first point with max_error
};

Measurement measure(const LookupTable& table, const PointSet& set, int threads) {
  std::vector<const double*> pointers;
  std::vector<int> counts;
  const TableView<double> view = view_of(table, pointers, counts);
  Measurement result;
  result.errors.assign(set.size(), 0.0);
  run_parallel(set.size(), threads, [&](int, std::size_t i) {
    std::vector<double> out(set.outputs);
    interpolate_table(view, set.point(i), out.data());
    double error = 0.0;
    for (std::size_t o = 0; o < set.outputs; ++o) {
      const double difference = std::fabs(out[o] - set.reference[i * set.outputs + o]);
      error = std::isnan(difference) ? std::numeric_limits<double>::infinity() : std::max(error, difference);
    }
    result.errors[i] = error;
  });
  for (std::size_t i = 0; i < result.errors.size(); ++i)
    if (result.errors[i] > result.max_error) {
      result.max_error = result.errors[i];
      result.worst = i;
    }
  return result;
}

double stored(double value, TableValueType type) {
  return type == TableValueType::Float32 ? static_cast<double>(static_cast<float>(value)) : value;
}

std::string point_text(const LookupTable& table, const double* point) {
  std::string text;
  for (std::size_t a = 0; a < table.axes.size(); ++a)
    text += (a ? ", " : "") + table.axes[a].input_name + " = " + format_number(point[a]);
  return text;
}

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

// The ends of the input's range and the tops, shoulders and centres of its terms inside it.
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

class GridBuilder {
 public:
  GridBuilder(LookupTable& table, Evaluators& evaluators, const TableBuildOptions& options, TableBuildStatistics& stats)
      : table_(table), evaluators_(evaluators), options_(options), stats_(stats) {}

  // Replaces the grid's axes by `axes` (each a superset of the current one), evaluating only the new points.
  bool set_axes(const std::vector<std::vector<double>>& axes, DiagnosticList& diagnostics) {
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
    std::vector<double> values(static_cast<std::size_t>(total) * outputs, 0.0);
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
      if (present)
        std::copy_n(table_.values.begin() + previous_flat * static_cast<long long>(outputs), outputs,
                    values.begin() + static_cast<std::ptrdiff_t>(flat * outputs));
      else
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
    return true;
  }

 private:
  LookupTable& table_;
  Evaluators& evaluators_;
  const TableBuildOptions& options_;
  TableBuildStatistics& stats_;
};

struct Refinement {
  std::size_t axis = 0;
  std::size_t cell = 0;
  double error = 0.0;  // how far linear interpolation along the axis misses at the point
};

// For each of the worst training points, the axis along which interpolating between its cell's ends misses most.
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

}  // namespace

std::optional<LookupTable> build_table(const FuzzySystem& source, const CompileResult& compiled,
                                       const TableBuildOptions& options, DiagnosticList& diagnostics,
                                       TableBuildStatistics* statistics) {
  TableBuildStatistics local;
  TableBuildStatistics& stats = statistics ? *statistics : local;
  const FuzzySystem& system = compiled.system;
  const SourceRange where{options.source_path, 0, 0, 0, 0};
  if (!(options.max_error > 0.0) || !std::isfinite(options.max_error)) {
    diagnostics.error(where, "--max-error must be a positive number, not " + format_number(options.max_error));
    return std::nullopt;
  }
  if (system.inputs.empty() || system.inputs.size() > static_cast<std::size_t>(kMaxTableAxes)) {
    diagnostics.error(where, "a table has 1 to " + std::to_string(kMaxTableAxes) + " axes; " +
                                 std::to_string(system.inputs.size()) + " inputs vary",
                      {"fix more inputs with --fix NAME=VALUE"});
    return std::nullopt;
  }
  const int threads = std::max(1, options.threads);
  LookupTable table;
  table.system_name = system.name;
  table.source_path = options.source_path;
  table.source_hash = options.source_hash;
  table.value_type = options.value_type;
  for (const Variable& output : system.outputs) table.output_names.push_back(output.name);
  for (const auto& [index, value] : compiled.fixed)
    table.fixed_inputs.emplace_back(source.inputs[static_cast<std::size_t>(index)].name, value);

  std::vector<std::vector<double>> axes;
  std::vector<bool> refinable;
  for (std::size_t a = 0; a < system.inputs.size(); ++a) {
    const Variable& input = system.inputs[a];
    TableAxis axis;
    axis.input_name = input.name;
    axis.input_index = static_cast<std::uint32_t>(compiled.source_inputs[a]);
    axis.breakpoints = {input.min, input.max};
    table.axes.push_back(axis);
    const int points = a < compiled.axis_points.size() ? compiled.axis_points[a] : 0;
    refinable.push_back(points == 0);
    if (points > 0) axes.push_back(uniform_axis(input.min, input.max, points));
    else if (options.spacing == BreakpointSpacing::Uniform) axes.push_back(uniform_axis(input.min, input.max, 2));
    else axes.push_back(feature_axis(input));
  }
  if (grid_size(axes) > options.max_grid_points) {
    diagnostics.error(where, "the starting grid, " + counts_text(axes) + ", exceeds the budget of " +
                                 std::to_string(options.max_grid_points) + " points",
                      {"raise --max-grid-points, give fewer points with --vary NAME:points, or fix more inputs"});
    return std::nullopt;
  }

  Evaluators evaluators(source, compiled, options.evaluation, threads);
  GridBuilder grid(table, evaluators, options, stats);
  if (!grid.set_axes(axes, diagnostics)) return std::nullopt;
  PointSet training = draw_points(table, options.seed, options.training_points, evaluators, threads);
  stats.probe_evaluations += training.size();
  std::uint64_t held_out_seed = options.seed ^ 0x9E3779B97F4A7C15ULL;
  std::optional<PointSet> held_out;
  const double threshold = kTrainingMargin * options.max_error;

  bool grid_final = false;       // the budget (or fixed counts) allow no further refinement
  bool only_fixed_axes = false;  // ... because only axes with a fixed count could reduce the error
  for (;;) {
    ++stats.rounds;
    Measurement measured = measure(table, training, threads);
    stats.training_error = measured.max_error;
    if (options.progress || options.early_refusal_factor > 0) {
      TableBuildProgress progress;
      progress.round = stats.rounds;
      progress.grid_points = grid_size(axes);
      progress.budget = options.max_grid_points;
      progress.training_error = measured.max_error;
      progress.target = options.max_error;
      const double ratio = std::max(1.0, measured.max_error / options.max_error);
      progress.estimated_grid_points =
          static_cast<double>(progress.grid_points) * std::pow(ratio, 0.5 * static_cast<double>(axes.size()));
      if (options.progress) options.progress(progress);
      const bool refinable_axis = std::find(refinable.begin(), refinable.end(), true) != refinable.end();
      if (options.early_refusal_factor > 0 && refinable_axis && stats.rounds >= kEarlyRefusalRounds &&
          progress.estimated_grid_points >
              options.early_refusal_factor * static_cast<double>(options.max_grid_points)) {
        diagnostics.error(where,
                          "cannot reach --max-error " + format_number(options.max_error) + " within " +
                              std::to_string(options.max_grid_points) + " grid points: after " +
                              std::to_string(stats.rounds) + " rounds the grid, " + counts_text(axes) +
                              ", has a maximum error of " + format_number(measured.max_error) +
                              ", and even if the error falls as h^2 the target needs about " +
                              format_number(std::round(progress.estimated_grid_points)) +
                              " grid points (an estimate; refused now instead of refining on)",
                          {"raise --max-error or --max-grid-points, or fix more inputs (--fix NAME=VALUE), or use "
                           "--target cpp for an evaluator without interpolation error"});
        return std::nullopt;
      }
    }
    std::vector<Refinement> refinements;
    std::vector<std::vector<double>> next = axes;
    bool verify = measured.max_error <= threshold;
    if (!verify && !grid_final) {
      refinements = worst_axes(table, training, measured, refinable, threshold, evaluators, options, stats);
      if (options.spacing == BreakpointSpacing::Uniform) {
        std::vector<double> worst_per_axis(axes.size(), 0.0);
        for (const Refinement& r : refinements) worst_per_axis[r.axis] = std::max(worst_per_axis[r.axis], r.error);
        const std::size_t axis = static_cast<std::size_t>(
            std::max_element(worst_per_axis.begin(), worst_per_axis.end()) - worst_per_axis.begin());
        if (!refinements.empty()) {
          const std::vector<double>& current = axes[axis];
          next[axis] = uniform_axis(current.front(), current.back(), static_cast<int>(2 * current.size() - 1));
          // Nested doubling: the old breakpoints are exactly the even ones (set them so, not recomputed).
          for (std::size_t k = 0; k < current.size(); ++k) next[axis][2 * k] = current[k];
        }
      } else {
        std::set<std::pair<std::size_t, std::size_t>> split;
        for (const Refinement& r : refinements) {
          if (!split.insert({r.axis, r.cell}).second) continue;
          std::vector<std::vector<double>> candidate = next;
          const double mid = 0.5 * (axes[r.axis][r.cell] + axes[r.axis][r.cell + 1]);
          auto& axis = candidate[r.axis];
          axis.insert(std::upper_bound(axis.begin(), axis.end(), mid), mid);
          if (grid_size(candidate) > options.max_grid_points) continue;
          next = std::move(candidate);
        }
      }
      grid_final = next == axes || grid_size(next) > options.max_grid_points;
      only_fixed_axes = refinements.empty();
    }
    // A grid that cannot be refined further is still measured when it meets the target on the training points.
    verify = verify || (grid_final && measured.max_error <= options.max_error);
    if (verify) {
      if (!held_out) {
        held_out = draw_points(table, held_out_seed++, options.held_out_points, evaluators, threads);
        stats.probe_evaluations += held_out->size();
        ++stats.held_out_sets;
      }
      const Measurement verified = measure(table, *held_out, threads);
      if (verified.max_error <= options.max_error) {
        table.max_error = verified.max_error;
        const double* worst = held_out->point(verified.worst);
        table.max_error_location.assign(worst, worst + table.axes.size());
        stats.held_out_points = held_out->size();
        return table;
      }
      if (stats.held_out_sets >= kMaxHeldOutSets) {
        diagnostics.error(where, "held-out points keep finding errors above --max-error " +
                                     format_number(options.max_error) + " (" + format_number(verified.max_error) +
                                     " at " + point_text(table, held_out->point(verified.worst)) + ")",
                          {"the function has features narrower than the training points resolve: raise "
                           "--max-error or fix more inputs"});
        return std::nullopt;
      }
      // The failed held-out set joins the training set; the next verification draws a fresh one.
      training.points.insert(training.points.end(), held_out->points.begin(), held_out->points.end());
      training.reference.insert(training.reference.end(), held_out->reference.begin(), held_out->reference.end());
      held_out.reset();
      continue;
    }

    if (grid_final) {
      diagnostics.error(where,
                        std::string(only_fixed_axes ? "cannot refine the grid to reach" : "cannot reach") +
                            " --max-error " + format_number(options.max_error) + " within " +
                            std::to_string(options.max_grid_points) + " grid points: the grid reached " +
                            counts_text(axes) + " with a maximum error of " + format_number(measured.max_error) +
                            " at " + point_text(table, training.point(measured.worst)),
                        {only_fixed_axes
                             ? "the error lies along axes whose point count is fixed (--vary NAME:points): give "
                               "them more points or leave the count out"
                             : "raise --max-grid-points or --max-error, fix more inputs (--fix NAME=VALUE), or use "
                               "--target cpp for an evaluator without interpolation error"});
      return std::nullopt;
    }
    if (!grid.set_axes(next, diagnostics)) return std::nullopt;
    axes = std::move(next);
  }
}

}  // namespace fmpc

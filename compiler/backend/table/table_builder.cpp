#include "compiler/backend/table/table_builder.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "compiler/backend/table/cell_bound.h"
#include "compiler/backend/table/table_bound.h"
#include "compiler/backend/table/table_estimate.h"
#include "compiler/backend/table/table_grid.h"
#include "compiler/backend/table/table_points.h"
#include "diagnostics/number_format.h"

// The build's pieces by job: table_points.h (threads, interpreters, point sets, measurement), table_grid.h (axes,
// grid values, refinement), table_bound.h (the derived bound over every cell), table_estimate.h (the estimate).
namespace fmpc {

namespace {

constexpr double kTrainingMargin = 0.8;  // train below 0.8 of the target before measuring held-out points
constexpr int kMaxHeldOutSets = 6;

struct Training {
  table_build::PointSet points;
  table_build::Measurement measured;
  bool grid_final = false;       // the budget (or fixed counts) allow no further refinement
  bool only_fixed_axes = false;  // ... because only axes with a fixed count could reduce the error
};

}  // namespace

double reachable_error_floor(const CompileResult& compiled, TableValueType value_type) {
  double largest = 0.0, range = 0.0;
  for (const Variable& output : compiled.system.outputs) {
    largest = std::max({largest, std::fabs(output.min), std::fabs(output.max)});
    range = std::max(range, output.max - output.min);
  }
  const double unit_roundoff = value_type == TableValueType::Float32 ? 0x1.0p-24 : 0x1.0p-53;
  const double passes = std::isfinite(compiled.error_bound()) ? compiled.error_bound() : 0.0;
  return unit_roundoff * largest + 1e-12 * range + passes;
}

std::optional<LookupTable> build_table(const FuzzySystem& source, const CompileResult& compiled,
                                       const TableBuildOptions& options, DiagnosticList& diagnostics,
                                       TableBuildStatistics* statistics) {
  using namespace table_build;
  TableBuildStatistics local;
  TableBuildStatistics& stats = statistics ? *statistics : local;
  const FuzzySystem& system = compiled.system;
  const SourceRange where{options.source_path, 0, 0, 0, 0};
  const SourceRange command_line{"command line", 0, 0, 0, 0};
  if (!(options.max_error > 0.0) || !std::isfinite(options.max_error)) {
    diagnostics.error(command_line, "--max-error must be a positive number, not " + format_number(options.max_error));
    return std::nullopt;
  }
  if (const double floor = reachable_error_floor(compiled, options.value_type); options.max_error <= floor) {
    diagnostics.error(command_line,
                      "--max-error " + format_number(options.max_error) + " is below what a table of '" +
                          system.name + "' can reach: its floor is " + format_number(floor),
                      {"the floor is the rounding of the stored " +
                           std::string(options.value_type == TableValueType::Float32 ? "float" : "double") +
                           " values plus the interpreter's own rounding (1e-12 of the output range)" +
                           (std::isfinite(compiled.error_bound()) && compiled.error_bound() > 0.0
                                ? " and the passes' error bound"
                                : "") +
                           "; give --max-error above it, or use --target cpp for an evaluator without "
                           "interpolation error"});
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
  for (const Variable& output : system.outputs) {
    table.output_names.push_back(output.name);
    table.output_units.push_back(output.unit);
  }
  for (const auto& [index, value] : compiled.fixed) {
    const Variable& input = source.inputs[static_cast<std::size_t>(index)];
    table.fixed_inputs.push_back(TableFixedInput{input.name, input.unit, value});
  }

  std::vector<std::vector<double>> axes;
  std::vector<bool> refinable;
  for (std::size_t a = 0; a < system.inputs.size(); ++a) {
    const Variable& input = system.inputs[a];
    TableAxis axis;
    axis.input_name = input.name;
    axis.input_unit = input.unit;
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

  // Refinement driven by measured errors at seeded training points: cheap, and where both statements start.
  Training training;
  training.points = draw_points(table, options.seed, options.training_points, evaluators, threads);
  stats.probe_evaluations += training.points.size();
  const double threshold = kTrainingMargin * options.max_error;
  const auto refine_by_training = [&]() -> bool {
    for (;;) {
      ++stats.rounds;
      training.measured = measure(table, training.points, threads);
      stats.training_error = training.measured.max_error;
      if (options.progress || options.early_refusal_factor > 0) {
        TableBuildProgress progress;
        progress.round = stats.rounds;
        progress.grid_points = grid_size(axes);
        progress.budget = options.max_grid_points;
        progress.training_error = training.measured.max_error;
        progress.target = options.max_error;
        // Optimistic: the interpolation error falls as h^2 on every axis at once.
        const double ratio = std::max(1.0, training.measured.max_error / options.max_error);
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
                                ", has a maximum error of " + format_number(training.measured.max_error) +
                                ", and even if the error falls as h^2 the target needs about " +
                                format_number(std::round(progress.estimated_grid_points)) +
                                " grid points (an estimate; refused now instead of refining on)",
                            {"raise --max-error or --max-grid-points, or fix more inputs (--fix NAME=VALUE), or use "
                             "--target cpp for an evaluator without interpolation error"});
          return false;
        }
      }
      if (training.measured.max_error <= threshold || training.grid_final) return true;
      const std::vector<Refinement> refinements =
          worst_axes(table, training.points, training.measured, refinable, threshold, evaluators, options, stats);
      std::vector<std::vector<double>> next = axes;
      std::vector<std::pair<std::size_t, std::size_t>> splits;
      for (const Refinement& r : refinements) splits.emplace_back(r.axis, r.cell);
      std::vector<double> weights;
      for (const Refinement& r : refinements) weights.push_back(r.error);
      refine_axes(axes, splits, weights, options, next);
      training.grid_final = next == axes || grid_size(next) > options.max_grid_points;
      training.only_fixed_axes = refinements.empty();
      if (training.grid_final) return true;
      if (!grid.set_axes(next, diagnostics)) return false;
      axes = std::move(next);
    }
  };

  // The statement is a bound where the rule base admits one (cell_bound.h) and the passes' own error is known.
  std::optional<std::string> limitation = cell_bound_limitation(system, options.evaluation);
  if (!limitation && !std::isfinite(compiled.error_bound()))
    limitation = std::string("the passes' error has no known bound");
  stats.bound_limitation = limitation.value_or("");
  // The training points' error is a lower bound of any bound: where refinement stopped above the target, say so.
  const auto unreachable = [&]() {
    diagnostics.error(where,
                      std::string(training.only_fixed_axes ? "cannot refine the grid to reach" : "cannot reach") +
                          " --max-error " + format_number(options.max_error) + " within " +
                          std::to_string(options.max_grid_points) + " grid points: the grid reached " +
                          counts_text(axes) + " with a maximum error of " +
                          format_number(training.measured.max_error) + " at " +
                          point_text(table, training.points.point(training.measured.worst)),
                      {training.only_fixed_axes
                           ? "the error lies along axes whose point count is fixed (--vary NAME:points): give "
                             "them more points or leave the count out"
                           : "raise --max-grid-points or --max-error, fix more inputs (--fix NAME=VALUE), or use "
                             "--target cpp for an evaluator without interpolation error"});
  };
  if (!limitation) {
    if (!refine_by_training()) return std::nullopt;
    if (training.measured.max_error > options.max_error) {
      unreachable();
      return std::nullopt;
    }
    // The interpreter's own rounding, against which the table is stated: far below any target that matters.
    double range = 0.0;
    for (const Variable& output : system.outputs) range = std::max(range, output.max - output.min);
    const double slack = compiled.error_bound() + 1e-12 * range;
    std::vector<CellBounder> bounders;
    for (int t = 0; t < threads; ++t) bounders.emplace_back(system, options.evaluation);
    std::vector<double> worst_bounds;
    for (;;) {
      ++stats.rounds;
      const CellBounds cells = bound_cells(table, grid.rounding(), bounders, evaluators, refinable,
                                           options.max_error - slack, threads, stats);
      const double stated = cells.bound[cells.worst] + slack;
      worst_bounds.push_back(stated);
      const bool stalled = worst_bounds.size() > static_cast<std::size_t>(kStalledBoundRounds) &&
                           !(stated < kStalledBoundRatio * worst_bounds[worst_bounds.size() - 1 - kStalledBoundRounds]);
      if (stated <= options.max_error) {
        table.max_error = stated;
        table.error_kind = TableErrorKind::Bound;
        table.max_error_location = cell_centre(table, cells, cells.worst);
        stats.cells = cells.size();
        return table;
      }
      // Refine the cells whose bound exceeds the target, each along its own axis (uniform: the axis most of
      // that excess asks for, doubled).
      std::vector<std::size_t> over;
      for (std::size_t c = 0; c < cells.size(); ++c)
        if (cells.bound[c] + slack > options.max_error && cells.split[c] >= 0) over.push_back(c);
      std::stable_sort(over.begin(), over.end(),
                       [&](std::size_t a, std::size_t b) { return cells.bound[a] > cells.bound[b]; });
      std::vector<std::pair<std::size_t, std::size_t>> splits;
      std::vector<double> weights;
      std::vector<std::size_t> origin(axes.size());
      for (std::size_t c : over) {
        cell_origin(c, cells.counts, origin);
        const auto a = static_cast<std::size_t>(cells.split[c]);
        splits.emplace_back(a, origin[a]);
        weights.push_back(std::min(cells.bound[c], 1e300));
      }
      std::vector<std::vector<double>> next = axes;
      refine_axes(axes, splits, weights, options, next);
      if (next == axes || grid_size(next) > options.max_grid_points || stalled) {
        const std::vector<double> centre = cell_centre(table, cells, cells.worst);
        const bool fixed_axes_only = over.empty();
        diagnostics.error(where,
                          "cannot bound the table's error below --max-error " + format_number(options.max_error) +
                              (fixed_axes_only ? " by refining the automatic axes"
                               : stalled ? " by refining: " + std::to_string(kStalledBoundRounds) +
                                               " refinements left the bound where it was, as at a jump in the rules"
                                         : " within " + std::to_string(options.max_grid_points) + " grid points") +
                              ": the grid reached " + counts_text(axes) + " and its error bound is " +
                              format_number(stated) + ", largest in the cell around " +
                              point_text(table, centre.data()),
                          {fixed_axes_only
                               ? "the error lies along axes whose point count is fixed (--vary NAME:points): give "
                                 "them more points or leave the count out"
                               : stalled ? "where the rules jump (a step in a membership function, a region where no rule "
                                           "fires), no grid interpolates them within less than half the jump: raise "
                                           "--max-error above it, fix the input that jumps (--fix NAME=VALUE), or use "
                                           "--target cpp for an evaluator without interpolation error"
                               : "raise --max-grid-points or --max-error, fix more inputs (--fix NAME=VALUE), or use "
                                 "--target cpp for an evaluator without interpolation error; where the rules jump "
                                 "(a step in a membership function, a region where no rule fires), no grid "
                                 "interpolates them within less than half the jump"});
        return std::nullopt;
      }
      if (!grid.set_axes(next, diagnostics)) return std::nullopt;
      axes = std::move(next);
    }
  }

  // The estimate: training refinement, then a held-out set, every cell's centre and local searches from the worst
  // points found; where they exceed the target, they join the training points and refinement goes on.
  std::uint64_t held_out_seed = options.seed ^ 0x9E3779B97F4A7C15ULL;
  for (;;) {
    if (!refine_by_training()) return std::nullopt;
    if (training.measured.max_error > options.max_error) {  // the budget (or fixed counts) stopped refinement
      unreachable();
      return std::nullopt;
    }
    const PointSet held_out = draw_points(table, held_out_seed++, options.held_out_points, evaluators, threads);
    stats.probe_evaluations += held_out.size();
    ++stats.held_out_sets;
    const Estimate estimate = estimate_error(table, held_out, evaluators, options, threads, stats);
    if (estimate.error <= options.max_error) {
      table.max_error = estimate.error;
      table.error_kind = TableErrorKind::Estimate;
      table.max_error_location = estimate.location;
      stats.held_out_points = held_out.size();
      return table;
    }
    if (stats.held_out_sets >= kMaxHeldOutSets) {
      diagnostics.error(where, "held-out points, cell centres and local searches keep finding errors above "
                               "--max-error " +
                                   format_number(options.max_error) + " (" + format_number(estimate.error) +
                                   " at " + point_text(table, estimate.location.data()) + ")",
                        {"the function has features narrower than the training points resolve: raise "
                         "--max-error or fix more inputs"});
      return std::nullopt;
    }
    // The held-out set and the points found above the target join the training set.
    training.points.points.insert(training.points.points.end(), held_out.points.begin(), held_out.points.end());
    training.points.reference.insert(training.points.reference.end(), held_out.reference.begin(),
                                     held_out.reference.end());
    if (!estimate.above_target.empty()) {
      const PointSet extra = with_reference(table, estimate.above_target, evaluators, threads);
      training.points.points.insert(training.points.points.end(), extra.points.begin(), extra.points.end());
      training.points.reference.insert(training.points.reference.end(), extra.reference.begin(),
                                       extra.reference.end());
    }
    training.grid_final = false;
  }
}

double default_table_max_error(const FuzzySystem& source) {
  double narrowest = std::numeric_limits<double>::infinity();
  for (const Variable& output : source.outputs) narrowest = std::min(narrowest, output.max - output.min);
  return 0.01 * narrowest;
}

}  // namespace fmpc

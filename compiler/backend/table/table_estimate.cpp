#include "compiler/backend/table/table_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "compiler/backend/table/table_bound.h"

namespace fmpc::table_build {

namespace {

constexpr std::size_t kLocalSearches = 32;  // compass searches from the worst held-out points and centres

// The largest |table - reference| at `start` and around it: a compass search (each axis in turn, +- a step that
// starts at a quarter of the point's cell and halves when no move improves), inside the axes' box.
std::pair<double, std::vector<double>> local_search(const LookupTable& table, const TableView<double>& view,
                                                    std::vector<double> point, Evaluators& evaluators, int thread,
                                                    std::uint64_t& evaluations) {
  const std::size_t d = table.axes.size(), m = table.output_names.size();
  std::vector<double> out(m);
  const auto error_at = [&](const std::vector<double>& x) {
    interpolate_table(view, x.data(), out.data());
    const std::vector<double> reference = evaluators.reference(thread, x.data());
    ++evaluations;
    double error = 0.0;
    for (std::size_t o = 0; o < m; ++o) {
      const double difference = std::fabs(out[o] - reference[o]);
      error = std::isnan(difference) ? std::numeric_limits<double>::infinity() : std::max(error, difference);
    }
    return error;
  };
  std::vector<double> step(d);
  for (std::size_t a = 0; a < d; ++a) {
    const std::vector<double>& axis = table.axes[a].breakpoints;
    int cell = 0;
    double fraction = 0.0;
    locate_on_axis(axis.data(), static_cast<int>(axis.size()), point[a], cell, fraction);
    step[a] = 0.25 * (axis[static_cast<std::size_t>(cell) + 1] - axis[static_cast<std::size_t>(cell)]);
  }
  double best = error_at(point);
  for (int round = 0; round < 40; ++round) {
    bool moved = false;
    for (std::size_t a = 0; a < d; ++a)
      for (const double sign : {1.0, -1.0}) {
        std::vector<double> candidate = point;
        candidate[a] = std::clamp(point[a] + sign * step[a], table.axes[a].breakpoints.front(),
                                  table.axes[a].breakpoints.back());
        if (candidate[a] == point[a]) continue;
        const double error = error_at(candidate);
        if (error > best) {
          best = error;
          point = std::move(candidate);
          moved = true;
        }
      }
    if (!moved)
      for (double& s : step) s /= 2.0;
  }
  return {best, point};
}

}  // namespace

Estimate estimate_error(const LookupTable& table, const PointSet& held_out, Evaluators& evaluators,
                        const TableBuildOptions& options, int threads, TableBuildStatistics& stats) {
  const std::size_t d = table.axes.size();
  const Measurement at_held_out = measure(table, held_out, threads);
  std::vector<double> centres;
  CellBounds shape;
  for (const TableAxis& axis : table.axes) shape.counts.push_back(axis.breakpoints.size() - 1);
  std::size_t cells = 1;
  for (std::size_t c : shape.counts) cells *= c;
  for (std::size_t c = 0; c < cells; ++c) {
    const std::vector<double> centre = cell_centre(table, shape, c);
    centres.insert(centres.end(), centre.begin(), centre.end());
  }
  const PointSet centre_set = with_reference(table, std::move(centres), evaluators, threads);
  const Measurement at_centres = measure(table, centre_set, threads);
  stats.probe_evaluations += centre_set.size();
  stats.cells = centre_set.size();
  std::vector<std::vector<double>> starts;
  for (const PointSet* set : {&held_out, &centre_set}) {
    const Measurement& measured = set == &centre_set ? at_centres : at_held_out;
    std::vector<std::size_t> order(measured.errors.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    const std::size_t take = std::min<std::size_t>(order.size(), kLocalSearches / 2);
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(take), order.end(),
                      [&](std::size_t a, std::size_t b) {
                        return measured.errors[a] != measured.errors[b] ? measured.errors[a] > measured.errors[b]
                                                                        : a < b;
                      });
    for (std::size_t k = 0; k < take; ++k) starts.emplace_back(set->point(order[k]), set->point(order[k]) + d);
  }
  std::vector<const double*> pointers;
  std::vector<int> counts;
  const TableView<double> view = view_of(table, pointers, counts);
  std::vector<std::pair<double, std::vector<double>>> searched(starts.size());
  std::vector<std::uint64_t> evaluations(starts.size(), 0);
  run_parallel(starts.size(), threads, [&](int thread, std::size_t k) {
    searched[k] = local_search(table, view, starts[k], evaluators, thread, evaluations[k]);
  });
  for (std::uint64_t e : evaluations) stats.probe_evaluations += e;
  stats.local_searches = searched.size();

  Estimate estimate;
  estimate.error = at_held_out.max_error;
  estimate.location.assign(held_out.point(at_held_out.worst), held_out.point(at_held_out.worst) + d);
  if (at_centres.max_error > estimate.error) {
    estimate.error = at_centres.max_error;
    estimate.location.assign(centre_set.point(at_centres.worst), centre_set.point(at_centres.worst) + d);
  }
  for (const auto& [error, point] : searched) {
    if (error > estimate.error) {
      estimate.error = error;
      estimate.location = point;
    }
    if (error > options.max_error) estimate.above_target.insert(estimate.above_target.end(), point.begin(), point.end());
  }
  for (const PointSet* set : {&held_out, &centre_set}) {
    const Measurement& measured = set == &centre_set ? at_centres : at_held_out;
    for (std::size_t i = 0; i < set->size(); ++i)
      if (measured.errors[i] > options.max_error)
        estimate.above_target.insert(estimate.above_target.end(), set->point(i), set->point(i) + d);
  }
  return estimate;
}

}  // namespace fmpc::table_build

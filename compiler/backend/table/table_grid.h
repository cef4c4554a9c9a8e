#pragma once
// The grid of a table build (table_builder.h): its starting axes, the values at its points (only new points are
// evaluated when axes grow), and where refinement goes next. Internal to the table builder.
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "compiler/backend/table/table_builder.h"
#include "compiler/backend/table/table_points.h"
#include "diagnostics/diagnostic.h"

namespace fmpc::table_build {

// The number of grid points (saturating above 2^62).
std::uint64_t grid_size(const std::vector<std::vector<double>>& axes);
// "5 x 9 = 45 points".
std::string counts_text(const std::vector<std::vector<double>>& axes);
// `count` breakpoints evenly from lo to hi (both included exactly).
std::vector<double> uniform_axis(double lo, double hi, int count);
// The refined spacing's starting axis: the ends of the input's range and the tops, shoulders and centres of its
// terms inside it.
std::vector<double> feature_axis(const Variable& input);

// The table's values over a grid that only grows.
class GridBuilder {
 public:
  GridBuilder(LookupTable& table, Evaluators& evaluators, const TableBuildOptions& options, TableBuildStatistics& stats)
      : table_(table), evaluators_(evaluators), options_(options), stats_(stats) {}

  // Replaces the grid's axes by `axes` (each a superset of the current one), evaluating only the new points; false
  // after an error when an output is not finite at a grid point (no rule fires there and the policy is `error`).
  bool set_axes(const std::vector<std::vector<double>>& axes, DiagnosticList& diagnostics);

  // |stored value - computed value| per value of the table (non-zero for float32 tables).
  const std::vector<double>& rounding() const { return rounding_; }

 private:
  LookupTable& table_;
  Evaluators& evaluators_;
  const TableBuildOptions& options_;
  TableBuildStatistics& stats_;
  std::vector<double> rounding_;
};

struct Refinement {
  std::size_t axis = 0;
  std::size_t cell = 0;
  double error = 0.0;  // how far linear interpolation along the axis misses at the point
};

// For each of the (at most 64) worst training points above `threshold`, the axis along which
// interpolating between its cell's ends misses most; points whose worst axis is not `refinable` are left out.
std::vector<Refinement> worst_axes(const LookupTable& table, const PointSet& training, const Measurement& measured,
                                   const std::vector<bool>& refinable, double threshold, Evaluators& evaluators,
                                   const TableBuildOptions& options, TableBuildStatistics& stats);

// The next axes (`next`, a copy of `axes` on entry) for the cells asking to be split, (axis, cell index along it)
// with a weight each. Uniform: the axis with the largest total weight is doubled (n -> 2n - 1, nested, so no grid
// point is evaluated twice); refined: each cell is split at its midpoint on its axis, as long as the grid stays
// within the budget.
void refine_axes(const std::vector<std::vector<double>>& axes,
                 const std::vector<std::pair<std::size_t, std::size_t>>& splits, const std::vector<double>& weights,
                 const TableBuildOptions& options, std::vector<std::vector<double>>& next);

}  // namespace fmpc::table_build

#pragma once
// Builds the `--target table` lookup table of a compiled system (docs/compiler.md, "Table builder"): a grid over
// the varying inputs whose resolution is chosen so that multilinear interpolation (kernels/table_math.h) stays
// within an absolute error of the reference interpreter, measured on held-out points.
//
// Method. The grid values are the specialised system's outputs (exact passes; their error, if any, is part of
// what is measured). The reference is the interpreter on the SOURCE system with the fixed inputs plugged in.
// Starting from a coarse grid, each round measures the error on a seeded training set of points, takes the worst
// points and, for each, finds the axis along which linear interpolation between its cell's ends misses the most
// (two evaluations per axis), then refines that axis:
//   uniform: the axis of the worst point is doubled (n -> 2n - 1, nested, so no point is evaluated twice);
//   refined: the cell of each of the worst points is split at its midpoint on its own worst axis (several
//            insertions per round), the initial axis holding the ends and the tops of the input's terms.
// Once the training error is below 0.8 of the target, a separate held-out set (100,000 points by default, its own
// seed) is measured; if it is above the target, it joins the training set and a fresh held-out set is drawn, so the
// reported error always comes from points that took no part in choosing the grid. Axes with a fixed point count
// (--vary NAME:points) stay uniform at that count. A grid that would exceed the budget stops the build with an
// error saying what was reached; so does a grid whose optimistic size estimate (TableBuildProgress) is far over
// the budget after a few rounds, so that an unreachable target is refused early rather than after minutes.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "compiler/backend/table/lookup_table.h"
#include "compiler/eval/interpreter.h"
#include "compiler/passes/pipeline.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

enum class BreakpointSpacing { Uniform, Refined };

// Where a build stands after each round, for a caller that shows progress (the library prints nothing).
struct TableBuildProgress {
  int round = 0;
  std::uint64_t grid_points = 0;
  std::uint64_t budget = 0;       // max_grid_points
  double training_error = 0.0;    // max error on the training points this round
  double target = 0.0;            // max_error
  // Grid points the target needs if the error keeps falling as h^2 (multilinear interpolation of a smooth
  // function, h the spacing): grid_points * (training_error / target)^(axes / 2). An estimate, and an optimistic
  // one: near a kink of a membership function the error falls only as h.
  double estimated_grid_points = 0.0;
};

struct TableBuildOptions {
  double max_error = 0.0;  // absolute, in output units, for every output; > 0
  BreakpointSpacing spacing = BreakpointSpacing::Refined;
  TableValueType value_type = TableValueType::Float64;  // the stored values are rounded to it before measuring
  std::uint64_t max_grid_points = 1ULL << 21;
  std::size_t held_out_points = 100000;
  std::size_t training_points = 50000;
  std::uint64_t seed = 1;
  int threads = 2;
  EvaluationOptions evaluation;
  std::string source_path;
  std::uint64_t source_hash = 0;
  // Called after each round's measurement; null for none.
  std::function<void(const TableBuildProgress&)> progress;
  // Stop with an error, instead of refining on, once round >= kEarlyRefusalRounds and even the optimistic estimate
  // above needs more than early_refusal_factor x max_grid_points (0 turns the early refusal off).
  double early_refusal_factor = 16.0;
};

inline constexpr int kEarlyRefusalRounds = 2;

struct TableBuildStatistics {
  int rounds = 0;
  int held_out_sets = 0;           // how many held-out sets were drawn (1 when the first one passed)
  std::uint64_t grid_evaluations = 0;
  std::uint64_t probe_evaluations = 0;  // reference evaluations of training and held-out points, and axis probes
  double training_error = 0.0;
  std::size_t held_out_points = 0;
};

// The table, with max_error and max_error_location measured on the last held-out set; nullopt with an error when
// the target is unreachable within the budget or an output is not finite somewhere (policy `error`).
std::optional<LookupTable> build_table(const FuzzySystem& source, const CompileResult& compiled,
                                       const TableBuildOptions& options, DiagnosticList& diagnostics,
                                       TableBuildStatistics* statistics = nullptr);

}  // namespace fmpc

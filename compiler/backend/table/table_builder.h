#pragma once
// Builds the `--target table` lookup table of a compiled system (docs/compiler.md, "Builder" and "Error
// statement"): a grid over the varying inputs whose resolution is chosen so that multilinear interpolation
// (kernels/table_math.h) stays within an absolute error of the reference interpreter, and a statement of that
// error which is a bound where the rule base admits one.
//
// Method. The grid values are the specialised system's outputs (exact passes; a pass's own bound is added). The
// reference is the interpreter on the SOURCE system with the fixed inputs plugged in. Starting from a coarse grid,
// training rounds measure the error on seeded training points and refine the axis (uniform: doubled, nested) or
// the cells (refined: split at the midpoint) where the worst points' interpolation misses most, until the training
// error is below 0.8 of the target. Then:
//   bound (cell_bound.h covers the system): every cell's error is bounded from the rule base's derivatives over
//     the cell; cells above the target are split along the axis their bound blames, until the largest bound is
//     below the target; the table states that bound (TableErrorKind::Bound);
//   estimate (otherwise): a held-out set (100,000 points by default, its own seed), every cell's centre and local
//     searches from the worst points; where they find the target exceeded, those points join the training set and
//     refinement goes on; the table states the largest error found (TableErrorKind::Estimate).
// Axes with a fixed point count (--vary NAME:points) stay uniform at that count. A grid that would exceed the
// budget stops the build with an error saying what was reached; so does a grid whose optimistic size estimate
// (TableBuildProgress) is far over the budget after a few rounds, so that an unreachable target is refused early
// rather than after minutes.
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
  // The memory this process may use (runtime/io/memory_limit.h's memory_limit(); 0: unchecked) and what sets it:
  // every grid is sized against it before it is allocated (a 1.6e9-point grid inside --max-grid-points once took
  // 5.7 GiB before anything refused it).
  std::uint64_t memory_limit_bytes = 0;
  std::string memory_limit_source;
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

// The certified bound's refinement stops, as a jump in the rules, once the worst bound has not fallen below
// kStalledBoundRatio of what it was kStalledBoundRounds refinements before: each refinement at least halves the
// width of every cell above the target, which takes a smooth rule base's bound down by about 4 and a kink's by 2 a
// round (1/16 over four), while a jump's bound stays at half the jump however narrow its cell gets.
inline constexpr int kStalledBoundRounds = 4;
inline constexpr double kStalledBoundRatio = 0.5;

struct TableBuildStatistics {
  int rounds = 0;
  std::uint64_t grid_evaluations = 0;
  // Bound: the cells of the final grid, and how many cell bounds were computed over all rounds. Estimate: the
  // cells whose centres were measured.
  std::size_t cells = 0;
  std::uint64_t cells_bounded = 0;
  // Why the statement is an estimate (cell_bound_limitation), empty for a bound.
  std::string bound_limitation;
  // Estimate only.
  int held_out_sets = 0;           // how many held-out sets were drawn (1 when the first one passed)
  std::uint64_t probe_evaluations = 0;  // reference evaluations of training, held-out and centre points, probes
  double training_error = 0.0;
  std::size_t held_out_points = 0;
  std::size_t local_searches = 0;
};

// The error target when the caller names none (`fmpc compile --target table` without --max-error, the Python
// module's compile_table without max_error): 1% of the narrowest output range.
double default_table_max_error(const FuzzySystem& source);

// The smallest maximum error a table of `compiled` can state: the stored values' rounding (half an ulp of the
// value type at the largest |output|), the interpreter's own rounding against which the table is measured (1e-12
// of the widest output range) and the passes' error bound where it is finite. A --max-error at or below it is
// refused before anything is evaluated (docs/compiler.md, "Error statement").
double reachable_error_floor(const CompileResult& compiled, TableValueType value_type);

// The table, with its error statement (max_error, error_kind, max_error_location); nullopt with an error when the
// target is unreachable within the budget or an output is not finite somewhere (policy `error`). Throws what the
// interpreter throws (an internal error), from any of its threads.
std::optional<LookupTable> build_table(const FuzzySystem& source, const CompileResult& compiled,
                                       const TableBuildOptions& options, DiagnosticList& diagnostics,
                                       TableBuildStatistics* statistics = nullptr);

}  // namespace fmpc

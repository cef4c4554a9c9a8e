#pragma once
// Lint: warnings about systems that are valid but probably wrong. Each warning has a code (the name in brackets)
// that `fmpc check` prints and that docs/lint.md explains.
#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

struct LintOptions {
  // A point of an input's range is a coverage hole when no term of that input reaches this grade there, or, over
  // the grid of all inputs, when no rule fires above it.
  double coverage_threshold = 0.1;
  int coverage_points_per_input = 101;  // grid for the per-input check
  long coverage_grid_budget = 200000;   // total points for the joint (all inputs) check
  double near_zero_width_fraction = 1e-6;  // of the variable's range
  bool require_units = true;  // unit warnings; off for MATLAB files, whose format has no units
};

// Codes: unused-term, rule-never-fires, duplicate-rule, conflicting-rules, coverage-hole, term-out-of-range,
// terms-out-of-order, near-zero-width, unit, lower-exceeds-upper (interval type-2 explicit lower MFs).
void lint_system(const FuzzySystem& system, const LintOptions& options, DiagnosticList& diagnostics);

}  // namespace fmpc

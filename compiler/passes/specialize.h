#pragma once
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "compiler/passes/pass_report.h"

namespace fmpc {

struct InputValue {
  int input = -1;  // index into the system's inputs
  double value = 0.0;
};

// Folds inputs fixed by bindings into the system, which keeps only the other inputs, in their declaration order.
// A rule's clauses on fixed inputs are evaluated once (hedge, then negation, as the interpreter does) and combined
// with the rule's connective into Rule::folded_grade, which starts the fold of its remaining clauses; Sugeno
// linear outputs p1 x1 + ... + pn xn + c absorb p_i v_i of each fixed input into c and drop its coefficient.
// Exact: the output equals the original's at every point (bitwise when every fold is min or max; with prod,
// probor, sum, Einstein norms or linear outputs the operands are regrouped, which changes rounding only).
// Interval type-2 systems: each fixed clause's grade is the interval [lower, upper] of its term (footprint,
// hedge, then `not` swapping the ends: the interpreter's semantics), folded end by end into Rule::folded_grade
// (upper) and Rule::folded_grade_lower (lower); the same exactness holds for each end.
// Precondition: each input appears at most once in `fixed`, values are not NaN.
PassReport specialize(FuzzySystem& system, const std::vector<InputValue>& fixed);

}  // namespace fmpc

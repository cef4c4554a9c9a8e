#pragma once
// The reference interpreter: type-1 Mamdani and Sugeno in double, with MATLAB's semantics by default
// (docs/numerics.md). Every faster path in fmpc states its error against this one.
#include <vector>

#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

// What happened during one evaluation that a caller may want to report. Never printed here.
struct EvaluationFlags {
  std::vector<int> inputs_out_of_range;   // indices of inputs outside [min, max] (evaluated as given)
  std::vector<int> inputs_nan;            // indices of NaN inputs (their outputs are NaN)
  std::vector<int> outputs_no_rule_fired; // outputs for which the no-fire policy applied
  bool no_fire_error = false;             // policy `error` was hit: those outputs are NaN
};

struct Evaluation {
  std::vector<double> outputs;           // one per output variable
  std::vector<double> firing_strengths;  // one per rule: antecedent strength times weight
  EvaluationFlags flags;
};

// Aggregated output fuzzy set of a Mamdani output, sampled where the defuzzifier sampled it (101 points by
// default; for `samples exact`, the points the quadrature used, sorted). Sugeno outputs give the (value, weight)
// pairs instead.
struct OutputExplanation {
  std::vector<double> x;
  std::vector<double> membership;  // Mamdani: aggregated grade at x; Sugeno: rule weight at rule output x
};

struct Explanation {
  Evaluation evaluation;
  std::vector<OutputExplanation> outputs;
};

// Evaluates `system` at `inputs` (one value per input variable, in declaration order).
// Precondition: the system passed sema without errors and inputs.size() == system.inputs.size().
Evaluation evaluate(const FuzzySystem& system, const std::vector<double>& inputs);
Explanation explain(const FuzzySystem& system, const std::vector<double>& inputs);

}  // namespace fmpc

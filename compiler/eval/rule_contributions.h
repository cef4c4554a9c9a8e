#pragma once
// "Why this stiffness": how much each rule contributes to each output at one point (the studio's patient panel).
//
// - Type-1 Sugeno under MATLAB semantics: exact. The output is sum_i h_i z_i / D (wtaver; fis.c divides by the
//   firing strengths of all rules, D, those without a consequent on the output included) or sum_i h_i z_i (wtsum),
//   where h_i is rule i's height (its firing strength, hedged and negated as its consequent says) and z_i its
//   consequent's value. Rule i's contribution is h_i z_i / D (h_i z_i for wtsum): the contributions add up to the
//   output, to rounding.
// - Everything else (Mamdani, interval type-2, Octave semantics): leave one rule out. Rule i's contribution is the
//   output minus the output of the same system without rule i, at the same point. These do not add up to the
//   output: a rule whose conclusion others repeat contributes little alone, however strongly it fires.
//   Removing a rule is evaluated exactly as the interpreter would without it (Interpreter::evaluate_without_rule);
//   when nothing else fires on the output,
//   the output without it is the no-fire policy's value, and `policy_without` says so.
#include <cstddef>
#include <vector>

#include "compiler/eval/interpreter.h"
#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

enum class ContributionMethod { ExactShare, LeaveOneOut };

struct OutputContributions {
  ContributionMethod method = ContributionMethod::ExactShare;
  double output = 0.0;  // the evaluation's output (equal to evaluate()'s)
  bool no_rule_fired = false;  // the no-fire policy gave `output`: every contribution is 0
  // Per rule of the system, in order: 0 for a rule that does not conclude on this output or does not fire.
  std::vector<double> contribution;
  // LeaveOneOut only (empty for ExactShare): per rule, the output without it (equal to `output` for rules that do
  // not fire or do not conclude on this output), and whether the no-fire policy produced it.
  std::vector<double> output_without;
  std::vector<bool> policy_without;
};

struct RuleContributions {
  // explain(system, inputs, options): the evaluation (outputs, firing strengths, flags) and the aggregated sets.
  Explanation explanation;
  std::vector<OutputContributions> outputs;  // one per output
};

// Precondition: as evaluate() (the system passed sema, one input value per input). A NaN input gives NaN outputs
// and NaN contributions, as evaluate() gives NaN outputs.
RuleContributions rule_contributions(const FuzzySystem& system, const std::vector<double>& inputs,
                                     const EvaluationOptions& options = {});

// Which method rule_contributions uses for `system` under `options`.
ContributionMethod contribution_method(const FuzzySystem& system, const EvaluationOptions& options = {});

}  // namespace fmpc

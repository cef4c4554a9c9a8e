#include "compiler/eval/rule_contributions.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fmpc {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool concludes_on(const Rule& rule, std::size_t output) {
  for (const Clause& clause : rule.consequent)
    if (clause.variable == static_cast<int>(output)) return true;
  return false;
}

bool policy_applied(const EvaluationFlags& flags, std::size_t output) {
  return std::find(flags.outputs_no_rule_fired.begin(), flags.outputs_no_rule_fired.end(),
                   static_cast<int>(output)) != flags.outputs_no_rule_fired.end();
}

// The interpreter's Sugeno explanation lists (z, height) for every rule that concludes on the output and fires
// (firing != 0), in rule order (compiler/eval/interpreter.cpp, sugeno_output): matched back to the rules here, so
// that the heights are the interpreter's own, hedges and negation included.
void exact_sugeno_shares(const FuzzySystem& system, const Explanation& explanation, std::size_t o,
                         OutputContributions& result) {
  const std::vector<double>& firing = explanation.evaluation.firing_strengths;
  const OutputExplanation& singletons = explanation.outputs[o];
  // fis.c's denominator: the heights of this output's rules and the firing strengths of the rules that conclude on
  // other outputs only.
  double denominator = 0.0;
  for (double height : singletons.membership) denominator += height;
  for (std::size_t r = 0; r < system.rules.size(); ++r)
    if (!concludes_on(system.rules[r], o)) denominator += firing[r];
  const bool weighted_sum = system.defuzzifier == Defuzzifier::WeightedSum;
  std::size_t next = 0;
  for (std::size_t r = 0; r < system.rules.size(); ++r) {
    if (!concludes_on(system.rules[r], o) || firing[r] == 0.0) continue;
    const double z = singletons.x[next], height = singletons.membership[next];
    ++next;
    result.contribution[r] = weighted_sum ? height * z : height * z / denominator;
  }
}

}  // namespace

ContributionMethod contribution_method(const FuzzySystem& system, const EvaluationOptions& options) {
  return system.type == SystemType::Sugeno && !system.interval_type2 && options.reference == Reference::Matlab
             ? ContributionMethod::ExactShare
             : ContributionMethod::LeaveOneOut;
}

RuleContributions rule_contributions(const FuzzySystem& system, const std::vector<double>& inputs,
                                     const EvaluationOptions& options) {
  const ContributionMethod method = contribution_method(system, options);
  RuleContributions result;
  result.explanation = explain(system, inputs, options);
  const Explanation& explanation = result.explanation;
  const Evaluation& evaluation = explanation.evaluation;
  const std::size_t rules = system.rules.size();
  result.outputs.resize(system.outputs.size());
  for (std::size_t o = 0; o < system.outputs.size(); ++o) {
    OutputContributions& out = result.outputs[o];
    out.method = method;
    out.output = evaluation.outputs[o];
    out.no_rule_fired = policy_applied(evaluation.flags, o);
    out.contribution.assign(rules, std::isnan(out.output) ? kNaN : 0.0);
    if (method == ContributionMethod::LeaveOneOut) {
      out.output_without.assign(rules, out.output);
      out.policy_without.assign(rules, out.no_rule_fired);
    }
    if (method == ContributionMethod::ExactShare && !out.no_rule_fired && !std::isnan(out.output))
      exact_sugeno_shares(system, explanation, o, out);
  }
  if (method == ContributionMethod::ExactShare) return result;

  // Only rules that fire can change an output when removed (type-2: the upper end of the firing interval).
  Interpreter interpreter(system, options);
  for (std::size_t r = 0; r < rules; ++r) {
    if (!(evaluation.firing_strengths[r] > 0.0)) continue;
    const Evaluation other = interpreter.evaluate_without_rule(inputs, r);
    for (std::size_t o = 0; o < system.outputs.size(); ++o) {
      OutputContributions& out = result.outputs[o];
      out.output_without[r] = other.outputs[o];
      out.policy_without[r] = policy_applied(other.flags, o);
      out.contribution[r] = out.output - other.outputs[o];
    }
  }
  return result;
}

}  // namespace fmpc

#include "compiler/passes/specialize.h"

#include <optional>
#include <string>

#include "compiler/eval/interpreter.h"
#include "diagnostics/number_format.h"
#include "kernels/fuzzy_math.h"
#include "kernels/type2_math.h"

namespace fmpc {

namespace {

std::string with_unit(double value, const Variable& variable) {
  return format_number(value) + (variable.unit.empty() || variable.unit == "dimensionless" ? "" : " " + variable.unit);
}

bool regroups_rounding(const FuzzySystem& system, bool any_linear) {
  return any_linear || system.and_method != TNorm::Minimum || system.or_method != SNorm::Maximum;
}

}  // namespace

PassReport specialize(FuzzySystem& system, const std::vector<InputValue>& fixed) {
  PassReport report;
  report.pass = "specialize";
  const std::size_t input_count = system.inputs.size();
  std::vector<std::optional<double>> value_of(input_count);
  for (const InputValue& binding : fixed)
    if (binding.input >= 0 && static_cast<std::size_t>(binding.input) < input_count)
      value_of[static_cast<std::size_t>(binding.input)] = binding.value;

  std::vector<int> new_index(input_count, -1);
  int kept = 0;
  for (std::size_t i = 0; i < input_count; ++i)
    if (!value_of[i]) new_index[i] = kept++;

  std::vector<std::size_t> folded_clauses(input_count, 0);
  std::size_t constant_rules = 0;
  for (Rule& rule : system.rules) {
    const bool conjunction = rule.connective == Connective::And;
    const double identity = conjunction ? tnorm_identity<double>() : snorm_identity<double>();
    // Type-1 rules fold into `folded`; type-2 rules fold each end of the interval (the interpreter's
    // compute_firing_intervals), the upper end into `folded`, the lower into `folded_lower`.
    std::optional<double> folded = rule.folded_grade;
    std::optional<double> folded_lower = system.interval_type2 ? rule.folded_grade_lower : std::nullopt;
    std::vector<Clause> remaining;
    for (const Clause& clause : rule.antecedent) {
      const std::size_t variable = static_cast<std::size_t>(clause.variable);
      if (!value_of[variable]) {
        Clause moved = clause;
        moved.variable = new_index[variable];
        remaining.push_back(moved);
        continue;
      }
      const Term& term = system.inputs[variable].terms[static_cast<std::size_t>(clause.term)];
      const double x = *value_of[variable];
      if (system.interval_type2) {
        GradeInterval<double> mu = interval_hedge(term_membership(term, x), hedge_exponent(clause.hedge));
        if (clause.negated) mu = interval_not(mu);
        const GradeInterval<double> start{folded_lower.value_or(folded.value_or(identity)), folded.value_or(identity)};
        const GradeInterval<double> next = conjunction ? interval_tnorm(system.and_method, start, mu)
                                                       : interval_snorm(system.or_method, start, mu);
        folded = next.upper;
        folded_lower = next.lower;
      } else {
        double mu = apply_hedge(membership(term.mf.kind, term.mf.params.data(), x), hedge_exponent(clause.hedge));
        if (clause.negated) mu = fuzzy_not(mu);
        const double start = folded.value_or(identity);
        folded = conjunction ? tnorm(system.and_method, start, mu) : snorm(system.or_method, start, mu);
      }
      ++folded_clauses[variable];
    }
    const bool had_clauses = !rule.antecedent.empty();
    rule.antecedent = std::move(remaining);
    rule.folded_grade = folded;
    rule.folded_grade_lower = folded_lower;
    if (had_clauses && rule.antecedent.empty()) ++constant_rules;
  }

  bool any_linear = false;
  if (system.type == SystemType::Sugeno) {
    for (Variable& output : system.outputs)
      for (Term& term : output.terms) {
        if (term.mf.kind != MfKind::Linear || term.mf.params.size() != input_count + 1) continue;
        any_linear = any_linear || !fixed.empty();
        std::vector<double> params;
        double constant = term.mf.params[input_count];
        for (std::size_t i = 0; i < input_count; ++i) {
          if (value_of[i]) constant += term.mf.params[i] * *value_of[i];
          else params.push_back(term.mf.params[i]);
        }
        params.push_back(constant);
        term.mf.params = std::move(params);
      }
  }

  std::size_t total_folded = 0;
  for (std::size_t i = 0; i < input_count; ++i) {
    if (!value_of[i]) continue;
    total_folded += folded_clauses[i];
    report.details.push_back("fixed " + system.inputs[i].name + " = " + with_unit(*value_of[i], system.inputs[i]) +
                             ": " + std::to_string(folded_clauses[i]) + " clauses folded");
  }
  if (constant_rules > 0)
    report.details.push_back(std::to_string(constant_rules) +
                             " rules have no clause left: their strength is a constant");
  if (any_linear) report.details.push_back("linear outputs: fixed inputs' terms moved into the constant");

  std::vector<Variable> inputs;
  for (std::size_t i = 0; i < input_count; ++i)
    if (!value_of[i]) inputs.push_back(std::move(system.inputs[i]));
  system.inputs = std::move(inputs);

  const std::size_t fixed_count = input_count - static_cast<std::size_t>(kept);
  report.summary = "folded " + std::to_string(fixed_count) + (fixed_count == 1 ? " input, " : " inputs, ") +
                   std::to_string(total_folded) + " clauses";
  report.error_bound = 0.0;
  report.error_note = !fixed.empty() && regroups_rounding(system, any_linear) ? "exact up to floating-point regrouping" : "exact";
  return report;
}

}  // namespace fmpc

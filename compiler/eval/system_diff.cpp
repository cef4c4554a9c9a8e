#include "compiler/eval/system_diff.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "compiler/eval/output_comparison.h"
#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

int find_by_name(const std::vector<Variable>& variables, const std::string& name) {
  for (std::size_t i = 0; i < variables.size(); ++i)
    if (variables[i].name == name) return static_cast<int>(i);
  return -1;
}

// Numbers compare as doubles, NaN equal to NaN.
bool same_numbers(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size()) return false;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!(x[i] == y[i] || (std::isnan(x[i]) && std::isnan(y[i])))) return false;
  return true;
}

bool same_footprint(const std::optional<Footprint>& x, const std::optional<Footprint>& y) {
  if (x.has_value() != y.has_value()) return false;
  if (!x) return true;
  return x->kind == y->kind && same_numbers({x->first, x->second}, {y->first, y->second}) &&
         x->lower.kind == y->lower.kind && same_numbers(x->lower.params, y->lower.params);
}

void compare_variables(const FuzzySystem& a, const FuzzySystem& b, bool output, SystemDifferences& result) {
  const std::vector<Variable>& va = output ? a.outputs : a.inputs;
  const std::vector<Variable>& vb = output ? b.outputs : b.inputs;
  for (std::size_t i = 0; i < va.size(); ++i) {
    const int j = find_by_name(vb, va[i].name);
    if (j < 0) {
      result.variables.push_back({ChangeKind::Removed, output, static_cast<int>(i), -1, {}});
      continue;
    }
    const Variable& x = va[i];
    const Variable& y = vb[static_cast<std::size_t>(j)];
    VariableChange change{ChangeKind::Changed, output, static_cast<int>(i), j, {}};
    if (!same_numbers({x.min, x.max}, {y.min, y.max}))
      change.what.push_back("range [" + format_number(x.min) + ", " + format_number(x.max) + "] -> [" +
                            format_number(y.min) + ", " + format_number(y.max) + "]");
    if (x.unit != y.unit)
      change.what.push_back("unit " + (x.unit.empty() ? std::string("(none)") : x.unit) + " -> " +
                            (y.unit.empty() ? std::string("(none)") : y.unit));
    if (!change.what.empty()) result.variables.push_back(change);
    for (std::size_t t = 0; t < x.terms.size(); ++t) {
      const int u = y.find_term(x.terms[t].name);
      TermChange term{ChangeKind::Changed, output, x.name, static_cast<int>(i), j, static_cast<int>(t), u};
      if (u < 0) {
        term.kind = ChangeKind::Removed;
        result.terms.push_back(term);
        continue;
      }
      const Term& p = x.terms[t];
      const Term& q = y.terms[static_cast<std::size_t>(u)];
      term.family_changed = p.mf.kind != q.mf.kind;
      term.parameters_changed = !term.family_changed && !same_numbers(p.mf.params, q.mf.params);
      term.footprint_changed = !same_footprint(p.footprint, q.footprint);
      if (term.family_changed || term.parameters_changed || term.footprint_changed) result.terms.push_back(term);
    }
    for (std::size_t u = 0; u < y.terms.size(); ++u)
      if (x.find_term(y.terms[u].name) < 0)
        result.terms.push_back(
            {ChangeKind::Added, output, x.name, static_cast<int>(i), j, -1, static_cast<int>(u)});
  }
  for (std::size_t j = 0; j < vb.size(); ++j)
    if (find_by_name(va, vb[j].name) < 0)
      result.variables.push_back({ChangeKind::Added, output, -1, static_cast<int>(j), {}});
}

// A clause by names, so that two versions with reordered variables or terms compare by what the rule says.
using ClauseKey = std::tuple<std::string, std::string, bool, int>;  // variable, term, not, hedge

std::vector<ClauseKey> clause_keys(const FuzzySystem& system, const std::vector<Clause>& clauses, bool consequent) {
  const std::vector<Variable>& variables = consequent ? system.outputs : system.inputs;
  std::vector<ClauseKey> keys;
  for (const Clause& clause : clauses) {
    const bool variable_ok = clause.variable >= 0 && static_cast<std::size_t>(clause.variable) < variables.size();
    const Variable* variable = variable_ok ? &variables[static_cast<std::size_t>(clause.variable)] : nullptr;
    const bool term_ok =
        variable && clause.term >= 0 && static_cast<std::size_t>(clause.term) < variable->terms.size();
    keys.emplace_back(variable ? variable->name : "#" + std::to_string(clause.variable),
                      term_ok ? variable->terms[static_cast<std::size_t>(clause.term)].name
                              : "#" + std::to_string(clause.term),
                      clause.negated, static_cast<int>(clause.hedge));
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

// With one clause, `and` and `or` say the same thing.
int connective_key(const Rule& rule) {
  return rule.antecedent.size() <= 1 ? -1 : static_cast<int>(rule.connective);
}

void compare_rules(const FuzzySystem& a, const FuzzySystem& b, SystemDifferences& result) {
  const std::size_t na = a.rules.size(), nb = b.rules.size();
  std::vector<int> match(na, -1);
  std::vector<bool> taken(nb, false);
  for (std::size_t i = 0; i < na; ++i) {
    if (a.rules[i].label.empty()) continue;
    for (std::size_t j = 0; j < nb; ++j)
      if (!taken[j] && b.rules[j].label == a.rules[i].label) {
        match[i] = static_cast<int>(j);
        taken[j] = true;
        break;
      }
  }
  std::vector<std::vector<ClauseKey>> conditions_a(na), conditions_b(nb);
  for (std::size_t i = 0; i < na; ++i) conditions_a[i] = clause_keys(a, a.rules[i].antecedent, false);
  for (std::size_t j = 0; j < nb; ++j) conditions_b[j] = clause_keys(b, b.rules[j].antecedent, false);
  for (std::size_t i = 0; i < na; ++i) {
    if (match[i] >= 0) continue;
    for (std::size_t j = 0; j < nb; ++j)
      if (!taken[j] && conditions_a[i] == conditions_b[j] &&
          connective_key(a.rules[i]) == connective_key(b.rules[j]) &&
          (a.rules[i].label.empty() || b.rules[j].label.empty())) {
        match[i] = static_cast<int>(j);
        taken[j] = true;
        break;
      }
  }
  for (std::size_t i = 0; i < na; ++i) {
    if (match[i] < 0) {
      result.rules.push_back({ChangeKind::Removed, static_cast<int>(i), -1, false, false, false});
      continue;
    }
    const auto j = static_cast<std::size_t>(match[i]);
    RuleChange change{ChangeKind::Changed, static_cast<int>(i), match[i], false, false, false};
    change.conditions_changed = conditions_a[i] != conditions_b[j] ||
                                connective_key(a.rules[i]) != connective_key(b.rules[j]);
    change.conclusions_changed =
        clause_keys(a, a.rules[i].consequent, true) != clause_keys(b, b.rules[j].consequent, true);
    change.weight_changed = !same_numbers({a.rules[i].weight}, {b.rules[j].weight});
    if (change.conditions_changed || change.conclusions_changed || change.weight_changed)
      result.rules.push_back(change);
  }
  for (std::size_t j = 0; j < nb; ++j)
    if (!taken[j]) result.rules.push_back({ChangeKind::Added, -1, static_cast<int>(j), false, false, false});
}

}  // namespace

SystemDifferences system_differences(const FuzzySystem& a, const FuzzySystem& b) {
  SystemDifferences result;
  result.settings = setting_changes(a, b);
  compare_variables(a, b, false, result);
  compare_variables(a, b, true, result);
  compare_rules(a, b, result);
  return result;
}

int dominant_term(const FuzzySystem& system, std::size_t output, double value) {
  if (std::isnan(value) || output >= system.outputs.size()) return -1;
  const Variable& variable = system.outputs[output];
  int best = -1;
  if (system.type == SystemType::Sugeno) {
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < variable.terms.size(); ++t) {
      const Term& term = variable.terms[t];
      if (term.mf.kind != MfKind::Constant || term.mf.params.empty()) continue;
      const double centre = term.footprint && term.footprint->kind == FootprintKind::IntervalValue
                                ? (term.footprint->first + term.footprint->second) / 2.0
                                : term.mf.params[0];
      const double distance = std::fabs(centre - value);
      if (distance < nearest) {
        nearest = distance;
        best = static_cast<int>(t);
      }
    }
    return best;
  }
  double highest = 0.0;
  for (std::size_t t = 0; t < variable.terms.size(); ++t) {
    const double grade = term_membership(variable.terms[t], value).upper;
    if (grade > highest) {
      highest = grade;
      best = static_cast<int>(t);
    }
  }
  return best;
}

std::vector<OutputComparisonOverPoints> compare_evaluations(const FuzzySystem& a, const FuzzySystem& b,
                                                            const std::vector<Evaluation>& evaluations_a,
                                                            const std::vector<Evaluation>& evaluations_b) {
  std::vector<OutputComparisonOverPoints> result;
  for (std::size_t o = 0; o < a.outputs.size(); ++o) {
    const int ob = find_by_name(b.outputs, a.outputs[o].name);
    if (ob < 0) continue;
    OutputComparisonOverPoints entry;
    entry.name = a.outputs[o].name;
    entry.in_a = static_cast<int>(o);
    entry.in_b = ob;
    result.push_back(std::move(entry));
  }
  const auto applied = [](const Evaluation& e, int output) {
    const auto& list = e.flags.outputs_no_rule_fired;
    return std::find(list.begin(), list.end(), output) != list.end();
  };
  for (std::size_t k = 0; k < evaluations_a.size(); ++k) {
    const Evaluation& ea = evaluations_a[k];
    const Evaluation& eb = evaluations_b[k];
    for (OutputComparisonOverPoints& entry : result) {
      const double x = ea.outputs[static_cast<std::size_t>(entry.in_a)];
      const double y = eb.outputs[static_cast<std::size_t>(entry.in_b)];
      entry.a.push_back(x);
      entry.b.push_back(y);
      entry.difference.push_back(std::isnan(x) || std::isnan(y) ? kNaN : y - x);
      entry.policy_a.push_back(applied(ea, entry.in_a));
      entry.policy_b.push_back(applied(eb, entry.in_b));
      const int sa = dominant_term(a, static_cast<std::size_t>(entry.in_a), x);
      const int sb = dominant_term(b, static_cast<std::size_t>(entry.in_b), y);
      entry.stage_a.push_back(sa);
      entry.stage_b.push_back(sb);
      const std::string name_a =
          sa < 0 ? "" : a.outputs[static_cast<std::size_t>(entry.in_a)].terms[static_cast<std::size_t>(sa)].name;
      const std::string name_b =
          sb < 0 ? "" : b.outputs[static_cast<std::size_t>(entry.in_b)].terms[static_cast<std::size_t>(sb)].name;
      if ((sa < 0) != (sb < 0) || name_a != name_b) entry.stage_changes.push_back(k);
    }
  }
  for (OutputComparisonOverPoints& entry : result) {
    std::vector<double> finite_a, finite_b;
    for (std::size_t k = 0; k < entry.a.size(); ++k)
      if (std::isfinite(entry.a[k]) && std::isfinite(entry.b[k])) {
        finite_a.push_back(entry.a[k]);
        finite_b.push_back(entry.b[k]);
      }
    if (!finite_a.empty()) entry.agreement = measure_agreement(finite_b, finite_a);
  }
  return result;
}

std::vector<OutputComparisonOverPoints> compare_over_points(const FuzzySystem& a, const FuzzySystem& b,
                                                            const std::vector<std::vector<double>>& points_a,
                                                            const std::vector<std::vector<double>>& points_b,
                                                            const EvaluationOptions& options) {
  Interpreter ia(a, options), ib(b, options);
  std::vector<Evaluation> ea, eb;
  for (std::size_t k = 0; k < points_a.size(); ++k) {
    ea.push_back(ia.evaluate(points_a[k]));
    eb.push_back(ib.evaluate(points_b[k]));
  }
  return compare_evaluations(a, b, ea, eb);
}

}  // namespace fmpc

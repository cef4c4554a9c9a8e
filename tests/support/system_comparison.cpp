#include "tests/support/system_comparison.h"

#include <algorithm>
#include <cmath>

#include "diagnostics/number_format.h"

namespace fmpc::testing {

namespace {

bool same_number(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

std::string numbers(double a, double b) { return format_number(a) + " vs " + format_number(b); }

std::vector<Clause> by_variable(std::vector<Clause> clauses) {
  std::stable_sort(clauses.begin(), clauses.end(),
                   [](const Clause& a, const Clause& b) { return a.variable < b.variable; });
  return clauses;
}

std::string compare_clauses(const std::string& where, const std::vector<Clause>& expected_clauses,
                            const std::vector<Clause>& actual_clauses) {
  if (expected_clauses.size() != actual_clauses.size())
    return where + " clause count: " + std::to_string(expected_clauses.size()) + " vs " +
           std::to_string(actual_clauses.size());
  const std::vector<Clause> expected = by_variable(expected_clauses);
  const std::vector<Clause> actual = by_variable(actual_clauses);
  for (std::size_t c = 0; c < expected.size(); ++c) {
    const std::string at = where + " clause " + std::to_string(c + 1);
    if (expected[c].variable != actual[c].variable) return at + " variable";
    if (expected[c].term != actual[c].term)
      return at + " term: " + std::to_string(expected[c].term) + " vs " + std::to_string(actual[c].term);
    if (expected[c].negated != actual[c].negated) return at + " negation";
    if (expected[c].hedge != actual[c].hedge)
      return at + " hedge: '" + to_string(expected[c].hedge) + "' vs '" + to_string(actual[c].hedge) + "'";
  }
  return "";
}

std::string compare_variables(const char* role, const std::vector<Variable>& expected,
                              const std::vector<Variable>& actual, const ComparisonOptions& options) {
  if (expected.size() != actual.size())
    return std::string(role) + " count: " + std::to_string(expected.size()) + " vs " + std::to_string(actual.size());
  for (std::size_t v = 0; v < expected.size(); ++v) {
    const Variable& a = expected[v];
    const Variable& b = actual[v];
    const std::string where = std::string(role) + " '" + a.name + "'";
    if (a.name != b.name) return std::string(role) + " " + std::to_string(v + 1) + " name: '" + a.name + "' vs '" +
                                 b.name + "'";
    if (!same_number(a.min, b.min)) return where + " min: " + numbers(a.min, b.min);
    if (!same_number(a.max, b.max)) return where + " max: " + numbers(a.max, b.max);
    if (options.descriptions_units_and_labels) {
      if (a.unit != b.unit) return where + " unit: '" + a.unit + "' vs '" + b.unit + "'";
      if (a.description != b.description) return where + " description";
    }
    if (a.terms.size() != b.terms.size())
      return where + " term count: " + std::to_string(a.terms.size()) + " vs " + std::to_string(b.terms.size());
    for (std::size_t t = 0; t < a.terms.size(); ++t) {
      const Term& x = a.terms[t];
      const Term& y = b.terms[t];
      const std::string term = where + " term " + std::to_string(t + 1);
      if (x.name != y.name) return term + " name: '" + x.name + "' vs '" + y.name + "'";
      if (x.mf.kind != y.mf.kind)
        return term + " kind: " + matlab_name(x.mf.kind) + " vs " + matlab_name(y.mf.kind);
      if (x.mf.params.size() != y.mf.params.size())
        return term + " parameter count: " + std::to_string(x.mf.params.size()) + " vs " +
               std::to_string(y.mf.params.size());
      for (std::size_t p = 0; p < x.mf.params.size(); ++p)
        if (!same_number(x.mf.params[p], y.mf.params[p]))
          return term + " parameter " + std::to_string(p + 1) + ": " + numbers(x.mf.params[p], y.mf.params[p]);
      if (x.footprint.has_value() != y.footprint.has_value())
        return term + " footprint: " + (x.footprint ? "present" : "absent") + " vs " +
               (y.footprint ? "present" : "absent");
      if (x.footprint) {
        const Footprint& f = *x.footprint;
        const Footprint& g = *y.footprint;
        if (f.kind != g.kind)
          return term + " footprint kind: " + std::to_string(static_cast<int>(f.kind)) + " vs " +
                 std::to_string(static_cast<int>(g.kind));
        if (!same_number(f.first, g.first)) return term + " footprint first: " + numbers(f.first, g.first);
        if (!same_number(f.second, g.second)) return term + " footprint second: " + numbers(f.second, g.second);
        if (f.kind == FootprintKind::ExplicitLower) {
          if (f.lower.kind != g.lower.kind || f.lower.params.size() != g.lower.params.size())
            return term + " lower MF kind or parameter count";
          for (std::size_t p = 0; p < f.lower.params.size(); ++p)
            if (!same_number(f.lower.params[p], g.lower.params[p]))
              return term + " lower MF parameter " + std::to_string(p + 1) + ": " +
                     numbers(f.lower.params[p], g.lower.params[p]);
        }
      }
    }
  }
  return "";
}

}  // namespace

std::string first_difference(const FuzzySystem& expected, const FuzzySystem& actual,
                             const ComparisonOptions& options) {
  const FuzzySystem& a = expected;
  const FuzzySystem& b = actual;
  if (a.name != b.name) return "name: '" + a.name + "' vs '" + b.name + "'";
  if (a.type != b.type) return std::string("type: ") + to_string(a.type) + " vs " + to_string(b.type);
  if (a.and_method != b.and_method) return std::string("and: ") + to_string(a.and_method) + " vs " +
                                           to_string(b.and_method);
  if (a.or_method != b.or_method) return std::string("or: ") + to_string(a.or_method) + " vs " + to_string(b.or_method);
  if (a.implication != b.implication)
    return std::string("implication: ") + to_string(a.implication) + " vs " + to_string(b.implication);
  if (a.aggregation != b.aggregation)
    return std::string("aggregation: ") + to_string(a.aggregation) + " vs " + to_string(b.aggregation);
  if (a.defuzzifier != b.defuzzifier)
    return std::string("defuzzifier: ") + to_string(a.defuzzifier) + " vs " + to_string(b.defuzzifier);
  if (a.interval_type2 != b.interval_type2)
    return std::string("interval type-2: ") + (a.interval_type2 ? "yes" : "no") + " vs " +
           (b.interval_type2 ? "yes" : "no");
  if (a.interval_type2 && a.type_reduction != b.type_reduction)
    return std::string("type reduction: ") + to_string(a.type_reduction) + " vs " + to_string(b.type_reduction);
  if (a.samples != b.samples) return "samples: " + std::to_string(a.samples) + " vs " + std::to_string(b.samples);
  if (a.no_fire != b.no_fire) return "no-fire policy";
  if (a.no_fire == NoFirePolicy::Value && !same_number(a.no_fire_value, b.no_fire_value))
    return "no-fire value: " + numbers(a.no_fire_value, b.no_fire_value);
  if (options.descriptions_units_and_labels && a.description != b.description) return "description";
  if (std::string d = compare_variables("input", a.inputs, b.inputs, options); !d.empty()) return d;
  if (std::string d = compare_variables("output", a.outputs, b.outputs, options); !d.empty()) return d;
  if (a.rules.size() != b.rules.size())
    return "rule count: " + std::to_string(a.rules.size()) + " vs " + std::to_string(b.rules.size());
  for (std::size_t r = 0; r < a.rules.size(); ++r) {
    const Rule& x = a.rules[r];
    const Rule& y = b.rules[r];
    const std::string where = "rule " + std::to_string(r + 1);
    if (options.descriptions_units_and_labels && x.label != y.label)
      return where + " label: '" + x.label + "' vs '" + y.label + "'";
    if (x.connective != y.connective) return where + " connective";
    if (!same_number(x.weight, y.weight)) return where + " weight: " + numbers(x.weight, y.weight);
    if (std::string d = compare_clauses(where + " antecedent", x.antecedent, y.antecedent); !d.empty()) return d;
    if (std::string d = compare_clauses(where + " consequent", x.consequent, y.consequent); !d.empty()) return d;
  }
  return "";
}

}  // namespace fmpc::testing

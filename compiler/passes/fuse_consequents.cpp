#include "compiler/passes/fuse_consequents.h"

#include <algorithm>
#include <optional>
#include <string>
#include <tuple>

#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

using ClauseKey = std::tuple<int, int, bool, int>;

std::vector<ClauseKey> clause_keys(const std::vector<Clause>& clauses) {
  std::vector<ClauseKey> keys;
  for (const Clause& c : clauses) keys.emplace_back(c.variable, c.term, c.negated, static_cast<int>(c.hedge));
  std::sort(keys.begin(), keys.end());
  return keys;
}

bool same_clause(const Clause& a, const Clause& b) {
  return a.variable == b.variable && a.term == b.term && a.negated == b.negated && a.hedge == b.hedge;
}

// With at most one clause and no folded grade the connective does not change the strength.
Connective effective_connective(const Rule& rule) {
  if (rule.antecedent.size() <= 1 && !rule.folded_grade) return Connective::And;
  return rule.connective;
}

double identity_of(Connective connective) { return connective == Connective::And ? 1.0 : 0.0; }

// A rule's folded grade on each end: `upper` is Rule::folded_grade; `lower` is Rule::folded_grade_lower in type-2
// rules and the same as `upper` otherwise.
struct FoldedEnds {
  std::optional<double> upper, lower;
};

FoldedEnds folded_ends(const Rule& rule) {
  return {rule.folded_grade, rule.folded_grade_lower ? rule.folded_grade_lower : rule.folded_grade};
}

void set_folded(Rule& rule, std::optional<double> upper, std::optional<double> lower, bool interval_type2) {
  rule.folded_grade = upper;
  rule.folded_grade_lower = interval_type2 && upper ? lower : std::nullopt;
}

// Kind 1: identical antecedents. Returns true and updates `into` when `other` was absorbed. Type-2 rules fold each
// end of their interval with the same nondecreasing fold, so the argument holds on each end (the lower end never
// exceeds the upper one for grades in [0, 1], so the interpreter's span of the ends is the ends themselves).
bool fuse_identical(Rule& into, const Rule& other, bool interval_type2) {
  const Connective connective = effective_connective(into);
  if (connective != effective_connective(other)) return false;
  if (clause_keys(into.antecedent) != clause_keys(other.antecedent)) return false;
  const double identity = identity_of(connective);
  const FoldedEnds a = folded_ends(into), b = folded_ends(other);
  const double mine = a.upper.value_or(identity), theirs = b.upper.value_or(identity);
  const double mine_lower = a.lower.value_or(identity), theirs_lower = b.lower.value_or(identity);
  if (into.weight == other.weight) {
    if (!into.folded_grade && !other.folded_grade) return true;
    const double fused = std::max(mine, theirs), fused_lower = std::max(mine_lower, theirs_lower);
    if (fused == identity && fused_lower == identity && connective == Connective::And)
      set_folded(into, std::nullopt, std::nullopt, interval_type2);
    else
      set_folded(into, fused, fused_lower, interval_type2);
    return true;
  }
  if (mine == theirs && mine_lower == theirs_lower) {
    into.weight = std::max(into.weight, other.weight);
    return true;
  }
  return false;
}

bool disjunctive(const Rule& rule) {
  return rule.connective == Connective::Or || rule.antecedent.empty() ||
         (rule.antecedent.size() == 1 && !rule.folded_grade);
}

// Kind 2: the `or` of two disjunctive rules, when no input gets two different clauses (on each end for type-2).
bool fuse_disjunction(Rule& into, const Rule& other, bool interval_type2) {
  if (!disjunctive(into) || !disjunctive(other) || into.weight != other.weight) return false;
  std::vector<Clause> added;
  for (const Clause& clause : other.antecedent) {
    bool present = false;
    for (const Clause& mine : into.antecedent) {
      if (mine.variable != clause.variable) continue;
      if (!same_clause(mine, clause)) return false;
      present = true;
    }
    if (!present) added.push_back(clause);
  }
  // An empty AND rule has strength 1: as a disjunction, a folded grade of 1.
  const auto disjunctive_grade = [](const Rule& rule) -> FoldedEnds {
    const FoldedEnds ends = folded_ends(rule);
    if (rule.connective == Connective::And && rule.antecedent.empty()) return {ends.upper.value_or(1.0), ends.lower.value_or(1.0)};
    return ends;
  };
  const FoldedEnds mine = disjunctive_grade(into), theirs = disjunctive_grade(other);
  into.antecedent.insert(into.antecedent.end(), added.begin(), added.end());
  into.connective = Connective::Or;
  if (mine.upper || theirs.upper)
    set_folded(into, std::max(mine.upper.value_or(0.0), theirs.upper.value_or(0.0)),
               std::max(mine.lower.value_or(0.0), theirs.lower.value_or(0.0)), interval_type2);
  return true;
}

std::string join(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

// Merges rules into earlier ones with the same consequent using `fuse`; returns how many rules were absorbed.
template <typename Fuse>
std::size_t fuse_pass(FuzzySystem& system, std::vector<std::string>& names, Fuse fuse, const char* why,
                      std::vector<std::string>& details) {
  std::vector<Rule> result;
  std::vector<std::string> result_names;
  std::vector<std::vector<std::string>> absorbed;
  for (std::size_t r = 0; r < system.rules.size(); ++r) {
    const Rule& rule = system.rules[r];
    bool merged = false;
    for (std::size_t k = 0; k < result.size() && !merged; ++k) {
      if (clause_keys(result[k].consequent) != clause_keys(rule.consequent)) continue;
      Rule candidate = result[k];
      if (!fuse(candidate, rule)) continue;
      result[k] = std::move(candidate);
      absorbed[k].push_back(names[r]);
      merged = true;
    }
    if (merged) continue;
    result.push_back(rule);
    result_names.push_back(names[r]);
    absorbed.emplace_back();
  }
  std::size_t count = 0;
  for (std::size_t k = 0; k < result.size(); ++k) {
    if (absorbed[k].empty()) continue;
    count += absorbed[k].size();
    details.push_back(join(absorbed[k]) + " -> " + result_names[k] + " (" + why + ")");
  }
  system.rules = std::move(result);
  names = std::move(result_names);
  return count;
}

}  // namespace

PassReport fuse_consequents(FuzzySystem& system) {
  PassReport report;
  report.pass = "fuse_consequents";
  report.error_bound = 0.0;
  report.error_note = "exact";
  if (system.type != SystemType::Mamdani || system.aggregation != SNorm::Maximum) {
    report.summary = "fused 0 rules";
    report.details.push_back(std::string("not applicable: needs a Mamdani system with max aggregation (this one: ") +
                             to_string(system.type) + ", aggregation " + to_string(system.aggregation) + ")");
    return report;
  }
  std::vector<std::string> names;
  for (std::size_t r = 0; r < system.rules.size(); ++r) names.push_back(system.rule_display_name(r));
  const std::size_t before = system.rules.size();
  const bool interval_type2 = system.interval_type2;
  fuse_pass(
      system, names, [interval_type2](Rule& into, const Rule& other) { return fuse_identical(into, other, interval_type2); },
      "identical antecedents", report.details);
  if (system.or_method == SNorm::Maximum)
    fuse_pass(
        system, names,
        [interval_type2](Rule& into, const Rule& other) { return fuse_disjunction(into, other, interval_type2); },
        "or of the antecedents", report.details);
  report.summary = "fused " + std::to_string(before) + " rules into " + std::to_string(system.rules.size());
  return report;
}

}  // namespace fmpc

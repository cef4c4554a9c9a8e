#include "compiler/sema/coverage.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "compiler/sema/term_shape.h"
#include "kernels/fuzzy_math.h"

namespace fmpc {

namespace {

bool has_usable_range(const Variable& variable) {
  return std::isfinite(variable.min) && std::isfinite(variable.max) && variable.min < variable.max;
}

// Point `index` of `count` evenly spaced points of the variable's range, ends exact. Interior points are rounded
// to 10 significant digits of the range width, so that reports say 0.04 rather than 0.040000000000000036 (the
// sum's rounding noise); the shift, under 1e-10 of the width, changes no grade that matters.
double sample_point(const Variable& variable, long index, long count) {
  if (index == 0) return variable.min;
  if (index == count - 1) return variable.max;
  const double span = variable.max - variable.min;
  const double x = variable.min + span * static_cast<double>(index) / static_cast<double>(count - 1);
  const int digits = 10 - static_cast<int>(std::floor(std::log10(span)));
  if (digits < 0 || digits > 22) return x;
  // Powers of ten up to 1e22 are exact doubles, so the division rounds once, to the double nearest the decimal.
  const double scale = std::pow(10.0, digits);
  return std::round(x * scale) / scale;
}

const Term& clause_term(const FuzzySystem& system, const Clause& clause) {
  return system.inputs[static_cast<std::size_t>(clause.variable)].terms[static_cast<std::size_t>(clause.term)];
}

// The largest k with k^dimensions <= budget.
long points_per_axis_within(long budget, std::size_t dimensions) {
  long k = static_cast<long>(std::floor(std::pow(static_cast<double>(budget), 1.0 / static_cast<double>(dimensions))));
  auto fits = [&](long candidate) {
    double total = 1.0;
    for (std::size_t d = 0; d < dimensions; ++d) total *= static_cast<double>(candidate);
    return total <= static_cast<double>(budget);
  };
  while (k > 1 && !fits(k)) --k;
  while (fits(k + 1)) ++k;
  return k;
}

std::vector<long> first_primes(std::size_t count) {
  std::vector<long> primes;
  for (long candidate = 2; primes.size() < count; ++candidate) {
    bool prime = true;
    for (long p : primes) {
      if (p * p > candidate) break;
      if (candidate % p == 0) {
        prime = false;
        break;
      }
    }
    if (prime) primes.push_back(candidate);
  }
  return primes;
}

// Van der Corput radical inverse of `index` in `base`: the Halton sequence's coordinate (Halton 1960).
double radical_inverse(long index, long base) {
  double result = 0.0;
  double scale = 1.0 / static_cast<double>(base);
  for (long i = index; i > 0; i /= base) {
    result += static_cast<double>(i % base) * scale;
    scale /= static_cast<double>(base);
  }
  return result;
}

// The highest grade any term of `input` reaches at x (terms that cannot be evaluated count as 0).
double best_term_grade(const Variable& input, double x) {
  double highest = 0.0;
  for (const Term& term : input.terms)
    if (is_gradable(term)) highest = std::max(highest, term_grade(term, x));
  return highest;
}

struct RuleOutcome {
  double strength = 0.0;
  bool pruned = false;  // stopped early: its strength cannot exceed the best one already seen at this point
};

// Strength of a rule at a point from the grades of its `count` clauses (`grade(c)`). Any t-norm satisfies
// T(a, b) <= min(a, b), so a conjunction whose partial value times the weight is already <= `best` cannot win.
template <typename GradeOf>
RuleOutcome rule_outcome(const FuzzySystem& system, bool conjunction, double weight, std::size_t count, double best,
                         const GradeOf& grade) {
  if (conjunction) {
    double strength = tnorm_identity<double>();
    for (std::size_t c = 0; c < count; ++c) {
      strength = tnorm(system.and_method, strength, grade(c));
      if (strength * weight <= best) return {strength * weight, true};
    }
    return {strength * weight, false};
  }
  double strength = snorm_identity<double>();
  for (std::size_t c = 0; c < count; ++c) strength = snorm(system.or_method, strength, grade(c));
  return {strength * weight, false};
}

// The evaluable rules in flat arrays: the scan visits every rule at every hole point, so it must be cheap.
struct ScanClause {
  std::size_t axis = 0;
  std::size_t block = 0;  // grid: where this clause's grades along its axis start in the table
  const Term* term = nullptr;
  const Clause* clause = nullptr;
};

struct ScanRule {
  int rule = 0;
  bool conjunction = true;
  double weight = 1.0;
  std::size_t first = 0;  // into the clause array
  std::size_t count = 0;
};

class JointCoverageScan {
 public:
  JointCoverageScan(const FuzzySystem& system, double threshold) : system_(system), threshold_(threshold) {
    for (std::size_t r = 0; r < system.rules.size(); ++r) {
      if (!rule_is_evaluable(system, r)) continue;
      const Rule& rule = system.rules[r];
      rules_.push_back({static_cast<int>(r), rule.connective == Connective::And, rule.weight, clauses_.size(),
                        rule.antecedent.size()});
      for (const Clause& clause : rule.antecedent)
        clauses_.push_back({static_cast<std::size_t>(clause.variable), 0, &clause_term(system, clause), &clause});
    }
  }

  // Visits one point; `grade(scan_clause)` gives a clause's grade there, `values()` the inputs. Neighbouring
  // points are mostly covered by the same rule, so the scan starts at the rule that covered the previous point.
  template <typename GradeOf, typename Values>
  void visit(bool in_single_input_hole, const GradeOf& grade, const Values& values) {
    ++result_.points_checked;
    if (in_single_input_hole) {
      ++result_.single_input_holes;
      return;
    }
    double best = -1.0;
    int best_rule = -1;
    const std::size_t count = rules_.size();
    for (std::size_t k = 0, i = start_; k < count; ++k, i = i + 1 == count ? 0 : i + 1) {
      const ScanRule& rule = rules_[i];
      const ScanClause* clauses = clauses_.data() + rule.first;
      const RuleOutcome outcome = rule_outcome(system_, rule.conjunction, rule.weight, rule.count, best,
                                               [&](std::size_t c) { return grade(clauses[c]); });
      if (outcome.pruned || outcome.strength <= best) continue;
      best = outcome.strength;
      best_rule = rule.rule;
      if (best >= threshold_) {
        start_ = i;
        return;
      }
    }
    ++result_.holes;
    const bool fires = best >= kNegligibleFiringStrength;
    const double strength = fires ? best : 0.0;
    if (result_.holes == 1 || strength < result_.worst_strength) {
      result_.worst_strength = strength;
      result_.strongest_rule = fires ? best_rule : -1;
      result_.worst_point = values();
    }
  }

  bool has_rules() const { return !rules_.empty(); }
  std::vector<ScanClause>& clauses() { return clauses_; }
  JointCoverage& result() { return result_; }

 private:
  const FuzzySystem& system_;
  double threshold_;
  std::vector<ScanRule> rules_;
  std::vector<ScanClause> clauses_;
  std::size_t start_ = 0;  // the rule that covered the last covered point
  JointCoverage result_;
};

void scan_grid(const FuzzySystem& system, JointCoverageScan& scan, double threshold, long k) {
  const std::size_t n = system.inputs.size();
  const std::size_t points = static_cast<std::size_t>(k);
  std::vector<std::vector<char>> axis_hole(n);
  for (std::size_t d = 0; d < n; ++d)
    for (long i = 0; i < k; ++i)
      axis_hole[d].push_back(best_term_grade(system.inputs[d], sample_point(system.inputs[d], i, k)) < threshold);
  // Clause grades along each clause's own axis, computed once: the scan then only looks them up.
  std::vector<double> table;
  for (ScanClause& clause : scan.clauses()) {
    clause.block = table.size();
    const Variable& input = system.inputs[clause.axis];
    for (long i = 0; i < k; ++i) table.push_back(clause_grade(*clause.term, *clause.clause, sample_point(input, i, k)));
  }
  std::vector<std::size_t> index(n, 0);
  auto grade = [&](const ScanClause& clause) { return table[clause.block + index[clause.axis]]; };
  auto values = [&] {
    std::vector<double> point(n);
    for (std::size_t d = 0; d < n; ++d) point[d] = sample_point(system.inputs[d], static_cast<long>(index[d]), k);
    return point;
  };
  auto in_single_input_hole = [&] {
    for (std::size_t d = 0; d < n; ++d)
      if (axis_hole[d][index[d]]) return true;
    return false;
  };
  for (;;) {
    scan.visit(in_single_input_hole(), grade, values);
    std::size_t d = n;
    while (d > 0 && ++index[d - 1] == points) index[--d] = 0;
    if (d == 0) break;
  }
}

void scan_halton(const FuzzySystem& system, JointCoverageScan& scan, double threshold, long count) {
  const std::size_t n = system.inputs.size();
  const std::vector<long> bases = first_primes(n);
  // Every term's grade at the current point, computed once per point (rules share terms).
  std::vector<std::size_t> first_term(n + 1, 0);
  for (std::size_t d = 0; d < n; ++d) first_term[d + 1] = first_term[d] + system.inputs[d].terms.size();
  std::vector<double> term_grades(first_term[n], 0.0);
  std::vector<double> point(n);
  auto grade = [&](const ScanClause& clause) {
    const std::size_t slot = first_term[clause.axis] + static_cast<std::size_t>(clause.clause->term);
    return clause_grade_of_term_grade(*clause.clause, term_grades[slot]);
  };
  auto values = [&] { return point; };
  for (long j = 1; j <= count; ++j) {
    bool in_single_input_hole = false;
    for (std::size_t d = 0; d < n; ++d) {
      const Variable& input = system.inputs[d];
      point[d] = input.min + (input.max - input.min) * radical_inverse(j, bases[d]);
      double highest = 0.0;
      for (std::size_t t = 0; t < input.terms.size(); ++t) {
        const Term& term = input.terms[t];
        const double mu = is_gradable(term) ? term_grade(term, point[d]) : 0.0;
        term_grades[first_term[d] + t] = mu;
        highest = std::max(highest, mu);
      }
      in_single_input_hole = in_single_input_hole || highest < threshold;
    }
    scan.visit(in_single_input_hole, grade, values);
  }
}

}  // namespace

std::vector<CoverageInterval> input_coverage_holes(const Variable& input, double threshold, int points) {
  std::vector<CoverageInterval> holes;
  if (!has_usable_range(input) || input.terms.empty()) return holes;
  const long count = std::max(points, 2);
  bool in_hole = false;
  for (long i = 0; i < count; ++i) {
    if (best_term_grade(input, sample_point(input, i, count)) < threshold) {
      const double x = sample_point(input, i, count);
      if (!in_hole) holes.push_back({x, x});
      holes.back().to = x;
      in_hole = true;
    } else {
      in_hole = false;
    }
  }
  return holes;
}

bool rule_is_evaluable(const FuzzySystem& system, std::size_t rule_index) {
  const Rule& rule = system.rules[rule_index];
  if (rule.antecedent.empty()) return false;
  for (const Clause& clause : rule.antecedent) {
    if (clause.variable < 0 || static_cast<std::size_t>(clause.variable) >= system.inputs.size()) return false;
    const Variable& input = system.inputs[static_cast<std::size_t>(clause.variable)];
    if (clause.term < 0 || static_cast<std::size_t>(clause.term) >= input.terms.size()) return false;
    if (!is_gradable(input.terms[static_cast<std::size_t>(clause.term)])) return false;
  }
  return true;
}

double rule_firing_strength(const FuzzySystem& system, std::size_t rule_index, const std::vector<double>& inputs) {
  const Rule& rule = system.rules[rule_index];
  return rule_outcome(system, rule.connective == Connective::And, rule.weight, rule.antecedent.size(),
                      -std::numeric_limits<double>::infinity(), [&](std::size_t c) {
                        const Clause& clause = rule.antecedent[c];
                        return clause_grade(clause_term(system, clause), clause,
                                            inputs[static_cast<std::size_t>(clause.variable)]);
                      })
      .strength;
}

JointCoverage joint_coverage(const FuzzySystem& system, double threshold, long budget, long max_points_per_axis) {
  if (system.inputs.empty() || budget < 1) return {};
  for (const Variable& input : system.inputs)
    if (!has_usable_range(input)) return {};
  JointCoverageScan scan(system, threshold);
  if (!scan.has_rules()) return {};  // nothing can fire: check_system has reported why
  const long k = std::min(points_per_axis_within(budget, system.inputs.size()), max_points_per_axis);
  if (k >= 3) {
    scan_grid(system, scan, threshold, k);
    scan.result().regular_grid = true;
    scan.result().points_per_axis = k;
  } else {
    scan_halton(system, scan, threshold, budget);
  }
  scan.result().analysed = true;
  return scan.result();
}

}  // namespace fmpc

#include "compiler/sema/lint.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "diagnostics/number_format.h"
#include "compiler/sema/coverage.h"
#include "compiler/sema/term_shape.h"
#include "kernels/fuzzy_math.h"

namespace fmpc {

namespace {

// Samples per variable for the never-fires bounds (plus each MF's own breakpoints).
constexpr int kBoundSamples = 1001;

std::string in_quotes(const std::string& name) { return "'" + name + "'"; }

std::string position_text(const SourceRange& range) {
  return std::to_string(range.line) + ":" + std::to_string(range.column);
}

std::string interval_text(double lo, double hi) { return "[" + format_number(lo) + ", " + format_number(hi) + "]"; }

bool has_usable_range(const Variable& variable) {
  return std::isfinite(variable.min) && std::isfinite(variable.max) && variable.min < variable.max;
}

bool clause_resolves(const std::vector<Variable>& variables, const Clause& clause) {
  return clause.variable >= 0 && static_cast<std::size_t>(clause.variable) < variables.size() && clause.term >= 0 &&
         static_cast<std::size_t>(clause.term) < variables[static_cast<std::size_t>(clause.variable)].terms.size();
}

// "'HCV' is not very 'F4'"
std::string clause_text(const std::vector<Variable>& variables, const Clause& clause) {
  const Variable& variable = variables[static_cast<std::size_t>(clause.variable)];
  std::string text = in_quotes(variable.name) + " is ";
  if (clause.negated) text += "not ";
  if (clause.hedge != Hedge::None) text += std::string(to_string(clause.hedge)) + " ";
  return text + in_quotes(variable.terms[static_cast<std::size_t>(clause.term)].name);
}

// Clauses as comparable tuples, in a canonical order: rules that differ only in clause order are the same rule.
using ClauseKey = std::tuple<int, int, bool, int>;
std::vector<ClauseKey> clause_keys(const std::vector<Clause>& clauses) {
  std::vector<ClauseKey> keys;
  for (const Clause& clause : clauses)
    keys.emplace_back(clause.variable, clause.term, clause.negated, static_cast<int>(clause.hedge));
  std::sort(keys.begin(), keys.end());
  return keys;
}

class SystemLinter {
 public:
  SystemLinter(const FuzzySystem& system, const LintOptions& options, DiagnosticList& diagnostics)
      : system_(system), options_(options), diagnostics_(diagnostics) {}

  void run() {
    for (const Variable& variable : system_.inputs) lint_variable(variable, "input");
    for (const Variable& variable : system_.outputs) lint_variable(variable, "output");
    lint_unused_terms();
    lint_rules_that_never_fire();
    lint_repeated_antecedents();
    lint_input_coverage();
    lint_joint_coverage();
  }

 private:
  void lint_variable(const Variable& variable, const char* role) {
    if (options_.require_units && variable.unit.empty())
      diagnostics_.warning(variable.name_range, "unit",
                           std::string(role) + " " + in_quotes(variable.name) +
                               " has no unit; write one after its range (e.g. 'in [0, 75] kPa'), or 'dimensionless' "
                               "for a pure number");
    if (!has_usable_range(variable)) return;
    const double span = variable.max - variable.min;
    for (const Term& term : variable.terms) {
      const std::string what = "term " + in_quotes(term.name) + " of " + in_quotes(variable.name);
      if (const std::optional<CoreInterval> core = term_core(term)) {
        if (core->hi < variable.min || core->lo > variable.max)
          diagnostics_.warning(term.name_range, "term-out-of-range",
                               "the " + core_description(what, *core) + ", lies outside the range " +
                                   interval_text(variable.min, variable.max) +
                                   "; move the term inside the range or widen the range");
      }
      const double limit = options_.near_zero_width_fraction * span;
      for (const TermWidth& width : term_widths(term)) {
        if (width.value >= limit) continue;
        diagnostics_.warning(term.range, "near-zero-width",
                             what + " has " + width.name + " " + format_number(width.value) + ", less than " +
                                 format_number(options_.near_zero_width_fraction) + " of the width of the range " +
                                 interval_text(variable.min, variable.max) +
                                 "; inputs will almost never meet it: widen the term");
        break;
      }
      lint_lower_exceeds_upper(variable, term, what);
    }
    lint_term_order(variable);
  }

  // An explicit lower MF above its upper MF somewhere on the range: the footprint there is [upper, lower]
  // (kernels/type2_math.h swaps the ends), which is rarely what the author meant. Sampled densely, plus every
  // parameter of both MFs inside the range, where the pieces of the piecewise families meet.
  void lint_lower_exceeds_upper(const Variable& variable, const Term& term, const std::string& what) {
    if (!term.footprint || term.footprint->kind != FootprintKind::ExplicitLower) return;
    const MembershipFunction& upper = term.mf;
    const MembershipFunction& lower = term.footprint->lower;
    if (upper.params.size() < static_cast<std::size_t>(std::max(mf_param_count(upper.kind), 0)) ||
        lower.params.size() < static_cast<std::size_t>(std::max(mf_param_count(lower.kind), 0)))
      return;
    std::vector<double> points;
    constexpr int kSamples = 10001;
    for (int k = 0; k < kSamples; ++k)
      points.push_back(variable.min + (variable.max - variable.min) * k / (kSamples - 1));
    for (const std::vector<double>* params : {&upper.params, &lower.params})
      for (double p : *params)
        if (p > variable.min && p < variable.max) points.push_back(p);
    double worst = 0.0, worst_x = 0.0;
    for (double x : points) {
      const double excess = membership(lower.kind, lower.params.data(), x) - membership(upper.kind, upper.params.data(), x);
      if (excess > worst) {
        worst = excess;
        worst_x = x;
      }
    }
    // Grades are compared after rounding: an excess of a few ulps is the same curve written twice.
    if (!(worst > 1e-12)) return;
    const SourceRange& where = term.footprint->range.valid() ? term.footprint->range : term.range;
    diagnostics_.warning(where, "lower-exceeds-upper",
                         "the lower MF of " + what + " exceeds its upper MF by up to " + format_number(worst) +
                             " (at " + format_number(worst_x) + "); make the lower MF lie under the upper one "
                             "everywhere on " + interval_text(variable.min, variable.max),
                         {"where it does, fmpc uses [upper, lower] as the grade interval"});
  }

  // "peak of term 'T' of 'x', at 12" / "core of ..., [11, 12]" / "part of ... above grade 0.5, from 14 up"
  static std::string core_description(const std::string& what, const CoreInterval& core) {
    if (core.lo == core.hi) return "peak of " + what + ", at " + format_number(core.lo);
    if (std::isinf(core.lo)) return "part of " + what + " above grade 0.5, up to " + format_number(core.hi);
    if (std::isinf(core.hi)) return "part of " + what + " above grade 0.5, from " + format_number(core.lo) + " up";
    return "core of " + what + ", " + interval_text(core.lo, core.hi);
  }

  void lint_term_order(const Variable& variable) {
    struct Placed {
      std::size_t term;
      double centre;
    };
    std::vector<Placed> placed;
    for (std::size_t t = 0; t < variable.terms.size(); ++t)
      if (const std::optional<double> centre = term_centre(variable.terms[t], variable.min, variable.max))
        placed.push_back({t, *centre});
    if (placed.size() < 3) return;  // two terms are always in one order or the other
    // The intended direction is the one from the first term to the last (or, when those tie, of the first step),
    // so that one misplaced term is the one reported.
    auto sign_of = [](double step) { return step > 0.0 ? 1 : (step < 0.0 ? -1 : 0); };
    int direction = sign_of(placed.back().centre - placed.front().centre);
    for (std::size_t i = 1; i < placed.size() && direction == 0; ++i)
      direction = sign_of(placed[i].centre - placed[i - 1].centre);
    for (std::size_t i = 1; i < placed.size(); ++i) {
      const int sign = sign_of(placed[i].centre - placed[i - 1].centre);
      if (sign == 0 || sign == direction) continue;
      const Term& term = variable.terms[placed[i].term];
      const Term& previous = variable.terms[placed[i - 1].term];
      diagnostics_.warning(term.name_range, "terms-out-of-order",
                           "term " + in_quotes(term.name) + " of " + in_quotes(variable.name) + " (centre " +
                               format_number(placed[i].centre) + ") comes after " + in_quotes(previous.name) +
                               " (centre " + format_number(placed[i - 1].centre) + ") but lies " +
                               (direction > 0 ? "below" : "above") + " it, while the terms run from " +
                               (direction > 0 ? "low to high" : "high to low") +
                               "; declare the terms in order of their centres");
      return;
    }
  }

  void lint_unused_terms() {
    std::set<std::pair<int, int>> used_inputs;
    std::set<std::pair<int, int>> used_outputs;
    for (const Rule& rule : system_.rules) {
      for (const Clause& clause : rule.antecedent) used_inputs.emplace(clause.variable, clause.term);
      for (const Clause& clause : rule.consequent) used_outputs.emplace(clause.variable, clause.term);
    }
    auto visit = [&](const std::vector<Variable>& variables, const std::set<std::pair<int, int>>& used,
                     const char* role) {
      for (std::size_t v = 0; v < variables.size(); ++v)
        for (std::size_t t = 0; t < variables[v].terms.size(); ++t) {
          if (used.count({static_cast<int>(v), static_cast<int>(t)})) continue;
          const Term& term = variables[v].terms[t];
          diagnostics_.warning(term.name_range, "unused-term",
                               "term " + in_quotes(term.name) + " of " + role + " " + in_quotes(variables[v].name) +
                                   " is not used by any rule; use it in a rule or remove it");
        }
    };
    visit(system_.inputs, used_inputs, "input");
    visit(system_.outputs, used_outputs, "output");
  }

  // The antecedent clauses sit on different inputs, so over the box of input ranges the best strength of an AND
  // rule is the t-norm of each clause's best grade, and of an OR rule the s-norm: both norms are monotone.
  void lint_rules_that_never_fire() {
    for (std::size_t r = 0; r < system_.rules.size(); ++r) {
      const Rule& rule = system_.rules[r];
      if (!rule_is_evaluable(system_, r)) continue;
      const std::string name = system_.rule_display_name(r);
      if (rule.weight == 0.0) {
        diagnostics_.warning(rule.range, "rule-never-fires",
                             name + " never fires: its weight is 0; raise the weight or remove the rule");
        continue;
      }
      bool ranges_usable = true;
      for (const Clause& clause : rule.antecedent)
        ranges_usable = ranges_usable && has_usable_range(system_.inputs[static_cast<std::size_t>(clause.variable)]);
      if (!ranges_usable) continue;
      const bool conjunction = rule.connective == Connective::And;
      double best = conjunction ? tnorm_identity<double>() : snorm_identity<double>();
      std::size_t weakest = 0;
      double weakest_grade = 2.0;
      for (std::size_t c = 0; c < rule.antecedent.size(); ++c) {
        const Clause& clause = rule.antecedent[c];
        const Variable& input = system_.inputs[static_cast<std::size_t>(clause.variable)];
        const Term& term = input.terms[static_cast<std::size_t>(clause.term)];
        const double highest = clause_grade_bounds(term, clause, input.min, input.max, kBoundSamples).highest;
        best = conjunction ? tnorm(system_.and_method, best, highest) : snorm(system_.or_method, best, highest);
        if (highest < weakest_grade) {
          weakest_grade = highest;
          weakest = c;
        }
      }
      if (!(best * rule.weight < kNegligibleFiringStrength)) continue;
      std::string reason;
      if (weakest_grade < kNegligibleFiringStrength && (conjunction || rule.antecedent.size() == 1)) {
        const Clause& clause = rule.antecedent[weakest];
        const Variable& input = system_.inputs[static_cast<std::size_t>(clause.variable)];
        reason = "the condition " + clause_text(system_.inputs, clause) + " stays below " +
                 format_number(kNegligibleFiringStrength) + " everywhere in the range " +
                 interval_text(input.min, input.max) + " of " + in_quotes(input.name);
      } else if (!conjunction) {
        reason = "none of its conditions reaches " + format_number(kNegligibleFiringStrength) +
                 " anywhere in the input ranges";
      } else {
        reason = "its firing strength stays below " + format_number(kNegligibleFiringStrength) +
                 " everywhere in the input ranges";
      }
      diagnostics_.warning(rule.range, "rule-never-fires",
                           name + " never fires: " + reason + "; fix the terms or remove the rule");
    }
  }

  void lint_repeated_antecedents() {
    using AntecedentKey = std::pair<int, std::vector<ClauseKey>>;
    std::map<AntecedentKey, std::vector<std::size_t>> earlier_rules;
    for (std::size_t r = 0; r < system_.rules.size(); ++r) {
      const Rule& rule = system_.rules[r];
      if (rule.antecedent.empty()) continue;
      // With one clause AND and OR mean the same.
      const int connective = rule.antecedent.size() == 1 ? -1 : static_cast<int>(rule.connective);
      std::vector<std::size_t>& same = earlier_rules[{connective, clause_keys(rule.antecedent)}];
      report_repeat(r, same);
      same.push_back(r);
    }
  }

  void report_repeat(std::size_t r, const std::vector<std::size_t>& same_antecedent) {
    const Rule& rule = system_.rules[r];
    const std::vector<ClauseKey> consequent = clause_keys(rule.consequent);
    const std::string name = system_.rule_display_name(r);
    auto location_note = [&](std::size_t other) {
      std::vector<std::string> notes;
      if (system_.rules[other].range.valid())
        notes.push_back(system_.rule_display_name(other) + " is here: " + position_text(system_.rules[other].range));
      return notes;
    };
    for (std::size_t other : same_antecedent) {
      if (clause_keys(system_.rules[other].consequent) != consequent) continue;
      diagnostics_.warning(rule.range, "duplicate-rule",
                           name + " repeats " + system_.rule_display_name(other) +
                               " (same conditions, same conclusion); remove one of them",
                           location_note(other));
      return;
    }
    for (std::size_t other : same_antecedent) {
      for (const Clause& mine : rule.consequent) {
        if (!clause_resolves(system_.outputs, mine)) continue;
        for (const Clause& theirs : system_.rules[other].consequent) {
          if (theirs.variable != mine.variable || !clause_resolves(system_.outputs, theirs)) continue;
          if (theirs.term == mine.term && theirs.negated == mine.negated && theirs.hedge == mine.hedge) continue;
          diagnostics_.warning(rule.range, "conflicting-rules",
                               name + " has the same conditions as " + system_.rule_display_name(other) +
                                   " but concludes " + clause_text(system_.outputs, mine) + " where " +
                                   system_.rule_display_name(other) + " concludes " +
                                   clause_text(system_.outputs, theirs) +
                                   "; merge them into one rule or make their conditions differ",
                               location_note(other));
          return;
        }
      }
    }
  }

  void lint_input_coverage() {
    for (const Variable& input : system_.inputs) {
      for (const CoverageInterval& hole :
           input_coverage_holes(input, options_.coverage_threshold, options_.coverage_points_per_input)) {
        const std::string where =
            hole.from == hole.to ? "at " + format_number(hole.from) : "on " + interval_text(hole.from, hole.to);
        diagnostics_.warning(input.range, "coverage-hole",
                             "no term of input " + in_quotes(input.name) + " reaches " +
                                 format_number(options_.coverage_threshold) + " " + where +
                                 "; add or widen a term there, or narrow the range");
      }
    }
  }

  // Holes the rules leave where every input on its own is covered; points inside an input's own hole are that
  // input's warning already. The grid is never finer per axis than the per-input check.
  void lint_joint_coverage() {
    if (system_.rules.empty()) return;
    const JointCoverage coverage = joint_coverage(system_, options_.coverage_threshold, options_.coverage_grid_budget,
                                                  options_.coverage_points_per_input);
    if (!coverage.analysed || coverage.holes == 0) return;
    std::string point;
    for (std::size_t d = 0; d < system_.inputs.size(); ++d)
      point += (d ? ", " : "") + in_quotes(system_.inputs[d].name) + " = " + format_number(coverage.worst_point[d]);
    std::string strongest = "no rule fires there at all";
    if (coverage.strongest_rule >= 0)
      strongest = "the strongest rule there, " +
                  system_.rule_display_name(static_cast<std::size_t>(coverage.strongest_rule)) + ", reaches " +
                  format_number(coverage.worst_strength);
    const long considered = coverage.points_checked - coverage.single_input_holes;
    const double percent = 100.0 * static_cast<double>(coverage.holes) / static_cast<double>(considered);
    std::string sampled = coverage.regular_grid
                              ? "points of a grid of " + std::to_string(coverage.points_per_axis) + " per input"
                              : "Halton points";
    if (coverage.single_input_holes > 0) sampled += " where every input has a term reaching " +
                                                    format_number(options_.coverage_threshold);
    diagnostics_.warning(
        system_.range, "coverage-hole",
        "no rule reaches a firing strength of " + format_number(options_.coverage_threshold) + " at " + point +
            "; add a rule for that region or widen the terms it uses",
        {strongest, std::to_string(coverage.holes) + " of " + std::to_string(considered) + " " + sampled + " (" +
                        format_number(std::round(percent * 100.0) / 100.0) + "%) are such holes"});
  }

  const FuzzySystem& system_;
  const LintOptions& options_;
  DiagnosticList& diagnostics_;
};

}  // namespace

void lint_system(const FuzzySystem& system, const LintOptions& options, DiagnosticList& diagnostics) {
  SystemLinter(system, options, diagnostics).run();
}

}  // namespace fmpc

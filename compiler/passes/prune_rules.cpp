#include "compiler/passes/prune_rules.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "compiler/eval/defuzzify.h"
#include "compiler/eval/interpreter.h"
#include "diagnostics/number_format.h"
#include "kernels/fuzzy_math.h"

namespace fmpc {

namespace {

std::optional<GradeBounds> monotone_bounds(double at_lo, double at_hi) {
  if (std::isnan(at_lo) || std::isnan(at_hi)) return std::nullopt;
  return GradeBounds{std::min(at_lo, at_hi), std::max(at_lo, at_hi)};
}

// A quasi-concave grade with top [p, q]: nondecreasing below p, nonincreasing above q, at most 1 everywhere.
std::optional<GradeBounds> quasi_concave_bounds(double at_lo, double at_hi, double lo, double hi, double p, double q) {
  if (std::isnan(at_lo) || std::isnan(at_hi) || std::isnan(p) || std::isnan(q)) return std::nullopt;
  const bool meets_top = lo <= std::max(p, q) && hi >= std::min(p, q);
  return GradeBounds{std::min(at_lo, at_hi), meets_top ? 1.0 : std::max(at_lo, at_hi)};
}

std::optional<GradeBounds> sigmoid_bounds(double a, double c, double lo, double hi) {
  return monotone_bounds(mf::sigmoid(lo, a, c), mf::sigmoid(hi, a, c));
}

double fold(bool conjunction, const FuzzySystem& system, double a, double b) {
  return conjunction ? tnorm(system.and_method, a, b) : snorm(system.or_method, a, b);
}

double consequent_grade(const Variable& output, const Clause& clause, double y) {
  const MembershipFunction& mf = output.terms[static_cast<std::size_t>(clause.term)].mf;
  const double mu = apply_hedge(membership(mf.kind, mf.params.data(), y), hedge_exponent(clause.hedge));
  return clause.negated ? fuzzy_not(mu) : mu;
}

// min(R, R n epsilon / S_min) for output `o` after pruning (see prune_rules.h).
double centroid_bound(const FuzzySystem& pruned, std::size_t o, double epsilon) {
  const Variable& output = pruned.outputs[o];
  const double range = output.max - output.min;
  if (pruned.defuzzifier != Defuzzifier::Centroid || pruned.samples <= 0) return range;
  const std::vector<double> y = output_sample_points(output.min, output.max, pruned.samples, Reference::Matlab);
  std::vector<double> lowest(y.size(), 0.0);
  for (std::size_t r = 0; r < pruned.rules.size(); ++r) {
    const std::optional<GradeBounds> firing = firing_bounds(pruned, r);
    if (!firing || !(firing->low > 0.0)) continue;
    for (const Clause& clause : pruned.rules[r].consequent) {
      if (static_cast<std::size_t>(clause.variable) != o) continue;
      for (std::size_t k = 0; k < y.size(); ++k)
        lowest[k] = std::max(lowest[k], tnorm(pruned.implication, firing->low, consequent_grade(output, clause, y[k])));
    }
  }
  double mass = 0.0;
  for (double g : lowest) mass += g;
  if (!(mass > 0.0)) return range;
  return std::min(range, range * static_cast<double>(y.size()) * epsilon / mass);
}

double term_upper_grade(const Term& term, double x) { return term_membership(term, x).upper; }
double term_lower_grade(const Term& term, double x) { return term_membership(term, x).lower; }

// Bounds of the footprint's upper end (`upper`) or lower end over [lo, hi] (kernels/type2_math.h gives each end).
std::optional<GradeBounds> footprint_end_bounds(const Term& term, double lo, double hi, bool upper) {
  if (!term.footprint || term.footprint->kind == FootprintKind::None) return membership_bounds(term.mf, lo, hi);
  const Footprint& footprint = *term.footprint;
  const double first = footprint.first, second = footprint.second;
  switch (footprint.kind) {
    case FootprintKind::None: break;
    case FootprintKind::UncertainMean: {
      // Upper: 1 on [m1, m2], a Gaussian falling away on each side; lower: rising to (m1 + m2) / 2, falling beyond.
      // Both are quasi-concave when m1 <= m2.
      if (!(first <= second) || term.mf.params.empty() || std::isnan(term.mf.params[0])) return std::nullopt;
      const double top_low = upper ? first : (first + second) / 2.0;
      const double top_high = upper ? second : (first + second) / 2.0;
      const auto grade = upper ? term_upper_grade : term_lower_grade;
      return quasi_concave_bounds(grade(term, lo), grade(term, hi), lo, hi, top_low, top_high);
    }
    case FootprintKind::UncertainSd: {
      if (term.mf.params.size() < 2) return std::nullopt;
      return membership_bounds(MembershipFunction{MfKind::Gaussian, {upper ? second : first, term.mf.params[1]}}, lo,
                               hi);
    }
    case FootprintKind::ExplicitLower: {
      // [min(l, u), max(l, u)]: min and max are nondecreasing in each argument.
      const auto a = membership_bounds(term.mf, lo, hi);
      const auto b = membership_bounds(footprint.lower, lo, hi);
      if (!a || !b) return std::nullopt;
      if (upper) return GradeBounds{std::max(a->low, b->low), std::max(a->high, b->high)};
      return GradeBounds{std::min(a->low, b->low), std::min(a->high, b->high)};
    }
    case FootprintKind::ScaleLag: {
      const auto mf = membership_bounds(term.mf, lo, hi);
      if (!mf || upper) return mf;
      // lower = scale * max(0, (mf - lag) / (1 - lag)): nondecreasing in mf when scale >= 0 and lag < 1.
      if (!(first >= 0.0) || !(second < 1.0)) return std::nullopt;
      const auto lowered = [&](double v) { return first * std::max(0.0, (v - second) / (1.0 - second)); };
      return GradeBounds{lowered(mf->low), lowered(mf->high)};
    }
    case FootprintKind::IntervalValue: return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace

std::optional<GradeBounds> membership_bounds(const MembershipFunction& mf, double lo, double hi) {
  const std::vector<double>& p = mf.params;
  if (mf.kind != MfKind::Linear && static_cast<int>(p.size()) < mf_param_count(mf.kind)) return std::nullopt;
  for (double v : p)
    if (std::isnan(v)) return std::nullopt;
  const double at_lo = mf.kind == MfKind::Linear ? 0.0 : membership(mf.kind, p.data(), lo);
  const double at_hi = mf.kind == MfKind::Linear ? 0.0 : membership(mf.kind, p.data(), hi);
  switch (mf.kind) {
    case MfKind::Triangle: return quasi_concave_bounds(at_lo, at_hi, lo, hi, p[1], p[1]);
    case MfKind::Trapezoid: return quasi_concave_bounds(at_lo, at_hi, lo, hi, p[1], p[2]);
    case MfKind::Gaussian: return quasi_concave_bounds(at_lo, at_hi, lo, hi, p[1], p[1]);
    case MfKind::Gaussian2: return quasi_concave_bounds(at_lo, at_hi, lo, hi, p[1], p[3]);
    case MfKind::GeneralizedBell:
      if (!(p[1] > 0.0)) return std::nullopt;
      return quasi_concave_bounds(at_lo, at_hi, lo, hi, p[2], p[2]);
    case MfKind::PiShape: return quasi_concave_bounds(at_lo, at_hi, lo, hi, p[1], p[2]);
    case MfKind::Sigmoid:
    case MfKind::SShape:
    case MfKind::ZShape:
    case MfKind::LinearS:
    case MfKind::LinearZ: return monotone_bounds(at_lo, at_hi);
    case MfKind::ProductSigmoid: {
      const auto first = sigmoid_bounds(p[0], p[1], lo, hi);
      const auto second = sigmoid_bounds(p[2], p[3], lo, hi);
      if (!first || !second) return std::nullopt;
      return GradeBounds{first->low * second->low, first->high * second->high};
    }
    case MfKind::DifferenceSigmoid: {
      const auto first = sigmoid_bounds(p[0], p[1], lo, hi);
      const auto second = sigmoid_bounds(p[2], p[3], lo, hi);
      if (!first || !second) return std::nullopt;
      const GradeBounds bounds{first->low - second->high, std::min(1.0, first->high - second->low)};
      if (bounds.low < 0.0) return std::nullopt;  // grades may be negative: the norms' monotonicity may not hold
      return bounds;
    }
    case MfKind::Constant: return GradeBounds{p[0], p[0]};
    case MfKind::Linear: return std::nullopt;
  }
  return std::nullopt;
}

std::optional<GradeBounds> firing_bounds(const FuzzySystem& system, std::size_t rule_index) {
  const Rule& rule = system.rules[rule_index];
  const bool conjunction = rule.connective == Connective::And;
  const double identity = conjunction ? tnorm_identity<double>() : snorm_identity<double>();
  GradeBounds strength{rule.folded_grade.value_or(identity), rule.folded_grade.value_or(identity)};
  for (const Clause& clause : rule.antecedent) {
    const Variable& input = system.inputs[static_cast<std::size_t>(clause.variable)];
    std::optional<GradeBounds> grade =
        membership_bounds(input.terms[static_cast<std::size_t>(clause.term)].mf, input.min, input.max);
    if (!grade || grade->low < 0.0) return std::nullopt;
    const double exponent = hedge_exponent(clause.hedge);
    GradeBounds hedged{apply_hedge(grade->low, exponent), apply_hedge(grade->high, exponent)};
    if (clause.negated) hedged = GradeBounds{fuzzy_not(hedged.high), fuzzy_not(hedged.low)};
    strength.low = fold(conjunction, system, strength.low, hedged.low);
    strength.high = fold(conjunction, system, strength.high, hedged.high);
  }
  if (std::isnan(strength.low) || std::isnan(strength.high) || !(rule.weight >= 0.0)) return std::nullopt;
  return GradeBounds{rule.weight * strength.low, rule.weight * strength.high};
}

std::optional<FiringIntervalBounds> firing_interval_bounds(const FuzzySystem& system, std::size_t rule_index) {
  const Rule& rule = system.rules[rule_index];
  const bool conjunction = rule.connective == Connective::And;
  const double identity = conjunction ? tnorm_identity<double>() : snorm_identity<double>();
  const double start_upper = rule.folded_grade.value_or(identity);
  const double start_lower = rule.folded_grade_lower.value_or(start_upper);
  GradeBounds lower{start_lower, start_lower}, upper{start_upper, start_upper};
  for (const Clause& clause : rule.antecedent) {
    const Variable& input = system.inputs[static_cast<std::size_t>(clause.variable)];
    const Term& term = input.terms[static_cast<std::size_t>(clause.term)];
    std::optional<GradeBounds> term_lower = footprint_end_bounds(term, input.min, input.max, false);
    std::optional<GradeBounds> term_upper = footprint_end_bounds(term, input.min, input.max, true);
    if (!term_lower || !term_upper || term_lower->low < 0.0 || term_upper->low < 0.0) return std::nullopt;
    const double exponent = hedge_exponent(clause.hedge);
    GradeBounds clause_lower{apply_hedge(term_lower->low, exponent), apply_hedge(term_lower->high, exponent)};
    GradeBounds clause_upper{apply_hedge(term_upper->low, exponent), apply_hedge(term_upper->high, exponent)};
    if (clause.negated) {  // not [l, u] = [1 - u, 1 - l]
      const GradeBounds negated_lower{fuzzy_not(clause_upper.high), fuzzy_not(clause_upper.low)};
      clause_upper = GradeBounds{fuzzy_not(clause_lower.high), fuzzy_not(clause_lower.low)};
      clause_lower = negated_lower;
    }
    lower.low = fold(conjunction, system, lower.low, clause_lower.low);
    lower.high = fold(conjunction, system, lower.high, clause_lower.high);
    upper.low = fold(conjunction, system, upper.low, clause_upper.low);
    upper.high = fold(conjunction, system, upper.high, clause_upper.high);
  }
  for (double v : {lower.low, lower.high, upper.low, upper.high})
    if (std::isnan(v)) return std::nullopt;
  if (!(rule.weight >= 0.0)) return std::nullopt;
  // The interpreter's firing interval is the weight times the span of the two ends.
  const double w = rule.weight;
  return FiringIntervalBounds{GradeBounds{w * std::min(lower.low, upper.low), w * std::min(lower.high, upper.high)},
                              GradeBounds{w * std::max(lower.low, upper.low), w * std::max(lower.high, upper.high)}};
}

PassReport prune_rules(FuzzySystem& system, double epsilon) {
  PassReport report;
  report.pass = "prune_rules";
  const bool epsilon_applies = epsilon > 0.0 && system.type == SystemType::Mamdani &&
                               system.aggregation == SNorm::Maximum && !system.interval_type2;
  if (epsilon > 0.0 && system.interval_type2)
    report.details.push_back("epsilon " + format_number(epsilon) +
                             " ignored: no error bound is known for interval type-2 systems; only rules that "
                             "cannot fire are removed");
  else if (epsilon > 0.0 && !epsilon_applies)
    report.details.push_back("epsilon " + format_number(epsilon) +
                             " ignored: it needs a Mamdani system with max aggregation; only rules that cannot "
                             "fire are removed");
  std::vector<Rule> kept;
  std::vector<bool> output_touched(system.outputs.size(), false);
  std::size_t never = 0, weak = 0;
  bool removed_without_consequent = false;
  for (std::size_t r = 0; r < system.rules.size(); ++r) {
    // Type-2: the upper end of the firing interval bounds both ends.
    std::optional<GradeBounds> firing;
    if (!system.interval_type2) {
      firing = firing_bounds(system, r);
    } else if (const auto interval = firing_interval_bounds(system, r)) {
      firing = interval->upper;
    }
    if (firing && firing->high <= 0.0) {
      report.details.push_back(system.rule_display_name(r) + ": cannot fire on the inputs' ranges");
      ++never;
      if (system.rules[r].consequent.size() < system.outputs.size()) removed_without_consequent = true;
      continue;
    }
    if (firing && epsilon_applies && firing->high < epsilon) {
      report.details.push_back(system.rule_display_name(r) + ": firing strength <= " +
                               format_number(firing->high) + " < epsilon " + format_number(epsilon));
      for (const Clause& clause : system.rules[r].consequent)
        output_touched[static_cast<std::size_t>(clause.variable)] = true;
      ++weak;
      continue;
    }
    kept.push_back(system.rules[r]);
  }
  system.rules = std::move(kept);
  report.summary = "removed " + std::to_string(never + weak) + " rules (" + std::to_string(never) +
                   " cannot fire, " + std::to_string(weak) + " below epsilon)";
  report.error_bound = 0.0;
  for (std::size_t o = 0; o < system.outputs.size(); ++o)
    if (output_touched[o]) report.error_bound = std::max(report.error_bound, centroid_bound(system, o, epsilon));
  report.error_note = weak == 0 ? "exact" : "rules below epsilon: aggregate lowered by < epsilon; centroid bound";
  // A type-2 Sugeno rule without a consequent on an output is a point z = 0 of weight [0, 0] in that output's type
  // reduction: Karnik-Mendel and Nie-Tan give the same bits without it, but EKM's start and EIASC's incremental
  // sums depend on the number of points, so they agree to rounding only.
  const bool incremental_reduction = system.type_reduction == TypeReduction::EnhancedKarnikMendel ||
                                     system.type_reduction == TypeReduction::Eiasc;
  if (weak == 0 && removed_without_consequent && system.interval_type2 && system.type == SystemType::Sugeno &&
      system.defuzzifier != Defuzzifier::WeightedSum && incremental_reduction)
    report.error_note = "exact up to rounding: the type reduction runs over fewer zero-weight points";
  return report;
}

}  // namespace fmpc

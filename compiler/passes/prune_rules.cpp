#include "compiler/passes/prune_rules.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "compiler/eval/defuzzify.h"
#include "compiler/ir/number_format.h"
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

PassReport prune_rules(FuzzySystem& system, double epsilon) {
  PassReport report;
  report.pass = "prune_rules";
  const bool epsilon_applies =
      epsilon > 0.0 && system.type == SystemType::Mamdani && system.aggregation == SNorm::Maximum;
  if (epsilon > 0.0 && !epsilon_applies)
    report.details.push_back("epsilon " + format_number(epsilon) +
                             " ignored: it needs a Mamdani system with max aggregation; only rules that cannot "
                             "fire are removed");
  std::vector<Rule> kept;
  std::vector<bool> output_touched(system.outputs.size(), false);
  std::size_t never = 0, weak = 0;
  for (std::size_t r = 0; r < system.rules.size(); ++r) {
    const std::optional<GradeBounds> firing = firing_bounds(system, r);
    if (firing && firing->high <= 0.0) {
      report.details.push_back(system.rule_display_name(r) + ": cannot fire on the inputs' ranges");
      ++never;
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
  return report;
}

}  // namespace fmpc

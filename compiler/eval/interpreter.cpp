#include "compiler/eval/interpreter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "compiler/eval/defuzzify.h"
#include "kernels/fuzzy_math.h"
#include "kernels/type2_math.h"
#include "kernels/type_reduction_math.h"

namespace fmpc {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A rule's consequent on one output, resolved once.
struct ResolvedConsequent {
  int rule = -1;
  int term = -1;
  double hedge_exponent = 1.0;
  bool negated = false;
};

double clause_grade(double mu, Hedge hedge, bool negated) {
  mu = apply_hedge(mu, hedge_exponent(hedge));
  return negated ? fuzzy_not(mu) : mu;
}

// A Sugeno rule's output value z at the inputs: constant c, or linear p1 x1 + ... + pn xn + c.
double sugeno_rule_value(const MembershipFunction& mf, const std::vector<double>& inputs) {
  if (mf.kind == MfKind::Constant) return mf.params.empty() ? kNaN : mf.params[0];
  if (mf.kind == MfKind::Linear) {
    if (mf.params.size() != inputs.size() + 1) return kNaN;
    double z = 0.0;
    for (std::size_t i = 0; i < inputs.size(); ++i) z += mf.params[i] * inputs[i];
    return z + mf.params[inputs.size()];
  }
  return kNaN;  // sema only lets constant and linear terms into Sugeno outputs
}

GradeInterval<double> clause_interval(GradeInterval<double> mu, Hedge hedge, bool negated) {
  mu = interval_hedge(mu, hedge_exponent(hedge));
  return negated ? interval_not(mu) : mu;
}

}  // namespace

GradeInterval<double> term_membership(const Term& term, double x) {
  if (!term.footprint) {
    const double mu = membership(term.mf.kind, term.mf.params.data(), x);
    return {mu, mu};
  }
  const Footprint& footprint = *term.footprint;
  return footprint_membership(term.mf.kind, term.mf.params.data(), footprint.kind, footprint.first,
                              footprint.second, footprint.lower.kind, footprint.lower.params.data(), x);
}

struct Interpreter::State {
  FuzzySystem system;
  EvaluationOptions options;
  std::vector<std::vector<Clause>> antecedents;               // per rule, sorted by input (MATLAB's fold order)
  std::vector<std::vector<ResolvedConsequent>> consequents;   // per output: the rules that conclude on it
  std::vector<std::vector<double>> sample_points;             // per Mamdani output (samples > 0)
  std::vector<std::vector<std::vector<double>>> term_samples;  // per output, per term: grades at sample_points
  // Scratch reused across evaluations.
  std::vector<std::vector<double>> input_grades;  // per input, per term
  std::vector<double> aggregate;
  // Interval type-2 only: lower ends beside the upper ends kept in term_samples, input_grades and aggregate.
  std::vector<std::vector<std::vector<double>>> term_samples_lower;
  std::vector<std::vector<double>> input_grades_lower;
  std::vector<double> aggregate_lower;

  State(const FuzzySystem& source, EvaluationOptions chosen) : system(source), options(chosen) {
    antecedents.resize(system.rules.size());
    consequents.resize(system.outputs.size());
    for (std::size_t r = 0; r < system.rules.size(); ++r) {
      const Rule& rule = system.rules[r];
      antecedents[r] = rule.antecedent;
      std::stable_sort(antecedents[r].begin(), antecedents[r].end(),
                       [](const Clause& a, const Clause& b) { return a.variable < b.variable; });
      for (const Clause& clause : rule.consequent) {
        if (clause.variable < 0 || static_cast<std::size_t>(clause.variable) >= system.outputs.size()) continue;
        consequents[static_cast<std::size_t>(clause.variable)].push_back(
            {static_cast<int>(r), clause.term, hedge_exponent(clause.hedge), clause.negated});
      }
    }
    input_grades.resize(system.inputs.size());
    for (std::size_t i = 0; i < system.inputs.size(); ++i) input_grades[i].resize(system.inputs[i].terms.size());

    if (system.type == SystemType::Mamdani && system.samples > 0) {
      sample_points.resize(system.outputs.size());
      term_samples.resize(system.outputs.size());
      for (std::size_t o = 0; o < system.outputs.size(); ++o) {
        const Variable& output = system.outputs[o];
        sample_points[o] = output_sample_points(output.min, output.max, system.samples, options.reference);
        term_samples[o].resize(output.terms.size());
        for (std::size_t t = 0; t < output.terms.size(); ++t) {
          const MembershipFunction& mf = output.terms[t].mf;
          auto& grades = term_samples[o][t];
          grades.resize(sample_points[o].size());
          for (std::size_t k = 0; k < grades.size(); ++k)
            grades[k] = membership(mf.kind, mf.params.data(), sample_points[o][k]);
        }
      }
      aggregate.resize(static_cast<std::size_t>(system.samples));
    }
    if (system.interval_type2) prepare_type2();
  }

  void prepare_type2() {
    input_grades_lower = input_grades;
    if (system.type != SystemType::Mamdani || system.samples <= 0) return;
    term_samples_lower = term_samples;
    for (std::size_t o = 0; o < system.outputs.size(); ++o) {
      const Variable& output = system.outputs[o];
      for (std::size_t t = 0; t < output.terms.size(); ++t) {
        for (std::size_t k = 0; k < sample_points[o].size(); ++k) {
          const GradeInterval<double> mu = term_membership(output.terms[t], sample_points[o][k]);
          term_samples[o][t][k] = mu.upper;
          term_samples_lower[o][t][k] = mu.lower;
        }
      }
    }
    aggregate_lower.resize(aggregate.size());
  }

  double apply_no_fire_policy(std::size_t output, EvaluationFlags& flags) const {
    flags.outputs_no_rule_fired.push_back(static_cast<int>(output));
    switch (system.no_fire) {
      case NoFirePolicy::Midrange: return (system.outputs[output].min + system.outputs[output].max) / 2.0;
      case NoFirePolicy::Value: return system.no_fire_value;
      case NoFirePolicy::Error: flags.no_fire_error = true; return kNaN;
    }
    return kNaN;
  }

  void compute_firing_strengths(const std::vector<double>& inputs, std::vector<double>& firing) {
    for (std::size_t i = 0; i < system.inputs.size(); ++i) {
      const Variable& input = system.inputs[i];
      for (std::size_t t = 0; t < input.terms.size(); ++t)
        input_grades[i][t] = membership(input.terms[t].mf.kind, input.terms[t].mf.params.data(), inputs[i]);
    }
    firing.resize(system.rules.size());
    for (std::size_t r = 0; r < system.rules.size(); ++r) {
      const Rule& rule = system.rules[r];
      const bool conjunction = rule.connective == Connective::And;
      // A grade folded in by the specialize pass starts the fold (T(1, c) = S(0, c) = c for every norm).
      double strength = rule.folded_grade ? *rule.folded_grade
                                          : conjunction ? tnorm_identity<double>() : snorm_identity<double>();
      for (const Clause& clause : antecedents[r]) {
        const double mu = clause_grade(
            input_grades[static_cast<std::size_t>(clause.variable)][static_cast<std::size_t>(clause.term)],
            clause.hedge, clause.negated);
        strength = conjunction ? tnorm(system.and_method, strength, mu) : snorm(system.or_method, strength, mu);
      }
      firing[r] = rule.weight * strength;
    }
  }

  double mamdani_output(std::size_t o, const std::vector<double>& firing, EvaluationFlags& flags,
                        OutputExplanation* explanation) {
    const Variable& output = system.outputs[o];
    bool any_fired = false;
    for (const auto& consequent : consequents[o])
      if (firing[static_cast<std::size_t>(consequent.rule)] > 0.0) any_fired = true;

    if (system.samples <= 0) {
      ExactAggregate exact;
      exact.min = output.min;
      exact.max = output.max;
      exact.implication = system.implication;
      exact.aggregation = system.aggregation;
      for (const auto& consequent : consequents[o]) {
        const double w = firing[static_cast<std::size_t>(consequent.rule)];
        if (!(w > 0.0)) continue;
        const MembershipFunction& mf = output.terms[static_cast<std::size_t>(consequent.term)].mf;
        exact.rules.push_back({mf.kind, mf.params, consequent.hedge_exponent, consequent.negated, w});
      }
      ExactDefuzzification result = defuzzify_exact(system.defuzzifier, exact, options.reference);
      if (explanation) {
        explanation->x = result.points;
        explanation->membership.resize(result.points.size());
        for (std::size_t k = 0; k < result.points.size(); ++k)
          explanation->membership[k] = exact.grade(result.points[k]);
      }
      if (!any_fired || !result.value) return apply_no_fire_policy(o, flags);
      return *result.value;
    }

    const std::vector<double>& x = sample_points[o];
    std::fill(aggregate.begin(), aggregate.end(), snorm_identity<double>());
    for (const auto& consequent : consequents[o]) {
      const double w = firing[static_cast<std::size_t>(consequent.rule)];
      // A rule that did not fire adds implication(0, .) == 0 for every norm fmpc has: skipping it is exact
      // (Octave's eval_rules_mamdani skips it too).
      if (!(w > 0.0)) continue;
      const std::vector<double>& grades = term_samples[o][static_cast<std::size_t>(consequent.term)];
      const bool plain = consequent.hedge_exponent == 1.0 && !consequent.negated;
      for (std::size_t k = 0; k < aggregate.size(); ++k) {
        double mu = grades[k];
        if (!plain) {
          mu = apply_hedge(mu, consequent.hedge_exponent);
          if (consequent.negated) mu = fuzzy_not(mu);
        }
        aggregate[k] = snorm(system.aggregation, aggregate[k], tnorm(system.implication, w, mu));
      }
    }
    if (explanation) {
      explanation->x = x;
      explanation->membership = aggregate;
    }
    if (!any_fired) return apply_no_fire_policy(o, flags);
    const std::optional<double> value = defuzzify_sampled(system.defuzzifier, x, aggregate, options.reference);
    if (!value) return apply_no_fire_policy(o, flags);
    return *value;
  }

  double sugeno_output(std::size_t o, const std::vector<double>& inputs, const std::vector<double>& firing,
                       EvaluationFlags& flags, OutputExplanation* explanation) {
    const Variable& output = system.outputs[o];
    const bool weighted_sum = system.defuzzifier == Defuzzifier::WeightedSum;
    // (location z, height) of every rule that fired and concludes on this output. The height is the firing
    // strength, hedged as Octave's eval_rules_sugeno does (w ^ (1 / hedge)), then negated (1 - height).
    std::vector<std::pair<double, double>> singletons;
    for (const auto& consequent : consequents[o]) {
      const double w = firing[static_cast<std::size_t>(consequent.rule)];
      if (w == 0.0) continue;
      double height = w;
      if (consequent.hedge_exponent != 1.0) height = std::pow(height, 1.0 / consequent.hedge_exponent);
      if (consequent.negated) height = fuzzy_not(height);
      const double z = sugeno_rule_value(output.terms[static_cast<std::size_t>(consequent.term)].mf, inputs);
      singletons.emplace_back(z, height);
    }

    double numerator = 0.0, denominator = 0.0;
    bool any_fired = false;
    if (options.reference == Reference::Octave) {
      // aggregate_output_sugeno: sort by location, merge equal locations with the aggregation method, drop zero
      // heights; then defuzz wtaver / wtsum over what is left.
      std::stable_sort(singletons.begin(), singletons.end(),
                       [](const auto& a, const auto& b) { return a.first < b.first; });
      for (std::size_t k = 0; k + 1 < singletons.size(); ++k) {
        if (singletons[k].first != singletons[k + 1].first) continue;
        singletons[k + 1].second = snorm(system.aggregation, singletons[k].second, singletons[k + 1].second);
        singletons[k].second = 0.0;
      }
      singletons.erase(std::remove_if(singletons.begin(), singletons.end(),
                                      [](const auto& s) { return s.second == 0.0; }),
                       singletons.end());
      for (const auto& [z, height] : singletons) {
        numerator += height * z;
        denominator += height;
      }
      any_fired = !singletons.empty();
    } else {
      // fis.c fisEvaluate: sum of w z over the rules, divided by the sum of the firing strengths of ALL rules,
      // including those with no consequent on this output (their z counts as 0).
      for (const auto& [z, height] : singletons) {
        numerator += height * z;
        if (height != 0.0) any_fired = true;
      }
      std::vector<bool> concludes(system.rules.size(), false);
      for (const auto& consequent : consequents[o]) concludes[static_cast<std::size_t>(consequent.rule)] = true;
      for (const auto& [z, height] : singletons) denominator += height;
      for (std::size_t r = 0; r < system.rules.size(); ++r)
        if (!concludes[r]) denominator += firing[r];
    }
    if (explanation) {
      explanation->x.clear();
      explanation->membership.clear();
      for (const auto& [z, height] : singletons) {
        explanation->x.push_back(z);
        explanation->membership.push_back(height);
      }
    }
    if (!any_fired || denominator == 0.0) return apply_no_fire_policy(o, flags);
    return weighted_sum ? numerator : numerator / denominator;
  }

  // ---- interval type-2 (docs/numerics.md, "Interval type-2") ------------------------------------------------

  // Rule firing intervals: every operation on each end (kernels/type2_math.h), in the type-1 fold order.
  void compute_firing_intervals(const std::vector<double>& inputs, std::vector<double>& lower,
                                std::vector<double>& upper) {
    for (std::size_t i = 0; i < system.inputs.size(); ++i) {
      const Variable& input = system.inputs[i];
      for (std::size_t t = 0; t < input.terms.size(); ++t) {
        const GradeInterval<double> mu = term_membership(input.terms[t], inputs[i]);
        input_grades[i][t] = mu.upper;
        input_grades_lower[i][t] = mu.lower;
      }
    }
    lower.resize(system.rules.size());
    upper.resize(system.rules.size());
    for (std::size_t r = 0; r < system.rules.size(); ++r) {
      const Rule& rule = system.rules[r];
      const bool conjunction = rule.connective == Connective::And;
      const double identity = conjunction ? tnorm_identity<double>() : snorm_identity<double>();
      // Grades folded in by the specialize pass start the fold on each end, as in type-1.
      GradeInterval<double> strength{rule.folded_grade_lower.value_or(rule.folded_grade.value_or(identity)),
                                     rule.folded_grade.value_or(identity)};
      for (const Clause& clause : antecedents[r]) {
        const auto v = static_cast<std::size_t>(clause.variable);
        const auto t = static_cast<std::size_t>(clause.term);
        const GradeInterval<double> mu =
            clause_interval({input_grades_lower[v][t], input_grades[v][t]}, clause.hedge, clause.negated);
        strength = conjunction ? interval_tnorm(system.and_method, strength, mu)
                               : interval_snorm(system.or_method, strength, mu);
      }
      // MATLAB's `sum` is not clipped to 1, and past 1 probor and the Einstein norms decrease: the ends may cross.
      // The firing interval is then the span of the two (docs/numerics.md).
      lower[r] = rule.weight * nan_min(strength.lower, strength.upper);
      upper[r] = rule.weight * nan_max(strength.lower, strength.upper);
    }
  }

  double no_fire_type2(std::size_t o, EvaluationFlags& flags, TypeReducedOutput& interval) const {
    const double value = apply_no_fire_policy(o, flags);
    interval.lower = interval.upper = value;
    interval.left_switch = interval.right_switch = -1;
    interval.left_switch_x = interval.right_switch_x = kNaN;
    return value;
  }

  // KM and EKM end within N + 1 steps (kernels/type_reduction_math.h); reaching their cap is a bug in fmpc,
  // reported as such rather than returned as a number.
  void check_reduction(const TypeReducedInterval<double>& reduced, std::size_t output, int points) const {
    if (!reduced.iteration_cap_hit) return;
    throw std::logic_error("type reduction (" + std::string(to_string(system.type_reduction)) + ") of output '" +
                           system.outputs[output].name + "' of system '" + system.name +
                           "' reached its iteration cap over " + std::to_string(points) + " points");
  }

  static void record_reduction(const TypeReducedInterval<double>& reduced, const double* x_left,
                               const double* x_right, TypeReducedOutput& interval) {
    interval.lower = reduced.left;
    interval.upper = reduced.right;
    interval.left_switch = reduced.left_switch;
    interval.right_switch = reduced.right_switch;
    interval.left_switch_x = reduced.left_switch > 0 ? x_left[reduced.left_switch - 1] : kNaN;
    interval.right_switch_x = reduced.right_switch > 0 ? x_right[reduced.right_switch - 1] : kNaN;
    interval.left_iterations = reduced.left_iterations;
    interval.right_iterations = reduced.right_iterations;
  }

  // Mamdani: implication and aggregation on each end of the sampled output sets, then type reduction over the
  // sample points with the aggregated [lower, upper] grades as weights (MATLAB mamfistype2's centroid).
  double mamdani_type2_output(std::size_t o, const std::vector<double>& lower, const std::vector<double>& upper,
                              EvaluationFlags& flags, TypeReducedOutput& interval, OutputExplanation* explanation) {
    const std::vector<double>& x = sample_points[o];
    std::fill(aggregate.begin(), aggregate.end(), snorm_identity<double>());
    std::fill(aggregate_lower.begin(), aggregate_lower.end(), snorm_identity<double>());
    bool any_fired = false;
    for (const auto& consequent : consequents[o]) {
      const auto r = static_cast<std::size_t>(consequent.rule);
      // As in type-1: a rule with zero firing adds implication(0, .) == 0, which every s-norm ignores.
      if (!(upper[r] > 0.0)) continue;
      any_fired = true;
      const auto t = static_cast<std::size_t>(consequent.term);
      const std::vector<double>& grades = term_samples[o][t];
      const std::vector<double>& grades_lower = term_samples_lower[o][t];
      for (std::size_t k = 0; k < aggregate.size(); ++k) {
        GradeInterval<double> mu{grades_lower[k], grades[k]};
        mu = interval_hedge(mu, consequent.hedge_exponent);
        if (consequent.negated) mu = interval_not(mu);
        aggregate[k] = snorm(system.aggregation, aggregate[k], tnorm(system.implication, upper[r], mu.upper));
        aggregate_lower[k] =
            snorm(system.aggregation, aggregate_lower[k], tnorm(system.implication, lower[r], mu.lower));
      }
    }
    // Past 1 (after an unclipped `sum`) probor and the Einstein sum decrease, so the ends may cross: keep the span.
    bool nan = false;
    for (std::size_t k = 0; k < aggregate.size(); ++k) {
      if (std::isnan(aggregate[k]) || std::isnan(aggregate_lower[k])) nan = true;
      else if (aggregate_lower[k] > aggregate[k]) std::swap(aggregate_lower[k], aggregate[k]);
    }
    if (explanation) {
      explanation->x = x;
      explanation->membership = aggregate;
      explanation->membership_lower = aggregate_lower;
    }
    if (!any_fired) return no_fire_type2(o, flags, interval);
    if (nan) {
      interval.lower = interval.upper = kNaN;
      return kNaN;
    }
    const TypeReducedInterval<double> reduced =
        reduce_type(system.type_reduction, x.data(), aggregate_lower.data(), aggregate.data(),
                    static_cast<int>(x.size()));
    check_reduction(reduced, o, static_cast<int>(x.size()));
    if (!reduced.fired) return no_fire_type2(o, flags, interval);
    record_reduction(reduced, x.data(), x.data(), interval);
    return (reduced.left + reduced.right) / 2.0;
  }

  // Sugeno: each rule's output z (an interval for constant(value [c1, c2])) weighted by its firing interval;
  // wtaver type-reduces (yl over the rules sorted by their low z, yr by their high z), wtsum takes the extreme
  // weighted sums. Rules without a consequent on this output count as z = 0, as in type-1 (fis.c).
  double sugeno_type2_output(std::size_t o, const std::vector<double>& inputs, const std::vector<double>& lower,
                             const std::vector<double>& upper, EvaluationFlags& flags, TypeReducedOutput& interval,
                             OutputExplanation* explanation) {
    const Variable& output = system.outputs[o];
    struct Point {
      double z_low, z_high, w_low, w_high;
    };
    std::vector<Point> points;
    bool any_fired = false;
    for (const auto& consequent : consequents[o]) {
      const auto r = static_cast<std::size_t>(consequent.rule);
      if (upper[r] == 0.0) continue;
      GradeInterval<double> height{lower[r], upper[r]};
      if (consequent.hedge_exponent != 1.0) {
        height.lower = std::pow(height.lower, 1.0 / consequent.hedge_exponent);
        height.upper = std::pow(height.upper, 1.0 / consequent.hedge_exponent);
      }
      if (consequent.negated) height = interval_not(height);
      if (height.upper != 0.0) any_fired = true;
      const Term& term = output.terms[static_cast<std::size_t>(consequent.term)];
      double z_low = sugeno_rule_value(term.mf, inputs), z_high = z_low;
      if (term.footprint && term.footprint->kind == FootprintKind::IntervalValue) {
        z_low = term.footprint->first;
        z_high = term.footprint->second;
      }
      points.push_back({z_low, z_high, height.lower, height.upper});
    }
    std::vector<bool> concludes(system.rules.size(), false);
    for (const auto& consequent : consequents[o]) concludes[static_cast<std::size_t>(consequent.rule)] = true;
    const std::size_t concluding = points.size();
    for (std::size_t r = 0; r < system.rules.size(); ++r)
      if (!concludes[r]) points.push_back({0.0, 0.0, lower[r], upper[r]});
    if (explanation) {
      explanation->x.clear();
      explanation->membership.clear();
      explanation->membership_lower.clear();
      for (std::size_t i = 0; i < concluding; ++i) {
        explanation->x.push_back(points[i].z_low);
        explanation->membership.push_back(points[i].w_high);
        explanation->membership_lower.push_back(points[i].w_low);
      }
    }
    if (!any_fired) return no_fire_type2(o, flags, interval);
    for (const Point& p : points)
      if (std::isnan(p.z_low) || std::isnan(p.z_high) || std::isnan(p.w_low) || std::isnan(p.w_high)) {
        interval.lower = interval.upper = kNaN;
        return kNaN;
      }

    const bool degenerate = std::all_of(points.begin(), points.end(), [](const Point& p) {
      return p.w_low == p.w_high && p.z_low == p.z_high;
    });
    if (system.defuzzifier == Defuzzifier::WeightedSum || degenerate) {
      // Weighted sums need no search: each term takes the weight end that lowers (yl) or raises (yr) it. With
      // every weight and z exact (zero-width footprints) this is the type-1 weighted average, in rule order.
      double yl = 0.0, yr = 0.0, total = 0.0;
      for (const Point& p : points) {
        yl += p.z_low * (p.z_low >= 0.0 ? p.w_low : p.w_high);
        yr += p.z_high * (p.z_high >= 0.0 ? p.w_high : p.w_low);
        total += p.w_high;
      }
      if (system.defuzzifier != Defuzzifier::WeightedSum) {
        if (total == 0.0) return no_fire_type2(o, flags, interval);
        yl /= total;
        yr = yl;
      }
      interval.lower = yl;
      interval.upper = yr;
      interval.left_switch = interval.right_switch = -1;
      interval.left_switch_x = interval.right_switch_x = kNaN;
      return yl == yr ? yl : (yl + yr) / 2.0;
    }

    const int n = static_cast<int>(points.size());
    const auto reduce_sorted = [&](bool by_low) {
      std::vector<Point> sorted = points;
      std::stable_sort(sorted.begin(), sorted.end(), [by_low](const Point& a, const Point& b) {
        return by_low ? a.z_low < b.z_low : a.z_high < b.z_high;
      });
      std::vector<double> x(sorted.size()), w_low(sorted.size()), w_high(sorted.size());
      for (std::size_t i = 0; i < sorted.size(); ++i) {
        x[i] = by_low ? sorted[i].z_low : sorted[i].z_high;
        w_low[i] = sorted[i].w_low;
        w_high[i] = sorted[i].w_high;
      }
      const TypeReducedInterval<double> reduced =
          reduce_type(system.type_reduction, x.data(), w_low.data(), w_high.data(), n);
      check_reduction(reduced, o, n);
      return std::make_pair(reduced, x);
    };
    const auto [left, x_left] = reduce_sorted(true);
    if (!left.fired) return no_fire_type2(o, flags, interval);
    const bool crisp_z = std::all_of(points.begin(), points.end(), [](const Point& p) { return p.z_low == p.z_high; });
    if (crisp_z) {
      record_reduction(left, x_left.data(), x_left.data(), interval);
    } else {
      const auto [right, x_right] = reduce_sorted(false);
      TypeReducedInterval<double> combined = left;
      combined.right = right.right;
      combined.right_switch = right.right_switch;
      combined.right_iterations = right.right_iterations;
      record_reduction(combined, x_left.data(), x_right.data(), interval);
    }
    return (interval.lower + interval.upper) / 2.0;
  }

  void run_type2(const std::vector<double>& inputs, Explanation& result, bool want_explanation) {
    Evaluation& evaluation = result.evaluation;
    compute_firing_intervals(inputs, evaluation.firing_lower, evaluation.firing_strengths);
    evaluation.intervals.assign(system.outputs.size(), TypeReducedOutput{});
    for (std::size_t o = 0; o < system.outputs.size(); ++o) {
      TypeReducedOutput& interval = evaluation.intervals[o];
      interval.method = system.type_reduction;
      OutputExplanation* explanation = want_explanation ? &result.outputs[o] : nullptr;
      evaluation.outputs[o] =
          system.type == SystemType::Mamdani
              ? mamdani_type2_output(o, evaluation.firing_lower, evaluation.firing_strengths, evaluation.flags,
                                     interval, explanation)
              : sugeno_type2_output(o, inputs, evaluation.firing_lower, evaluation.firing_strengths,
                                    evaluation.flags, interval, explanation);
    }
  }

  Explanation run(const std::vector<double>& inputs, bool want_explanation) {
    Explanation result;
    Evaluation& evaluation = result.evaluation;
    EvaluationFlags& flags = evaluation.flags;
    const std::size_t output_count = system.outputs.size();
    evaluation.outputs.assign(output_count, kNaN);
    if (want_explanation) result.outputs.resize(output_count);

    for (std::size_t i = 0; i < system.inputs.size(); ++i) {
      const double value = i < inputs.size() ? inputs[i] : kNaN;
      if (std::isnan(value)) flags.inputs_nan.push_back(static_cast<int>(i));
      else if (value < system.inputs[i].min || value > system.inputs[i].max)
        flags.inputs_out_of_range.push_back(static_cast<int>(i));
    }
    if (!flags.inputs_nan.empty() || inputs.size() < system.inputs.size()) {
      evaluation.firing_strengths.assign(system.rules.size(), kNaN);
      if (system.interval_type2) {
        evaluation.firing_lower.assign(system.rules.size(), kNaN);
        TypeReducedOutput unknown;
        unknown.method = system.type_reduction;
        unknown.lower = unknown.upper = kNaN;
        evaluation.intervals.assign(output_count, unknown);
      }
      return result;
    }
    if (system.interval_type2) {
      run_type2(inputs, result, want_explanation);
      return result;
    }

    compute_firing_strengths(inputs, evaluation.firing_strengths);
    for (std::size_t o = 0; o < output_count; ++o) {
      OutputExplanation* explanation = want_explanation ? &result.outputs[o] : nullptr;
      evaluation.outputs[o] = system.type == SystemType::Mamdani
                                  ? mamdani_output(o, evaluation.firing_strengths, flags, explanation)
                                  : sugeno_output(o, inputs, evaluation.firing_strengths, flags, explanation);
    }
    return result;
  }
};

Interpreter::Interpreter(const FuzzySystem& system, EvaluationOptions options)
    : state_(std::make_unique<State>(system, options)) {}
Interpreter::~Interpreter() = default;
Interpreter::Interpreter(Interpreter&&) noexcept = default;
Interpreter& Interpreter::operator=(Interpreter&&) noexcept = default;

Evaluation Interpreter::evaluate(const std::vector<double>& inputs) {
  return std::move(state_->run(inputs, false).evaluation);
}
Explanation Interpreter::explain(const std::vector<double>& inputs) { return state_->run(inputs, true); }

Evaluation Interpreter::evaluate_without_rule(const std::vector<double>& inputs, std::size_t rule) {
  double& weight = state_->system.rules.at(rule).weight;
  const double kept = weight;
  weight = 0.0;
  Evaluation evaluation = std::move(state_->run(inputs, false).evaluation);
  weight = kept;
  return evaluation;
}

Evaluation evaluate(const FuzzySystem& system, const std::vector<double>& inputs) {
  return Interpreter(system).evaluate(inputs);
}
Explanation explain(const FuzzySystem& system, const std::vector<double>& inputs) {
  return Interpreter(system).explain(inputs);
}
Evaluation evaluate(const FuzzySystem& system, const std::vector<double>& inputs, const EvaluationOptions& options) {
  return Interpreter(system, options).evaluate(inputs);
}
Explanation explain(const FuzzySystem& system, const std::vector<double>& inputs, const EvaluationOptions& options) {
  return Interpreter(system, options).explain(inputs);
}

}  // namespace fmpc

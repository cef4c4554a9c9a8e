#include "compiler/eval/interpreter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "compiler/eval/defuzzify.h"
#include "kernels/fuzzy_math.h"

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

}  // namespace

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
      double strength = conjunction ? tnorm_identity<double>() : snorm_identity<double>();
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

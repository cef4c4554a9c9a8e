#include "tests/support/random_system.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

namespace fmpc::testing {

namespace {

const std::vector<MfKind> kInputKinds = {
    MfKind::Triangle,      MfKind::Trapezoid,         MfKind::Gaussian,       MfKind::Gaussian2,
    MfKind::GeneralizedBell, MfKind::Sigmoid,         MfKind::DifferenceSigmoid, MfKind::ProductSigmoid,
    MfKind::ZShape,        MfKind::SShape,            MfKind::PiShape,        MfKind::LinearS,
    MfKind::LinearZ};
const std::vector<TNorm> kTNorms = {TNorm::Minimum, TNorm::Product, TNorm::EinsteinProduct};
const std::vector<SNorm> kSNorms = {SNorm::Maximum, SNorm::ProbabilisticSum, SNorm::Sum, SNorm::EinsteinSum};
const std::vector<Defuzzifier> kMamdaniDefuzzifiers = {
    Defuzzifier::Centroid, Defuzzifier::Bisector, Defuzzifier::MeanOfMaximum, Defuzzifier::SmallestOfMaximum,
    Defuzzifier::LargestOfMaximum};
const std::vector<Defuzzifier> kSugenoDefuzzifiers = {Defuzzifier::WeightedAverage, Defuzzifier::WeightedSum};
const std::vector<Hedge> kHedges = {Hedge::None, Hedge::Somewhat, Hedge::Very, Hedge::Extremely, Hedge::VeryVery};

const std::vector<std::string> kPlainTermNames = {"low", "mid", "high", "small", "big", "cold", "warm", "hot",
                                                  "slow", "fast", "near", "far"};
const std::vector<std::string> kFancyTermNames = {"F0-F1", "very low", "About-Ten", "not quite", "x-y z",
                                                  "High-Borderline", "is high", "and"};

// Draws with a mapping the test suite owns, so that a seed means the same system under every standard library.
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : engine_(seed) {}

  double unit() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  bool chance(double probability) { return unit() < probability; }
  int integer(int lo, int hi) {  // [lo, hi]
    const auto span = static_cast<std::uint64_t>(hi - lo + 1);
    return lo + static_cast<int>(engine_() % span);
  }
  template <typename T>
  T pick(const std::vector<T>& items) {
    return items[static_cast<std::size_t>(integer(0, static_cast<int>(items.size()) - 1))];
  }

 private:
  std::mt19937_64 engine_;
};

template <typename T>
const std::vector<T>& or_default(const std::vector<T>& chosen, const std::vector<T>& all) {
  return chosen.empty() ? all : chosen;
}

class Generator {
 public:
  Generator(std::uint64_t seed, const RandomSystemOptions& options) : draw_(seed), options_(options) {}

  FuzzySystem system() {
    FuzzySystem system;
    const bool sugeno = options_.sugeno && (!options_.mamdani || draw_.chance(0.5));
    system.type = sugeno ? SystemType::Sugeno : SystemType::Mamdani;
    system.name = "random_" + std::to_string(draw_.integer(0, 99999));
    if (options_.descriptions_and_units && draw_.chance(0.5)) system.description = "a generated system";
    system.and_method = draw_.pick(or_default(options_.and_methods, kTNorms));
    system.or_method = draw_.pick(or_default(options_.or_methods, kSNorms));
    system.implication = draw_.pick(or_default(options_.implication_methods, kTNorms));
    system.aggregation = draw_.pick(or_default(options_.aggregation_methods, kSNorms));
    system.defuzzifier = sugeno ? draw_.pick(or_default(options_.sugeno_defuzzifiers, kSugenoDefuzzifiers))
                                : draw_.pick(or_default(options_.mamdani_defuzzifiers, kMamdaniDefuzzifiers));
    if (options_.exact_samples && draw_.chance(0.3)) system.samples = draw_.chance(0.5) ? 0 : draw_.integer(11, 501);
    if (options_.no_fire_policies && draw_.chance(0.3)) {
      system.no_fire = draw_.chance(0.5) ? NoFirePolicy::Error : NoFirePolicy::Value;
      if (system.no_fire == NoFirePolicy::Value) system.no_fire_value = number(draw_.uniform(-10.0, 10.0));
    }

    const int input_count = draw_.integer(options_.min_inputs, options_.max_inputs);
    const int output_count = draw_.integer(options_.min_outputs, options_.max_outputs);
    for (int i = 0; i < input_count; ++i)
      system.inputs.push_back(variable("in" + std::to_string(i + 1), or_default(options_.input_kinds, kInputKinds)));
    for (int i = 0; i < output_count; ++i) {
      Variable output = sugeno ? sugeno_output("out" + std::to_string(i + 1), input_count)
                               : variable("out" + std::to_string(i + 1),
                                          or_default(options_.mamdani_output_kinds, kInputKinds));
      system.outputs.push_back(std::move(output));
    }

    const int rule_count = draw_.integer(options_.min_rules, options_.max_rules);
    for (int r = 0; r < rule_count; ++r) system.rules.push_back(rule(system, r));
    return system;
  }

 private:
  double number(double value) const {
    if (options_.decimals < 0) return value;
    const double scale = std::pow(10.0, options_.decimals);
    const double rounded = std::round(value * scale) / scale;
    return rounded == 0.0 ? 0.0 : rounded;  // no -0: printers fold it and a round trip would then differ
  }
  double smallest_step() const { return options_.decimals < 0 ? 0.0 : std::pow(10.0, -options_.decimals); }

  // Rounds `values` and keeps them strictly ascending, so that rounding cannot make a triangle degenerate.
  std::vector<double> ascending(std::vector<double> values) const {
    for (std::size_t i = 0; i < values.size(); ++i) {
      values[i] = number(values[i]);
      if (i > 0 && values[i] <= values[i - 1]) values[i] = number(values[i - 1] + smallest_step());
    }
    return values;
  }
  double positive(double value) const { return std::max(number(value), smallest_step() > 0 ? smallest_step() : value); }

  std::vector<std::string> term_names(int count) {
    std::vector<std::string> names;
    for (int t = 0; t < count; ++t) {
      std::string base = options_.names_with_dashes_and_spaces && draw_.chance(0.3) ? draw_.pick(kFancyTermNames)
                                                                                     : draw_.pick(kPlainTermNames);
      // A suffix keeps names distinct within the variable.
      names.push_back(std::find(names.begin(), names.end(), base) == names.end() ? base
                                                                                  : base + std::to_string(t + 1));
    }
    return names;
  }

  void draw_range(Variable& variable) {
    const double width = draw_.uniform(1.0, 200.0);
    variable.min = number(draw_.uniform(-100.0, 100.0));
    variable.max = number(variable.min + width);
    if (variable.max <= variable.min) variable.max = variable.min + 1.0;
  }

  MembershipFunction input_mf(MfKind kind, double lo, double hi) {
    const double w = hi - lo;
    const double centre = draw_.uniform(lo, hi);
    auto spread = [&] { return draw_.uniform(0.05 * w, 0.5 * w); };
    MembershipFunction mf;
    mf.kind = kind;
    switch (kind) {
      case MfKind::Triangle:
        mf.params = ascending({centre - spread(), centre, centre + spread()});
        break;
      case MfKind::Trapezoid:
      case MfKind::PiShape: {
        const double half = draw_.uniform(0.01 * w, 0.2 * w);
        mf.params = ascending({centre - half - spread(), centre - half, centre + half, centre + half + spread()});
        break;
      }
      case MfKind::Gaussian:
        mf.params = {positive(draw_.uniform(0.05 * w, 0.4 * w)), number(centre)};
        break;
      case MfKind::Gaussian2: {
        const std::vector<double> centres = ascending({centre, centre + draw_.uniform(0.0, 0.3 * w)});
        mf.params = {positive(draw_.uniform(0.05 * w, 0.3 * w)), centres[0],
                     positive(draw_.uniform(0.05 * w, 0.3 * w)), centres[1]};
        break;
      }
      case MfKind::GeneralizedBell:
        mf.params = {positive(draw_.uniform(0.05 * w, 0.4 * w)), positive(draw_.uniform(0.5, 4.0)), number(centre)};
        break;
      case MfKind::Sigmoid: {
        const double slope = draw_.uniform(2.0, 20.0) / w;
        mf.params = {number(draw_.chance(0.5) ? slope : -slope), number(centre)};
        if (mf.params[0] == 0.0) mf.params[0] = smallest_step();
        break;
      }
      case MfKind::DifferenceSigmoid:
      case MfKind::ProductSigmoid: {
        // A bump: rising at c1, falling at c2 (dsigmf: both slopes positive; psigmf: the second negative).
        const std::vector<double> centres = ascending({centre - spread() / 2, centre + spread() / 2});
        const double a1 = positive(draw_.uniform(2.0, 20.0) / w);
        const double a2 = positive(draw_.uniform(2.0, 20.0) / w);
        mf.params = {a1, centres[0], kind == MfKind::ProductSigmoid ? -a2 : a2, centres[1]};
        break;
      }
      case MfKind::ZShape:
      case MfKind::SShape:
      case MfKind::LinearS:
      case MfKind::LinearZ:
        mf.params = ascending({centre - spread() / 2, centre + spread() / 2});
        break;
      case MfKind::Constant:
        mf.params = {number(centre)};
        break;
      case MfKind::Linear:
        break;  // outputs only: see sugeno_output
    }
    return mf;
  }

  std::string variable_name(const std::string& plain) {
    // MATLAB files name variables like 'Food-Quality' or 'Risk Tolerance'.
    if (options_.names_with_dashes_and_spaces && draw_.chance(0.3)) return "Risk Tolerance-" + plain;
    return plain;
  }

  Variable variable(const std::string& name, const std::vector<MfKind>& kinds) {
    Variable variable;
    variable.name = variable_name(name);
    if (options_.descriptions_and_units) {
      if (draw_.chance(0.5)) variable.description = "generated " + name;
      if (draw_.chance(0.5)) variable.unit = draw_.pick(std::vector<std::string>{"kPa", "m", "s", "1"});
    }
    draw_range(variable);
    const int term_count = draw_.integer(options_.min_terms, options_.max_terms);
    for (const std::string& term_name : term_names(term_count)) {
      Term term;
      term.name = term_name;
      term.mf = input_mf(draw_.pick(kinds), variable.min, variable.max);
      variable.terms.push_back(std::move(term));
    }
    return variable;
  }

  Variable sugeno_output(const std::string& name, int input_count) {
    Variable variable;
    variable.name = variable_name(name);
    if (options_.descriptions_and_units && draw_.chance(0.5)) variable.unit = "kPa";
    draw_range(variable);
    const int term_count = draw_.integer(options_.min_terms, options_.max_terms);
    for (const std::string& term_name : term_names(term_count)) {
      Term term;
      term.name = term_name;
      const bool linear = options_.linear_outputs && (!options_.constant_outputs || draw_.chance(0.5));
      if (linear) {
        term.mf.kind = MfKind::Linear;
        for (int i = 0; i < input_count; ++i) term.mf.params.push_back(number(draw_.uniform(-2.0, 2.0)));
        term.mf.params.push_back(number(draw_.uniform(variable.min, variable.max)));
      } else {
        term.mf.kind = MfKind::Constant;
        term.mf.params = {number(draw_.uniform(variable.min, variable.max))};
      }
      variable.terms.push_back(std::move(term));
    }
    return variable;
  }

  Clause clause(const Variable& variable, int index, bool may_negate, bool may_hedge) {
    Clause clause;
    clause.variable = index;
    clause.term = draw_.integer(0, static_cast<int>(variable.terms.size()) - 1);
    clause.negated = may_negate && draw_.chance(0.15);
    if (may_hedge && draw_.chance(0.25)) clause.hedge = draw_.pick(or_default(options_.hedges, kHedges));
    return clause;
  }

  Rule rule(const FuzzySystem& system, int index) {
    Rule rule;
    if (options_.rule_labels && draw_.chance(0.5)) rule.label = "r" + std::to_string(index + 1);
    rule.connective = options_.or_rules && draw_.chance(0.3) ? Connective::Or : Connective::And;
    for (std::size_t i = 0; i < system.inputs.size(); ++i)
      if (!options_.dont_care || draw_.chance(0.7))
        rule.antecedent.push_back(clause(system.inputs[i], static_cast<int>(i), options_.negation, true));
    if (rule.antecedent.empty()) {
      const int i = draw_.integer(0, static_cast<int>(system.inputs.size()) - 1);
      rule.antecedent.push_back(clause(system.inputs[static_cast<std::size_t>(i)], i, options_.negation, true));
    }
    for (std::size_t o = 0; o < system.outputs.size(); ++o)
      if (!options_.dont_care || draw_.chance(0.8))
        rule.consequent.push_back(clause(system.outputs[o], static_cast<int>(o), options_.consequent_negation,
                                         options_.consequent_hedges));
    if (rule.consequent.empty()) {
      const int o = draw_.integer(0, static_cast<int>(system.outputs.size()) - 1);
      rule.consequent.push_back(clause(system.outputs[static_cast<std::size_t>(o)], o, options_.consequent_negation,
                                       options_.consequent_hedges));
    }
    if (options_.weights && draw_.chance(0.3)) {
      rule.weight = number(draw_.uniform(0.05, 1.0));
      if (rule.weight <= 0.0) rule.weight = 1.0;
    }
    return rule;
  }

  Draw draw_;
  const RandomSystemOptions& options_;
};

}  // namespace

RandomSystemOptions RandomSystemOptions::matlab_fis() {
  RandomSystemOptions options;
  options.descriptions_and_units = false;
  options.rule_labels = false;
  options.exact_samples = false;
  options.no_fire_policies = false;
  return options;
}

RandomSystemOptions RandomSystemOptions::matlab() {
  RandomSystemOptions options = matlab_fis();
  options.hedges = {Hedge::None};
  options.and_methods = {TNorm::Minimum, TNorm::Product};
  options.implication_methods = {TNorm::Minimum, TNorm::Product};
  options.or_methods = {SNorm::Maximum, SNorm::ProbabilisticSum, SNorm::Sum};
  options.aggregation_methods = {SNorm::Maximum, SNorm::ProbabilisticSum, SNorm::Sum};
  return options;
}

RandomSystemOptions RandomSystemOptions::fuzzylite() {
  RandomSystemOptions options = matlab_fis();
  options.hedges = {Hedge::None};
  options.names_with_dashes_and_spaces = false;
  return options;
}

namespace {

// A footprint for `term` drawn from `draw`, or none (zero width). Explicit lower MFs are the upper MF with a
// smaller height (the same kind scaled is not a family, so a narrower copy of the triangle/gaussian is used), so
// that the lower MF never exceeds the upper one.
void add_footprint(Draw& draw, Term& term, bool sugeno_output) {
  if (draw.chance(0.2)) return;
  Footprint footprint;
  if (sugeno_output) {
    if (term.mf.kind != MfKind::Constant) return;
    const double c = term.mf.params[0];
    const double half = draw.uniform(0.0, 0.2) * (1.0 + std::fabs(c));
    footprint.kind = FootprintKind::IntervalValue;
    footprint.first = c - half;
    footprint.second = c + half;
    term.mf.params[0] = 0.5 * (footprint.first + footprint.second);  // as lowering computes the type-1 view
    term.footprint = footprint;
    return;
  }
  const double pick = draw.unit();
  if (term.mf.kind == MfKind::Gaussian && pick < 0.35) {
    const double sd = term.mf.params[0], mean = term.mf.params[1];
    footprint.kind = FootprintKind::UncertainMean;
    footprint.first = mean - draw.uniform(0.0, 0.5) * sd;
    footprint.second = mean + draw.uniform(0.0, 0.5) * sd;
    term.mf.params[1] = 0.5 * (footprint.first + footprint.second);
  } else if (term.mf.kind == MfKind::Gaussian && pick < 0.7) {
    const double sd = term.mf.params[0];
    footprint.kind = FootprintKind::UncertainSd;
    footprint.first = sd * draw.uniform(0.4, 1.0);
    footprint.second = sd;
    term.mf.params[0] = 0.5 * (footprint.first + footprint.second);
  } else if (term.mf.kind == MfKind::Triangle && pick < 0.5) {
    // A triangle inside the upper one, with the same peak: lower <= upper everywhere.
    const double a = term.mf.params[0], b = term.mf.params[1], c = term.mf.params[2];
    footprint.kind = FootprintKind::ExplicitLower;
    footprint.lower.kind = MfKind::Triangle;
    footprint.lower.params = {b - (b - a) * draw.uniform(0.3, 1.0), b, b + (c - b) * draw.uniform(0.3, 1.0)};
  } else {
    footprint.kind = FootprintKind::ScaleLag;
    footprint.first = draw.uniform(0.3, 1.0);
    footprint.second = draw.chance(0.3) ? 0.0 : draw.uniform(0.0, 0.6);
  }
  term.footprint = footprint;
}

}  // namespace

FuzzySystem random_system(std::uint64_t seed, const RandomSystemOptions& options) {
  FuzzySystem system = Generator(seed, options).system();
  if (!options.interval_type2) return system;
  // A separate stream, so that the type-1 part of the system is the one the same seed gives without type-2.
  Draw draw(seed ^ 0x9E3779B97F4A7C15ULL);
  system.interval_type2 = true;
  const std::vector<TypeReduction> all = {TypeReduction::KarnikMendel, TypeReduction::EnhancedKarnikMendel,
                                          TypeReduction::Eiasc, TypeReduction::NieTan};
  system.type_reduction = draw.pick(options.type_reductions.empty() ? all : options.type_reductions);
  const bool sugeno = system.type == SystemType::Sugeno;
  if (!sugeno) {
    system.defuzzifier = Defuzzifier::Centroid;
    if (system.samples == 0) system.samples = 101;
  }
  for (Variable& input : system.inputs)
    for (Term& term : input.terms) add_footprint(draw, term, false);
  for (Variable& output : system.outputs)
    for (Term& term : output.terms) add_footprint(draw, term, sugeno);
  return system;
}

std::vector<std::vector<double>> random_inputs(const FuzzySystem& system, std::uint64_t seed, std::size_t count) {
  Draw draw(seed);
  std::vector<std::vector<double>> points(count);
  for (std::vector<double>& point : points)
    for (const Variable& input : system.inputs) point.push_back(draw.uniform(input.min, input.max));
  return points;
}

}  // namespace fmpc::testing

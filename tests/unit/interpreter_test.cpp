// compiler/eval: the reference interpreter and its defuzzifiers on hand-made sets and systems built in code,
// exact (`samples exact`) centroids against closed forms and 1e6-sample Riemann sums, no-fire policies, NaN and
// out-of-range inputs, and seeded property tests on random systems.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "compiler/eval/defuzzify.h"
#include "compiler/eval/interpreter.h"
#include "tests/support/random_system.h"

namespace {

using fmpc::Defuzzifier;
using fmpc::FuzzySystem;
using fmpc::MfKind;
using fmpc::Reference;
using fmpc::SNorm;
using fmpc::TNorm;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct TermSpec {
  std::string name;
  MfKind kind;
  std::vector<double> params;
};

fmpc::Variable variable(const std::string& name, double min, double max, const std::vector<TermSpec>& terms) {
  fmpc::Variable v;
  v.name = name;
  v.min = min;
  v.max = max;
  for (const auto& spec : terms) {
    fmpc::Term term;
    term.name = spec.name;
    term.mf.kind = spec.kind;
    term.mf.params = spec.params;
    v.terms.push_back(term);
  }
  return v;
}

fmpc::Clause clause(int var, int term, bool negated = false, fmpc::Hedge hedge = fmpc::Hedge::None) {
  fmpc::Clause c;
  c.variable = var;
  c.term = term;
  c.negated = negated;
  c.hedge = hedge;
  return c;
}

fmpc::Rule rule(std::vector<fmpc::Clause> antecedent, std::vector<fmpc::Clause> consequent, double weight = 1.0,
                fmpc::Connective connective = fmpc::Connective::And) {
  fmpc::Rule r;
  r.antecedent = std::move(antecedent);
  r.consequent = std::move(consequent);
  r.weight = weight;
  r.connective = connective;
  return r;
}

// One input x in [0, 10] with terms low = trimf [0 0 5] (index 0) and high = trimf [5 10 10] (index 1); one output
// y in [0, 10] with small = trimf [0 2 4] and large = trimf [6 8 10]; rules low -> small, high -> large.
FuzzySystem two_rule_mamdani() {
  FuzzySystem s;
  s.name = "two_rules";
  s.inputs.push_back(variable("x", 0, 10, {{"low", MfKind::Triangle, {0, 0, 5}},
                                           {"high", MfKind::Triangle, {5, 10, 10}}}));
  s.outputs.push_back(variable("y", 0, 10, {{"small", MfKind::Triangle, {0, 2, 4}},
                                            {"large", MfKind::Triangle, {6, 8, 10}}}));
  s.rules.push_back(rule({clause(0, 0)}, {clause(0, 0)}));
  s.rules.push_back(rule({clause(0, 1)}, {clause(0, 1)}));
  return s;
}

// MATLAB's centroid written out: sum(x mu) / sum(mu) over x_k = min + k (max - min) / 100.
double matlab_centroid(const FuzzySystem& s, double w_small, double w_large) {
  double num = 0.0, den = 0.0;
  for (int k = 0; k <= 100; ++k) {
    const double x = 0.0 + 0.1 * k;
    const double small = std::max(0.0, std::min((x - 0.0) / 2.0, (4.0 - x) / 2.0));
    const double large = std::max(0.0, std::min((x - 6.0) / 2.0, (10.0 - x) / 2.0));
    const double g = std::max(std::min(w_small, small), std::min(w_large, large));
    num += x * g;
    den += g;
  }
  (void)s;
  return num / den;
}

fmpc::ImpliedConsequent implied(MfKind kind, std::vector<double> params, double firing, bool negated = false,
                                double hedge = 1.0) {
  fmpc::ImpliedConsequent c;
  c.kind = kind;
  c.params = std::move(params);
  c.firing = firing;
  c.negated = negated;
  c.hedge_exponent = hedge;
  return c;
}

// Midpoint Riemann sum with n cells: the reference for exact centroids of any shape.
double riemann_centroid(const fmpc::ExactAggregate& aggregate, int n) {
  const double h = (aggregate.max - aggregate.min) / n;
  double area = 0.0, moment = 0.0;
  for (int k = 0; k < n; ++k) {
    const double y = aggregate.min + (k + 0.5) * h;
    const double g = aggregate.grade(y);
    area += g;
    moment += g * y;
  }
  return moment / area;
}

double trapezoid_centroid(double a, double b, double c, double d) {
  return (c * c + d * d + c * d - a * a - b * b - a * b) / (3.0 * (c + d - a - b));
}

}  // namespace

TEST_CASE("sampled defuzzifiers on hand-made sets, MATLAB and Octave", "[interpreter]") {
  const std::vector<double> x{1, 2, 3, 4}, g{1, 2, 3, 4};
  CHECK(*fmpc::defuzzify_sampled(Defuzzifier::Centroid, x, g, Reference::Matlab) == Approx(3.0).epsilon(1e-15));
  // Octave defuzz.m's own test: trapz centroid 2.8667 (= 8.6 / 3).
  CHECK(*fmpc::defuzzify_sampled(Defuzzifier::Centroid, x, g, Reference::Octave) ==
        Approx(43.0 / 15.0).epsilon(1e-15));
  CHECK(*fmpc::defuzzify_sampled(Defuzzifier::Bisector, x, g, Reference::Matlab) == 3.0);  // 1+2+3 >= 10/2
  CHECK(*fmpc::defuzzify_sampled(Defuzzifier::MeanOfMaximum, x, g, Reference::Matlab) == 4.0);
  CHECK(*fmpc::defuzzify_sampled(Defuzzifier::SmallestOfMaximum, x, g, Reference::Matlab) == 4.0);
  CHECK(*fmpc::defuzzify_sampled(Defuzzifier::LargestOfMaximum, x, g, Reference::Matlab) == 4.0);

  // MATLAB Answers 368956: x = -1:0.5:1, mf = [0.1 0.8 0.8 0.8 0.1] gives som 0, lom -0.5, mom 0 in MATLAB
  // (smallest / largest magnitude, first on ties); Octave picks signed extremes.
  const std::vector<double> xs{-1, -0.5, 0, 0.5, 1}, plateau{0.1, 0.8, 0.8, 0.8, 0.1};
  CHECK(*fmpc::defuzzify_sampled(Defuzzifier::SmallestOfMaximum, xs, plateau, Reference::Matlab) == 0.0);
  CHECK(*fmpc::defuzzify_sampled(Defuzzifier::LargestOfMaximum, xs, plateau, Reference::Matlab) == -0.5);
  CHECK(*fmpc::defuzzify_sampled(Defuzzifier::MeanOfMaximum, xs, plateau, Reference::Matlab) == 0.0);
  CHECK(*fmpc::defuzzify_sampled(Defuzzifier::SmallestOfMaximum, xs, plateau, Reference::Octave) == -0.5);
  CHECK(*fmpc::defuzzify_sampled(Defuzzifier::LargestOfMaximum, xs, plateau, Reference::Octave) == 0.5);

  const std::vector<double> zeros(4, 0.0);
  for (auto method : {Defuzzifier::Centroid, Defuzzifier::Bisector, Defuzzifier::MeanOfMaximum,
                      Defuzzifier::SmallestOfMaximum, Defuzzifier::LargestOfMaximum}) {
    CHECK_FALSE(fmpc::defuzzify_sampled(method, x, zeros, Reference::Matlab).has_value());
    CHECK_FALSE(fmpc::defuzzify_sampled(method, x, zeros, Reference::Octave).has_value());
  }
  CHECK(std::isnan(*fmpc::defuzzify_sampled(Defuzzifier::Centroid, x, {1, kNaN, 1, 1}, Reference::Matlab)));
}

TEST_CASE("output sample points follow fis.c (min + k step) and Octave's linspace", "[interpreter]") {
  const auto matlab = fmpc::output_sample_points(0.0, 30.0, 101, Reference::Matlab);
  REQUIRE(matlab.size() == 101);
  CHECK(matlab[0] == 0.0);
  CHECK(matlab[10] == 0.3 * 10);
  const auto octave = fmpc::output_sample_points(0.1, 0.7, 7, Reference::Octave);
  CHECK(octave.back() == 0.7);
}

TEST_CASE("exact centroid: closed forms for triangles and trapezoids", "[interpreter]") {
  fmpc::ExactAggregate a;
  a.min = 0;
  a.max = 4;
  a.rules = {implied(MfKind::Triangle, {0, 1, 4}, 1.0)};
  REQUIRE(a.piecewise_linear());
  auto centroid = [&](const fmpc::ExactAggregate& agg) {
    return *fmpc::defuzzify_exact(Defuzzifier::Centroid, agg, Reference::Matlab).value;
  };
  CHECK(centroid(a) == Approx(5.0 / 3.0).epsilon(1e-14));  // triangle centroid (a + b + c) / 3
  a.rules = {implied(MfKind::Triangle, {0, 1, 4}, 0.5)};   // clipped: trapezoid [0 .5 2.5 4] of height .5
  CHECK(centroid(a) == Approx(trapezoid_centroid(0, 0.5, 2.5, 4)).epsilon(1e-14));
  a.implication = TNorm::Product;                           // scaled: same centroid as the triangle
  CHECK(centroid(a) == Approx(5.0 / 3.0).epsilon(1e-14));
  a.implication = TNorm::Minimum;
  a.rules = {implied(MfKind::Trapezoid, {0, 1, 2, 4}, 1.0)};
  CHECK(centroid(a) == Approx(trapezoid_centroid(0, 1, 2, 4)).epsilon(1e-14));
  CHECK(centroid(a) == Approx(1.8).epsilon(1e-14));
  // A vertical edge (a == b) is integrated exactly too: the rectangle [1, 3] has centroid 2.
  a.rules = {implied(MfKind::Trapezoid, {1, 1, 3, 3}, 1.0)};
  CHECK(centroid(a) == Approx(2.0).epsilon(1e-14));
  // Negated consequent: 1 - trimf [1 2 3] on [0, 4] is symmetric about 2.
  a.rules = {implied(MfKind::Triangle, {1, 2, 3}, 1.0, true)};
  CHECK(centroid(a) == Approx(2.0).epsilon(1e-14));
  // Nothing fired: no value, the caller applies the no-fire policy.
  a.rules.clear();
  CHECK_FALSE(fmpc::defuzzify_exact(Defuzzifier::Centroid, a, Reference::Matlab).value.has_value());
}

TEST_CASE("exact centroid agrees with a 1e6-sample Riemann sum for every aggregate shape", "[interpreter]") {
  struct Case {
    const char* name;
    fmpc::ExactAggregate aggregate;
  };
  std::vector<Case> cases;
  auto make = [](TNorm imp, SNorm agg, std::vector<fmpc::ImpliedConsequent> rules) {
    fmpc::ExactAggregate a;
    a.min = -3;
    a.max = 7;
    a.implication = imp;
    a.aggregation = agg;
    a.rules = std::move(rules);
    return a;
  };
  cases.push_back({"max-min triangles (envelope crossings)",
                   make(TNorm::Minimum, SNorm::Maximum,
                        {implied(MfKind::Triangle, {-3, 0, 3}, 0.7), implied(MfKind::Triangle, {1, 4, 6}, 0.4),
                         implied(MfKind::Trapezoid, {0, 2, 5, 7}, 0.25)})});
  cases.push_back({"sum-prod trapezoids, linsmf, linzmf",
                   make(TNorm::Product, SNorm::Sum,
                        {implied(MfKind::Trapezoid, {-2, -1, 1, 2}, 0.9), implied(MfKind::LinearS, {3, 6}, 0.3),
                         implied(MfKind::LinearZ, {-3, 0}, 0.6)})});
  cases.push_back({"gaussians max-min (adaptive)",
                   make(TNorm::Minimum, SNorm::Maximum,
                        {implied(MfKind::Gaussian, {1.2, 0}, 0.8), implied(MfKind::Gaussian, {0.7, 4}, 0.3)})});
  cases.push_back({"probor of gbell and trimf (adaptive)",
                   make(TNorm::Product, SNorm::ProbabilisticSum,
                        {implied(MfKind::GeneralizedBell, {2, 2, 1}, 0.6), implied(MfKind::Triangle, {2, 3, 6}, 0.9)})});
  cases.push_back({"einstein, hedged and negated sigmoids (adaptive)",
                   make(TNorm::EinsteinProduct, SNorm::EinsteinSum,
                        {implied(MfKind::Sigmoid, {3, 1}, 0.5, false, 2.0),
                         implied(MfKind::DifferenceSigmoid, {4, -1, 4, 2}, 0.7, true),
                         implied(MfKind::PiShape, {0, 1, 3, 5}, 0.4, false, 0.5)})});
  cases.push_back({"step edge trapmf a == b with a gaussian (adaptive)",
                   make(TNorm::Minimum, SNorm::Maximum,
                        {implied(MfKind::Trapezoid, {1, 1, 2, 4}, 0.6), implied(MfKind::Gaussian2, {0.5, -1, 1, 0}, 1.0)})});
  for (const auto& test : cases) {
    INFO(test.name);
    const auto exact = fmpc::defuzzify_exact(Defuzzifier::Centroid, test.aggregate, Reference::Matlab);
    REQUIRE(exact.value.has_value());
    const double riemann = riemann_centroid(test.aggregate, 1000000);
    // The midpoint rule's own error is O(h^2) on smooth parts and O(h) only at the few jumps: 1e-9 of the range.
    CHECK(std::fabs(*exact.value - riemann) <= 1e-9 * (test.aggregate.max - test.aggregate.min));
    CHECK(std::is_sorted(exact.points.begin(), exact.points.end()));
  }
}

TEST_CASE("exact bisector and maxima on a clipped asymmetric triangle", "[interpreter]") {
  fmpc::ExactAggregate a;
  a.min = 0;
  a.max = 4;
  a.rules = {implied(MfKind::Triangle, {0, 1, 4}, 0.5)};  // plateau [0.5, 2.5] at 0.5
  CHECK(*fmpc::defuzzify_exact(Defuzzifier::MeanOfMaximum, a, Reference::Matlab).value == Approx(1.5));
  CHECK(*fmpc::defuzzify_exact(Defuzzifier::SmallestOfMaximum, a, Reference::Matlab).value == Approx(0.5));
  CHECK(*fmpc::defuzzify_exact(Defuzzifier::LargestOfMaximum, a, Reference::Matlab).value == Approx(2.5));
  // Total area (4 + 2) / 2 * 0.5 = 1.5; the left ramp holds 0.125, so the bisector is at 0.5 + 0.625 / 0.5.
  CHECK(*fmpc::defuzzify_exact(Defuzzifier::Bisector, a, Reference::Matlab).value == Approx(1.75).epsilon(1e-14));
  // Adaptive path: a symmetric Gaussian bisects at its centre.
  a.rules = {implied(MfKind::Gaussian, {0.5, 2}, 1.0)};
  CHECK(*fmpc::defuzzify_exact(Defuzzifier::Bisector, a, Reference::Matlab).value == Approx(2.0).margin(1e-9));
  CHECK(*fmpc::defuzzify_exact(Defuzzifier::MeanOfMaximum, a, Reference::Matlab).value == Approx(2.0).margin(1e-4));
}

TEST_CASE("Mamdani evaluation reproduces MATLAB's 101-point centroid", "[interpreter]") {
  FuzzySystem s = two_rule_mamdani();
  for (double x : {0.0, 2.5, 4.0, 6.0, 7.5, 10.0}) {
    const double w_low = std::max(0.0, (5.0 - x) / 5.0), w_high = std::max(0.0, (x - 5.0) / 5.0);
    if (w_low == 0.0 && w_high == 0.0) continue;
    const fmpc::Evaluation e = fmpc::evaluate(s, {x});
    INFO("x = " << x);
    REQUIRE(e.firing_strengths.size() == 2);
    CHECK(e.firing_strengths[0] == Approx(w_low).margin(1e-15));
    CHECK(e.firing_strengths[1] == Approx(w_high).margin(1e-15));
    CHECK(e.outputs[0] == Approx(matlab_centroid(s, w_low, w_high)).epsilon(1e-14));
    CHECK(e.flags.outputs_no_rule_fired.empty());
    CHECK(e.flags.inputs_out_of_range.empty());
  }
}

TEST_CASE("no rule fired: midrange, value or error, each flagged", "[interpreter]") {
  FuzzySystem s = two_rule_mamdani();  // at x == 5 neither triangle fires
  fmpc::Evaluation e = fmpc::evaluate(s, {5.0});
  CHECK(e.outputs[0] == 5.0);
  CHECK(e.flags.outputs_no_rule_fired == std::vector<int>{0});
  CHECK_FALSE(e.flags.no_fire_error);
  s.no_fire = fmpc::NoFirePolicy::Value;
  s.no_fire_value = 3.25;
  e = fmpc::evaluate(s, {5.0});
  CHECK(e.outputs[0] == 3.25);
  CHECK(e.flags.outputs_no_rule_fired == std::vector<int>{0});
  s.no_fire = fmpc::NoFirePolicy::Error;
  e = fmpc::evaluate(s, {5.0});
  CHECK(std::isnan(e.outputs[0]));
  CHECK(e.flags.no_fire_error);
  s.samples = 0;  // the exact path applies the same policy
  e = fmpc::evaluate(s, {5.0});
  CHECK(std::isnan(e.outputs[0]));
  CHECK(e.flags.no_fire_error);
  // Sugeno: nothing fired, same policies.
  FuzzySystem sugeno = two_rule_mamdani();
  sugeno.type = fmpc::SystemType::Sugeno;
  sugeno.defuzzifier = Defuzzifier::WeightedAverage;
  sugeno.outputs[0] = variable("y", 0, 10, {{"small", MfKind::Constant, {2}}, {"large", MfKind::Constant, {8}}});
  e = fmpc::evaluate(sugeno, {5.0});
  CHECK(e.outputs[0] == 5.0);
  CHECK(e.flags.outputs_no_rule_fired == std::vector<int>{0});
  e = fmpc::evaluate(sugeno, {5.0}, {Reference::Octave});
  CHECK(e.outputs[0] == 5.0);  // Octave itself gives NaN here (0/0); fmpc applies its policy in both modes
}

TEST_CASE("NaN inputs give NaN outputs and a flag; out-of-range inputs are evaluated as given", "[interpreter]") {
  FuzzySystem s = two_rule_mamdani();
  fmpc::Evaluation e = fmpc::evaluate(s, {kNaN});
  CHECK(std::isnan(e.outputs[0]));
  CHECK(e.flags.inputs_nan == std::vector<int>{0});
  CHECK(std::isnan(e.firing_strengths[0]));
  e = fmpc::evaluate(s, {-2.0});  // low = trimf [0 0 5] is 0 left of 0: nothing fires, midrange, both flagged
  CHECK(e.flags.inputs_out_of_range == std::vector<int>{0});
  CHECK(e.outputs[0] == 5.0);
  s.inputs[0].terms[0].mf = {MfKind::ZShape, {0, 5}};  // 1 left of 0: out-of-range value still fires
  e = fmpc::evaluate(s, {-2.0});
  CHECK(e.flags.inputs_out_of_range == std::vector<int>{0});
  CHECK(e.firing_strengths[0] == 1.0);
  CHECK(e.outputs[0] == Approx(2.0).margin(1e-12));
  s.inputs[0].terms[1].mf = {MfKind::SShape, {5, 10}};  // +inf takes the MF's limit, 1
  e = fmpc::evaluate(s, {std::numeric_limits<double>::infinity()});
  CHECK(e.flags.inputs_out_of_range == std::vector<int>{0});
  CHECK(e.outputs[0] == Approx(8.0).margin(1e-12));
}

TEST_CASE("weights, NOT and hedges on antecedents and Mamdani consequents, OR rules", "[interpreter]") {
  FuzzySystem s = two_rule_mamdani();
  s.rules[0].weight = 0.5;
  s.rules[0].antecedent[0].hedge = fmpc::Hedge::Very;
  s.rules[1] = rule({clause(0, 1, true)}, {clause(0, 1)}, 1.0, fmpc::Connective::Or);
  fmpc::Evaluation e = fmpc::evaluate(s, {2.0});
  CHECK(e.firing_strengths[0] == Approx(0.5 * 0.6 * 0.6).epsilon(1e-15));  // weight * (very low)
  CHECK(e.firing_strengths[1] == 1.0);                                      // not high
  // Negated consequent: 1 - large over the whole range, clipped at 1; symmetric pieces give a checkable centroid.
  FuzzySystem n = two_rule_mamdani();
  n.rules = {rule({clause(0, 0)}, {clause(0, 1, true)})};
  n.samples = 0;
  e = fmpc::evaluate(n, {0.0});  // aggregate = 1 - trimf [6 8 10]: area 10 - 2, moment 50 - 16
  CHECK(e.outputs[0] == Approx((50.0 - 16.0) / 8.0).epsilon(1e-13));
  n.rules = {rule({clause(0, 0)}, {clause(0, 0, false, fmpc::Hedge::Very)})};
  e = fmpc::evaluate(n, {0.0});  // very small is still symmetric about 2
  CHECK(e.outputs[0] == Approx(2.0).epsilon(1e-12));
}

TEST_CASE("multiple outputs, Sugeno constant and linear, wtaver and wtsum", "[interpreter]") {
  FuzzySystem s;
  s.type = fmpc::SystemType::Sugeno;
  s.defuzzifier = Defuzzifier::WeightedAverage;
  s.inputs.push_back(variable("a", 0, 1, {{"lo", MfKind::LinearZ, {0, 1}}, {"hi", MfKind::LinearS, {0, 1}}}));
  s.inputs.push_back(variable("b", 0, 1, {{"any", MfKind::Trapezoid, {-1, 0, 1, 2}}}));
  s.outputs.push_back(variable("z", 0, 10, {{"c", MfKind::Constant, {2}}, {"l", MfKind::Linear, {4, 2, 1}}}));
  s.outputs.push_back(variable("q", 0, 10, {{"c", MfKind::Constant, {7}}}));
  s.rules.push_back(rule({clause(0, 0), clause(1, 0)}, {clause(0, 0), clause(1, 0)}));
  s.rules.push_back(rule({clause(0, 1)}, {clause(0, 1)}));  // no consequent on q
  const double a = 0.25, b = 0.5;
  fmpc::Evaluation e = fmpc::evaluate(s, {a, b});
  const double w1 = 0.75, w2 = 0.25, z2 = 4 * a + 2 * b + 1;
  CHECK(e.outputs[0] == Approx((w1 * 2 + w2 * z2) / (w1 + w2)).epsilon(1e-15));
  // MATLAB (fis.c) divides by the firing of ALL rules, also those without a consequent on this output.
  CHECK(e.outputs[1] == Approx(w1 * 7 / (w1 + w2)).epsilon(1e-15));
  // Octave drops the rule without consequent.
  CHECK(fmpc::evaluate(s, {a, b}, {Reference::Octave}).outputs[1] == Approx(7.0).epsilon(1e-15));
  s.defuzzifier = Defuzzifier::WeightedSum;
  e = fmpc::evaluate(s, {a, b});
  CHECK(e.outputs[0] == Approx(w1 * 2 + w2 * z2).epsilon(1e-15));
  const fmpc::Explanation x = fmpc::explain(s, {a, b});
  REQUIRE(x.outputs.size() == 2);
  CHECK(x.outputs[0].x == std::vector<double>{2.0, z2});
  CHECK(x.outputs[0].membership == std::vector<double>{w1, w2});
}

TEST_CASE("Octave merges Sugeno singletons at one location with the aggregation method", "[interpreter]") {
  FuzzySystem s;
  s.type = fmpc::SystemType::Sugeno;
  s.aggregation = SNorm::Maximum;
  s.inputs.push_back(variable("a", 0, 1, {{"lo", MfKind::LinearZ, {0, 1}}, {"hi", MfKind::LinearS, {0, 1}}}));
  s.outputs.push_back(variable("z", 0, 10, {{"two", MfKind::Constant, {2}}, {"eight", MfKind::Constant, {8}}}));
  s.rules.push_back(rule({clause(0, 0)}, {clause(0, 0)}));
  s.rules.push_back(rule({clause(0, 1)}, {clause(0, 0)}));
  s.rules.push_back(rule({clause(0, 1)}, {clause(0, 1)}, 0.5));
  const double a = 0.25;  // lo 0.75, hi 0.25
  // MATLAB: (0.75*2 + 0.25*2 + 0.125*8) / (0.75 + 0.25 + 0.125)
  CHECK(fmpc::evaluate(s, {a}).outputs[0] == Approx((1.5 + 0.5 + 1.0) / 1.125).epsilon(1e-15));
  // Octave: the two singletons at 2 merge to max(0.75, 0.25) = 0.75 first.
  CHECK(fmpc::evaluate(s, {a}, {Reference::Octave}).outputs[0] == Approx((1.5 + 1.0) / 0.875).epsilon(1e-15));
  // Octave hedges a Sugeno consequent's height as w^(1/p) and negates it after (eval_rules_sugeno.m).
  s.rules[2].consequent[0].hedge = fmpc::Hedge::Very;
  CHECK(fmpc::evaluate(s, {a}, {Reference::Octave}).outputs[0] ==
        Approx((1.5 + std::sqrt(0.125) * 8) / (0.75 + std::sqrt(0.125))).epsilon(1e-15));
}

TEST_CASE("exact and finely sampled centroids converge; Interpreter reuse equals the free function",
          "[interpreter]") {
  auto options = fmpc::testing::RandomSystemOptions::matlab();
  options.sugeno = false;
  options.mamdani_defuzzifiers = {Defuzzifier::Centroid};
  for (std::uint64_t seed = 1; seed <= 25; ++seed) {
    FuzzySystem sampled = fmpc::testing::random_system(seed, options);
    sampled.samples = 20001;
    FuzzySystem exact = sampled;
    exact.samples = 0;
    fmpc::Interpreter fine(sampled), analytic(exact);
    for (const auto& point : fmpc::testing::random_inputs(sampled, seed + 1000, 5)) {
      const fmpc::Evaluation a = fine.evaluate(point), b = analytic.evaluate(point);
      const fmpc::Evaluation c = fmpc::evaluate(exact, point);
      for (std::size_t o = 0; o < sampled.outputs.size(); ++o) {
        INFO("seed " << seed << " output " << o);
        const double range = sampled.outputs[o].max - sampled.outputs[o].min;
        CHECK(b.outputs[o] == c.outputs[o]);
        // A 20001-point endpoint sum differs from the integral by O(1/N) at jumps and ends: 1e-3 of the range.
        CHECK(std::fabs(a.outputs[o] - b.outputs[o]) <= 1e-3 * range);
      }
    }
  }
}

TEST_CASE("property: centroids lie in the output range, wtaver between the rule outputs", "[interpreter]") {
  auto options = fmpc::testing::RandomSystemOptions::matlab_fis();
  int evaluated = 0;
  for (std::uint64_t seed = 100; seed < 300; ++seed) {
    const FuzzySystem s = fmpc::testing::random_system(seed, options);
    fmpc::Interpreter interpreter(s);
    for (const auto& point : fmpc::testing::random_inputs(s, seed, 10)) {
      const fmpc::Explanation x = interpreter.explain(point);
      for (std::size_t o = 0; o < s.outputs.size(); ++o) {
        INFO("seed " << seed << " output " << o << " value " << x.evaluation.outputs[o]);
        const double value = x.evaluation.outputs[o];
        REQUIRE_FALSE(std::isnan(value));
        ++evaluated;
        if (s.type == fmpc::SystemType::Mamdani) {
          CHECK(value >= s.outputs[o].min - 1e-12);
          CHECK(value <= s.outputs[o].max + 1e-12);
          CHECK(x.outputs[o].x.size() == static_cast<std::size_t>(s.samples));
        } else if (s.defuzzifier == Defuzzifier::WeightedAverage && !x.outputs[o].x.empty()) {
          bool negated_or_dont_care = false;
          for (const auto& r : s.rules) {
            bool has = false;
            for (const auto& c : r.consequent)
              if (static_cast<std::size_t>(c.variable) == o) {
                has = true;
                negated_or_dont_care |= c.negated || c.hedge != fmpc::Hedge::None;
              }
            negated_or_dont_care |= !has;
          }
          if (negated_or_dont_care) continue;  // MATLAB's denominator includes rules without this output
          const auto [lo, hi] = std::minmax_element(x.outputs[o].x.begin(), x.outputs[o].x.end());
          CHECK(value >= *lo - 1e-9 * (1 + std::fabs(*lo)));
          CHECK(value <= *hi + 1e-9 * (1 + std::fabs(*hi)));
        }
      }
    }
  }
  CHECK(evaluated > 1000);
}

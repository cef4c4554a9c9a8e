// Mamdani -> Sugeno conversion (compiler/passes/mamdani_to_sugeno.h): constants against centroids computed here
// independently, the settings MATLAB's convertToSugeno sets, errors, and the liver controller.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "compiler/eval/interpreter.h"
#include "compiler/frontend/rule_file_loader.h"
#include "compiler/passes/mamdani_to_sugeno.h"

namespace fs = std::filesystem;
using namespace fmpc;

namespace {

MembershipFunction mf_of(MfKind kind, std::vector<double> params) { return MembershipFunction{kind, std::move(params)}; }

// One input x in [0, 10] with a single term; one output y in [out_min, out_max] with the given terms; rule i maps
// input term 1 to output term i.
FuzzySystem one_input_system(std::vector<MembershipFunction> output_terms, double out_min, double out_max) {
  FuzzySystem system;
  system.name = "test";
  Variable x;
  x.name = "x";
  x.min = 0;
  x.max = 10;
  x.terms.push_back(Term{"all", mf_of(MfKind::Trapezoid, {-1, 0, 10, 11}), {}, {}});
  system.inputs.push_back(x);
  Variable y;
  y.name = "y";
  y.min = out_min;
  y.max = out_max;
  for (std::size_t t = 0; t < output_terms.size(); ++t) {
    y.terms.push_back(Term{"t" + std::to_string(t), output_terms[t], {}, {}});
    Rule rule;
    rule.antecedent.push_back(Clause{0, 0, false, Hedge::None, {}});
    rule.consequent.push_back(Clause{0, static_cast<int>(t), false, Hedge::None, {}});
    system.rules.push_back(rule);
  }
  system.outputs.push_back(y);
  return system;
}

// MATLAB: x = linspace(lo, hi, 101); sum(x .* mf) / sum(mf), written out here without fmpc's sampling helpers.
double sampled_centroid(const std::function<double(double)>& mf, double lo, double hi, int n) {
  double numerator = 0, denominator = 0;
  for (int k = 0; k < n; ++k) {
    const double x = k == n - 1 ? hi : lo + (hi - lo) * k / (n - 1);
    numerator += x * mf(x);
    denominator += mf(x);
  }
  return numerator / denominator;
}

// Mean of a normal(mean, sd) truncated to [lo, hi]: mean + sd (phi(a) - phi(b)) / (Phi(b) - Phi(a)).
double truncated_gaussian_centroid(double mean, double sd, double lo, double hi) {
  const double a = (lo - mean) / sd, b = (hi - mean) / sd;
  const auto phi = [](double t) { return std::exp(-t * t / 2) / std::sqrt(2 * M_PI); };
  const auto Phi = [](double t) { return 0.5 * std::erfc(-t / std::sqrt(2.0)); };
  return mean + sd * (phi(a) - phi(b)) / (Phi(b) - Phi(a));
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

}  // namespace

TEST_CASE("a symmetric term's constant is its peak", "[mam2sug]") {
  // Triangle [2 5 8] and gaussian mean 5 on [0, 10]: symmetric on the 101 samples, so the centroid is the centre.
  for (int samples : {101, 0}) {
    CAPTURE(samples);
    CHECK(membership_centroid(mf_of(MfKind::Triangle, {2, 5, 8}), 0, 10, samples).value() == Approx(5).epsilon(1e-12));
    CHECK(membership_centroid(mf_of(MfKind::Gaussian, {1.5, 5}), 0, 10, samples).value() ==
          Approx(5).epsilon(1e-10));
  }
}

TEST_CASE("a gaussian clipped by the range has the truncated-normal mean", "[mam2sug]") {
  // gaussmf [sd 1.45, c 1] on [0, 75] loses its left tail: the centroid moves right of the centre.
  const auto mf = mf_of(MfKind::Gaussian, {1.45, 1.0});
  const double exact = truncated_gaussian_centroid(1.0, 1.45, 0, 75);
  CHECK(exact > 1.0);
  CHECK(membership_centroid(mf, 0, 75, 0).value() == Approx(exact).epsilon(1e-9));
  // 101 samples 0.75 apart: MATLAB's number, not the exact one.
  const auto gauss = [](double x) { return std::exp(-(x - 1.0) * (x - 1.0) / (2 * 1.45 * 1.45)); };
  const double sampled = sampled_centroid(gauss, 0, 75, 101);
  CHECK(membership_centroid(mf, 0, 75, 101).value() == Approx(sampled).epsilon(1e-13));
  CHECK(sampled != Approx(exact).epsilon(1e-6));
}

TEST_CASE("an asymmetric trapezoid's exact constant is its area centroid", "[mam2sug]") {
  // trapmf [0 1 4 10]: pieces (triangle 0-1, rectangle 1-4, triangle 4-10). Area 0.5 + 3 + 3 = 6.5;
  // moment 0.5*(2/3) + 3*2.5 + 3*6 = 25.8333...
  const double expected = (0.5 * (2.0 / 3.0) + 3.0 * 2.5 + 3.0 * 6.0) / 6.5;
  CHECK(membership_centroid(mf_of(MfKind::Trapezoid, {0, 1, 4, 10}), 0, 10, 0).value() ==
        Approx(expected).epsilon(1e-12));
}

TEST_CASE("random triangles: the constant equals MATLAB's sampled centroid", "[mam2sug]") {
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> u(-5, 15);
  for (int trial = 0; trial < 200; ++trial) {
    double p[3] = {u(rng), u(rng), u(rng)};
    std::sort(p, p + 3);
    if (p[2] - p[0] < 0.5) continue;
    const auto tri = [&](double x) {
      if (x <= p[0] || x >= p[2]) return x == p[1] ? 1.0 : 0.0;
      return x <= p[1] ? (p[1] == p[0] ? 1.0 : (x - p[0]) / (p[1] - p[0]))
                       : (p[2] == p[1] ? 1.0 : (p[2] - x) / (p[2] - p[1]));
    };
    const double expected_den = [&] {
      double s = 0;
      for (int k = 0; k < 101; ++k) s += tri(k == 100 ? 10.0 : 10.0 * k / 100);
      return s;
    }();
    const std::optional<double> c = membership_centroid(mf_of(MfKind::Triangle, {p[0], p[1], p[2]}), 0, 10, 101);
    if (expected_den == 0) {
      CHECK_FALSE(c.has_value());
      continue;
    }
    REQUIRE(c.has_value());
    CHECK(*c == Approx(sampled_centroid(tri, 0, 10, 101)).epsilon(1e-11));
  }
}

TEST_CASE("conversion sets MATLAB's Sugeno settings and keeps rules", "[mam2sug]") {
  FuzzySystem system = one_input_system(
      {mf_of(MfKind::Triangle, {0, 2, 4}), mf_of(MfKind::Gaussian, {1, 7}), mf_of(MfKind::Trapezoid, {6, 8, 10, 12})},
      0, 10);
  system.rules[1].weight = 0.5;
  system.rules[2].consequent[0].hedge = Hedge::Very;
  DiagnosticList diagnostics;
  const std::vector<ConvertedTerm> converted = convert_mamdani_to_sugeno(system, diagnostics);
  CHECK(diagnostics.items().empty());
  REQUIRE(converted.size() == 3);
  CHECK(system.type == SystemType::Sugeno);
  CHECK(system.defuzzifier == Defuzzifier::WeightedAverage);
  CHECK(system.implication == TNorm::Product);
  CHECK(system.aggregation == SNorm::Sum);
  CHECK(system.and_method == TNorm::Minimum);
  CHECK(system.or_method == SNorm::Maximum);
  CHECK(system.rules[1].weight == 0.5);
  CHECK(system.rules[2].consequent[0].hedge == Hedge::Very);
  for (const ConvertedTerm& c : converted) {
    const Term& term = system.outputs[0].terms[static_cast<std::size_t>(c.term)];
    CHECK(term.mf.kind == MfKind::Constant);
    REQUIRE(term.mf.params.size() == 1);
    CHECK(term.mf.params[0] == c.constant);
  }
  CHECK(converted[0].constant == Approx(2).epsilon(1e-12));
  CHECK(converted[1].constant == Approx(sampled_centroid(
                                     [](double x) { return std::exp(-(x - 7) * (x - 7) / 2); }, 0, 10, 101))
                                     .epsilon(1e-13));
  // The trapezoid is clipped at 10: its part inside is [6 8 10] rising then flat.
  CHECK(converted[2].constant > 8.0);
  CHECK(converted[2].constant < 9.0);
  // One rule firing fully gives exactly its constant (weighted average of one value).
  const Evaluation e = evaluate(system, {5.0});
  CHECK(std::isfinite(e.outputs[0]));
}

TEST_CASE("conversion errors leave the system unchanged", "[mam2sug]") {
  SECTION("a term outside the range has no centroid") {
    FuzzySystem system = one_input_system({mf_of(MfKind::Triangle, {0, 2, 4}), mf_of(MfKind::Triangle, {20, 25, 30})}, 0, 10);
    DiagnosticList diagnostics;
    CHECK(convert_mamdani_to_sugeno(system, diagnostics).empty());
    REQUIRE(diagnostics.error_count() == 1);
    CHECK_THAT(diagnostics.items()[0].message, Catch::Contains("'t1'") && Catch::Contains("no centroid"));
    CHECK(system.type == SystemType::Mamdani);
    CHECK(system.outputs[0].terms[0].mf.kind == MfKind::Triangle);
  }
  SECTION("a Sugeno system") {
    FuzzySystem system = one_input_system({mf_of(MfKind::Triangle, {0, 2, 4})}, 0, 10);
    system.type = SystemType::Sugeno;
    DiagnosticList diagnostics;
    CHECK(convert_mamdani_to_sugeno(system, diagnostics).empty());
    CHECK(diagnostics.error_count() == 1);
  }
  SECTION("another defuzzifier is a warning, and the constants stay centroids") {
    FuzzySystem system = one_input_system({mf_of(MfKind::Trapezoid, {0, 1, 4, 10})}, 0, 10);
    system.defuzzifier = Defuzzifier::LargestOfMaximum;
    DiagnosticList diagnostics;
    const auto converted = convert_mamdani_to_sugeno(system, diagnostics);
    CHECK(diagnostics.error_count() == 0);
    CHECK(diagnostics.warning_count() == 1);
    REQUIRE(converted.size() == 1);
    CHECK(converted[0].constant ==
          Approx(membership_centroid(mf_of(MfKind::Trapezoid, {0, 1, 4, 10}), 0, 10, 101).value()));
  }
}

TEST_CASE("the liver controller converts, evaluates, and matches the checked-in sugeno.fis", "[mam2sug]") {
  const fs::path dir = fs::path(FMPC_SOURCE_DIR) / "rulesets" / "liver_fibrosis";
  DiagnosticList diagnostics;
  RuleFile mamdani = load_rule_file((dir / "mamdani.fis").string(), read_file(dir / "mamdani.fis"), diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(mamdani.systems.size() == 1);
  FuzzySystem converted = mamdani.systems[0];
  const std::vector<ConvertedTerm> terms = convert_mamdani_to_sugeno(converted, diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(terms.size() == 4);
  // Output terms F0-F1, F2, F3 (narrow gaussians well inside [0, 75]) sit at their centres to the sampling
  // accuracy; F4 (sd 10.62 about 22.5) loses part of its left tail at 0 and moves right.
  CHECK(terms[0].constant == Approx(5.3).margin(0.01));
  CHECK(terms[1].constant == Approx(7.65).margin(0.01));
  CHECK(terms[2].constant == Approx(10.15).margin(0.01));
  CHECK(terms[3].constant > 22.5);
  // 101 samples 0.75 kPa apart: within 0.05 kPa of the exact truncated-normal mean.
  CHECK(terms[3].constant == Approx(truncated_gaussian_centroid(22.5, 10.62, 0, 75)).margin(0.05));

  const Evaluation e = evaluate(converted, {8, 7, 10, 9, 7});
  REQUIRE(std::isfinite(e.outputs[0]));
  CHECK(e.outputs[0] >= terms[0].constant);
  CHECK(e.outputs[0] <= terms[3].constant);

  DiagnosticList checked_in_diagnostics;
  RuleFile checked_in =
      load_rule_file((dir / "sugeno.fis").string(), read_file(dir / "sugeno.fis"), checked_in_diagnostics);
  REQUIRE_FALSE(checked_in_diagnostics.has_errors());
  REQUIRE(checked_in.systems.size() == 1);
  const FuzzySystem& file = checked_in.systems[0];
  CHECK(file.type == SystemType::Sugeno);
  REQUIRE(file.outputs.size() == 1);
  REQUIRE(file.outputs[0].terms.size() == 4);
  for (const ConvertedTerm& c : terms) {
    const MembershipFunction& mf = file.outputs[0].terms[static_cast<std::size_t>(c.term)].mf;
    CHECK(mf.kind == MfKind::Constant);
    // The file holds the constants as format_number printed them (shortest round trip).
    CHECK(mf.params.at(0) == c.constant);
  }
  CHECK(file.rules.size() == converted.rules.size());
  const Evaluation from_file = evaluate(file, {8, 7, 10, 9, 7});
  CHECK(from_file.outputs[0] == e.outputs[0]);
}

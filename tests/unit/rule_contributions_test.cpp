// compiler/eval/rule_contributions.h ("why this stiffness"): exact Sugeno shares add up to the output (hand-made
// systems, MATLAB's denominator with rules on other outputs, the shipped Sugeno liver, seeded random systems with
// hedged and negated consequents), and leave-one-rule-out equals evaluating the system with the rule erased (the
// Mamdani liver, random systems), the no-fire policy when nothing else fires, NaN inputs.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "compiler/eval/rule_contributions.h"
#include "tests/support/random_system.h"
#include "tests/support/rule_text.h"

namespace fmpc {
namespace {

using testing::system_from_text;

FuzzySystem shipped(const std::string& relative) {
  std::ifstream in(std::string(FMPC_SOURCE_DIR) + "/" + relative);
  std::stringstream text;
  text << in.rdbuf();
  return system_from_text(text.str());
}

FuzzySystem without_rule(FuzzySystem system, std::size_t rule) {
  system.rules.erase(system.rules.begin() + static_cast<std::ptrdiff_t>(rule));
  return system;
}

double sum(const std::vector<double>& values) {
  double total = 0.0;
  for (double v : values) total += v;
  return total;
}

const char* kTwoOutputs = R"(system s
  type sugeno
  defuzzify wtaver
input x in [0, 10] kPa
  low is triangle(start -10, peak 0, end 10)
  high is triangle(start 0, peak 10, end 20)
output y in [0, 100] kPa
  a is constant(value 20)
  b is constant(value 80)
output z in [0, 1] dimensionless
  c is constant(value 1)
rule r1: if x is low then y is a
rule r2: if x is high then y is b
rule r3: if x is high then z is c
)";

TEST_CASE("Sugeno shares are exact, with fis.c's denominator", "[contributions]") {
  const FuzzySystem system = system_from_text(kTwoOutputs);
  REQUIRE(contribution_method(system) == ContributionMethod::ExactShare);
  // x = 2.5: low 0.75, high 0.25. y = (0.75 * 20 + 0.25 * 80) / (0.75 + 0.25 + 0.25): r3 fires but concludes on z
  // only, and MATLAB still counts it in y's denominator.
  const RuleContributions result = rule_contributions(system, {2.5});
  const OutputContributions& y = result.outputs[0];
  CHECK(y.method == ContributionMethod::ExactShare);
  CHECK(y.output == Approx((0.75 * 20 + 0.25 * 80) / 1.25).epsilon(1e-15));
  CHECK(y.contribution[0] == Approx(0.75 * 20 / 1.25).epsilon(1e-15));
  CHECK(y.contribution[1] == Approx(0.25 * 80 / 1.25).epsilon(1e-15));
  CHECK(y.contribution[2] == 0.0);
  CHECK(sum(y.contribution) == Approx(y.output).epsilon(1e-15));
  CHECK(y.output_without.empty());
  const OutputContributions& z = result.outputs[1];
  CHECK(sum(z.contribution) == Approx(z.output).epsilon(1e-15));
  CHECK(z.contribution[0] == 0.0);
}

TEST_CASE("Sugeno with wtsum: contributions are height times value", "[contributions]") {
  std::string text = kTwoOutputs;
  text.replace(text.find("wtaver"), 6, "wtsum");
  const RuleContributions result = rule_contributions(system_from_text(text), {2.5});
  CHECK(result.outputs[0].contribution[0] == 0.75 * 20);
  CHECK(result.outputs[0].contribution[1] == 0.25 * 80);
  CHECK(sum(result.outputs[0].contribution) == result.outputs[0].output);
}

TEST_CASE("no rule fired: the policy's output and no contributions", "[contributions]") {
  std::string text = kTwoOutputs;
  text.replace(text.find("in [0, 10]"), 10, "in [0, 30]");
  const RuleContributions result = rule_contributions(system_from_text(text), {25});
  CHECK(result.outputs[0].no_rule_fired);
  CHECK(result.outputs[0].output == 50);  // midrange of [0, 100]
  for (double c : result.outputs[0].contribution) CHECK(c == 0.0);
}

TEST_CASE("NaN input: NaN contributions", "[contributions]") {
  const RuleContributions result = rule_contributions(system_from_text(kTwoOutputs), {std::nan("")});
  CHECK(std::isnan(result.outputs[0].output));
  for (double c : result.outputs[0].contribution) CHECK(std::isnan(c));
}

TEST_CASE("shipped Sugeno liver: shares add up to the output", "[contributions]") {
  const FuzzySystem system = shipped("rulesets/liver_fibrosis/sugeno.fis");
  for (const std::vector<double>& patient :
       {std::vector<double>{5, 5, 5, 5, 5}, {7.6, 7.2, 9.5, 11, 7.7}, {13.8, 12, 22.4, 8.3, 21.6}}) {
    const RuleContributions result = rule_contributions(system, patient);
    CHECK(result.explanation.evaluation.outputs == evaluate(system, patient).outputs);
    CHECK(sum(result.outputs[0].contribution) == Approx(result.outputs[0].output).epsilon(1e-12));
  }
}

TEST_CASE("random Sugeno systems: shares add up to every output", "[contributions]") {
  testing::RandomSystemOptions options;
  options.mamdani = false;
  options.consequent_hedges = true;
  options.consequent_negation = true;
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    const FuzzySystem system = testing::random_system(seed, options);
    for (const std::vector<double>& x : testing::random_inputs(system, seed, 5)) {
      const RuleContributions result = rule_contributions(system, x);
      for (const OutputContributions& out : result.outputs) {
        if (out.no_rule_fired) continue;
        const double scale = std::max(1.0, std::fabs(out.output));
        double magnitude = 0.0;
        for (double c : out.contribution) magnitude += std::fabs(c);
        INFO("seed " << seed);
        CHECK(std::fabs(sum(out.contribution) - out.output) <= 1e-12 * std::max(scale, magnitude));
      }
    }
  }
}

TEST_CASE("leave one rule out equals evaluating without the rule", "[contributions]") {
  SECTION("the thesis's Mamdani liver, every 13th rule") {
    const FuzzySystem system = shipped("rulesets/liver_fibrosis/mamdani.fis");
    const std::vector<double> patient = {9.7, 9.5, 12, 11, 11.2};
    const RuleContributions result = rule_contributions(system, patient);
    REQUIRE(contribution_method(system) == ContributionMethod::LeaveOneOut);
    const OutputContributions& out = result.outputs[0];
    CHECK(out.output == evaluate(system, patient).outputs[0]);
    for (std::size_t r = 0; r < system.rules.size(); r += 13) {
      const double without = evaluate(without_rule(system, r), patient).outputs[0];
      CHECK(out.output_without[r] == without);
      CHECK(out.contribution[r] == out.output - without);
    }
  }
  SECTION("random Mamdani and type-2 systems") {
    for (bool type2 : {false, true}) {
      testing::RandomSystemOptions options;
      options.sugeno = type2;  // type-1 Sugeno has exact shares (above)
      options.interval_type2 = type2;
      for (std::uint64_t seed = 100; seed < 130; ++seed) {
        const FuzzySystem system = testing::random_system(seed, options);
        const std::vector<double> x = testing::random_inputs(system, seed, 1).front();
        const RuleContributions result = rule_contributions(system, x);
        for (std::size_t r = 0; r < system.rules.size(); ++r) {
          const Evaluation without = evaluate(without_rule(system, r), x);
          for (std::size_t o = 0; o < system.outputs.size(); ++o) {
            INFO("seed " << seed << " rule " << r << " output " << o);
            const double expected = without.outputs[o];
            const double got = result.outputs[o].output_without[r];
            CHECK((got == expected || (std::isnan(got) && std::isnan(expected))));
          }
        }
      }
    }
  }
}

TEST_CASE("leave one rule out: the only rule firing leaves the policy's value", "[contributions]") {
  const FuzzySystem system = system_from_text(R"(system m
input x in [0, 10] kPa
  low is triangle(start 0, peak 0, end 5)
  high is triangle(start 5, peak 10, end 10)
output y in [0, 10] kPa
  small is triangle(start 0, peak 2, end 4)
  big is triangle(start 6, peak 8, end 10)
rule r1: if x is low then y is small
rule r2: if x is high then y is big
)");
  const RuleContributions result = rule_contributions(system, {1});
  const OutputContributions& out = result.outputs[0];
  CHECK(out.method == ContributionMethod::LeaveOneOut);
  CHECK(out.policy_without[0]);
  CHECK(out.output_without[0] == 5);  // midrange
  CHECK(out.contribution[0] == out.output - 5);
  CHECK_FALSE(out.policy_without[1]);  // r2 does not fire: removing it changes nothing
  CHECK(out.contribution[1] == 0.0);
  CHECK(out.output_without[1] == out.output);
}

TEST_CASE("Octave semantics use leave one rule out for Sugeno", "[contributions]") {
  EvaluationOptions octave;
  octave.reference = Reference::Octave;
  const FuzzySystem system = system_from_text(kTwoOutputs);
  CHECK(contribution_method(system, octave) == ContributionMethod::LeaveOneOut);
  const RuleContributions result = rule_contributions(system, {2.5}, octave);
  CHECK(result.outputs[0].output_without[0] == evaluate(without_rule(system, 0), {2.5}, octave).outputs[0]);
}

}  // namespace
}  // namespace fmpc

// write_fmpc and format_rule_body: hand-made and seeded random systems survive write -> read with the same IR, in
// the canonical layout; every setting and MATLAB-ordered parameters are printed by name.
#include <catch2/catch.hpp>

#include "compiler/frontend/fmpc_language.h"
#include "tests/support/fmpc_text_checks.h"
#include "tests/support/random_system.h"

namespace fmpc {
namespace {

using testing::difference;
using testing::format_ok;
using testing::kLiver;
using testing::read_ok;
using testing::read_one;

FuzzySystem hand_made_mamdani() {
  FuzzySystem s;
  s.name = "hand made";
  s.description = "every family, every hedge";
  s.and_method = TNorm::EinsteinProduct;
  s.or_method = SNorm::EinsteinSum;
  s.implication = TNorm::Product;
  s.aggregation = SNorm::ProbabilisticSum;
  s.defuzzifier = Defuzzifier::Bisector;
  s.samples = 0;
  s.no_fire = NoFirePolicy::Value;
  s.no_fire_value = 0.1 + 0.2;
  Variable x;
  x.name = "input";  // a reserved word
  x.unit = "kPa";
  x.min = -1.5;
  x.max = 1e10;
  const std::vector<std::pair<MfKind, std::vector<double>>> families = {
      {MfKind::Triangle, {1, 2, 3}},        {MfKind::Trapezoid, {1, 2, 3, 4}},
      {MfKind::Gaussian, {0.91, 7.64}},     {MfKind::Gaussian2, {1, 2, 3, 4}},
      {MfKind::GeneralizedBell, {1, 2, 3}}, {MfKind::Sigmoid, {-2, 3}},
      {MfKind::DifferenceSigmoid, {1, 2, 3, 4}}, {MfKind::ProductSigmoid, {1, 2, -3, 4}},
      {MfKind::ZShape, {1, 2}},             {MfKind::SShape, {1, 2}},
      {MfKind::PiShape, {1, 2, 3, 4}},      {MfKind::LinearS, {1e-300, 2}},
      {MfKind::LinearZ, {1, 2.5e300}},
  };
  for (std::size_t i = 0; i < families.size(); ++i)
    x.terms.push_back(Term{"t" + std::to_string(i), MembershipFunction{families[i].first, families[i].second}, {}, {}});
  x.terms[0].name = "F0-F1";
  x.terms[1].name = "value";
  x.terms[2].name = "is";
  s.inputs.push_back(x);
  Variable y = x;
  y.name = "y";
  y.unit = "%";
  y.description = "second";
  s.inputs.push_back(y);
  Variable out;
  out.name = "out put";
  out.unit = "";
  out.terms.push_back(Term{"low", MembershipFunction{MfKind::Triangle, {0, 0.25, 0.5}}, {}, {}});
  out.terms.push_back(Term{"high", MembershipFunction{MfKind::Triangle, {0.5, 0.75, 1}}, {}, {}});
  s.outputs.push_back(out);
  Variable out2 = out;
  out2.name = "b";
  s.outputs.push_back(out2);
  const std::vector<Hedge> hedges = {Hedge::None, Hedge::Somewhat, Hedge::Very, Hedge::Extremely, Hedge::VeryVery};
  for (std::size_t i = 0; i < hedges.size(); ++i) {
    Rule rule;
    rule.label = i % 2 ? "r" + std::to_string(i) : "";
    rule.connective = i % 2 ? Connective::Or : Connective::And;
    rule.antecedent.push_back(Clause{1, static_cast<int>(i), i % 3 == 0, hedges[i], {}});
    rule.antecedent.push_back(Clause{0, static_cast<int>(12 - i), i % 2 == 0, hedges[4 - i], {}});
    rule.consequent.push_back(Clause{0, static_cast<int>(i % 2), i == 2, hedges[i], {}});
    if (i != 3) rule.consequent.push_back(Clause{1, 1, false, Hedge::None, {}});
    rule.weight = i == 4 ? 0.125 : 1.0;
    s.rules.push_back(rule);
  }
  Rule single;
  single.label = "then";
  single.antecedent.push_back(Clause{0, 0, false, Hedge::None, {}});
  single.consequent.push_back(Clause{1, 0, false, Hedge::None, {}});
  s.rules.push_back(single);
  return s;
}

FuzzySystem hand_made_sugeno() {
  FuzzySystem s;
  s.name = "sug";
  s.type = SystemType::Sugeno;
  s.and_method = TNorm::Product;
  s.or_method = SNorm::Sum;
  s.implication = TNorm::Minimum;
  s.aggregation = SNorm::Maximum;
  s.defuzzifier = Defuzzifier::WeightedSum;
  s.samples = 7;  // not used by wtsum, but kept
  s.no_fire = NoFirePolicy::Error;
  for (const char* name : {"offset", "x"}) {
    Variable v;
    v.name = name;
    v.terms.push_back(Term{"a", MembershipFunction{MfKind::Gaussian, {1, 0}}, {}, {}});
    s.inputs.push_back(v);
  }
  Variable z;
  z.name = "z";
  z.unit = "N";
  z.terms.push_back(Term{"c", MembershipFunction{MfKind::Constant, {-0.0}}, {}, {}});
  z.terms.push_back(Term{"l", MembershipFunction{MfKind::Linear, {1.5, -2, 1.0 / 3.0}}, {}, {}});
  s.outputs.push_back(z);
  Rule rule;
  rule.antecedent.push_back(Clause{1, 0, true, Hedge::None, {}});
  rule.antecedent.push_back(Clause{0, 0, false, Hedge::None, {}});
  rule.consequent.push_back(Clause{0, 1, false, Hedge::None, {}});
  s.rules.push_back(rule);
  return s;
}

void check_round_trip(const RuleFile& original) {
  const std::string text = write_fmpc(original);
  INFO(text);
  const RuleFile read_back = read_ok(text);
  REQUIRE(read_back.systems.size() == original.systems.size());
  for (std::size_t i = 0; i < original.systems.size(); ++i)
    CHECK(difference(original.systems[i], read_back.systems[i]).empty());
  // What write_fmpc produces is already in the canonical layout.
  CHECK(format_ok(text) == text);
}

TEST_CASE("fmpc language: write_fmpc -> read_fmpc gives the same IR (hand-made systems)", "[fmpc-language]") {
  RuleFile file;
  file.path = "t.fis";
  file.systems.push_back(hand_made_mamdani());
  file.systems.push_back(hand_made_sugeno());
  check_round_trip(file);

  // The liver example survives read -> write -> read as well.
  check_round_trip(read_ok(kLiver));
}

TEST_CASE("fmpc language: write_fmpc prints every setting and MATLAB-ordered parameters by name",
          "[fmpc-language]") {
  RuleFile file;
  file.systems.push_back(hand_made_sugeno());
  CHECK(write_fmpc(file) == R"(system sug
  type sugeno
  and prod
  or sum
  implication min
  aggregation max
  defuzzify wtsum samples 7
  when no rule fires: error

input offset in [0, 1]
  a is gauss(mean 0, sd 1)

input x in [0, 1]
  a is gauss(mean 0, sd 1)

output z in [0, 1] N
  c is constant(value 0)
  l is linear("offset" 1.5, x -2, offset 0.3333333333333333)

rule: if x is not a and offset is a then z is l
)");
}

TEST_CASE("fmpc language: format_rule_body prints one rule without its label", "[fmpc-language]") {
  const FuzzySystem s = read_one(kLiver);
  CHECK(format_rule_body(s, 0) == "if HCV is F2 and HBV is \"F0-F1\" then stiffness is \"F0-F1\"");
  CHECK(format_rule_body(s, 1) == "if HCV is not F4 or HBV is very F2 then stiffness is F2 weight 0.5");
  CHECK(format_rule_body(s, 3) ==
        "if HBV is extremely F2 and HCV is not very very F4 then stiffness is not somewhat F2");
  CHECK(format_rule_body(s, 4).empty());
}

TEST_CASE("fmpc language: write_fmpc -> read_fmpc gives the same IR (seeded random systems)", "[fmpc-language]") {
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    INFO("seed " << seed);
    RuleFile file;
    file.path = "t.fis";
    file.systems.push_back(testing::random_system(seed));
    if (seed % 4 == 0) {
      file.systems.push_back(testing::random_system(seed + 1000));
      file.systems.back().name += "_second";
    }
    check_round_trip(file);
  }
}

}  // namespace
}  // namespace fmpc

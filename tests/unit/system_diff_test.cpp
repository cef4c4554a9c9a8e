// compiler/eval/system_diff.h, control_surface.h and compiler/ir/units.h: structural differences between two
// versions (settings, variables, terms, rules matched by label and by conditions), stages (dominant_term), the
// comparison of outputs over points, control surfaces against the interpreter, and unit conversion.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "compiler/eval/control_surface.h"
#include "compiler/eval/system_diff.h"
#include "compiler/ir/units.h"
#include "tests/support/rule_text.h"

namespace fmpc {
namespace {

using testing::system_from_text;

const char* kBase = R"(system s
input x in [0, 10] kPa
  low is triangle(start 0, peak 0, end 5)
  high is triangle(start 5, peak 10, end 10)
input w in [0, 1] dimensionless
  off is linear_z(start 0, end 1)
  on is linear_s(start 0, end 1)
output y in [0, 10] kPa
  small is triangle(start 0, peak 2, end 4)
  big is triangle(start 6, peak 8, end 10)
rule r1: if x is low then y is small
rule r2: if x is high then y is big
rule: if x is low and w is on then y is big
rule: if w is off then y is small weight 0.5
)";

std::string edited(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

TEST_CASE("system_differences: nothing between equal systems", "[diff]") {
  CHECK(system_differences(system_from_text(kBase), system_from_text(kBase)).empty());
}

TEST_CASE("system_differences: settings, variables and terms", "[diff]") {
  std::string text = edited(kBase, "system s\n", "system s\n  defuzzify bisector\n");
  text = edited(text, "in [0, 10] kPa\n  low", "in [0, 12] kPa\n  low");
  text = edited(text, "high is triangle(start 5, peak 10, end 10)", "high is triangle(start 5, peak 9, end 10)");
  text = edited(text, "  big is triangle(start 6, peak 8, end 10)\n",
                "  big is gauss(mean 8, sd 1)\n  huge is triangle(start 8, peak 10, end 10)\n");
  const SystemDifferences d = system_differences(system_from_text(kBase), system_from_text(text));
  REQUIRE(d.settings.size() == 1);
  CHECK(d.settings[0] == "the defuzzifier changes from centroid to bisector");
  REQUIRE(d.variables.size() == 1);
  CHECK(d.variables[0].kind == ChangeKind::Changed);
  CHECK(d.variables[0].what == std::vector<std::string>{"range [0, 10] -> [0, 12]"});
  REQUIRE(d.terms.size() == 3);
  CHECK(d.terms[0].variable == "x");
  CHECK(d.terms[0].in_a == 1);
  CHECK(d.terms[0].parameters_changed);
  CHECK_FALSE(d.terms[0].family_changed);
  CHECK(d.terms[1].variable == "y");
  CHECK(d.terms[1].family_changed);
  CHECK(d.terms[2].kind == ChangeKind::Added);
  CHECK(d.terms[2].in_b == 2);
  CHECK(d.rules.empty());
}

TEST_CASE("system_differences: rules by label and by conditions", "[diff]") {
  std::string text = edited(kBase, "rule r2: if x is high then y is big", "rule r2: if x is high then y is small");
  // The unlabelled rule with its clauses in another order is the same rule; its weight changed.
  text = edited(text, "rule: if x is low and w is on then y is big\n", "rule: if w is on and x is low then y is big\n");
  text = edited(text, "weight 0.5", "weight 0.25");
  text += "rule r9: if x is high and w is on then y is big\n";
  text = edited(text, "rule r1: if x is low then y is small\n", "");
  const FuzzySystem a = system_from_text(kBase), b = system_from_text(text);
  const SystemDifferences d = system_differences(a, b);
  CHECK(d.settings.empty());
  CHECK(d.terms.empty());
  REQUIRE(d.rules.size() == 4);
  CHECK(d.rules[0].kind == ChangeKind::Removed);
  CHECK(d.rules[0].in_a == 0);
  CHECK(d.rules[1].kind == ChangeKind::Changed);  // r2's conclusion
  CHECK(d.rules[1].in_a == 1);
  CHECK(d.rules[1].in_b == 0);
  CHECK(d.rules[1].conclusions_changed);
  CHECK_FALSE(d.rules[1].conditions_changed);
  CHECK(d.rules[2].kind == ChangeKind::Changed);  // the weight of the last unlabelled rule
  CHECK(d.rules[2].in_a == 3);
  CHECK(d.rules[2].weight_changed);
  CHECK(d.rules[3].kind == ChangeKind::Added);
  CHECK(b.rules[static_cast<std::size_t>(d.rules[3].in_b)].label == "r9");
}

TEST_CASE("dominant_term: the best-describing output term", "[diff]") {
  const FuzzySystem s = system_from_text(kBase);
  CHECK(dominant_term(s, 0, 2) == 0);
  CHECK(dominant_term(s, 0, 8) == 1);
  CHECK(dominant_term(s, 0, 5) == -1);  // between the terms: no grade above 0
  CHECK(dominant_term(s, 0, std::nan("")) == -1);
  const FuzzySystem tie = system_from_text(edited(edited(kBase, "small is triangle(start 0, peak 2, end 4)",
                                                    "small is triangle(start 0, peak 2, end 7)"),
                                             "big is triangle(start 6, peak 8, end 10)",
                                             "big is triangle(start 3, peak 8, end 10)"));
  CHECK(dominant_term(tie, 0, 5) == 0);  // both 0.4: the first
  const FuzzySystem sugeno = system_from_text(R"(system g
  type sugeno
input x in [0, 1] dimensionless
  a is linear_s(start 0, end 1)
output y in [0, 10] kPa
  low is constant(value 2)
  mid is linear(x 1, offset 5)
  high is constant(value 8)
rule: if x is a then y is low
)");
  CHECK(dominant_term(sugeno, 0, 4.9) == 0);
  CHECK(dominant_term(sugeno, 0, 5) == 0);  // equally near 2 and 8: the first
  CHECK(dominant_term(sugeno, 0, 5.1) == 2);
}

TEST_CASE("compare_over_points: changes and stage changes", "[diff]") {
  const FuzzySystem a = system_from_text(kBase);
  const FuzzySystem same = system_from_text(kBase);
  const std::vector<std::vector<double>> points = {{1, 0.2}, {4, 0.9}, {9, 0.5}};
  const auto unchanged = compare_over_points(a, same, points, points);
  REQUIRE(unchanged.size() == 1);
  CHECK(unchanged[0].name == "y");
  CHECK(unchanged[0].difference == std::vector<double>{0, 0, 0});
  CHECK(unchanged[0].stage_changes.empty());
  CHECK(unchanged[0].agreement.count == 3);
  CHECK(unchanged[0].agreement.mean_absolute_error == 0);
  // r2 now concludes small: the patient at x = 9 moves from big to small.
  const FuzzySystem b = system_from_text(edited(kBase, "then y is big\nrule:", "then y is small\nrule:"));
  const auto changed = compare_over_points(a, b, points, points);
  CHECK(changed[0].stage_changes == std::vector<std::size_t>{2});
  CHECK(changed[0].stage_a[2] == 1);
  CHECK(changed[0].stage_b[2] == 0);
  CHECK(changed[0].difference[2] < -4);
  CHECK(changed[0].difference[0] == 0);
}

TEST_CASE("control_surface equals the interpreter at every grid point", "[diff]") {
  const FuzzySystem s = system_from_text(kBase);
  const ControlSurface surface = control_surface(s, 1, 0, 0, {5, 0.5}, 5);
  REQUIRE(surface.x == std::vector<double>{0, 0.25, 0.5, 0.75, 1});
  REQUIRE(surface.y == std::vector<double>{0, 2.5, 5, 7.5, 10});
  for (std::size_t r = 0; r < 5; ++r)
    for (std::size_t c = 0; c < 5; ++c) {
      const Evaluation e = evaluate(s, {surface.y[r], surface.x[c]});
      CHECK(surface.z[r * 5 + c] == e.outputs[0]);
      double strongest = 0;
      for (double w : e.firing_strengths) strongest = std::max(strongest, w);
      CHECK(surface.strongest_firing[r * 5 + c] == strongest);
    }
  CHECK(surface.nan_points == 0);
}

TEST_CASE("units convert by powers of ten within a dimension", "[diff]") {
  CHECK(convert_unit(5300, "Pa", "kPa") == 5.3);
  CHECK(convert_unit(5.3, "kPa", "Pa") == 5300);
  CHECK(convert_unit(50, "%", "dimensionless") == 0.5);
  CHECK(convert_unit(1, "\xC2\xB5m", "mm") == 0.001);
  CHECK(convert_unit(7, "mL/min", "mL/min") == 7);  // equal spellings need no knowledge of the unit
  CHECK_FALSE(convert_unit(1, "kPa", "mm"));
  CHECK_FALSE(convert_unit(1, "furlong", "m"));
}

}  // namespace
}  // namespace fmpc

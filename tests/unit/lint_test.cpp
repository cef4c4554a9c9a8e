// lint_system and the coverage analysis behind coverage-hole: every warning code with its exact message and
// position, that a clean system gives nothing, and seeded property checks against direct evaluation.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "diagnostics/number_format.h"
#include "compiler/frontend/rule_file_loader.h"
#include "compiler/sema/check.h"
#include "compiler/sema/coverage.h"
#include "compiler/sema/lint.h"
#include "compiler/sema/term_shape.h"
#include "kernels/fuzzy_math.h"
#include "tests/support/ir_builders.h"
#include "tests/support/random_system.h"

namespace fmpc {
namespace {

using testing::at;
using testing::clause;
using testing::rule;
using testing::term;
using testing::variable;

FuzzySystem clean_mamdani() { return testing::two_input_mamdani(); }

DiagnosticList linted(const FuzzySystem& system, const LintOptions& options = {}) {
  DiagnosticList diagnostics;
  lint_system(system, options, diagnostics);
  return diagnostics;
}

std::vector<Diagnostic> with_code(const DiagnosticList& diagnostics, const std::string& code) {
  std::vector<Diagnostic> found;
  for (const Diagnostic& d : diagnostics.items()) {
    CHECK(d.severity == Severity::Warning);
    if (d.code == code) found.push_back(d);
  }
  return found;
}

// The one warning of `code` that `system` gets.
Diagnostic only_warning(const FuzzySystem& system, const std::string& code, const LintOptions& options = {}) {
  const DiagnosticList diagnostics = linted(system, options);
  INFO(render_all(diagnostics, SourceFiles{}));
  const std::vector<Diagnostic> found = with_code(diagnostics, code);
  REQUIRE(found.size() == 1);
  return found[0];
}

void require_position(const Diagnostic& diagnostic, int line, int column) {
  CHECK(diagnostic.range.file == "t.fis");
  CHECK(diagnostic.range.line == line);
  CHECK(diagnostic.range.column == column);
}

TEST_CASE("a clean system gives no warnings", "[lint]") {
  const FuzzySystem s = clean_mamdani();
  DiagnosticList errors;
  check_system(s, errors);
  REQUIRE(errors.empty());
  const DiagnosticList diagnostics = linted(s);
  INFO(render_all(diagnostics, SourceFiles{}));
  CHECK(diagnostics.empty());
}

// The warning's advice must be something the parser takes: the suggested unit, written as the advice says, gives a
// file with no error and no unit warning.
TEST_CASE("unit: the advice 'dimensionless' is valid syntax", "[lint]") {
  const std::string text =
      "system s\n  type mamdani\n"
      "input x in [0, 1] dimensionless\n  low is triangle(start 0, peak 0, end 1)\n"
      "output z in [0, 1] dimensionless\n  small is triangle(start 0, peak 0, end 1)\n"
      "rule r1: if x is low then z is small\n";
  DiagnosticList diagnostics;
  const RuleFile file = load_rule_file("advice.fmpc", text, diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(file.systems.size() == 1);
  CHECK(file.systems[0].inputs[0].unit == "dimensionless");
  CHECK(with_code(linted(file.systems[0]), "unit").empty());
}

TEST_CASE("unit (a variable without one)", "[lint]") {
  FuzzySystem s = clean_mamdani();
  s.inputs[1].unit.clear();
  const Diagnostic d = only_warning(s, "unit");
  require_position(d, 5, 7);
  CHECK(d.message == "input 'y' has no unit; write one after its range (e.g. 'in [0, 75] kPa'), or "
                     "'dimensionless' for a pure number");
  s.outputs[0].unit.clear();
  CHECK(with_code(linted(s), "unit").size() == 2);
  LintOptions matlab;
  matlab.require_units = false;
  CHECK(linted(s, matlab).empty());
}

TEST_CASE("unused-term", "[lint]") {
  FuzzySystem s = clean_mamdani();
  s.inputs[1].terms.push_back(term("top", MfKind::Gaussian, {3, 10}, 20));
  Diagnostic d = only_warning(s, "unused-term");
  require_position(d, 20, 3);
  CHECK(d.range.end_column == 6);
  CHECK(d.message == "term 'top' of input 'y' is not used by any rule; use it in a rule or remove it");

  s = clean_mamdani();
  s.rules[3].consequent[0].term = 1;
  d = only_warning(s, "unused-term");
  require_position(d, 11, 3);
  CHECK(d.message == "term 'big' of output 'z' is not used by any rule; use it in a rule or remove it");
}

TEST_CASE("rule-never-fires", "[lint]") {
  SECTION("a clause term that is 0 on the whole range") {
    FuzzySystem s = clean_mamdani();
    s.inputs[0].terms.push_back(term("far", MfKind::Triangle, {20, 25, 30}, 20));
    s.rules.push_back(rule("r5", {clause(0, 2, 21, 9), clause(1, 0, 21, 25)}, {clause(0, 0, 21, 40)}, 21));
    const Diagnostic d = only_warning(s, "rule-never-fires");
    require_position(d, 21, 1);
    CHECK(d.message == "r5 never fires: the condition 'x' is 'far' stays below 1e-12 everywhere in the range [0, 10] "
                       "of 'x'; fix the terms or remove the rule");
  }
  SECTION("weight 0") {
    FuzzySystem s = clean_mamdani();
    s.rules[1].weight = 0;
    s.rules[1].label.clear();
    const Diagnostic d = only_warning(s, "rule-never-fires");
    require_position(d, 13, 1);
    CHECK(d.message == "rule 2 never fires: its weight is 0; raise the weight or remove the rule");
  }
  SECTION("a negated term that is 1 everywhere, with a hedge") {
    FuzzySystem s = clean_mamdani();
    s.inputs[0].terms.push_back(term("all", MfKind::Trapezoid, {-100, -100, 100, 100}, 20));
    Clause c = clause(0, 2, 21, 9);
    c.negated = true;
    c.hedge = Hedge::Very;
    s.rules.push_back(rule("r5", {c}, {clause(0, 0, 21, 40)}, 21));
    CHECK(only_warning(s, "rule-never-fires").message ==
          "r5 never fires: the condition 'x' is not very 'all' stays below 1e-12 everywhere in the range [0, 10] of "
          "'x'; fix the terms or remove the rule");
  }
  SECTION("OR of conditions that are all 0") {
    FuzzySystem s = clean_mamdani();
    s.inputs[0].terms.push_back(term("far", MfKind::Gaussian, {1, 100}, 20));
    s.inputs[1].terms.push_back(term("far", MfKind::Gaussian, {1, -100}, 21));
    Rule r = rule("r5", {clause(0, 2, 22, 9), clause(1, 2, 22, 25)}, {clause(0, 0, 22, 40)}, 22);
    r.connective = Connective::Or;
    s.rules.push_back(r);
    CHECK(only_warning(s, "rule-never-fires").message ==
          "r5 never fires: none of its conditions reaches 1e-12 anywhere in the input ranges; fix the terms or "
          "remove the rule");
    s.rules.back().antecedent[1].negated = true;  // "or y is not far" holds everywhere
    CHECK(with_code(linted(s), "rule-never-fires").empty());
  }
  SECTION("a product of tiny grades") {
    FuzzySystem s = clean_mamdani();
    // Each grade reaches exp(-5.678^2 / 2) ~ 1e-7 at the range's lower end: min keeps 1e-7, prod gives 1e-14.
    s.inputs[0].terms.push_back(term("edge", MfKind::Gaussian, {1, -5.678}, 20));
    s.inputs[1].terms.push_back(term("edge", MfKind::Gaussian, {1, -5.678}, 21));
    s.rules.push_back(rule("r5", {clause(0, 2, 22, 9), clause(1, 2, 22, 25)}, {clause(0, 0, 22, 40)}, 22));
    CHECK(with_code(linted(s), "rule-never-fires").empty());
    s.and_method = TNorm::Product;
    CHECK(only_warning(s, "rule-never-fires").message ==
          "r5 never fires: its firing strength stays below 1e-12 everywhere in the input ranges; fix the terms or "
          "remove the rule");
  }
  SECTION("a narrow peak inside the range is found even between samples") {
    FuzzySystem s = clean_mamdani();
    s.inputs[0].terms.push_back(term("spot", MfKind::Triangle, {3.00001, 3.000015, 3.00002}, 20));
    s.rules.push_back(rule("r5", {clause(0, 2, 21, 9)}, {clause(0, 0, 21, 40)}, 21));
    CHECK(with_code(linted(s), "rule-never-fires").empty());
  }
}

TEST_CASE("duplicate-rule and conflicting-rules", "[lint]") {
  FuzzySystem s = clean_mamdani();
  s.rules.push_back(rule("r5", {clause(1, 0, 16, 9), clause(0, 0, 16, 25)}, {clause(0, 0, 16, 40)}, 16));
  Diagnostic d = only_warning(s, "duplicate-rule");
  require_position(d, 16, 1);
  CHECK(d.message == "r5 repeats r1 (same conditions, same conclusion); remove one of them");
  CHECK(d.notes == std::vector<std::string>{"r1 is here: 12:1"});
  CHECK(with_code(linted(s), "conflicting-rules").empty());

  s.rules.back().label.clear();
  s.rules.back().weight = 0.5;  // the weight does not make it a different rule
  CHECK(only_warning(s, "duplicate-rule").message ==
        "rule 5 repeats r1 (same conditions, same conclusion); remove one of them");

  s.rules.back().consequent[0].term = 2;
  d = only_warning(s, "conflicting-rules");
  require_position(d, 16, 1);
  CHECK(d.message == "rule 5 has the same conditions as r1 but concludes 'z' is 'big' where r1 concludes 'z' is "
                     "'small'; merge them into one rule or make their conditions differ");
  CHECK(d.notes == std::vector<std::string>{"r1 is here: 12:1"});
  CHECK(with_code(linted(s), "duplicate-rule").empty());

  s.rules.back().consequent[0].term = 0;
  s.rules.back().consequent[0].negated = true;
  CHECK(only_warning(s, "conflicting-rules").message ==
        "rule 5 has the same conditions as r1 but concludes 'z' is not 'small' where r1 concludes 'z' is 'small'; "
        "merge them into one rule or make their conditions differ");

  // OR instead of AND, a negated or hedged condition: a different antecedent.
  s.rules.back().consequent[0].negated = false;
  s.rules.back().connective = Connective::Or;
  CHECK(with_code(linted(s), "duplicate-rule").empty());
  s.rules.back().connective = Connective::And;
  s.rules.back().antecedent[0].hedge = Hedge::Somewhat;
  CHECK(with_code(linted(s), "duplicate-rule").empty());

  // With a single clause AND and OR are the same rule.
  s = clean_mamdani();
  s.rules.push_back(rule("r5", {clause(0, 0, 16, 9)}, {clause(0, 0, 16, 40)}, 16));
  Rule same = rule("r6", {clause(0, 0, 17, 9)}, {clause(0, 0, 17, 40)}, 17);
  same.connective = Connective::Or;
  s.rules.push_back(same);
  CHECK(only_warning(s, "duplicate-rule").message ==
        "r6 repeats r5 (same conditions, same conclusion); remove one of them");

  // Without source positions there is no note.
  s.rules[4].range = SourceRange{};
  CHECK(only_warning(s, "duplicate-rule").notes.empty());
}

TEST_CASE("coverage-hole on one input", "[lint]") {
  FuzzySystem s = clean_mamdani();
  s.inputs[0].terms = {term("low", MfKind::Triangle, {0, 0, 2.5}, 3), term("high", MfKind::Triangle, {7.5, 10, 10}, 4)};
  // Only x's own warning: the joint scan leaves the points inside x's hole to it.
  const Diagnostic d = only_warning(s, "coverage-hole");
  require_position(d, 2, 1);
  CHECK(d.message == "no term of input 'x' reaches 0.1 on [2.3, 7.7]; add or widen a term there, or narrow the range");
  const JointCoverage joint = joint_coverage(s, 0.1, 10201, 101);
  CHECK(joint.points_checked == 10201);
  CHECK(joint.single_input_holes == 55 * 101);  // x = 2.3, 2.4, ..., 7.7
  CHECK(joint.holes == 0);

  const std::vector<CoverageInterval> runs = input_coverage_holes(s.inputs[0], 0.1, 101);
  REQUIRE(runs.size() == 1);
  CHECK(runs[0].from == 2.3);
  CHECK(runs[0].to == 7.7);

  // A hole of a single sample, and holes at both ends.
  Variable v = variable("v", 0, 4, {term("mid", MfKind::Triangle, {0.5, 2, 3.5}, 3)}, 2);
  const std::vector<CoverageInterval> ends = input_coverage_holes(v, 0.1, 5);
  REQUIRE(ends.size() == 2);
  CHECK(ends[0].from == 0);
  CHECK(ends[0].to == 0);
  CHECK(ends[1].from == 4);
  CHECK(ends[1].to == 4);
  s.inputs[0] = v;
  LintOptions coarse;
  coarse.coverage_points_per_input = 5;
  const std::vector<Diagnostic> point_holes = with_code(linted(s, coarse), "coverage-hole");
  REQUIRE(point_holes.size() >= 2);
  CHECK(point_holes[0].message ==
        "no term of input 'v' reaches 0.1 at 0; add or widen a term there, or narrow the range");
  CHECK(point_holes[1].message ==
        "no term of input 'v' reaches 0.1 at 4; add or widen a term there, or narrow the range");

  // Sample points are rounded to 10 digits of the range width: -0.054, not -0.054000000000000006.
  const Variable narrow = variable("n", -0.1, 0.1,
                                   {term("low", MfKind::Triangle, {-0.1, -0.1, -0.05}, 3),
                                    term("high", MfKind::Triangle, {0.05, 0.1, 0.1}, 4)},
                                   2);
  const std::vector<CoverageInterval> middle = input_coverage_holes(narrow, 0.1, 101);
  REQUIRE(middle.size() == 1);
  CHECK(middle[0].from == -0.054);
  CHECK(middle[0].to == 0.054);

  // Edge cases: no terms, an empty or non-finite range, a threshold no grade reaches.
  CHECK(input_coverage_holes(variable("e", 0, 1, {}, 2), 0.1, 11).empty());
  CHECK(input_coverage_holes(variable("e", 1, 1, {term("t", MfKind::Gaussian, {1, 1}, 3)}, 2), 0.1, 11).empty());
  CHECK(input_coverage_holes(variable("e", 0, INFINITY, {term("t", MfKind::Gaussian, {1, 1}, 3)}, 2), 0.1, 11)
            .empty());
  const std::vector<CoverageInterval> all = input_coverage_holes(
      variable("e", 0, 1, {term("t", MfKind::Gaussian, {1, 1}, 3)}, 2), 1.5, 11);
  REQUIRE(all.size() == 1);
  CHECK(all[0].from == 0);
  CHECK(all[0].to == 1);
}

// x and y each covered by low/high triangles, but only the rules (low, low) and (high, high).
FuzzySystem diagonal_rules() {
  FuzzySystem s = clean_mamdani();
  s.inputs[1].terms = {term("low", MfKind::Triangle, {-10, 0, 10}, 6), term("high", MfKind::Triangle, {0, 10, 20}, 7)};
  s.rules = {s.rules[0], s.rules[3]};
  return s;
}

TEST_CASE("coverage-hole over all inputs", "[lint]") {
  LintOptions options;
  options.coverage_grid_budget = 121;  // 11 x 11: the grid points are the integers 0..10
  Diagnostic d = only_warning(diagonal_rules(), "coverage-hole", options);
  require_position(d, 1, 1);
  CHECK(d.message == "no rule reaches a firing strength of 0.1 at 'x' = 0, 'y' = 10; add a rule for that region or "
                     "widen the terms it uses");
  CHECK(d.notes == std::vector<std::string>{"no rule fires there at all",
                                            "2 of 121 points of a grid of 11 per input (1.65%) are such holes"});

  const JointCoverage coverage = joint_coverage(diagonal_rules(), 0.1, 121, 101);
  CHECK(coverage.analysed);
  CHECK(coverage.regular_grid);
  CHECK(coverage.points_per_axis == 11);
  CHECK(coverage.points_checked == 121);
  CHECK(coverage.holes == 2);
  CHECK(coverage.worst_point == std::vector<double>{0, 10});
  CHECK(coverage.worst_strength == 0);
  CHECK(coverage.strongest_rule == -1);

  // A raised threshold gives more holes; the same worst point.
  const JointCoverage high = joint_coverage(diagonal_rules(), 0.6, 121, 101);
  CHECK(high.holes > 2);
  CHECK(high.worst_point == std::vector<double>{0, 10});

  // Gaussian y terms never reach 0: the worst point then names the strongest rule and its strength. (0, 10) and
  // (10, 0) tie at exp(-100 / 18); the first one in grid order is reported.
  FuzzySystem gaussian_y = clean_mamdani();
  gaussian_y.rules = {gaussian_y.rules[0], gaussian_y.rules[3]};
  d = only_warning(gaussian_y, "coverage-hole", options);
  CHECK(d.message == "no rule reaches a firing strength of 0.1 at 'x' = 0, 'y' = 10; add a rule for that region or "
                     "widen the terms it uses");
  REQUIRE(d.notes.size() == 2);
  CHECK(d.notes[0] == "the strongest rule there, r1, reaches " + format_number(mf::gaussian(10.0, 3.0, 0.0)));

  // The default budget allows 447 x 447 = 199809 <= 200000 < 448 x 448 points, but no axis gets more points than
  // the per-input check (101); a smaller budget caps it.
  d = only_warning(diagonal_rules(), "coverage-hole");
  REQUIRE(d.notes.size() == 2);
  CHECK(d.notes[1].find(" of 10201 points of a grid of 101 per input (") != std::string::npos);
  CHECK(joint_coverage(diagonal_rules(), 0.1, 200000, 1000).points_per_axis == 447);
  CHECK(joint_coverage(diagonal_rules(), 0.1, 448 * 448 - 1, 1000).points_per_axis == 447);
  CHECK(joint_coverage(diagonal_rules(), 0.1, 448 * 448, 1000).points_per_axis == 448);

  // The weight counts: at 0.05 r1 never reaches 0.1, so every point where r4 is below 0.1 (x or y = 0) is a hole.
  FuzzySystem weighted = diagonal_rules();
  weighted.rules[0].weight = 0.05;
  const JointCoverage weak = joint_coverage(weighted, 0.1, 121, 101);
  CHECK(weak.holes == 21);
  CHECK(weak.worst_point == std::vector<double>{0, 10});
  CHECK(weak.worst_strength == 0);
}

TEST_CASE("coverage over many inputs uses Halton points", "[lint]") {
  FuzzySystem s;
  s.name = "wide";
  for (int i = 0; i < 12; ++i)
    s.inputs.push_back(variable("in" + std::to_string(i), 0, 1,
                                {term("low", MfKind::Triangle, {-1, 0, 1}, 2), term("high", MfKind::Triangle, {0, 1, 2}, 3)},
                                1));
  s.outputs.push_back(variable("out", 0, 1, {term("t", MfKind::Triangle, {0, 0.5, 1}, 4)}, 4));
  std::vector<Clause> all_low;
  for (int i = 0; i < 12; ++i) all_low.push_back(clause(i, 0, 5, 1));
  s.rules.push_back(rule("r1", all_low, {clause(0, 0, 5, 50)}, 5));

  const JointCoverage coverage = joint_coverage(s, 0.1, 1000, 101);
  CHECK(coverage.analysed);
  CHECK_FALSE(coverage.regular_grid);
  CHECK(coverage.points_checked == 1000);
  // A point is a hole when some input exceeds 0.9: 1 - 0.9^12 = 72% of the cube.
  CHECK(coverage.holes > 650);
  CHECK(coverage.holes < 790);
  REQUIRE(coverage.worst_point.size() == 12);
  CHECK(rule_firing_strength(s, 0, coverage.worst_point) == coverage.worst_strength);
  for (double x : coverage.worst_point) {
    CHECK(x > 0);
    CHECK(x < 1);
  }
  // The first Halton point (index 1) in bases 2, 3, 5: 1/2, 1/3, 1/5 of the range. With weight 0 it is a hole.
  s.rules[0].weight = 0;
  const JointCoverage one = joint_coverage(s, 0.1, 1, 101);
  REQUIRE(one.worst_point.size() == 12);
  CHECK(one.worst_point[0] == 0.5);
  CHECK(one.worst_point[1] == 1.0 / 3.0);
  CHECK(one.worst_point[2] == 0.2);
}

TEST_CASE("term-out-of-range", "[lint]") {
  auto warning_for = [](Term extra) {
    FuzzySystem s = clean_mamdani();
    s.inputs[0].terms.push_back(std::move(extra));
    return only_warning(s, "term-out-of-range");
  };
  Diagnostic d = warning_for(term("beyond", MfKind::Gaussian, {1, 12}, 20));
  require_position(d, 20, 3);
  CHECK(d.message == "the peak of term 'beyond' of 'x', at 12, lies outside the range [0, 10]; move the term inside "
                     "the range or widen the range");
  CHECK(warning_for(term("shelf", MfKind::Trapezoid, {-5, -3, -2, 1}, 20)).message ==
        "the core of term 'shelf' of 'x', [-3, -2], lies outside the range [0, 10]; move the term inside the range "
        "or widen the range");
  CHECK(warning_for(term("huge", MfKind::SShape, {12, 16}, 20)).message ==
        "the part of term 'huge' of 'x' above grade 0.5, from 14 up, lies outside the range [0, 10]; move the term "
        "inside the range or widen the range");
  CHECK(warning_for(term("tiny", MfKind::Sigmoid, {-2, -1}, 20)).message ==
        "the part of term 'tiny' of 'x' above grade 0.5, up to -1, lies outside the range [0, 10]; move the term "
        "inside the range or widen the range");

  // On the edge is inside; a shoulder whose 0.5 point is inside is fine though its flat part is not.
  FuzzySystem s = clean_mamdani();
  s.inputs[0].terms.push_back(term("edge", MfKind::Triangle, {5, 10, 15}, 20));
  s.inputs[0].terms.push_back(term("shoulder", MfKind::ZShape, {-4, 6}, 21));
  s.inputs[0].terms.push_back(term("flat", MfKind::Sigmoid, {0, 50}, 22));
  CHECK(with_code(linted(s), "term-out-of-range").empty());
}

TEST_CASE("terms-out-of-order", "[lint]") {
  FuzzySystem s = clean_mamdani();
  s.inputs[0].terms.push_back(term("mid", MfKind::Triangle, {2, 5, 8}, 20));
  Diagnostic d = only_warning(s, "terms-out-of-order");
  require_position(d, 20, 3);
  CHECK(d.message == "term 'mid' of 'x' (centre 5) comes after 'high' (centre 10) but lies below it, while the terms "
                     "run from low to high; declare the terms in order of their centres");

  // Consistently decreasing is an order too; so is a tie.
  s.inputs[0].terms = {term("high", MfKind::Gaussian, {1, 9}, 3), term("mid", MfKind::Gaussian, {1, 5}, 4),
                       term("mid2", MfKind::Gaussian, {2, 5}, 5), term("low", MfKind::Gaussian, {1, 1}, 6)};
  CHECK(with_code(linted(s), "terms-out-of-order").empty());
  s.inputs[0].terms[3].mf.params = {1, 7};
  CHECK(only_warning(s, "terms-out-of-order").message ==
        "term 'low' of 'x' (centre 7) comes after 'mid2' (centre 5) but lies above it, while the terms run from high "
        "to low; declare the terms in order of their centres");

  // One-sided shapes are placed by their centroid on the range: zmf sorts below smf with the same breakpoints.
  s.inputs[0].terms = {term("young", MfKind::ZShape, {3, 7}, 3), term("middle", MfKind::Gaussian, {1, 5}, 4),
                       term("old", MfKind::SShape, {3, 7}, 5)};
  CHECK(with_code(linted(s), "terms-out-of-order").empty());
  s.inputs[0].terms = {term("old", MfKind::SShape, {3, 7}, 3), term("young", MfKind::ZShape, {3, 7}, 4),
                       term("middle", MfKind::Gaussian, {1, 5}, 5)};
  CHECK(with_code(linted(s), "terms-out-of-order").size() == 1);
}

TEST_CASE("near-zero-width", "[lint]") {
  auto warnings_for = [](Term extra) {
    FuzzySystem s = clean_mamdani();
    s.inputs[0].terms.push_back(std::move(extra));
    return with_code(linted(s), "near-zero-width");
  };
  std::vector<Diagnostic> found = warnings_for(term("spike", MfKind::Gaussian, {1e-9, 5}, 20));
  REQUIRE(found.size() == 1);
  require_position(found[0], 20, 3);
  CHECK(found[0].range.end_column == 40);
  CHECK(found[0].message == "term 'spike' of 'x' has sd 1e-09, less than 1e-06 of the width of the range [0, 10]; "
                            "inputs will almost never meet it: widen the term");
  found = warnings_for(term("point", MfKind::Triangle, {5, 5, 5}, 20));
  REQUIRE(found.size() == 1);
  CHECK(found[0].message == "term 'point' of 'x' has foot distance c - a 0, less than 1e-06 of the width of the "
                            "range [0, 10]; inputs will almost never meet it: widen the term");
  found = warnings_for(term("cliff", MfKind::Sigmoid, {1e8, 5}, 20));
  REQUIRE(found.size() == 1);
  CHECK(found[0].message == "term 'cliff' of 'x' has transition width 1/|a| 1e-08, less than 1e-06 of the width of "
                            "the range [0, 10]; inputs will almost never meet it: widen the term");
  found = warnings_for(term("two", MfKind::Gaussian2, {1, 4, 1e-7, 6}, 20));
  REQUIRE(found.size() == 1);
  CHECK(found[0].message.find("has sd2 1e-07,") != std::string::npos);
  // a == b is MATLAB's deliberate crisp step; a wide enough term is fine.
  CHECK(warnings_for(term("step", MfKind::LinearS, {4, 4}, 20)).empty());
  CHECK(warnings_for(term("narrow", MfKind::Gaussian, {1e-4, 5}, 20)).empty());
  LintOptions strict;
  strict.near_zero_width_fraction = 1e-3;
  FuzzySystem s = clean_mamdani();
  s.inputs[0].terms.push_back(term("narrow", MfKind::Gaussian, {1e-4, 5}, 20));
  CHECK(with_code(linted(s, strict), "near-zero-width").size() == 1);
}

TEST_CASE("lint survives systems that failed check", "[lint]") {
  FuzzySystem s = clean_mamdani();
  s.inputs[0].terms[0].mf.params = {1};                 // too few parameters
  s.inputs[1].terms[1].mf.params = {NAN, 3};            // not finite
  s.inputs[1].min = 20;                                 // inverted range
  s.outputs[0].terms[0].mf.kind = MfKind::Linear;       // wrong kind
  s.rules[0].antecedent[0].variable = 9;                // unresolved
  s.rules[1].antecedent[1].term = -4;
  s.rules[2].consequent[0].variable = 3;
  s.rules[3].antecedent.clear();
  s.rules.push_back(rule("r5", {}, {}, 16));
  const DiagnosticList diagnostics = linted(s);
  CHECK_FALSE(diagnostics.has_errors());

  FuzzySystem empty;
  CHECK(linted(empty).empty());
  empty.inputs.push_back(variable("x", 0, 1, {}, 2));
  empty.rules.push_back(rule("r1", {}, {}, 3));
  CHECK(linted(empty).empty());
}

TEST_CASE("seeded random systems: lint agrees with direct evaluation", "[lint]") {
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    const FuzzySystem s = testing::random_system(seed);
    LintOptions options;
    options.coverage_grid_budget = 2000;
    const DiagnosticList diagnostics = linted(s, options);
    INFO("seed " << seed << "\n" << render_all(diagnostics, SourceFiles{}));
    const std::vector<std::vector<double>> points = testing::random_inputs(s, seed, 300);
    // A rule said never to fire has strength below 1e-12 everywhere we look.
    for (const Diagnostic& d : with_code(diagnostics, "rule-never-fires"))
      for (std::size_t r = 0; r < s.rules.size(); ++r) {
        if (d.range.line != s.rules[r].range.line || !s.rules[r].range.valid()) continue;
        for (const std::vector<double>& point : points) CHECK(rule_firing_strength(s, r, point) < 1e-12);
      }
    // The joint scan's worst point, on a grid and on Halton points (a budget of 8 leaves fewer than 3 points per
    // axis): its best rule is what a plain loop over all rules finds there.
    for (long budget : {options.coverage_grid_budget, 8L}) {
      const JointCoverage coverage = joint_coverage(s, options.coverage_threshold, budget, 101);
      if (s.inputs.size() > 1) CHECK(coverage.regular_grid == (budget != 8));
      CHECK(coverage.holes + coverage.single_input_holes <= coverage.points_checked);
      if (coverage.holes == 0) continue;
      double best = 0.0;
      for (std::size_t r = 0; r < s.rules.size(); ++r)
        if (rule_is_evaluable(s, r)) best = std::max(best, rule_firing_strength(s, r, coverage.worst_point));
      CHECK((best < kNegligibleFiringStrength ? 0.0 : best) == coverage.worst_strength);
      CHECK(best < options.coverage_threshold);
    }
  }
}

std::vector<std::vector<std::string>> tsv_rows(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream cells_in(line);
    for (std::string cell; std::getline(cells_in, cell, '\t');) cells.push_back(cell);
    if (!cells.empty()) rows.push_back(cells);
  }
  return rows;
}

// The thesis ruleset (../shared/data/thesis): 5 inputs, 247 rules, gaussian terms: the scale lint must handle.
// Ranges [0, 75] kPa as in DESIGN.md; rule 2's output term "F0-F2" does not exist and is read as "F0-F1".
FuzzySystem thesis_liver_system(const std::filesystem::path& folder) {
  FuzzySystem s;
  s.name = "liver_fibrosis";
  s.range = at(1, 1, 10);
  int line = 2;
  for (const std::vector<std::string>& row : tsv_rows(folder / "membership_functions.tsv")) {
    std::vector<Variable>& variables = row[1] == "input" ? s.inputs : s.outputs;
    if (variables.empty() || variables.back().name != row[0]) variables.push_back(variable(row[0], 0, 75, {}, line++));
    std::vector<double> params;
    std::stringstream numbers(row[4]);
    for (double value; numbers >> value;) params.push_back(value);
    variables.back().terms.push_back(term(row[2], *mf_kind_from_matlab_name(row[3]), params, line++));
  }
  for (const std::vector<std::string>& row : tsv_rows(folder / "fmpc_rules.tsv")) {
    Rule r = rule("", {}, {}, line++);
    for (std::size_t i = 0; i < s.inputs.size(); ++i)
      if (row[i + 1] != "none") r.antecedent.push_back(clause(static_cast<int>(i), s.inputs[i].find_term(row[i + 1]), r.range.line, 1));
    const std::string stage = row[6] == "F0-F2" ? "F0-F1" : row[6];
    r.consequent.push_back(clause(0, s.outputs[0].find_term(stage), r.range.line, 50));
    s.rules.push_back(r);
  }
  return s;
}

TEST_CASE("the thesis liver ruleset", "[lint]") {
  const std::filesystem::path folder = std::filesystem::path(FMPC_SHARED_DATA_DIR) / "thesis";
  if (!std::filesystem::is_directory(folder)) {
    WARN("skipped: " << folder.string() << " is absent");
    return;
  }
  const FuzzySystem s = thesis_liver_system(folder);
  REQUIRE(s.inputs.size() == 5);
  REQUIRE(s.rules.size() == 247);
  DiagnosticList errors;
  check_system(s, errors);
  INFO(render_all(errors, SourceFiles{}));
  REQUIRE(errors.empty());
  const DiagnosticList diagnostics = linted(s);
  INFO(render_all(diagnostics, SourceFiles{}));
  // The defect the data README names: CLD 'F4' (centre 8.3) is declared after 'F3' (centre 43.8).
  const std::vector<Diagnostic> order = with_code(diagnostics, "terms-out-of-order");
  REQUIRE(order.size() == 1);
  CHECK(order[0].message == "term 'F4' of 'CLD' (centre 8.3) comes after 'F3' (centre 43.8) but lies below it, while "
                            "the terms run from low to high; declare the terms in order of their centres");
  // Every input's terms end far below 75 kPa.
  const std::vector<Diagnostic> holes = with_code(diagnostics, "coverage-hole");
  CHECK(holes.size() >= 5);
  CHECK(with_code(diagnostics, "unused-term").empty());
  CHECK(with_code(diagnostics, "term-out-of-range").empty());
  CHECK(with_code(diagnostics, "unit").empty());
}

}  // namespace
}  // namespace fmpc

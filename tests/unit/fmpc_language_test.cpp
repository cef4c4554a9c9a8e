// The fmpc rule language: parsing into the IR, every diagnostic with its exact message and position, the
// canonical layout (comments kept, idempotent) and write_fmpc -> read_fmpc identity.
#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>

#include "compiler/frontend/fmpc_language.h"
#include "diagnostics/number_format.h"
#include "tests/support/fmpc_text_checks.h"

namespace fmpc {
namespace {

using testing::difference;
using testing::format_ok;
using testing::kLiver;
using testing::read_ok;
using testing::read_one;

// Each diagnostic as "LINE:COL-ENDCOL: message | note | note".
std::vector<std::string> diagnostics_of(const std::string& text) {
  DiagnosticList diagnostics;
  read_fmpc("t.fis", text, diagnostics);
  std::vector<std::string> lines;
  for (const Diagnostic& d : diagnostics.items()) {
    std::string line = std::to_string(d.range.line) + ":" + std::to_string(d.range.column) + "-" +
                       std::to_string(d.range.end_column) + ": " + d.message;
    for (const std::string& note : d.notes) line += " | " + note;
    lines.push_back(line);
  }
  return lines;
}


TEST_CASE("fmpc language: the liver example parses into the expected IR", "[fmpc-language]") {
  const FuzzySystem s = read_one(kLiver);
  CHECK(s.name == "liver");
  CHECK(s.description == "Fuzzy MSM parameter controller");
  CHECK(s.type == SystemType::Mamdani);
  CHECK(s.defuzzifier == Defuzzifier::Centroid);
  CHECK(s.samples == 101);
  CHECK(s.no_fire == NoFirePolicy::Midrange);
  REQUIRE(s.inputs.size() == 2);
  REQUIRE(s.outputs.size() == 2);
  const Variable& hcv = s.inputs[0];
  CHECK(hcv.name == "HCV");
  CHECK(hcv.description == "FibroScan stiffness, hepatitis C");
  CHECK(hcv.unit == "kPa");
  CHECK(hcv.min == 0.0);
  CHECK(hcv.max == 75.0);
  REQUIRE(hcv.terms.size() == 3);
  CHECK(hcv.terms[0].mf.kind == MfKind::Gaussian);
  CHECK(hcv.terms[0].mf.params == std::vector<double>{0.91, 7.64});  // gaussmf [sd mean]
  CHECK(hcv.terms[1].mf.params == std::vector<double>{0.38, 9.72});  // named arguments in any order
  CHECK(s.inputs[1].terms[0].name == "F0-F1");
  CHECK(s.inputs[1].terms[0].mf.params == std::vector<double>{-20, 0, 20});
  CHECK(s.inputs[1].terms[1].mf.params == std::vector<double>{5, 6, 8, 9});
  CHECK(s.inputs[1].unit == "kPa");
  CHECK(s.inputs[1].description.empty());
  // 5300 Pa and 1.45 kPa in the output's kPa.
  CHECK(s.outputs[0].terms[0].mf.params == std::vector<double>{1.45, 5.3});
  CHECK(s.outputs[1].unit == "dimensionless");

  REQUIRE(s.rules.size() == 4);
  const Rule& r1 = s.rules[0];
  CHECK(r1.label == "r1");
  CHECK(r1.connective == Connective::And);
  REQUIRE(r1.antecedent.size() == 2);
  CHECK(r1.antecedent[1].variable == 1);
  CHECK(r1.antecedent[1].term == 0);
  CHECK(r1.weight == 1.0);
  const Rule& r7 = s.rules[1];
  CHECK(r7.connective == Connective::Or);
  CHECK(r7.antecedent[0].negated);
  CHECK(r7.antecedent[0].hedge == Hedge::None);
  CHECK(r7.antecedent[1].hedge == Hedge::Very);
  CHECK(r7.weight == 0.5);
  const Rule& r3 = s.rules[2];
  CHECK(r3.label.empty());
  CHECK(s.rule_display_name(2) == "rule 3");
  CHECK(r3.antecedent[0].hedge == Hedge::Somewhat);
  REQUIRE(r3.consequent.size() == 2);
  CHECK(r3.consequent[1].variable == 1);
  const Rule& r9 = s.rules[3];
  CHECK(r9.antecedent[0].variable == 1);  // clauses keep their order
  CHECK(r9.antecedent[0].hedge == Hedge::Extremely);
  CHECK(r9.antecedent[1].hedge == Hedge::VeryVery);
  CHECK(r9.antecedent[1].negated);
  CHECK(r9.consequent[0].negated);
  CHECK(r9.consequent[0].hedge == Hedge::Somewhat);
}

TEST_CASE("fmpc language: source ranges point at the exact tokens", "[fmpc-language]") {
  const FuzzySystem s = read_one(kLiver);
  CHECK(s.range.file == "t.fis");
  CHECK(s.range.line == 2);
  CHECK(s.range.column == 1);
  CHECK(s.range.end_column == 46);  // through the description
  const Variable& hcv = s.inputs[0];
  CHECK(hcv.range.line == 11);
  CHECK(hcv.range.column == 1);
  CHECK(hcv.range.end_column == 60);  // through the unit
  CHECK(hcv.name_range.line == 11);
  CHECK(hcv.name_range.column == 7);
  CHECK(hcv.name_range.end_column == 10);
  CHECK(hcv.terms[1].range.line == 13);
  CHECK(hcv.terms[1].range.column == 3);
  CHECK(hcv.terms[1].range.end_column == 34);
  CHECK(hcv.terms[1].name_range.column == 3);
  CHECK(hcv.terms[1].name_range.end_column == 5);
  CHECK(s.inputs[1].terms[0].name_range.column == 3);
  CHECK(s.inputs[1].terms[0].name_range.end_column == 10);  // the quotes included
  const Rule& r1 = s.rules[0];
  CHECK(r1.range.line == 28);
  CHECK(r1.range.column == 1);
  CHECK(r1.range.end_column == 67);
  CHECK(r1.antecedent[1].range.column == 27);
  CHECK(r1.antecedent[1].range.end_column == 41);
}

TEST_CASE("fmpc language: settings default to MATLAB's for each type", "[fmpc-language]") {
  const FuzzySystem mamdani = read_one("system m input x in [0, 1] a is triangle(start 0, peak 0.5, end 1)");
  CHECK(mamdani.type == SystemType::Mamdani);
  CHECK(mamdani.and_method == TNorm::Minimum);
  CHECK(mamdani.or_method == SNorm::Maximum);
  CHECK(mamdani.implication == TNorm::Minimum);
  CHECK(mamdani.aggregation == SNorm::Maximum);
  CHECK(mamdani.defuzzifier == Defuzzifier::Centroid);
  CHECK(mamdani.samples == 101);
  CHECK(mamdani.no_fire == NoFirePolicy::Midrange);
  CHECK(mamdani.inputs[0].unit.empty());

  const FuzzySystem sugeno = read_one("system s type sugeno");
  CHECK(sugeno.type == SystemType::Sugeno);
  CHECK(sugeno.and_method == TNorm::Product);
  CHECK(sugeno.or_method == SNorm::ProbabilisticSum);
  CHECK(sugeno.implication == TNorm::Product);
  CHECK(sugeno.aggregation == SNorm::Sum);
  CHECK(sugeno.defuzzifier == Defuzzifier::WeightedAverage);

  // Explicit settings override the type's defaults, in any order relative to `type`.
  const FuzzySystem mixed = read_one(R"(system s
    and min or einstein_sum implication einstein_product aggregation probor type sugeno
    defuzzify wtsum when no rule fires: value -5.25)");
  CHECK(mixed.and_method == TNorm::Minimum);
  CHECK(mixed.or_method == SNorm::EinsteinSum);
  CHECK(mixed.implication == TNorm::EinsteinProduct);
  CHECK(mixed.aggregation == SNorm::ProbabilisticSum);
  CHECK(mixed.defuzzifier == Defuzzifier::WeightedSum);
  CHECK(mixed.no_fire == NoFirePolicy::Value);
  CHECK(mixed.no_fire_value == -5.25);

  CHECK(read_one("system s defuzzify bisector samples exact").samples == 0);
  CHECK(read_one("system s defuzzify lom samples 1001").samples == 1001);
  CHECK(read_one("system s defuzzify som").defuzzifier == Defuzzifier::SmallestOfMaximum);
  CHECK(read_one("system s defuzzify mom").defuzzifier == Defuzzifier::MeanOfMaximum);
  CHECK(read_one("system s when no rule fires: error").no_fire == NoFirePolicy::Error);
  CHECK(read_one("system s aggregation sum").aggregation == SNorm::Sum);
  CHECK(read_one("system s and prod").and_method == TNorm::Product);
  CHECK(read_one("system s or probor").or_method == SNorm::ProbabilisticSum);
}

TEST_CASE("fmpc language: every MF family maps named parameters to MATLAB's order", "[fmpc-language]") {
  struct Case {
    const char* text;
    MfKind kind;
    std::vector<double> params;
  };
  const std::vector<Case> cases = {
      {"triangle(end 3, start 1, peak 2)", MfKind::Triangle, {1, 2, 3}},
      {"trapezoid(top_end 3, end 4, start 1, top_start 2)", MfKind::Trapezoid, {1, 2, 3, 4}},
      {"gauss(mean 2, sd 1)", MfKind::Gaussian, {1, 2}},
      {"gauss2(mean1 2, sd1 1, mean2 4, sd2 3)", MfKind::Gaussian2, {1, 2, 3, 4}},
      {"bell(center 3, slope 2, width 1)", MfKind::GeneralizedBell, {1, 2, 3}},
      {"sigmoid(center 2, slope -1.5)", MfKind::Sigmoid, {-1.5, 2}},
      {"dsigmoid(slope1 1, center1 2, slope2 3, center2 4)", MfKind::DifferenceSigmoid, {1, 2, 3, 4}},
      {"psigmoid(center2 4, slope2 3, center1 2, slope1 1)", MfKind::ProductSigmoid, {1, 2, 3, 4}},
      {"zshape(end 2, start 1)", MfKind::ZShape, {1, 2}},
      {"sshape(start 1, end 2)", MfKind::SShape, {1, 2}},
      {"pishape(start 1, top_start 2, top_end 3, end 4)", MfKind::PiShape, {1, 2, 3, 4}},
      {"linear_s(start 1, end 2)", MfKind::LinearS, {1, 2}},
      {"linear_z(start 1e-3, end 2.5E+1)", MfKind::LinearZ, {0.001, 25}},
      {"constant(value 7)", MfKind::Constant, {7}},
      {"linear(y 2, offset 3, x 1)", MfKind::Linear, {1, 2, 3}},
      {"linear(y 2)", MfKind::Linear, {0, 2, 0}},
      {"linear()", MfKind::Linear, {0, 0, 0}},
  };
  for (const Case& c : cases) {
    INFO(c.text);
    const FuzzySystem s = read_one(std::string("system s input x in [0, 10] input y in [0, 10] output z in [0, 10]\n"
                                               "  t is ") + c.text);
    REQUIRE(s.outputs[0].terms.size() == 1);
    CHECK(s.outputs[0].terms[0].mf.kind == c.kind);
    CHECK(s.outputs[0].terms[0].mf.params == c.params);
  }
}

TEST_CASE("fmpc language: quoted names, contextual keywords and an input called offset", "[fmpc-language]") {
  const FuzzySystem s = read_one(R"(system "my system" type sugeno
input "if" in [0, 1] "kg/m^3"
  value is triangle(start 0, peak 0.5, end 1)
  "very low" is triangle(start 0, peak 0.1, end 0.2)
input offset in [0, 1] %
  error is gauss(mean 0.5, sd 0.1)
output in in [-1, 1]
  type is linear("offset" 2, offset 3, "if" -1)
rule samples: if "if" is not "very low" and offset is error then in is type
)");
  CHECK(s.name == "my system");
  CHECK(s.inputs[0].name == "if");
  CHECK(s.inputs[0].unit == "kg/m^3");
  CHECK(s.inputs[0].terms[0].name == "value");
  CHECK(s.inputs[1].name == "offset");
  CHECK(s.inputs[1].unit == "%");
  CHECK(s.outputs[0].name == "in");
  CHECK(s.outputs[0].terms[0].mf.params == std::vector<double>{-1, 2, 3});
  CHECK(s.rules[0].label == "samples");
  CHECK(s.rules[0].antecedent[0].term == 1);
  CHECK(s.rules[0].antecedent[0].negated);
}

TEST_CASE("fmpc language: parameter units convert to the variable's unit", "[fmpc-language]") {
  const auto params = [](const std::string& variable_unit, const std::string& mf) {
    return read_one("system s input x in [0, 100] " + variable_unit + "\n  t is " + mf).inputs[0].terms[0].mf.params;
  };
  CHECK(params("kPa", "gauss(mean 5300 Pa, sd 1.45 kPa)") == std::vector<double>{1.45, 5.3});
  CHECK(params("Pa", "gauss(mean 5.3 kPa, sd 2 MPa)") == std::vector<double>{2e6, 5300});
  CHECK(params("mm", "triangle(start 1 cm, peak 0.05 m, end 60 mm)") == std::vector<double>{10, 50, 60});
  CHECK(params("cm", "triangle(start 1 mm, peak 2 um, end 3 \"\xC2\xB5m\")") ==
        std::vector<double>{0.1, 0.0002, 0.0003});
  CHECK(params("s", "zshape(start 500 ms, end 1 s)") == std::vector<double>{0.5, 1});
  CHECK(params("kN", "sshape(start 1000 N, end 2 kN)") == std::vector<double>{1, 2});
  CHECK(params("kg", "sshape(start 500 g, end 2 kg)") == std::vector<double>{0.5, 2});
  CHECK(params("%", "sshape(start 0.5 dimensionless, end 20 %)") == std::vector<double>{50, 20});
  CHECK(params("dimensionless", "sshape(start 50 %, end 1)") == std::vector<double>{0.5, 1});
  // An unknown unit is fine when it is exactly the variable's.
  CHECK(params("mmHg", "sshape(start 5 mmHg, end 10)") == std::vector<double>{5, 10});
  CHECK(params("kPa", "sigmoid(slope 2, center 3 Pa)") == std::vector<double>{2, 0.003});
  CHECK(params("kPa", "bell(width 1 kPa, slope 2, center 3 kPa)") == std::vector<double>{1, 2, 3});
}

TEST_CASE("fmpc language: unit errors name both units", "[fmpc-language]") {
  CHECK(diagnostics_of("system s input x in [0, 1] kPa\n  t is gauss(mean 1 mm, sd 1)") ==
        std::vector<std::string>{
            "2:21-23: unit 'mm' (length) of 'mean' does not convert to 'kPa' (pressure), the unit of 'x'"});
  CHECK(diagnostics_of("system s input x in [0, 1] kPa\n  t is gauss(mean 1 kPaa, sd 1)") ==
        std::vector<std::string>{"2:21-25: unknown unit 'kPaa' for 'mean'; 'x' is in 'kPa' | fmpc converts Pa, m, "
                                 "s, N and g with SI prefixes (kPa, mm, ms, ...), % and dimensionless"});
  CHECK(diagnostics_of("system s input x in [0, 1] mmHg\n  t is gauss(mean 1 kPa, sd 1)") ==
        std::vector<std::string>{"2:21-24: unit 'kPa' of 'mean' does not convert to 'mmHg', the unit of 'x' | "
                                 "fmpc converts Pa, m, s, N and g with SI prefixes (kPa, mm, ms, ...), % and "
                                 "dimensionless; write the value in mmHg"});
  CHECK(diagnostics_of("system s input x in [0, 1]\n  t is gauss(mean 1 kPa, sd 1)") ==
        std::vector<std::string>{"2:21-24: 'kPa' given for 'mean', but 'x' has no unit | give 'x' a unit after its "
                                 "range (in [0, 1] kPa) or drop this one"});
  CHECK(diagnostics_of("system s input x in [0, 1] kPa\n  t is sigmoid(slope 2 kPa, center 1)") ==
        std::vector<std::string>{"2:24-27: 'slope' of sigmoid takes no unit (it is per unit of 'x'); remove 'kPa'"});
  CHECK(diagnostics_of("system s input x in [0, 1] kPa\n  t is bell(width 1, slope 2 kPa, center 1)") ==
        std::vector<std::string>{"2:30-33: 'slope' of bell takes no unit (it is per unit of 'x'); remove 'kPa'"});
  CHECK(diagnostics_of("system s type sugeno input x in [0, 1] output y in [0, 1] kPa\n"
                       "  t is linear(x 1 kPa, offset 2 mm)") ==
        std::vector<std::string>{
            "2:19-22: the coefficient of 'x' takes no unit; remove 'kPa'",
            "2:33-35: unit 'mm' (length) of 'offset' does not convert to 'kPa' (pressure), the unit of 'y'"});
}

TEST_CASE("fmpc language: syntax errors read like a compiler's, all of them, sorted", "[fmpc-language]") {
  CHECK(diagnostics_of("system s input x in [0, 1]\n  F2 is (mean 1)\n") ==
        std::vector<std::string>{"2:9-10: expected a membership function such as 'gauss' after 'is', found '('"});
  CHECK(diagnostics_of("system s input x in [0, 1] a is gauss(mean 1, sd 1)\nrule r1: if x is (a) then y is b") ==
        std::vector<std::string>{"2:18-19: expected a term name after 'is', found '('"});
  // A missing ':' is inserted (a repair): the rule is read and checked as if it were written.
  CHECK(diagnostics_of("system s\nrule r1 if x is a then y is b") ==
        std::vector<std::string>{"2:9-11: expected ':' after 'r1', found 'if'",
                                 "2:12-13: unknown input 'x' in system 's'",
                                 "2:24-25: unknown output 'y' in system 's'"});
  CHECK(diagnostics_of("input x in [0, 1]") ==
        std::vector<std::string>{"1:1-6: a variable before the first 'system' line; start the file with: system NAME"});
  CHECK(diagnostics_of("hello") == std::vector<std::string>{"1:6-6: expected 'is' after 'hello', found end of file"});
  CHECK(diagnostics_of("system s input x in [0 1]") ==
        std::vector<std::string>{"1:24-25: expected ',' after '0', found '1'"});
  CHECK(diagnostics_of("system s input x in [0, 1]\n  a is gauss(mean 1,)") ==
        std::vector<std::string>{"2:21-22: expected a parameter name after ',', found ')'"});
  CHECK(diagnostics_of("system s\nrule r1: if x is a then") ==
        std::vector<std::string>{"2:24-24: expected an output name after 'then', found end of file"});
  CHECK(diagnostics_of("system s\nrule r1: if x is a and y is then z is c") ==
        std::vector<std::string>{"2:29-33: expected a term name after 'is', found 'then'"});
  // Several errors in one file: each is reported, in source order.
  CHECK(diagnostics_of("system s\n  type @\ninput x in [0, 1]\n  a is triangle(start 0 peak 1, end 2)\n"
                       "rule: if x is a then y is \"b\nrule: if x is a") ==
        std::vector<std::string>{
            "2:8-9: unexpected character '@'; a name with this character must be quoted: \"F0-F1\"",
            "4:30-31: expected ',' or ')' after 'peak', found '1'",
            "5:27-29: unterminated quoted name: close it with '\"' on the same line",
            "6:16-16: expected 'then', 'and' or 'or' after 'a', found end of file"});
  CHECK(diagnostics_of("system s input x in [0, - 1]") ==
        std::vector<std::string>{
            "1:25-28: a negative number is written without a space: write -1"});
  CHECK(diagnostics_of("system s \xff") ==
        std::vector<std::string>{"1:10-11: the file is not valid UTF-8 (save it as UTF-8)"});
  CHECK(diagnostics_of("system s input x in [0, 1e999]") ==
        std::vector<std::string>{"1:25-30: number 1e999 is too large (a double holds up to about 1.8e308)"});
}

TEST_CASE("fmpc language: the parser resumes at the next item, so later errors are reported", "[fmpc-language]") {
  const std::string text = R"(system liver
  type mamdani
input HCV in [0, 75] kPa
  F2 is gauss(mean 7.64, sd 0.91))
  F3 is gauss(mean 9.72 sd 0.38)
  F4 is gauss(mean 13.81, sd 2.38)
output stiffness in [0, 75] kPa
  low is gauss(mean 1, sd 1)
rule r1: if HCV is F2 and then stiffness is low
rule r2: if HCV F3 then stiffness is low
rule r3: if HCV is F0-F1 then stiffness is low
rule r4: if HCV is F4 then stiffness is low weight
rule r5 if HCV is F4 then stiffness is low
input HBV in [0 75]
)";
  CHECK(diagnostics_of(text) ==
        std::vector<std::string>{
            "4:34-35: expected a term, 'input', 'output', 'rule', 'system' or end of file after ')', found ')'",
            "5:28-32: expected ',' or ')' after 'sd', found '0.38'",
            "9:27-31: expected an input name after 'and', found 'then'",
            "10:17-19: expected 'is' after 'HCV', found 'F3'",
            "11:20-25: a name with '-' must be quoted: write \"F0-F1\"",
            "12:51-52: expected a number after 'weight', found 'rule'",
            "13:9-11: expected ':' after 'r5', found 'if'",
            "14:17-19: expected ',' after '0', found '75'"});
  CHECK(diagnostics_of("system s\nrule: if x is a then y is b\n  t is gauss(mean 1, sd 1)") ==
        std::vector<std::string>{"3:3-4: term 't' is not under an 'input' or 'output' line; a variable's terms follow "
                                 "its line, before any rule or setting"});
}

TEST_CASE("fmpc language: unknown names get 'did you mean'", "[fmpc-language]") {
  const std::string head = R"(system liver
input HCV in [0, 75] kPa
  F2 is gauss(mean 7.64, sd 0.91)
  F4 is gauss(mean 13.81, sd 2.38)
input HBV in [0, 75] kPa
  F2 is gauss(mean 7.64, sd 0.91)
output stiffness in [0, 75] kPa
  F2 is gauss(mean 7.64, sd 0.91)
)";
  CHECK(diagnostics_of(head + "rule r1: if HCVV is F2 then stiffness is F2") ==
        std::vector<std::string>{"9:13-17: unknown input 'HCVV' in system 'liver' | did you mean 'HCV'?"});
  CHECK(diagnostics_of(head + "rule r1: if ALD is F2 then stiffness is F2") ==
        std::vector<std::string>{"9:13-16: unknown input 'ALD' in system 'liver'"});
  CHECK(diagnostics_of(head + "rule r1: if HCV is F5 then stiffness is F2") ==
        std::vector<std::string>{"9:20-22: input 'HCV' has no term 'F5' | did you mean 'F2'? | terms of 'HCV': F2, F4"});
  CHECK(diagnostics_of(head + "rule r1: if HCV is F2 then stifness is F2") ==
        std::vector<std::string>{"9:28-36: unknown output 'stifness' in system 'liver' | did you mean 'stiffness'?"});
  CHECK(diagnostics_of(head + "rule r1: if stiffness is F2 then stiffness is F2") ==
        std::vector<std::string>{
            "9:13-22: 'stiffness' is an output of 'liver'; the conditions after 'if' name inputs"});
  CHECK(diagnostics_of(head + "rule r1: if HCV is F2 then HBV is F2") ==
        std::vector<std::string>{"9:28-31: 'HBV' is an input of 'liver'; the conclusions after 'then' name outputs"});
  CHECK(diagnostics_of(head + "rule r1: if HCV is F2 and HCV is F4 then stiffness is F2") ==
        std::vector<std::string>{"9:27-30: input 'HCV' appears twice in rule 'r1'; a rule names each input at most "
                                 "once | first used here: 9:13"});
  CHECK(diagnostics_of(head + "rule: if HCV is F2 then stiffness is F2 and stiffness is F2") ==
        std::vector<std::string>{"9:45-54: output 'stiffness' appears twice in rule 1; a rule names each output at "
                                 "most once | first used here: 9:25"});
  CHECK(diagnostics_of(head + "rule r2: if HCV is F2 and HBV is F2 or HCV is F4 then stiffness is F2") ==
        std::vector<std::string>{
            "9:37-39: rule 'r2' mixes 'and' and 'or'; a rule has one connective (as in MATLAB), so split it into "
            "several rules",
            "9:40-43: input 'HCV' appears twice in rule 'r2'; a rule names each input at most once | first used "
            "here: 9:13"});
  CHECK(diagnostics_of(head + "rule r1: if HCV is F2 then damping is F2\n"
                              "system other\noutput damping in [0, 1]\n  low is gauss(mean 0, sd 1)\n") ==
        std::vector<std::string>{"9:28-35: 'damping' is an output of system 'other'; a rule of 'liver' can only name "
                                 "its own variables"});
  CHECK(diagnostics_of("system a\nsystem a") ==
        std::vector<std::string>{"2:8-9: system 'a' is defined twice in this file; rename one | first defined here: "
                                 "1:8"});
}

TEST_CASE("fmpc language: bad settings get 'did you mean' and the choices", "[fmpc-language]") {
  CHECK(diagnostics_of("system s\n  type mamdan") ==
        std::vector<std::string>{
            "2:8-14: unknown system type 'mamdan' | did you mean 'mamdani'? | choose one of: mamdani, sugeno"});
  CHECK(diagnostics_of("system s\n  and mn") ==
        std::vector<std::string>{"2:7-9: unknown t-norm 'mn' for 'and' | did you mean 'min'? | choose one of: min, "
                                 "prod, einstein_product"});
  CHECK(diagnostics_of("system s\n  aggregation maxx") ==
        std::vector<std::string>{"2:15-19: unknown s-norm 'maxx' for 'aggregation' | did you mean 'max'? | choose "
                                 "one of: max, probor, sum, einstein_sum"});
  CHECK(diagnostics_of("system s\n  defuzzify centriod") ==
        std::vector<std::string>{"2:13-21: unknown defuzzifier 'centriod' | did you mean 'centroid'? | choose one "
                                 "of: centroid, bisector, mom, som, lom, wtaver, wtsum"});
  CHECK(diagnostics_of("system s\n  defuzzify centroid samples 10.5") ==
        std::vector<std::string>{
            "2:30-34: samples must be a whole number from 2 to 100000000, or 'exact' for the exact centroid"});
  CHECK(diagnostics_of("system s\n  and min\n  and prod") ==
        std::vector<std::string>{"3:3-11: 'and' is set twice in system 's'; keep one | first set here: 2:3"});
}

TEST_CASE("fmpc language: bad named MF arguments", "[fmpc-language]") {
  const std::string head = "system s type sugeno\ninput x in [0, 1]\ninput y in [0, 1]\noutput z in [0, 1]\n  t is ";
  CHECK(diagnostics_of(head + "gauss(mea 1, sd 1)") ==
        std::vector<std::string>{"5:8-13: gauss(...) of term 't' is missing parameter 'mean' | gauss takes: mean, sd",
                                 "5:14-17: 'gauss' has no parameter 'mea' | did you mean 'mean'? | gauss takes: "
                                 "mean, sd"});
  CHECK(diagnostics_of(head + "gauss(mean 1, sd 1, mean 2)") ==
        std::vector<std::string>{"5:28-32: parameter 'mean' is given twice | first given here: 5:14"});
  CHECK(diagnostics_of(head + "trapezoid(start 1, end 2)") ==
        std::vector<std::string>{"5:8-17: trapezoid(...) of term 't' is missing parameters 'top_start' and "
                                 "'top_end' | trapezoid takes: start, top_start, top_end, end"});
  CHECK(diagnostics_of(head + "gaus(mean 1, sd 1)") ==
        std::vector<std::string>{"5:8-12: unknown membership function 'gaus' | did you mean 'gauss'? | membership "
                                 "functions: triangle, trapezoid, gauss, gauss2, bell, sigmoid, dsigmoid, psigmoid, "
                                 "zshape, sshape, pishape, linear_s, linear_z, constant, linear | MATLAB's names "
                                 "are accepted too: trimf, trapmf, gaussmf, gauss2mf, gbellmf, sigmf, dsigmf, "
                                 "psigmf, zmf, smf, pimf, linsmf, linzmf"});
  CHECK(diagnostics_of(head + "linear(xx 1, y 2, offset 3)") ==
        std::vector<std::string>{"5:15-17: 'xx' is not an input of system 's' | did you mean 'x'? | linear(...) "
                                 "takes one coefficient per input of 's' (x, y) and an offset"});
  CHECK(diagnostics_of(head + "linear(x 1, offset 3, offset 4)") ==
        std::vector<std::string>{"5:30-36: the offset is given twice | first given here: 5:20"});
  CHECK(diagnostics_of(head + "linear(x 1, x 4)") ==
        std::vector<std::string>{"5:20-21: the coefficient of 'x' is given twice | first given here: 5:15"});
}

TEST_CASE("fmpc language: MATLAB's MF names read as fmpc's families; MATLAB's parameter spellings are refused",
          "[fmpc-language]") {
  // Every alias gives the IR of its fmpc family, parameters in MATLAB's order.
  const std::vector<std::pair<std::string, std::string>> pairs = {
      {"trimf(start 1, peak 2, end 3)", "triangle(start 1, peak 2, end 3)"},
      {"trapmf(start 1, top_start 2, top_end 3, end 4)", "trapezoid(start 1, top_start 2, top_end 3, end 4)"},
      {"gaussmf(mean 5, sd 1)", "gauss(mean 5, sd 1)"},
      {"gauss2mf(mean1 2, sd1 1, mean2 4, sd2 2)", "gauss2(mean1 2, sd1 1, mean2 4, sd2 2)"},
      {"gbellmf(width 2, slope 3, center 5)", "bell(width 2, slope 3, center 5)"},
      {"sigmf(slope 2, center 5)", "sigmoid(slope 2, center 5)"},
      {"dsigmf(slope1 2, center1 3, slope2 2, center2 7)", "dsigmoid(slope1 2, center1 3, slope2 2, center2 7)"},
      {"psigmf(slope1 2, center1 3, slope2 -2, center2 7)", "psigmoid(slope1 2, center1 3, slope2 -2, center2 7)"},
      {"zmf(start 2, end 6)", "zshape(start 2, end 6)"},
      {"smf(start 2, end 6)", "sshape(start 2, end 6)"},
      {"pimf(start 1, top_start 2, top_end 3, end 4)", "pishape(start 1, top_start 2, top_end 3, end 4)"},
      {"linsmf(start 2, end 6)", "linear_s(start 2, end 6)"},
      {"linzmf(start 2, end 6)", "linear_z(start 2, end 6)"}};
  const std::string head = "system s\ninput x in [0, 10]\n  t is ";
  const std::string tail = "\noutput y in [0, 1]\n  o is gauss(mean 0.5, sd 0.1)\nrule: if x is t then y is o\n";
  for (const auto& [matlab, fmpc] : pairs) {
    INFO(matlab);
    const FuzzySystem aliased = read_one(head + matlab + tail);
    const FuzzySystem plain = read_one(head + fmpc + tail);
    CHECK(aliased.inputs[0].terms[0].mf.kind == plain.inputs[0].terms[0].mf.kind);
    CHECK(aliased.inputs[0].terms[0].mf.params == plain.inputs[0].terms[0].mf.params);
    // fmt writes fmpc's name.
    CHECK(format_ok(head + matlab + tail) == format_ok(head + fmpc + tail));
  }
  // Positional values under a MATLAB name: MATLAB's order, spelled out with names, with a fix-it.
  CHECK(diagnostics_of(head + "gaussmf(0.91, 7.64)" + tail) ==
        std::vector<std::string>{"3:8-27: parameters are named in fmpc: write gauss(mean 7.64, sd 0.91) | MATLAB's "
                                 "gaussmf [sigma c] is gauss(mean c, sd sigma)"});
  CHECK(diagnostics_of(head + "gbellmf [2 3 5]" + tail) ==
        std::vector<std::string>{"3:8-23: parameters are named in fmpc: write bell(width 2, slope 3, center 5) | "
                                 "MATLAB's gbellmf [a b c] is bell(width a, slope b, center c)"});
  // MATLAB's own parameter names under any name.
  CHECK(diagnostics_of(head + "gauss2mf(sig1 1, c1 2, sig2 2, c2 4)" + tail) ==
        std::vector<std::string>{"3:8-44: these are MATLAB's parameter names; in fmpc write gauss2(mean1 2, sd1 1, "
                                 "mean2 4, sd2 2) | MATLAB's gauss2mf [sig1 c1 sig2 c2] is gauss2(mean1 c1, sd1 "
                                 "sig1, mean2 c2, sd2 sig2)"});
  // One MATLAB name among fmpc's: the note says which fmpc name it is.
  CHECK(diagnostics_of(head + "gaussmf(mean 5, sigma 1)" + tail) ==
        std::vector<std::string>{"3:8-15: gauss(...) of term 't' is missing parameter 'sd' | gauss takes: mean, sd",
                                 "3:24-29: 'gauss' has no parameter 'sigma' | MATLAB's gaussmf calls it sigma; fmpc "
                                 "calls it 'sd' | gauss takes: mean, sd"});
  // Under fmpc's name, positional values imply no order: none is guessed.
  CHECK(diagnostics_of(head + "gauss(7.64, 0.91)" + tail) ==
        std::vector<std::string>{"3:14-18: parameters are named in fmpc: write gauss(mean VALUE, sd VALUE) | gauss "
                                 "takes: mean, sd"});
  CHECK(diagnostics_of(head + "trimf(1, 2)" + tail) ==
        std::vector<std::string>{"3:14-15: parameters are named in fmpc: write triangle(start VALUE, peak VALUE, end "
                                 "VALUE) | triangle takes: start, peak, end | MATLAB's trimf [a b c] is "
                                 "triangle(start a, peak b, end c)"});
  // The fix-it replaces the whole call.
  DiagnosticList diagnostics;
  read_fmpc("t.fis", head + "trimf(1, 2, 3)" + tail, diagnostics);
  REQUIRE(diagnostics.items().size() == 1);
  REQUIRE(diagnostics.items()[0].fix);
  CHECK(diagnostics.items()[0].fix->replacement == "triangle(start 1, peak 2, end 3)");
  CHECK(diagnostics.items()[0].fix->range.column == 8);
  CHECK(diagnostics.items()[0].fix->range.end_column == 22);
}

TEST_CASE("fmpc language: what a newcomer writes is repaired with a fix-it, and reading goes on", "[fmpc-language]") {
  const std::string head = "system s\ninput x in [0, 10] kPa\n  a is gauss(mean 5, sd 1)\n";
  const std::string tail = "output y in [0, 1]\n  o is gauss(mean 0.5, sd 0.1)\nrule: if x is a then y is o\n";
  // Each repair is one error naming the fix, and the file is still read: the unknown term 'b' of the last line
  // is reported too (a semantic error, found only because the parse went on).
  const auto with_later_error = [&](const std::string& line) {
    return diagnostics_of(head + line + "\n" + tail + "rule: if x is b then y is o\n");
  };
  const std::string later = "8:15-16: input 'x' has no term 'b' | did you mean 'a'? | terms of 'x': a, c";
  CHECK(with_later_error("  c is gauss(mean .5, sd 1)") ==
        std::vector<std::string>{"4:19-21: a number starts with a digit: write 0.5", later});
  CHECK(with_later_error("  c is gauss(mean -.5e1, sd 1)") ==
        std::vector<std::string>{"4:19-24: a number starts with a digit: write -0.5e1", later});
  CHECK(with_later_error("  c is gauss(mean 5., sd 1)") ==
        std::vector<std::string>{"4:19-21: a number does not end with '.': write 5", later});
  CHECK(with_later_error("  c is gauss(mean +5, sd 1)") ==
        std::vector<std::string>{"4:19-21: a number has no leading '+': write 5", later});
  CHECK(with_later_error("  c is gauss(mean=5, sd 1)") ==
        std::vector<std::string>{"4:18-19: no '=' between a name and its value: write mean 5", later});
  CHECK(with_later_error("  \"c is gauss(mean 5, sd 1)") ==
        std::vector<std::string>{"4:3-28: unterminated quoted name: close it with '\"' on the same line",
                                 "4:28-29: expected 'is' after '\"c is gauss(mean 5, sd 1)\"', found 'output'"});
  // Rules: comparison and logic operators, names with a character an identifier cannot hold.
  const std::string rules = "system s\ninput x in [0, 10]\n  a is gauss(mean 5, sd 1)\n  \"F0-F1\" is gauss(mean 1, "
                            "sd 1)\noutput y in [0, 1]\n  o is gauss(mean 0.5, sd 0.1)\n";
  const std::string two_inputs = "system s\ninput x in [0, 10]\n  \"F0-F1\" is gauss(mean 1, sd 1)\ninput z in [0, 1]\n"
                                 "  a is gauss(mean 5, sd 1)\noutput y in [0, 1]\n  o is gauss(mean 0.5, sd 0.1)\n";
  CHECK(diagnostics_of(rules + "rule r1: if x == a then y is o weight = 0.5\nrule: if x is c then y is o") ==
        std::vector<std::string>{"7:15-17: write 'is' instead of '=='",
                                 "7:39-40: no '=' between a name and its value: write weight 0.5",
                                 "8:15-16: input 'x' has no term 'c' | did you mean 'a'? | terms of 'x': a, F0-F1"});
  CHECK(diagnostics_of(two_inputs + "rule: if x != F0-F1 || z is a then y is o\n"
                                    "rule: if x is F0-F1 & z is aa then y is o") ==
        std::vector<std::string>{"8:12-14: write 'is not' instead of '!='",
                                 "8:15-20: a name with '-' must be quoted: write \"F0-F1\"",
                                 "8:21-23: write 'or' instead of '||'",
                                 "9:15-20: a name with '-' must be quoted: write \"F0-F1\"",
                                 "9:21-22: write 'and' instead of '&'",
                                 "9:28-30: input 'z' has no term 'aa' | did you mean 'a'? | terms of 'z': a"});
  // Units: quoted when they hold '/', '^', a non-ASCII letter; a number may start a unit after a range.
  CHECK(diagnostics_of("system s\ninput x in [0, 10] mL/min\ninput z in [0, 1] µm\ninput w in [0, 1] 1/s\n"
                       "output y in [0, 1] kg/m^3") ==
        std::vector<std::string>{"2:20-26: a unit with '/' must be quoted: write \"mL/min\"",
                                 "3:19-22: a unit with 'µ' must be quoted: write \"µm\"",
                                 "4:19-22: a unit with '/' must be quoted: write \"1/s\"",
                                 "5:20-26: a unit with '/' must be quoted: write \"kg/m^3\""});
  // A missing ':' (after a rule label or `fires`) or ',' (in a range) is inserted.
  CHECK(diagnostics_of("system s\n  when no rule fires midrange\ninput x in [0 10]\n  a is gauss(mean 5, sd 1)\n"
                       "output y in [0, 1]\n  o is gauss(mean 0.5, sd 0.1)\nrule r1 if x is a then y is oo") ==
        std::vector<std::string>{"2:22-30: expected ':' after 'fires', found 'midrange'",
                                 "3:15-17: expected ',' after '0', found '10'",
                                 "7:9-11: expected ':' after 'r1', found 'if'",
                                 "7:29-31: output 'y' has no term 'oo' | did you mean 'o'? | terms of 'y': o"});
  // What has no clear meaning is not repaired: no AST, and nothing more on its line.
  CHECK(diagnostics_of("system s\ninput x in [0, 1] ° ≤\nrule: if x is a then y is zz") ==
        std::vector<std::string>{"2:19-21: unexpected character '°'; a name with this character must be quoted: "
                                 "\"F0-F1\"",
                                 "2:22-25: unexpected character '≤'; a name with this character must be quoted: "
                                 "\"F0-F1\""});
  // fmt refuses a file read through repairs: the fix-its are the user's to make.
  DiagnosticList diagnostics;
  CHECK_FALSE(format_fmpc("t.fis", head + "  c is gauss(mean .5, sd 1)\n" + tail, diagnostics).has_value());
  CHECK(diagnostics.error_count() == 1);
}

TEST_CASE("fmpc language: every repair's fix-it, applied, gives a file without errors", "[fmpc-language]") {
  const std::string text = "system s\n  type = mamdani\n  when no rule fires midrange\ninput x in [0 10] mL/min\n"
                           "  a is gauss(mean .5, sd +1)\n  b is gaussmf(1, 5)\n  F0-F1 is trimf(a 1, b 2, c 3)\n"
                           "output y in [0, 1] µm\n  o is gauss(mean - 0.5, sd 0.1)\n"
                           "input z in [0, 1]\n  c is linzmf(a 0, b 1)\n"
                           "rule r1 if x == a && z != c then y is o weight=0.5\nrule: if x is F0-F1 then y is o\n";
  DiagnosticList diagnostics;
  read_fmpc("t.fis", text, diagnostics);
  // Apply the fix-its from the last to the first (they do not overlap), by line and byte column.
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::vector<FixIt> fixes;
  for (const Diagnostic& d : diagnostics.items()) {
    INFO(d.message);
    REQUIRE(d.fix);
    fixes.push_back(*d.fix);
  }
  CHECK(fixes.size() == 18);
  std::sort(fixes.begin(), fixes.end(), [](const FixIt& a, const FixIt& b) { return b.range < a.range; });
  for (const FixIt& fix : fixes) {
    std::string& line = lines[static_cast<std::size_t>(fix.range.line - 1)];
    const auto begin = static_cast<std::size_t>(fix.range.column - 1);
    line.replace(begin, static_cast<std::size_t>(fix.range.end_column - fix.range.column), fix.replacement);
  }
  std::string fixed;
  for (const std::string& line : lines) fixed += line + "\n";
  INFO(fixed);
  const FuzzySystem system = read_one(fixed);
  CHECK(system.inputs[0].unit == "mL/min");
  CHECK(system.inputs[0].terms[0].mf.params == std::vector<double>{1, 0.5});
  CHECK(system.inputs[0].terms[1].mf.params == std::vector<double>{1, 5});
  CHECK(system.outputs[0].terms[0].mf.params[1] == -0.5);
  CHECK(system.rules[0].weight == 0.5);
}

TEST_CASE("fmpc language: a system with errors is left out, the others are kept", "[fmpc-language]") {
  DiagnosticList diagnostics;
  const RuleFile file = read_fmpc("t.fis", "system good\nsystem bad type nope\nsystem also_good", diagnostics);
  CHECK(diagnostics.error_count() == 1);
  REQUIRE(file.systems.size() == 2);
  CHECK(file.systems[0].name == "good");
  CHECK(file.systems[1].name == "also_good");

  DiagnosticList syntax;
  CHECK(read_fmpc("t.fis", "system good\nsystem (", syntax).systems.empty());
  CHECK(syntax.error_count() == 1);
}

TEST_CASE("fmpc language: empty and comment-only files", "[fmpc-language]") {
  CHECK(read_ok("").systems.empty());
  CHECK(read_ok("# nothing here\n\n   # at all\n").systems.empty());
  CHECK(format_ok("") == "");
  CHECK(format_ok("   # nothing here\n\n\n# at all   \n") == "# nothing here\n\n# at all\n");
}

TEST_CASE("fmpc language: fmt lays out canonically and keeps comments", "[fmpc-language]") {
  const std::string messy = R"(# The liver controller.
# Second header line.
system liver "Fuzzy MSM parameter controller" # the system
  type mamdani and min   # one line, two settings
     defuzzify centroid
input HCV "FibroScan" in [0, 75.0] kPa F2 is gauss(sd 0.91, mean 7.64) # F2 stage
    # F3 comes next
  F3 is gauss(mean 9.72, sd 0.38)


  F4 is gauss(mean 1.381e1 kPa, sd 2.38)
input HBV in [0, 75] kPa F4 is gauss(mean 13.81, sd 2.38)
output stiffness in [0,75] kPa
  low is triangle(end 20, peak 0, start -20)
rule r1: if HCV is F2 # first line of the rule
   then stiffness is low # second line of the rule
# about r2
rule r2: if HCV is very F3 or HBV is not F4 then stiffness is low weight 0.50
rule: if HCV is somewhat F4 then stiffness is low
# trailing file comment
)";
  const std::string expected = R"(# The liver controller.
# Second header line.
system liver "Fuzzy MSM parameter controller"  # the system
  type mamdani
  and min  # one line, two settings
  or max
  implication min
  aggregation max
  defuzzify centroid samples 101
  when no rule fires: midrange

input HCV "FibroScan" in [0, 75] kPa
  F2 is gauss(mean 7.64, sd 0.91)  # F2 stage
  # F3 comes next
  F3 is gauss(mean 9.72, sd 0.38)

  F4 is gauss(mean 13.81 kPa, sd 2.38)

input HBV in [0, 75] kPa
  F4 is gauss(mean 13.81, sd 2.38)

output stiffness in [0, 75] kPa
  low is triangle(start -20, peak 0, end 20)

# second line of the rule
rule r1: if HCV is F2 then stiffness is low  # first line of the rule
# about r2
rule r2: if HCV is very F3 or HBV is not F4 then stiffness is low weight 0.5
rule: if HCV is somewhat F4 then stiffness is low
# trailing file comment
)";
  const std::string formatted = format_ok(messy);
  CHECK(formatted == expected);
  CHECK(format_ok(formatted) == formatted);
  // The layout does not change what the file means.
  CHECK(difference(read_one(messy), read_one(formatted)).empty());
}

TEST_CASE("fmpc language: fmt keeps one blank line between a comment block and its line", "[fmpc-language]") {
  // rulesets/liver_fibrosis/mamdani.fis opens with a header block, a blank line, then `system`: that blank line is
  // part of the layout (at most one is kept, as everywhere).
  const std::string text = "# header\n#\n# more header\n\n\nsystem s\n  type mamdani\n  and min\n  or max\n"
                           "  implication min\n  aggregation max\n  defuzzify centroid samples 101\n"
                           "  when no rule fires: midrange\n\ninput a in [0, 1]\n  # about lo\n\n"
                           "  lo is triangle(start 0, peak 0, end 1)\n  # about hi\n  hi is triangle(start 0, peak 1, end 1)\n\n"
                           "output o in [0, 1]\n  x is triangle(start 0, peak 0, end 1)\n\n# the rules\n\n"
                           "rule r1: if a is lo then o is x  # end of line\n";
  std::string expected = text;
  expected.erase(expected.find("\n\n\nsystem"), 1);
  const std::string formatted = format_ok(text);
  CHECK(formatted == expected);
  CHECK(format_ok(formatted) == formatted);
  CHECK(difference(read_one(text), read_one(formatted)).empty());
}

TEST_CASE("fmpc language: fmt aligns the trailing comments of consecutive lines", "[fmpc-language]") {
  // As gofmt does: a run of lines that each end in a comment shares one column, two spaces after its longest code
  // (counted in code points: "µ" is one), a variable's header and its terms alike; a blank line, a comment line or a
  // line without a comment ends the run.
  const std::string header = "system s\n  type mamdani\n  and min\n  or max\n  implication min\n  aggregation max\n"
                             "  defuzzify centroid samples 101\n  when no rule fires: midrange\n\n";
  const std::string text = header + "input a in [0, 1]\n  lo is triangle(start 0, peak 0, end 1)     # one\n"
                           "  \"µ\" is triangle(start 0, peak 1, end 1) # two\n  # a comment line\n"
                           "  hi is triangle(start 0.5, peak 1, end 1)  # alone\n"
                           "  mid is triangle(start 0, peak 0.5, end 1)\n\noutput o in [0, 1]  # three\n"
                           "  x is triangle(start 0, peak 0, end 1)  # four\n\nrule r1: if a is lo then o is x\n";
  const std::string expected = header + "input a in [0, 1]\n  lo is triangle(start 0, peak 0, end 1)   # one\n"
                               "  \"µ\" is triangle(start 0, peak 1, end 1)  # two\n  # a comment line\n"
                               "  hi is triangle(start 0.5, peak 1, end 1)  # alone\n"
                               "  mid is triangle(start 0, peak 0.5, end 1)\n\n"
                               "output o in [0, 1]                       # three\n"
                               "  x is triangle(start 0, peak 0, end 1)  # four\n\nrule r1: if a is lo then o is x\n";
  const std::string formatted = format_ok(text);
  CHECK(formatted == expected);
  CHECK(format_ok(formatted) == formatted);
}

TEST_CASE("fmpc language: fmt fills in the sugeno defaults and keeps several systems apart", "[fmpc-language]") {
  const std::string text = "system a type sugeno input x in [0,1] a is gauss(mean 0, sd 1) output y in [0, 1]\n"
                           "k is linear(offset 1, x 2) rule: if x is a then y is k\n\n\n\nsystem b\n"
                           "# the end\n";
  const std::string expected = R"(system a
  type sugeno
  and prod
  or probor
  implication prod
  aggregation sum
  defuzzify wtaver
  when no rule fires: midrange

input x in [0, 1]
  a is gauss(mean 0, sd 1)

output y in [0, 1]
  k is linear(x 2, offset 1)

rule: if x is a then y is k

system b
  type mamdani
  and min
  or max
  implication min
  aggregation max
  defuzzify centroid samples 101
  when no rule fires: midrange
# the end
)";
  CHECK(format_ok(text) == expected);
  CHECK(format_ok(expected) == expected);
}

TEST_CASE("fmpc language: fmt keeps what it cannot check as written", "[fmpc-language]") {
  // fmt needs only a syntactically valid file: unknown names and units are printed as they are.
  const std::string text = "system s\n  type nonsense\ninput x in [0, 1] \"kg/m^3\"\n"
                           "  a is blob(zeta 1, alpha 2)\nrule: if y is b then z is c\n";
  const std::string formatted = format_ok(text);
  CHECK(formatted.find("  type nonsense\n") != std::string::npos);
  CHECK(formatted.find("input x in [0, 1] \"kg/m^3\"\n  a is blob(zeta 1, alpha 2)\n") != std::string::npos);
  CHECK(format_ok(formatted) == formatted);
}

}  // namespace
}  // namespace fmpc

// check_system / check_rule_file: every semantic error, its message, its position; and that valid systems (a
// hand-written one, seeded random ones, MATLAB's own example files) give none.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "compiler/frontend/matlab_fis.h"
#include "diagnostics/number_format.h"
#include "compiler/sema/check.h"
#include "tests/support/ir_builders.h"
#include "tests/support/random_system.h"

namespace fmpc {
namespace {

using testing::at;
using testing::clause;
using testing::rule;
using testing::term;
using testing::variable;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

FuzzySystem valid_mamdani() { return testing::two_input_mamdani(); }

FuzzySystem valid_sugeno() {
  FuzzySystem s = valid_mamdani();
  s.type = SystemType::Sugeno;
  s.defuzzifier = Defuzzifier::WeightedAverage;
  s.outputs[0].terms = {term("small", MfKind::Constant, {0}, 9), term("medium", MfKind::Linear, {0.02, 0.03, 0.1}, 10),
                        term("big", MfKind::Constant, {1}, 11)};
  return s;
}

DiagnosticList checked(const FuzzySystem& system) {
  DiagnosticList diagnostics;
  check_system(system, diagnostics);
  return diagnostics;
}

// The single diagnostic of `system`, which must be an error.
Diagnostic only_error(const FuzzySystem& system) {
  const DiagnosticList diagnostics = checked(system);
  INFO(render_all(diagnostics, SourceFiles{}));
  REQUIRE(diagnostics.items().size() == 1);
  REQUIRE(diagnostics.items()[0].severity == Severity::Error);
  CHECK(diagnostics.items()[0].code.empty());
  return diagnostics.items()[0];
}

void require_position(const Diagnostic& diagnostic, int line, int column) {
  CHECK(diagnostic.range.file == "t.fis");
  CHECK(diagnostic.range.line == line);
  CHECK(diagnostic.range.column == column);
}

Diagnostic error_for_input_term(MfKind kind, std::vector<double> params) {
  FuzzySystem s = valid_mamdani();
  s.inputs[0].terms[1] = term("high", kind, std::move(params), 4);
  const Diagnostic d = only_error(s);
  require_position(d, 4, 3);
  CHECK(d.range.end_column == 40);
  return d;
}

bool no_errors_for_input_term(MfKind kind, std::vector<double> params) {
  FuzzySystem s = valid_mamdani();
  s.inputs[0].terms[1] = term("high", kind, std::move(params), 4);
  const DiagnosticList diagnostics = checked(s);
  INFO(render_all(diagnostics, SourceFiles{}));
  return diagnostics.empty();
}

TEST_CASE("valid systems give no diagnostics", "[check]") {
  CHECK(checked(valid_mamdani()).empty());
  CHECK(checked(valid_sugeno()).empty());
  FuzzySystem wtsum = valid_sugeno();
  wtsum.defuzzifier = Defuzzifier::WeightedSum;
  CHECK(checked(wtsum).empty());
  for (Defuzzifier d : {Defuzzifier::Bisector, Defuzzifier::MeanOfMaximum, Defuzzifier::SmallestOfMaximum,
                        Defuzzifier::LargestOfMaximum}) {
    FuzzySystem s = valid_mamdani();
    s.defuzzifier = d;
    CHECK(checked(s).empty());
  }
}

TEST_CASE("gaussian sds must be positive", "[check]") {
  CHECK(error_for_input_term(MfKind::Gaussian, {0, 5}).message ==
        "term 'high' of 'x' has sd 0; the sd of a gaussian must be greater than 0");
  CHECK(error_for_input_term(MfKind::Gaussian, {-1.5, 5}).message ==
        "term 'high' of 'x' has sd -1.5; the sd of a gaussian must be greater than 0");
  CHECK(no_errors_for_input_term(MfKind::Gaussian, {1e-3, 5}));
  CHECK(error_for_input_term(MfKind::Gaussian2, {1, 4, 0, 6}).message ==
        "term 'high' of 'x' has sd1 1 and sd2 0; both sds of a 'gauss2mf' must be greater than 0");
  CHECK(error_for_input_term(MfKind::Gaussian2, {-2, 4, 1, 6}).message ==
        "term 'high' of 'x' has sd1 -2 and sd2 1; both sds of a 'gauss2mf' must be greater than 0");
  CHECK(no_errors_for_input_term(MfKind::Gaussian2, {1, 6, 1, 4}));  // c1 > c2: subnormal, as MATLAB allows
}

TEST_CASE("triangle, trapezoid and pi breakpoints must be in order", "[check]") {
  CHECK(error_for_input_term(MfKind::Triangle, {3, 2, 5}).message ==
        "the parameters of term 'high' of 'x' are out of order (a 3, b 2, c 5); 'trimf' needs a <= b <= c "
        "(feet a and c, peak b)");
  CHECK(error_for_input_term(MfKind::Triangle, {0, 6, 5}).message ==
        "the parameters of term 'high' of 'x' are out of order (a 0, b 6, c 5); 'trimf' needs a <= b <= c "
        "(feet a and c, peak b)");
  CHECK(no_errors_for_input_term(MfKind::Triangle, {5, 5, 5}));  // a crisp singleton is valid (lint warns)
  CHECK(no_errors_for_input_term(MfKind::Triangle, {0, 0, 5}));
  CHECK(error_for_input_term(MfKind::Trapezoid, {0, 2, 1, 5}).message ==
        "the parameters of term 'high' of 'x' are out of order (a 0, b 2, c 1, d 5); 'trapmf' needs a <= b <= c <= d "
        "(feet a and d, shoulders b and c)");
  CHECK(error_for_input_term(MfKind::Trapezoid, {0, 1, 2, 1.5}).message ==
        "the parameters of term 'high' of 'x' are out of order (a 0, b 1, c 2, d 1.5); 'trapmf' needs "
        "a <= b <= c <= d (feet a and d, shoulders b and c)");
  CHECK(no_errors_for_input_term(MfKind::Trapezoid, {-30, -30, -15, 0}));
  CHECK(error_for_input_term(MfKind::PiShape, {4, 3, 6, 8}).message ==
        "the parameters of term 'high' of 'x' are out of order (a 4, b 3, c 6, d 8); 'pimf' needs a <= b <= c <= d "
        "(feet a and d, shoulders b and c)");
  CHECK(no_errors_for_input_term(MfKind::PiShape, {0.5, 0.6, 0.6, 0.7}));
}

TEST_CASE("generalized bell width and one-sided breakpoints", "[check]") {
  CHECK(error_for_input_term(MfKind::GeneralizedBell, {0, 2, 5}).message ==
        "term 'high' of 'x' has width a 0; the width of a 'gbellmf' must not be 0");
  CHECK(no_errors_for_input_term(MfKind::GeneralizedBell, {-2, 2, 5}));  // MATLAB squares a
  CHECK(no_errors_for_input_term(MfKind::GeneralizedBell, {2, -1, 5}));
  for (MfKind kind : {MfKind::ZShape, MfKind::SShape, MfKind::LinearS, MfKind::LinearZ}) {
    INFO(matlab_name(kind));
    CHECK(error_for_input_term(kind, {8, 2}).message ==
          std::string("the parameters of term 'high' of 'x' are out of order (a 8, b 2); '") + matlab_name(kind) +
              "' needs a <= b (a == b for a crisp step)");
    CHECK(no_errors_for_input_term(kind, {4, 4}));
    CHECK(no_errors_for_input_term(kind, {2, 8}));
  }
  CHECK(no_errors_for_input_term(MfKind::Sigmoid, {-3, 5}));
  CHECK(no_errors_for_input_term(MfKind::Sigmoid, {0, 5}));
  CHECK(no_errors_for_input_term(MfKind::DifferenceSigmoid, {5, 2, 5, 7}));
  CHECK(no_errors_for_input_term(MfKind::ProductSigmoid, {2, 3, -5, 8}));
}

TEST_CASE("parameter counts, MATLAB's zero padding and non-finite parameters", "[check]") {
  CHECK(error_for_input_term(MfKind::Triangle, {0, 5}).message ==
        "term 'high' of 'x' is 'trimf' with 2 parameters; it takes 3 (a b c)");
  CHECK(error_for_input_term(MfKind::Gaussian, {}).message ==
        "term 'high' of 'x' is 'gaussmf' with 0 parameters; it takes 2 (sd mean)");
  CHECK(error_for_input_term(MfKind::Triangle, {0, 5, 10, 1}).message ==
        "term 'high' of 'x' is 'trimf' with 4 parameters; it takes 3 (a b c)");
  CHECK(no_errors_for_input_term(MfKind::Triangle, {0, 5, 10, 0}));  // shower.fis: "trimf [-10 0 10 0]"
  CHECK(no_errors_for_input_term(MfKind::Gaussian, {0.2, 0.5, 0, 0}));
  CHECK(error_for_input_term(MfKind::Gaussian, {kNaN, 5}).message ==
        "parameter sd of term 'high' of 'x' is nan; parameters must be finite numbers");
  CHECK(error_for_input_term(MfKind::Trapezoid, {0, 1, 2, kInf}).message ==
        "parameter d of term 'high' of 'x' is inf; parameters must be finite numbers");
  CHECK(error_for_input_term(MfKind::Triangle, {-kInf, 0, 1}).message ==
        "parameter a of term 'high' of 'x' is -inf; parameters must be finite numbers");
}

TEST_CASE("term kinds must fit the variable and the system type", "[check]") {
  CHECK(error_for_input_term(MfKind::Constant, {3}).message ==
        "term 'high' of 'x' is 'constant', which only a sugeno output can be; give the input a membership "
        "function such as 'trimf' or 'gaussmf'");
  CHECK(error_for_input_term(MfKind::Linear, {1, 2, 3}).message ==
        "term 'high' of 'x' is 'linear', which only a sugeno output can be; give the input a membership "
        "function such as 'trimf' or 'gaussmf'");

  FuzzySystem mamdani = valid_mamdani();
  mamdani.outputs[0].terms[2] = term("big", MfKind::Constant, {1}, 11);
  Diagnostic d = only_error(mamdani);
  require_position(d, 11, 3);
  CHECK(d.message ==
        "term 'big' of 'z' is 'constant', which only a sugeno output can be; use a membership function such as "
        "'trimf' or 'gaussmf', or make the system sugeno");

  FuzzySystem sugeno = valid_sugeno();
  sugeno.outputs[0].terms[0] = term("small", MfKind::Gaussian, {0.1, 0}, 9);
  d = only_error(sugeno);
  require_position(d, 9, 3);
  CHECK(d.message ==
        "term 'small' of 'z' is 'gaussmf', but the outputs of a sugeno system are 'constant' or 'linear'; use one "
        "of those or make the system mamdani");

  sugeno = valid_sugeno();
  sugeno.outputs[0].terms[1].mf.params = {1, 2};
  d = only_error(sugeno);
  require_position(d, 10, 3);
  CHECK(d.message ==
        "term 'medium' of 'z' is 'linear' with 2 coefficients; it needs 3 (one per input, in input order, then the "
        "constant)");
  sugeno.outputs[0].terms[1].mf.params = {1, 2, 3, 0};
  CHECK(only_error(sugeno).message ==
        "term 'medium' of 'z' is 'linear' with 4 coefficients; it needs 3 (one per input, in input order, then the "
        "constant)");
  sugeno.outputs[0].terms[1].mf.params = {1, kNaN, 3};
  CHECK(only_error(sugeno).message ==
        "coefficient 2 of term 'medium' of 'z' is nan; parameters must be finite numbers");

  sugeno = valid_sugeno();
  sugeno.outputs[0].terms[0].mf.params = {};
  CHECK(only_error(sugeno).message == "term 'small' of 'z' is 'constant' with 0 parameters; it takes 1 (c)");
}

TEST_CASE("variable ranges must be finite and non-empty", "[check]") {
  FuzzySystem s = valid_mamdani();
  s.inputs[1].min = 10;
  s.inputs[1].max = 0;
  Diagnostic d = only_error(s);
  require_position(d, 5, 1);
  CHECK(d.message == "the range [10, 0] of input 'y' is inverted; write the smaller bound first");

  s = valid_mamdani();
  s.inputs[1].min = 10;
  d = only_error(s);
  CHECK(d.message == "the range [10, 10] of input 'y' is empty; the upper bound must be greater than the lower one");

  s = valid_mamdani();
  s.outputs[0].max = kInf;
  d = only_error(s);
  require_position(d, 8, 1);
  CHECK(d.message == "the range [0, inf] of output 'z' is not finite; give finite bounds");

  s = valid_mamdani();
  s.inputs[0].min = kNaN;
  CHECK(only_error(s).message == "the range [nan, 10] of input 'x' is not finite; give finite bounds");

  // MATLAB's juggler.fis: a Sugeno output's range is never used, [0 0] is accepted.
  FuzzySystem sugeno = valid_sugeno();
  sugeno.outputs[0].min = 0;
  sugeno.outputs[0].max = 0;
  CHECK(checked(sugeno).empty());
  sugeno.outputs[0].min = 1;
  CHECK(only_error(sugeno).message == "the range [1, 0] of output 'z' is inverted; write the smaller bound first");
}

TEST_CASE("duplicate names", "[check]") {
  FuzzySystem s = valid_mamdani();
  s.outputs[0].name = "x";
  s.outputs[0].name_range = at(8, 8, 9);
  Diagnostic d = only_error(s);
  require_position(d, 8, 8);
  CHECK(d.message ==
        "variable 'x' is defined twice (inputs and outputs share one namespace); rename one of them");
  CHECK(d.notes == std::vector<std::string>{"first defined here: 2:7"});

  s.inputs[0].name_range = SourceRange{};
  CHECK(only_error(s).notes == std::vector<std::string>{"first defined as input 1"});

  s = valid_mamdani();
  s.inputs[1].name = "x";
  s.outputs[0].name = "x";
  const DiagnosticList both = checked(s);
  REQUIRE(both.error_count() == 2);
  CHECK(both.items()[0].range.line == 5);
  CHECK(both.items()[1].range.line == 8);
  CHECK(both.items()[1].notes == std::vector<std::string>{"first defined here: 2:7"});

  s = valid_mamdani();
  s.outputs[0].terms[2].name = "small";
  d = only_error(s);
  require_position(d, 11, 3);
  CHECK(d.range.end_column == 6);  // the name range of the term once called 'big'
  CHECK(d.message == "term 'small' is defined twice in output 'z'; rename one of them");
  CHECK(d.notes == std::vector<std::string>{"first defined here: 9:3"});

  // Same term name in different variables is fine ('low' in x and y above); names are case-sensitive.
  s = valid_mamdani();
  s.outputs[0].terms[2].name = "Small";
  CHECK(checked(s).empty());
}

TEST_CASE("rules: unresolved clauses, missing parts, weights", "[check]") {
  FuzzySystem s = valid_mamdani();
  s.rules[1].antecedent[1].variable = 2;
  Diagnostic d = only_error(s);
  require_position(d, 13, 25);
  CHECK(d.message == "r2 refers to input number 3, but the system has 2 inputs; name an existing one");

  s = valid_mamdani();
  s.rules[1].antecedent[0].variable = -1;
  CHECK(only_error(s).message == "r2 refers to input number 0, but the system has 2 inputs; name an existing one");

  s = valid_mamdani();
  s.rules[0].consequent[0].variable = 1;
  d = only_error(s);
  require_position(d, 12, 40);
  CHECK(d.message == "r1 refers to output number 2, but the system has 1 output; name an existing one");

  s = valid_mamdani();
  s.rules[2].antecedent[0].term = 2;
  d = only_error(s);
  require_position(d, 14, 9);
  CHECK(d.message == "r3 refers to term number 3 of 'x', which has 2 terms; name an existing one");

  s = valid_mamdani();
  s.rules[3].label.clear();
  s.rules[3].consequent[0].term = -1;
  CHECK(only_error(s).message == "rule 4 refers to term number 0 of 'z', which has 3 terms; name an existing one");

  s = valid_mamdani();
  s.rules[0].antecedent.clear();
  d = only_error(s);
  require_position(d, 12, 1);
  CHECK(d.message == "r1 has no condition; give it at least one 'if INPUT is TERM'");

  s = valid_mamdani();
  s.rules[0].consequent.clear();
  CHECK(only_error(s).message == "r1 has no conclusion; give it at least one 'then OUTPUT is TERM'");

  s = valid_mamdani();
  s.rules[1].antecedent[1] = clause(0, 1, 13, 25);
  d = only_error(s);
  require_position(d, 13, 25);
  CHECK(d.message == "r2 mentions 'x' twice; a rule takes one clause per variable, so split it into two rules");
  CHECK(d.notes == std::vector<std::string>{"first mentioned here: 13:9"});

  for (double weight : {1.5, -0.25, kNaN, kInf}) {
    s = valid_mamdani();
    s.rules[2].weight = weight;
    d = only_error(s);
    require_position(d, 14, 1);
    CHECK(d.message == "the weight of r3 is " + format_number(weight) + "; weights lie between 0 and 1");
  }
  for (double weight : {0.0, 1.0, 0.5}) {
    s = valid_mamdani();
    s.rules[2].weight = weight;
    CHECK(checked(s).empty());
  }
}

TEST_CASE("system settings: defuzzifier, samples, outputs, no-fire value", "[check]") {
  FuzzySystem s = valid_mamdani();
  s.defuzzifier = Defuzzifier::WeightedAverage;
  Diagnostic d = only_error(s);
  require_position(d, 1, 1);
  CHECK(d.message == "defuzzifier 'wtaver' is for sugeno systems; a mamdani system uses 'centroid', 'bisector', "
                     "'mom', 'som' or 'lom'");

  s = valid_sugeno();
  s.defuzzifier = Defuzzifier::LargestOfMaximum;
  CHECK(only_error(s).message == "defuzzifier 'lom' is for mamdani systems; a sugeno system uses 'wtaver' or 'wtsum'");

  for (int samples : {1, -3}) {
    s = valid_mamdani();
    s.samples = samples;
    CHECK(only_error(s).message ==
          "samples is " + std::to_string(samples) + "; use at least 2 output samples, or 'exact'");
  }
  for (int samples : {0, 2, 1001}) {
    s = valid_mamdani();
    s.samples = samples;
    CHECK(checked(s).empty());
  }

  s = valid_mamdani();
  s.outputs.clear();
  s.rules.clear();
  CHECK(only_error(s).message == "system 'demo' has no output; add one");

  s = valid_mamdani();
  s.no_fire = NoFirePolicy::Value;
  s.no_fire_value = 0.5;
  CHECK(checked(s).empty());
  s.no_fire_value = 1.5;
  const DiagnosticList warned = checked(s);
  REQUIRE(warned.items().size() == 1);
  CHECK(warned.items()[0].severity == Severity::Warning);
  CHECK(warned.items()[0].code == "no-fire-out-of-range");
  CHECK(warned.items()[0].message ==
        "the value used when no rule fires, 1.5, lies outside the range [0, 1] of output 'z'; pick a value inside it");
  s.no_fire_value = kNaN;
  CHECK(only_error(s).message == "the value used when no rule fires is nan; give a finite number");
  s.no_fire = NoFirePolicy::Midrange;  // the value is not used then
  CHECK(checked(s).empty());
}

TEST_CASE("every error at once, each at its own position", "[check]") {
  FuzzySystem s = valid_mamdani();
  s.inputs[0].terms[0].mf.params = {5, 0, 10};
  s.inputs[1].terms[1].mf.params = {0, 10};
  s.rules[3].weight = 7;
  s.samples = 1;
  DiagnosticList diagnostics = checked(s);
  CHECK(diagnostics.error_count() == 4);
  diagnostics.sort_by_position();
  std::vector<int> lines;
  for (const Diagnostic& d : diagnostics.items()) lines.push_back(d.range.line);
  CHECK(lines == std::vector<int>{1, 3, 7, 15});
}

TEST_CASE("rendered error with caret", "[check]") {
  FuzzySystem s = valid_mamdani();
  s.inputs[1].terms[0].mf.params = {-1, 0};
  s.inputs[1].terms[0].range = at(6, 3, 26);
  SourceFiles sources;
  sources.add("t.fis", "system demo\ninput x\n  low\n  high\ninput y\n  low is gauss(mean 0, sd -1)\n");
  CHECK(render_all(checked(s), sources) ==
        "t.fis:6:3: error: term 'low' of 'y' has sd -1; the sd of a gaussian must be greater than 0\n"
        " 6 |   low is gauss(mean 0, sd -1)\n"
        "   |   ^~~~~~~~~~~~~~~~~~~~~~~\n");
}

TEST_CASE("seeded random valid systems pass", "[check]") {
  for (std::uint64_t seed = 1; seed <= 300; ++seed) {
    const FuzzySystem s = testing::random_system(seed);
    const DiagnosticList diagnostics = checked(s);
    INFO("seed " << seed << "\n" << render_all(diagnostics, SourceFiles{}));
    CHECK(!diagnostics.has_errors());
  }
}

TEST_CASE("MATLAB's example files pass check", "[check]") {
  const std::filesystem::path folder = std::filesystem::path(FMPC_SHARED_DATA_DIR) / "matlab-fis";
  if (!std::filesystem::is_directory(folder)) {
    WARN("skipped: " << folder.string() << " is absent");
    return;
  }
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.path().extension() != ".fis") continue;
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    DiagnosticList read_diagnostics;
    const RuleFile file = read_matlab_fis(entry.path().string(), text.str(), read_diagnostics);
    INFO(entry.path().filename().string() << "\n" << render_all(read_diagnostics, SourceFiles{}));
    REQUIRE(file.systems.size() == 1);
    CheckOptions matlab;
    matlab.terms_named_by_index = true;
    DiagnosticList diagnostics;
    check_system(file.systems[0], matlab, diagnostics);
    INFO(render_all(diagnostics, SourceFiles{}));
    CHECK(diagnostics.error_count() == 0);
    // juggler.fis names all nine output terms 'out1mf' (its rules use numbers): eight repeats.
    const bool juggler = entry.path().filename() == "takagi-sugeno_matlab_juggler.fis";
    CHECK(diagnostics.warning_count() == (juggler ? 8u : 0u));
    ++files;
  }
  CHECK(files == 28);
}

TEST_CASE("repeated term names are a warning when rules name terms by number", "[check]") {
  FuzzySystem s = valid_mamdani();
  s.outputs[0].terms[1].name = "small";
  CheckOptions matlab;
  matlab.terms_named_by_index = true;
  DiagnosticList diagnostics;
  check_system(s, matlab, diagnostics);
  REQUIRE(diagnostics.items().size() == 1);
  const Diagnostic& d = diagnostics.items()[0];
  CHECK(d.severity == Severity::Warning);
  CHECK(d.code == "duplicate-term");
  require_position(d, 10, 3);
  CHECK(d.message ==
        "term 'small' is defined twice in output 'z'; rules refer to it by number here, but give each term its own "
        "name");
  CHECK(d.notes == std::vector<std::string>{"first defined here: 9:3"});
}

}  // namespace
}  // namespace fmpc

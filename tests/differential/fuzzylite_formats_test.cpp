// FLL and FCL (compiler/frontend/fll.h): fmpc's own readers and writers, round trips that keep every field, and
// differential tests against fuzzylite's importers and exporters (fuzzylite is GPL: linked into the tests only).
// Located diagnostics and recognition by content are checked on hand-written files.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "compiler/eval/interpreter.h"
#include "compiler/frontend/fll.h"
#include "compiler/frontend/rule_file_loader.h"
#include "compiler/sema/check.h"
#include "tests/support/random_system.h"
#include "tests/support/system_comparison.h"

#if FMPC_HAVE_FUZZYLITE
#include <fl/Headers.h>
#endif

namespace {

using namespace fmpc;

constexpr std::uint64_t kRandomSystems = 200;

std::string rendered(const DiagnosticList& diagnostics, const std::string& path, const std::string& text) {
  SourceFiles sources;
  sources.add(path, text);
  return render_all(diagnostics, sources);
}

// The systems FLL and FCL can hold: fuzzylite's preset plus the hedges both mean alike.
testing::RandomSystemOptions fuzzylite_formats() {
  testing::RandomSystemOptions options = testing::RandomSystemOptions::fuzzylite();
  options.hedges = {Hedge::None, Hedge::Somewhat, Hedge::Very, Hedge::VeryVery};
  return options;
}

FuzzySystem read_back(const std::string& format, const std::string& text) {
  DiagnosticList diagnostics;
  const RuleFile file = load_rule_file("back." + format, text, diagnostics);
  INFO(rendered(diagnostics, "back." + format, text));
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(file.systems.size() == 1);
  return file.systems[0];
}

// Largest difference between the two systems' outputs on seeded points, relative to each output's range.
double largest_difference(const FuzzySystem& a, const FuzzySystem& b, std::uint64_t seed) {
  Interpreter left(a), right(b);
  double worst = 0;
  for (const std::vector<double>& point : testing::random_inputs(a, seed, 50)) {
    const Evaluation x = left.evaluate(point), y = right.evaluate(point);
    for (std::size_t o = 0; o < x.outputs.size(); ++o) {
      if (std::isnan(x.outputs[o]) && std::isnan(y.outputs[o])) continue;
      const double range = a.outputs[o].max - a.outputs[o].min;
      worst = std::max(worst, std::fabs(x.outputs[o] - y.outputs[o]) / (range > 0 ? range : 1.0));
    }
  }
  return worst;
}

}  // namespace

TEST_CASE("FLL and FCL round trips keep every field of 200 random systems", "[fll][fcl]") {
  testing::ComparisonOptions comparison;
  comparison.descriptions_units_and_labels = false;
  for (std::uint64_t seed = 1; seed <= kRandomSystems; ++seed) {
    FuzzySystem original = testing::random_system(seed, fuzzylite_formats());
    // A rule with one condition has no connective in FLL or FCL (nor any use for one).
    for (Rule& rule : original.rules)
      if (rule.antecedent.size() < 2) rule.connective = Connective::And;
    INFO("seed " << seed);
    DiagnosticList written;
    const std::string fll = write_fll(original, written);
    REQUIRE_FALSE(written.has_errors());
    CHECK(detect_dialect(fll) == Dialect::Fll);
    CHECK(testing::first_difference(original, read_back("fll", fll)) == "");

    // FCL has no defuzzification resolution: fuzzylite and fmpc read COG with 100 points.
    if (original.type == SystemType::Mamdani) original.samples = 100;
    const std::string fcl = write_fcl(original, written);
    REQUIRE_FALSE(written.has_errors());
    CHECK(detect_dialect(fcl) == Dialect::Fcl);
    CHECK(testing::first_difference(original, read_back("fcl", fcl)) == "");
  }
}

TEST_CASE("what FLL and FCL cannot hold is an error or a warning naming it", "[fll][fcl]") {
  FuzzySystem system = testing::random_system(3, fuzzylite_formats());
  system.inputs[0].unit = "kPa";
  DiagnosticList diagnostics;
  write_fll(system, diagnostics);
  REQUIRE(diagnostics.warning_count() == 1);
  CHECK(diagnostics.items()[0].code == "format-difference");
  CHECK(diagnostics.items()[0].message.find("kPa") != std::string::npos);

  FuzzySystem extreme = testing::random_system(4, fuzzylite_formats());
  extreme.rules[0].antecedent[0].hedge = Hedge::Extremely;
  DiagnosticList refused;
  write_fll(extreme, refused);
  CHECK(refused.has_errors());
  DiagnosticList refused_fcl;
  write_fcl(extreme, refused_fcl);
  CHECK(refused_fcl.has_errors());
}

TEST_CASE("FLL errors name the line and column, and what to do", "[fll]") {
  const std::string text =
      "# a comment first\n"
      "Engine: demo\n"
      "InputVariable: x\n"
      "  range: 0 10\n"
      "  term: low Triangle 0 0 5\n"
      "  term: high Triangel 5 10 10\n"
      "  rnage: 0 1\n"
      "OutputVariable: z\n"
      "  range: 0 1\n"
      "  defuzzifier: Centroid 100\n"
      "  term: small Triangle 0 0 1\n"
      "RuleBlock: rules\n"
      "  rule: if x is low or x is extremely low then z is small\n"
      "  rule: if x is low and x is low or x is low then z is small\n";
  CHECK(detect_dialect(text) == Dialect::Fll);
  DiagnosticList diagnostics;
  load_rule_file("demo.fll", text, diagnostics);
  const std::string out = rendered(diagnostics, "demo.fll", text);
  INFO(out);
  CHECK(out.find("demo.fll:6:9: error: 'Triangel' is not a membership function fmpc has") != std::string::npos);
  CHECK(out.find("demo.fll:7:3: error: 'rnage' is not a key of an FLL input variable") != std::string::npos);
  CHECK(out.find("did you mean 'range'?") != std::string::npos);
  CHECK(out.find("demo.fll:13:29: error: hedge 'extremely' has no fmpc counterpart") != std::string::npos);
  CHECK(out.find("demo.fll:14:34: error: the rule mixes 'and' and 'or'") != std::string::npos);
}

TEST_CASE("FCL errors name the line and column", "[fcl]") {
  const std::string text =
      "FUNCTION_BLOCK demo\n"
      "VAR_INPUT\n"
      "  x : REAL;\n"
      "END_VAR\n"
      "VAR_OUTPUT\n"
      "  z : REAL;\n"
      "END_VAR\n"
      "FUZZIFY y\n"
      "  RANGE := (0 .. 10);\n"
      "END_FUZZIFY\n"
      "DEFUZZIFY z\n"
      "  RANGE := (0 .. 1);\n"
      "  TERM small := Triangle 0 0 1;\n"
      "  METHOD : XYZ;\n"
      "END_DEFUZZIFY\n"
      "RULEBLOCK rules\n"
      "  RULE 1 : if x is low then z is small;\n";
  CHECK(detect_dialect(text) == Dialect::Fcl);
  DiagnosticList diagnostics;
  load_rule_file("demo.fcl", text, diagnostics);
  const std::string out = rendered(diagnostics, "demo.fcl", text);
  INFO(out);
  CHECK(out.find("demo.fcl:8:9: error: 'y' is not declared in VAR_INPUT") != std::string::npos);
  CHECK(out.find("demo.fcl:14:12: error: 'XYZ' is not a method fmpc has") != std::string::npos);
  CHECK(out.find("demo.fcl:17:20: error: 'low' is not a term of 'x'") != std::string::npos);
  CHECK(out.find("the file ends inside a block") != std::string::npos);
}

TEST_CASE("a file is recognised by its content, and a format fmpc does not read is named", "[fll][fcl]") {
  CHECK(detect_dialect("// comment\n(* block\ncomment *)\nFUNCTION_BLOCK x\n") == Dialect::Fcl);
  CHECK(detect_dialect("\n# c\nEngine: e\n") == Dialect::Fll);
  CHECK(detect_dialect("% c\n[System]\n") == Dialect::Matlab);
  CHECK(detect_dialect("system s\n") == Dialect::Fmpc);
  const std::pair<const char*, const char*> foreign[] = {
      {"<?xml version=\"1.0\"?>\n<fuzzySystem/>\n", "an XML file"},
      {"{\"engine\": 1}\n", "a JSON file"},
      {"name: liver\nmesh: {box: {}}\n", "a YAML file"},
      {"HCV,HBV,ALD\n1,2,3\n", "CSV data"}};
  for (const auto& [text, named] : foreign) {
    DiagnosticList diagnostics;
    const RuleFile file = load_rule_file("input.txt", text, diagnostics);
    REQUIRE(diagnostics.error_count() == 1);
    CHECK(diagnostics.items()[0].message.find(named) != std::string::npos);
    CHECK(file.systems.empty());
  }
}

#if FMPC_HAVE_FUZZYLITE
TEST_CASE("fuzzylite's importers read fmpc's FLL and FCL, and fmpc reads what its exporters write", "[fll][fcl][fuzzylite]") {
  fl::fuzzylite::setDecimals(17);
  double worst_fll = 0, worst_fcl = 0;
  for (std::uint64_t seed = 1; seed <= kRandomSystems; ++seed) {
    FuzzySystem original = testing::random_system(seed, fuzzylite_formats());
    if (original.type == SystemType::Mamdani) original.samples = 100;
    INFO("seed " << seed);
    DiagnosticList written;
    for (const std::string format : {"fll", "fcl"}) {
      INFO(format);
      const std::string ours = format == "fll" ? write_fll(original, written) : write_fcl(original, written);
      std::unique_ptr<fl::Engine> engine;
      try {
        engine.reset(format == "fll" ? fl::FllImporter().fromString(ours) : fl::FclImporter().fromString(ours));
      } catch (const std::exception& e) {
        FAIL("fuzzylite refused fmpc's " << format << ": " << e.what() << "\n" << ours);
      }
      REQUIRE(engine->numberOfInputVariables() == original.inputs.size());
      REQUIRE(engine->numberOfOutputVariables() == original.outputs.size());
      REQUIRE(engine->numberOfRuleBlocks() == 1);
      CHECK(engine->getRuleBlock(0)->numberOfRules() == original.rules.size());
      const std::string theirs =
          format == "fll" ? fl::FllExporter().toString(engine.get()) : fl::FclExporter().toString(engine.get());
      const FuzzySystem back = read_back(format, theirs);
      // fuzzylite prints numbers with fixed decimals, so the parameters come back within rounding, not bit for bit.
      CHECK(back.rules.size() == original.rules.size());
      CHECK(back.defuzzifier == original.defuzzifier);
      CHECK(back.and_method == original.and_method);
      CHECK(back.or_method == original.or_method);
      CHECK(back.no_fire == original.no_fire);
      const double difference = largest_difference(original, back, seed * 31);
      // Bisector and the maximum methods pick a sample: a parameter rounded in the last digit can move them by one
      // sample step (1/99 of the range at 100 samples). Centroid and the weighted means move continuously.
      const bool picks_a_sample = original.type == SystemType::Mamdani && original.defuzzifier != Defuzzifier::Centroid;
      if (picks_a_sample) CHECK(difference <= 1.0 / (original.samples - 1) + 1e-9);
      else (format == "fll" ? worst_fll : worst_fcl) = std::max(format == "fll" ? worst_fll : worst_fcl, difference);
    }
  }
  INFO("worst FLL " << worst_fll << ", worst FCL " << worst_fcl);
  CHECK(worst_fll <= 1e-9);
  CHECK(worst_fcl <= 1e-9);
}
#endif

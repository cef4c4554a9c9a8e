// MATLAB .fis reader and writer: every key and rule-line feature, errors with positions, the real files in
// ../shared/data/matlab-fis, and the seeded random-system generator the round-trip tests rely on.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "compiler/eval/output_comparison.h"
#include "compiler/frontend/matlab_fis.h"
#include "diagnostics/number_format.h"
#include "tests/support/random_system.h"
#include "tests/support/system_comparison.h"

namespace {

using namespace fmpc;

struct ReadResult {
  RuleFile file;
  DiagnosticList diagnostics;
  const FuzzySystem& system() const { return file.systems.at(0); }
};

ReadResult read(const std::string& text) {
  ReadResult result;
  result.file = read_matlab_fis("test.fis", text, result.diagnostics);
  return result;
}

std::string rendered(const DiagnosticList& diagnostics, const std::string& text) {
  SourceFiles sources;
  sources.add("test.fis", text);
  return render_all(diagnostics, sources);
}

// The diagnostic of `severity` at line:column whose message contains `fragment`, or nullptr.
const Diagnostic* find(const DiagnosticList& diagnostics, Severity severity, int line, int column,
                       const std::string& fragment) {
  for (const Diagnostic& diagnostic : diagnostics.items())
    if (diagnostic.severity == severity && diagnostic.range.line == line && diagnostic.range.column == column &&
        diagnostic.message.find(fragment) != std::string::npos)
      return &diagnostic;
  return nullptr;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

const char* const kTipper = R"(% $Revision: 1.1 $
[System]
Name='tipper'
Type='mamdani'
NumInputs=2
NumOutputs=1
NumRules=3
AndMethod='min'
OrMethod='max'
ImpMethod='min'
AggMethod='max'
DefuzzMethod='centroid'

[Input1]
Name='service'
Range=[0 10]
NumMFs=3
MF1='poor':'gaussmf',[1.5 0]
MF2='good':'gaussmf',[1.5 5]
MF3='excellent':'gaussmf',[1.5 10]

[Input2]
Name='food'
Range=[0 10]
NumMFs=2
MF1='rancid':'trapmf',[0 0 1 3]
MF2='delicious':'trapmf',[7 9 10 10]

[Output1]
Name='tip'
Range=[0 30]
NumMFs=3
MF1='cheap':'trimf',[0 5 10]
MF2='average':'trimf',[10 15 20]
MF3='generous':'trimf',[20 25 30]

[Rules]
1 1, 1 (1) : 2
2 0, 2 (1) : 1
3 2, 3 (1) : 2)";

// A minimal valid file around a [Rules] body, for rule-line tests: inputs a (3 MFs), b (2 MFs); output o (2 MFs).
std::string with_rules(const std::string& rules, const std::string& num_rules = "") {
  std::string count = num_rules;
  if (count.empty()) {
    std::size_t lines = 0;
    std::istringstream in(rules);
    for (std::string line; std::getline(in, line);)
      if (line.find_first_not_of(" \t\r") != std::string::npos) ++lines;
    count = std::to_string(lines);
  }
  return "[System]\nName='s'\nType='mamdani'\nNumInputs=2\nNumOutputs=1\nNumRules=" + count +
         "\n\n[Input1]\nName='a'\nRange=[0 1]\nNumMFs=3\nMF1='x':'trimf',[0 0 0.5]\nMF2='y':'trimf',[0 0.5 1]\n"
         "MF3='z':'trimf',[0.5 1 1]\n\n[Input2]\nName='b'\nRange=[0 1]\nNumMFs=2\nMF1='p':'zmf',[0 1]\n"
         "MF2='q':'smf',[0 1]\n\n[Output1]\nName='o'\nRange=[0 1]\nNumMFs=2\nMF1='lo':'trimf',[0 0 1]\n"
         "MF2='hi':'trimf',[0 1 1]\n\n[Rules]\n" +
         rules;
}
constexpr int kRulesFirstLine = 31;  // line of the first rule in with_rules()

}  // namespace

TEST_CASE("MATLAB .fis: reads tipper with every field and source range", "[matlab-fis]") {
  const ReadResult result = read(kTipper);
  INFO(rendered(result.diagnostics, kTipper));
  REQUIRE(result.diagnostics.empty());
  REQUIRE(result.file.systems.size() == 1);
  const FuzzySystem& system = result.system();
  CHECK(result.file.path == "test.fis");
  CHECK(system.name == "tipper");
  CHECK(system.type == SystemType::Mamdani);
  CHECK(system.and_method == TNorm::Minimum);
  CHECK(system.or_method == SNorm::Maximum);
  CHECK(system.implication == TNorm::Minimum);
  CHECK(system.aggregation == SNorm::Maximum);
  CHECK(system.defuzzifier == Defuzzifier::Centroid);
  CHECK(system.samples == 101);
  CHECK(system.no_fire == NoFirePolicy::Midrange);
  CHECK(system.range.line == 2);
  CHECK(system.range.column == 1);

  REQUIRE(system.inputs.size() == 2);
  REQUIRE(system.outputs.size() == 1);
  const Variable& service = system.inputs[0];
  CHECK(service.name == "service");
  CHECK(service.unit.empty());
  CHECK(service.min == 0.0);
  CHECK(service.max == 10.0);
  CHECK(service.range.line == 14);
  CHECK(service.name_range.line == 15);
  CHECK(service.name_range.column == 7);
  CHECK(service.name_range.end_column == 14);
  REQUIRE(service.terms.size() == 3);
  CHECK(service.terms[2].name == "excellent");
  CHECK(service.terms[2].mf.kind == MfKind::Gaussian);
  CHECK(service.terms[2].mf.params == std::vector<double>{1.5, 10.0});
  CHECK(service.terms[2].range.line == 20);
  CHECK(service.terms[2].range.column == 1);
  CHECK(service.terms[2].name_range.column == 6);
  CHECK(service.terms[2].name_range.end_column == 15);
  CHECK(system.inputs[1].terms[1].mf.params == std::vector<double>{7, 9, 10, 10});

  REQUIRE(system.rules.size() == 3);
  const Rule& first = system.rules[0];
  CHECK(first.connective == Connective::Or);
  CHECK(first.weight == 1.0);
  CHECK(first.label.empty());
  REQUIRE(first.antecedent.size() == 2);
  CHECK(first.antecedent[1].variable == 1);
  CHECK(first.antecedent[1].term == 0);
  CHECK_FALSE(first.antecedent[1].negated);
  CHECK(first.antecedent[1].hedge == Hedge::None);
  CHECK(first.antecedent[1].range.line == 38);
  CHECK(first.antecedent[1].range.column == 3);
  REQUIRE(first.consequent.size() == 1);
  CHECK(first.consequent[0].term == 0);
  CHECK(first.range.line == 38);
  CHECK(first.range.end_column == 15);
  // "2 0": the 0 leaves food out of the rule (don't care).
  REQUIRE(system.rules[1].antecedent.size() == 1);
  CHECK(system.rules[1].antecedent[0].variable == 0);
  CHECK(system.rules[1].connective == Connective::And);
}

TEST_CASE("MATLAB .fis: spaces, blank lines, comments, CRLF and a byte order mark", "[matlab-fis]") {
  const std::string text =
      "\xEF\xBB\xBF## Octave style header\r\n\r\n[System]\r\n\r\n  Name = 'Heart-Disease Risk'   % MATLAB comment\r\n"
      "  Type = 'sugeno'\r\n  Version = 2.0\r\n  NumInputs = 1\r\n  NumOutputs = 1\r\n  NumRules = 1\r\n"
      "  # Octave comment\r\n[Input1]\r\n  Name = 'LDL Level-x'\r\n  Range = [ -1.5e2  3.1415926 ]\r\n"
      "  NumMFs = 1\r\n  MF1 = 'Low-Borderline'  : 'trapmf', [-1, 0, 90, 110]\r\n[Output1]\r\n"
      "  Name = 'Risk'\r\n  Range = [0 10]\r\n  NumMFs = 1\r\n  MF1 = 'No Risk' : 'constant', [0]\r\n"
      "[Rules]\r\n\r\n  1, 1 (1) : 1\r\n";
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  REQUIRE(result.diagnostics.empty());
  const FuzzySystem& system = result.system();
  CHECK(system.name == "Heart-Disease Risk");
  CHECK(system.type == SystemType::Sugeno);
  CHECK(system.defuzzifier == Defuzzifier::WeightedAverage);  // omitted: the Sugeno default
  CHECK(system.inputs[0].name == "LDL Level-x");
  CHECK(system.inputs[0].min == -150.0);
  CHECK(system.inputs[0].max == 3.1415926);
  CHECK(system.inputs[0].terms[0].name == "Low-Borderline");
  CHECK(system.inputs[0].terms[0].mf.params == std::vector<double>{-1, 0, 90, 110});
  CHECK(system.inputs[0].terms[0].name_range.line == 16);
  CHECK(system.inputs[0].terms[0].name_range.column == 10);
  CHECK(system.outputs[0].terms[0].name == "No Risk");
  CHECK(system.outputs[0].terms[0].mf.kind == MfKind::Constant);
  REQUIRE(system.rules.size() == 1);
  CHECK(system.rules[0].range.line == 24);
  CHECK(system.rules[0].range.column == 3);
}

TEST_CASE("MATLAB .fis: MATLAB's defaults for omitted keys, version 1 files", "[matlab-fis]") {
  const std::string text =
      "[System]\nNumInputs=1\nNumOutputs=1\nNumRules=1\n[Input1]\nName='x'\nRange=[0 1]\nNumMFs=1\n"
      "MF1='a':'trimf',[0 0.5 1]\n[Output1]\nName='y'\nRange=[0 1]\nNumMFs=1\nMF1='b':'trimf',[0 0.5 1]\n"
      "[Rules]\n1, 1 (0.25) : 1\n";
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  REQUIRE(result.diagnostics.empty());
  const FuzzySystem& system = result.system();
  CHECK(system.name == "Untitled");
  CHECK(system.type == SystemType::Mamdani);
  CHECK(system.and_method == TNorm::Minimum);
  CHECK(system.or_method == SNorm::Maximum);
  CHECK(system.implication == TNorm::Minimum);
  CHECK(system.aggregation == SNorm::Maximum);
  CHECK(system.defuzzifier == Defuzzifier::Centroid);
  CHECK(system.rules[0].weight == 0.25);
}

TEST_CASE("MATLAB .fis: every method name and MF family", "[matlab-fis]") {
  const std::string text =
      "[System]\nName='m'\nType='mamdani'\nVersion=2.0\nNumInputs=1\nNumOutputs=1\nNumRules=1\n"
      "AndMethod='einstein_product'\nOrMethod='einstein_sum'\nImpMethod='prod'\nAggMethod='probor'\n"
      "DefuzzMethod='bisector'\n[Input1]\nName='x'\nRange=[0 10]\nNumMFs=13\n"
      "MF1='a':'trimf',[0 1 2]\nMF2='b':'trapmf',[0 1 2 3]\nMF3='c':'gaussmf',[1 2]\nMF4='d':'gauss2mf',[1 2 1 3]\n"
      "MF5='e':'gbellmf',[1 2 3]\nMF6='f':'sigmf',[1 2]\nMF7='g':'dsigmf',[1 2 1 3]\nMF8='h':'psigmf',[1 2 -1 3]\n"
      "MF9='i':'zmf',[1 2]\nMF10='j':'smf',[1 2]\nMF11='k':'pimf',[1 2 3 4]\nMF12='l':'linsmf',[1 2]\n"
      "MF13='m':'linzmf',[1 2]\n[Output1]\nName='y'\nRange=[0 1]\nNumMFs=1\nMF1='o':'trimf',[0 0.5 1]\n"
      "[Rules]\n13, 1 (1) : 1\n";
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  REQUIRE(result.diagnostics.empty());
  const FuzzySystem& system = result.system();
  CHECK(system.and_method == TNorm::EinsteinProduct);
  CHECK(system.or_method == SNorm::EinsteinSum);
  CHECK(system.implication == TNorm::Product);
  CHECK(system.aggregation == SNorm::ProbabilisticSum);
  CHECK(system.defuzzifier == Defuzzifier::Bisector);
  const std::vector<MfKind> kinds = {MfKind::Triangle,        MfKind::Trapezoid, MfKind::Gaussian,
                                     MfKind::Gaussian2,       MfKind::GeneralizedBell, MfKind::Sigmoid,
                                     MfKind::DifferenceSigmoid, MfKind::ProductSigmoid, MfKind::ZShape,
                                     MfKind::SShape,          MfKind::PiShape,   MfKind::LinearS,
                                     MfKind::LinearZ};
  REQUIRE(system.inputs[0].terms.size() == kinds.size());
  for (std::size_t k = 0; k < kinds.size(); ++k) CHECK(system.inputs[0].terms[k].mf.kind == kinds[k]);
  CHECK(system.rules[0].antecedent[0].term == 12);
}

TEST_CASE("MATLAB .fis: Sugeno constant and linear outputs", "[matlab-fis]") {
  const std::string text =
      "[System]\nName='s'\nType='sugeno'\nNumInputs=2\nNumOutputs=1\nNumRules=2\nDefuzzMethod='wtsum'\n"
      "[Input1]\nName='x'\nRange=[0 1]\nNumMFs=1\nMF1='a':'trimf',[0 0.5 1]\n"
      "[Input2]\nName='z'\nRange=[0 1]\nNumMFs=1\nMF1='a':'trimf',[0 0.5 1]\n"
      "[Output1]\nName='y'\nRange=[0 1]\nNumMFs=2\nMF1='c':'constant',[0.7]\nMF2='l':'linear',[1 -2 0.5]\n"
      "[Rules]\n1 0, 1 (1) : 1\n0 1, 2 (1) : 1\n";
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  REQUIRE(result.diagnostics.empty());
  const FuzzySystem& system = result.system();
  CHECK(system.defuzzifier == Defuzzifier::WeightedSum);
  CHECK(system.outputs[0].terms[0].mf.params == std::vector<double>{0.7});
  CHECK(system.outputs[0].terms[1].mf.kind == MfKind::Linear);
  CHECK(system.outputs[0].terms[1].mf.params == std::vector<double>{1, -2, 0.5});
}

TEST_CASE("MATLAB .fis: rule entries: NOT, Octave hedge fractions, weights, connectives", "[matlab-fis]") {
  const std::string text = with_rules(
      "-1 2.05, 1 (0.5) : 1\n2.2 -1.3, 2.4 (1) : 2\n3.4 0, -1 (0) : 1\n1.30 2.20, 1.00 (1) : 1\n");
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  REQUIRE(result.diagnostics.empty());
  const auto& rules = result.system().rules;
  REQUIRE(rules.size() == 4);
  CHECK(rules[0].antecedent[0].negated);
  CHECK(rules[0].antecedent[0].term == 0);
  CHECK(rules[0].antecedent[0].hedge == Hedge::None);
  CHECK(rules[0].antecedent[1].hedge == Hedge::Somewhat);
  CHECK(rules[0].antecedent[1].term == 1);
  CHECK(rules[0].weight == 0.5);
  CHECK(rules[0].connective == Connective::And);
  CHECK(rules[1].antecedent[0].hedge == Hedge::Very);
  CHECK(rules[1].antecedent[1].negated);
  CHECK(rules[1].antecedent[1].hedge == Hedge::Extremely);
  CHECK(rules[1].consequent[0].hedge == Hedge::VeryVery);
  CHECK(rules[1].connective == Connective::Or);
  CHECK(rules[2].antecedent.size() == 1);
  CHECK(rules[2].antecedent[0].hedge == Hedge::VeryVery);
  CHECK(rules[2].consequent[0].negated);
  CHECK(rules[2].weight == 0.0);
  CHECK(rules[3].antecedent[0].hedge == Hedge::Extremely);  // Octave writes "1.30"
  CHECK(rules[3].antecedent[1].hedge == Hedge::Very);
  CHECK(rules[3].consequent[0].hedge == Hedge::None);
}

TEST_CASE("MATLAB .fis: unsupported hedge fractions and the identity fraction", "[matlab-fis]") {
  const std::string text = with_rules("1.15 1, 1 (1) : 1\n1.1 1, 1 (1) : 1\n0.2 1, 1 (1) : 1\n");
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  const Diagnostic* bad = find(result.diagnostics, Severity::Error, kRulesFirstLine, 1, "power 1.5");
  REQUIRE(bad != nullptr);
  CHECK(bad->range.end_column == 5);
  CHECK(find(result.diagnostics, Severity::Warning, kRulesFirstLine + 1, 1, "power 1") != nullptr);
  CHECK(find(result.diagnostics, Severity::Warning, kRulesFirstLine + 2, 1, "not part of rule 3") != nullptr);
  CHECK(result.diagnostics.error_count() == 1);
  // The two rules without errors are kept.
  CHECK(result.system().rules.size() == 2);
}

TEST_CASE("MATLAB .fis: rule MF index out of range: error at the number", "[matlab-fis]") {
  const std::string text = with_rules("1 2, 1 (1) : 1\n2   -3, 1 (1) : 1\n1 1, 3 (1) : 1\n");
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  CHECK(result.diagnostics.error_count() == 2);
  const Diagnostic* input = find(result.diagnostics, Severity::Error, kRulesFirstLine + 1, 5, "MF index 3");
  REQUIRE(input != nullptr);
  CHECK(input->message.find("input 'b' has 2 membership functions") != std::string::npos);
  CHECK(input->range.end_column == 7);
  CHECK(find(result.diagnostics, Severity::Error, kRulesFirstLine + 2, 6, "output 'o'") != nullptr);
}

TEST_CASE("MATLAB .fis: wrong number of rule columns: error at the offending column", "[matlab-fis]") {
  const std::string text = with_rules("1 2 3, 1 (1) : 1\n1, 1 (1) : 1\n1 1, 1 2 (1) : 1\n");
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  // Too many: at the first extra number; too few: at the separator after the last one.
  CHECK(find(result.diagnostics, Severity::Error, kRulesFirstLine, 5, "3 input columns but the system has 2") !=
        nullptr);
  CHECK(find(result.diagnostics, Severity::Error, kRulesFirstLine + 1, 2, "1 input column but the system has 2") !=
        nullptr);
  CHECK(find(result.diagnostics, Severity::Error, kRulesFirstLine + 2, 8, "2 output columns but the system has 1") !=
        nullptr);
  // A rule with no consequent number at all is not a rule line.
  const std::string no_consequent = with_rules("1 1, (1) : 1\n");
  const ReadResult syntax = read(no_consequent);
  CHECK(find(syntax.diagnostics, Severity::Error, kRulesFirstLine, 6, "syntax error") != nullptr);
  CHECK(syntax.file.systems.empty());
}

TEST_CASE("MATLAB .fis: connective other than 1 or 2, all-zero antecedent and consequent", "[matlab-fis]") {
  const std::string text = with_rules("1 1, 1 (1) : 3\n0 0, 1 (1) : 1\n1 1, 0 (1) : 1\n1 1, 1 (1) : 2\n");
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  CHECK(find(result.diagnostics, Severity::Error, kRulesFirstLine, 14, "1 (AND) or 2 (OR), not 3") != nullptr);
  CHECK(find(result.diagnostics, Severity::Error, kRulesFirstLine + 1, 1, "no antecedent") != nullptr);
  CHECK(find(result.diagnostics, Severity::Warning, kRulesFirstLine + 2, 6, "no consequent") != nullptr);
  CHECK(result.diagnostics.error_count() == 2);
  REQUIRE(result.system().rules.size() == 1);
  CHECK(result.system().rules[0].connective == Connective::Or);
}

TEST_CASE("MATLAB .fis: counts that disagree with the file: error at the count", "[matlab-fis]") {
  SECTION("NumRules") {
    const std::string text = with_rules("1 1, 1 (1) : 1\n", "3");
    const ReadResult result = read(text);
    INFO(rendered(result.diagnostics, text));
    const Diagnostic* d = find(result.diagnostics, Severity::Error, 6, 10, "NumRules is 3 but the file has 1 rule line");
    REQUIRE(d != nullptr);
    CHECK(d->range.end_column == 11);
  }
  SECTION("NumInputs and NumOutputs") {
    std::string text = with_rules("1 1, 1 (1) : 1\n");
    text.replace(text.find("NumInputs=2"), 11, "NumInputs=3");
    text.replace(text.find("NumOutputs=1"), 12, "NumOutputs=0");
    const ReadResult result = read(text);
    INFO(rendered(result.diagnostics, text));
    CHECK(find(result.diagnostics, Severity::Error, 4, 11, "NumInputs is 3 but the file has 2 [InputN] sections") !=
          nullptr);
    CHECK(find(result.diagnostics, Severity::Error, 5, 12, "NumOutputs is 0 but the file has 1 [OutputN] section") !=
          nullptr);
    CHECK(find(result.diagnostics, Severity::Error, 23, 1, "[Output1] is beyond NumOutputs=0") != nullptr);
  }
  SECTION("NumMFs") {
    std::string text = with_rules("1 1, 1 (1) : 1\n");
    text.replace(text.find("NumMFs=3"), 8, "NumMFs=4");
    const ReadResult result = read(text);
    INFO(rendered(result.diagnostics, text));
    CHECK(find(result.diagnostics, Severity::Error, 11, 8, "NumMFs is 4 but the file has 3 MF lines") != nullptr);
  }
  SECTION("a missing count is inferred with a warning") {
    std::string text = with_rules("1 1, 1 (1) : 1\n");
    text.erase(text.find("NumMFs=3\n"), 9);
    const ReadResult result = read(text);
    INFO(rendered(result.diagnostics, text));
    CHECK(result.diagnostics.error_count() == 0);
    CHECK(find(result.diagnostics, Severity::Warning, 8, 1, "NumMFs is missing") != nullptr);
    CHECK(result.system().inputs[0].terms.size() == 3);
  }
  SECTION("a gap in the section numbers") {
    std::string text = with_rules("1 1, 1 (1) : 1\n");
    text.replace(text.find("[Input2]"), 8, "[Input3]");
    const ReadResult result = read(text);
    INFO(rendered(result.diagnostics, text));
    CHECK(find(result.diagnostics, Severity::Error, 16, 1, "[Input2] is missing") != nullptr);
  }
}

TEST_CASE("MATLAB .fis: unknown keys warn, unknown values error with did-you-mean", "[matlab-fis]") {
  std::string text = with_rules("1 1, 1 (1) : 1\n");
  text.replace(text.find("NumRules"), 0, "DisableStructuralChecks=0\nAndMethod='prd'\nDefuzzMethod='centriod'\n");
  text.replace(text.find("NumMFs=2"), 0, "Units='kPa'\n");
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  const Diagnostic* unknown = find(result.diagnostics, Severity::Warning, 6, 1, "unknown key 'DisableStructuralChecks'");
  REQUIRE(unknown != nullptr);
  CHECK(unknown->code == "unknown-key");
  CHECK(find(result.diagnostics, Severity::Warning, 22, 1, "unknown key 'Units' in [Input2]") != nullptr);
  const Diagnostic* method = find(result.diagnostics, Severity::Error, 7, 12, "unsupported AndMethod 'prd'");
  REQUIRE(method != nullptr);
  CHECK(method->notes.at(0) == "did you mean 'prod'?");
  const Diagnostic* defuzz = find(result.diagnostics, Severity::Error, 8, 15, "unsupported DefuzzMethod 'centriod'");
  REQUIRE(defuzz != nullptr);
  CHECK(defuzz->notes.at(0) == "did you mean 'centroid'?");
  CHECK(result.diagnostics.error_count() == 2);
}

TEST_CASE("MATLAB .fis: unknown type, MF family, parameter counts", "[matlab-fis]") {
  std::string text = with_rules("1 1, 1 (1) : 1\n");
  text.replace(text.find("'mamdani'"), 9, "'mamdanitype3'");
  text.replace(text.find("'trimf',[0 0 0.5]"), 17, "'triangle',[0 0 0.5]");
  text.replace(text.find("'trimf',[0 0.5 1]"), 17, "'trimf',[0 0.5]");
  text.replace(text.find("'zmf',[0 1]"), 11, "'zmf',[0 1 0 0]");
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  const Diagnostic* type = find(result.diagnostics, Severity::Error, 3, 7, "unknown system type 'mamdanitype3'");
  REQUIRE(type != nullptr);
  CHECK(type->notes.at(0) == "did you mean 'mamdanitype2'?");
  CHECK(find(result.diagnostics, Severity::Error, 12, 10, "unknown membership function type 'triangle'") != nullptr);
  CHECK(find(result.diagnostics, Severity::Error, 13, 17, "'trimf' takes 3 parameters but 2 are given") != nullptr);
  const Diagnostic* extra = find(result.diagnostics, Severity::Warning, 20, 15, "the 2 extra values are ignored");
  REQUIRE(extra != nullptr);
  CHECK(extra->code == "extra-params");
  CHECK(result.system().inputs[1].terms[0].mf.params == std::vector<double>{0, 1});
}

TEST_CASE("MATLAB .fis: linear outputs need one coefficient per input plus a constant", "[matlab-fis]") {
  std::string text = with_rules("1 1, 1 (1) : 1\n");
  text.replace(text.find("'mamdani'"), 9, "'sugeno'");
  text.replace(text.find("'trimf',[0 0 1]"), 15, "'linear',[1 2]");
  text.replace(text.find("'trimf',[0 1 1]"), 15, "'linear',[1 2 3 4]");
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  CHECK(find(result.diagnostics, Severity::Error, 27, 19, "'linear' takes 3 parameters but 2 are given") != nullptr);
  CHECK(find(result.diagnostics, Severity::Warning, 28, 19, "1 extra value is ignored") != nullptr);
  CHECK(result.system().outputs[0].terms[1].mf.params == std::vector<double>{1, 2, 3});
}

TEST_CASE("MATLAB .fis: numbers: expressions, exponents, inf and nan, MF lines read in order", "[matlab-fis]") {
  std::string text = with_rules("1 1, 1 (1) : 1\n");
  text.replace(text.find("Range=[0 1]"), 11, "Range=[-pi/4 2^-1*(3+1)]");
  text.replace(text.find("[0 0.5 1]"), 9, "[1e-3 .5E+1 12.]");
  text.replace(text.find("MF3='z'"), 3, "MF7");
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  CHECK(result.diagnostics.error_count() == 0);
  const Diagnostic* order = find(result.diagnostics, Severity::Warning, 14, 1, "MATLAB reads MF lines in order");
  REQUIRE(order != nullptr);
  CHECK(order->code == "mf-index");
  const FuzzySystem& system = result.system();
  CHECK(system.inputs[0].min == -0.78539816339744828);
  CHECK(system.inputs[0].max == 2.0);
  CHECK(system.inputs[0].terms[1].mf.params == std::vector<double>{0.001, 5.0, 12.0});
  CHECK(system.inputs[0].terms[2].name == "z");

  std::string special = with_rules("1 1, 1 (1) : 1\n");
  special.replace(special.find("Range=[0 1]"), 11, "Range=[-inf Inf]");
  special.replace(special.find("[0 0.5 1]"), 9, "[nan 0.5 1]");
  const ReadResult infinite = read(special);
  CHECK(infinite.diagnostics.error_count() == 0);
  CHECK(infinite.system().inputs[0].min == -std::numeric_limits<double>::infinity());
  CHECK(std::isnan(infinite.system().inputs[0].terms[1].mf.params[0]));

  std::string unknown = with_rules("1 1, 1 (1) : 1\n");
  unknown.replace(unknown.find("Range=[0 1]"), 11, "Range=[0 pie]");
  const ReadResult bad = read(unknown);
  const Diagnostic* name = find(bad.diagnostics, Severity::Error, 10, 10, "unknown name 'pie'");
  REQUIRE(name != nullptr);
  CHECK(name->notes.at(0) == "did you mean 'pi'?");
}

TEST_CASE("MATLAB .fis: syntax errors carry file:line:column", "[matlab-fis]") {
  SECTION("unclosed quote") {
    const ReadResult result = read("[System]\nName='abc\nType='mamdani'\n");
    REQUIRE(result.diagnostics.error_count() == 1);
    const Diagnostic& d = result.diagnostics.items()[0];
    CHECK(d.range.file == "test.fis");
    CHECK(d.range.line == 2);
    CHECK(d.range.column == 6);
    CHECK(d.message.find("not closed") != std::string::npos);
    CHECK(result.file.systems.empty());
  }
  SECTION("unexpected character, byte columns after a multi-byte name") {
    const ReadResult result = read("[System]\nName='\xC2\xB5-tissue' ?\n");
    REQUIRE(result.diagnostics.error_count() == 1);
    CHECK(result.diagnostics.items()[0].range.line == 2);
    CHECK(result.diagnostics.items()[0].range.column == 18);
    CHECK(result.diagnostics.items()[0].message == "unexpected character '?'");
  }
  SECTION("a rule line in [System], a key in [Rules], a line before [System]") {
    const ReadResult result = read("Name='x'\n[System]\n1 1, 1 (1) : 1\n[Rules]\nName='y'\n");
    CHECK(find(result.diagnostics, Severity::Error, 1, 1, "before the [System] section") != nullptr);
    CHECK(find(result.diagnostics, Severity::Error, 3, 1, "rule lines belong in the [Rules] section") != nullptr);
    CHECK(find(result.diagnostics, Severity::Error, 5, 1, "expected a rule line") != nullptr);
  }
  SECTION("invalid UTF-8") {
    const ReadResult result = read("[System]\nName='a\xFF'\n");
    REQUIRE(result.diagnostics.error_count() == 1);
    CHECK(result.diagnostics.items()[0].range.line == 2);
    CHECK(result.diagnostics.items()[0].range.column == 8);
  }
  SECTION("empty file and no [System]") {
    const ReadResult empty = read("");
    REQUIRE(empty.diagnostics.error_count() == 1);
    CHECK(empty.diagnostics.items()[0].message.find("no [System] section") != std::string::npos);
    CHECK(empty.file.systems.empty());
    const ReadResult only_comments = read("% nothing\n# here\n\n");
    CHECK(only_comments.diagnostics.error_count() == 1);
  }
  SECTION("duplicate sections and keys") {
    std::string text = with_rules("1 1, 1 (1) : 1\n");
    text += "[Input1]\nName='again'\n";
    text.replace(text.find("Type="), 0, "Name='second'\n");
    const ReadResult result = read(text);
    CHECK(find(result.diagnostics, Severity::Error, 33, 1, "duplicate section [Input1]") != nullptr);
    CHECK(find(result.diagnostics, Severity::Warning, 3, 1, "'Name' is given twice") != nullptr);
    CHECK(result.system().name == "second");
    CHECK(result.system().inputs[0].name == "a");
  }
}

TEST_CASE("MATLAB .fis: missing Name and Range in a variable section", "[matlab-fis]") {
  std::string text = with_rules("1 1, 1 (1) : 1\n");
  text.erase(text.find("Name='a'\n"), 9);
  text.replace(text.find("Range=[0 1]"), 11, "Range=[0 1 2]");
  text.erase(text.find("Range=[0 1]"), 12);
  const ReadResult result = read(text);
  INFO(rendered(result.diagnostics, text));
  CHECK(find(result.diagnostics, Severity::Error, 8, 1, "[Input1] has no Name") != nullptr);
  CHECK(find(result.diagnostics, Severity::Error, 9, 7, "Range takes two numbers") != nullptr);
  CHECK(find(result.diagnostics, Severity::Error, 15, 1, "[Input2] has no Range") != nullptr);
}

TEST_CASE("MATLAB .fis writer: MATLAB's version 2.0 layout, exactly", "[matlab-fis]") {
  const ReadResult tipper = read(kTipper);
  DiagnosticList diagnostics;
  const std::string written = write_matlab_fis(tipper.system(), diagnostics);
  CHECK(diagnostics.empty());
  CHECK(written ==
        "[System]\nName='tipper'\nType='mamdani'\nVersion=2.0\nNumInputs=2\nNumOutputs=1\nNumRules=3\n"
        "AndMethod='min'\nOrMethod='max'\nImpMethod='min'\nAggMethod='max'\nDefuzzMethod='centroid'\n\n"
        "[Input1]\nName='service'\nRange=[0 10]\nNumMFs=3\nMF1='poor':'gaussmf',[1.5 0]\n"
        "MF2='good':'gaussmf',[1.5 5]\nMF3='excellent':'gaussmf',[1.5 10]\n\n"
        "[Input2]\nName='food'\nRange=[0 10]\nNumMFs=2\nMF1='rancid':'trapmf',[0 0 1 3]\n"
        "MF2='delicious':'trapmf',[7 9 10 10]\n\n"
        "[Output1]\nName='tip'\nRange=[0 30]\nNumMFs=3\nMF1='cheap':'trimf',[0 5 10]\n"
        "MF2='average':'trimf',[10 15 20]\nMF3='generous':'trimf',[20 25 30]\n\n"
        "[Rules]\n1 1, 1 (1) : 2\n2 0, 2 (1) : 1\n3 2, 3 (1) : 2\n");
}

TEST_CASE("MATLAB .fis writer: hedges, NOT, quotes in names, exact numbers", "[matlab-fis]") {
  FuzzySystem system;
  system.name = "it's";
  system.type = SystemType::Sugeno;
  system.defuzzifier = Defuzzifier::WeightedAverage;
  Variable input;
  input.name = "x-1 a";
  input.min = 0.1 + 0.2;
  input.max = 1e300;
  input.terms.push_back(Term{"lo", {MfKind::Gaussian, {1.0 / 3.0, -0.0}}, {}, {}});
  input.terms.push_back(Term{"hi", {MfKind::Sigmoid, {2.0, 5e-324}}, {}, {}});
  system.inputs.push_back(input);
  Variable output;
  output.name = "y";
  output.terms.push_back(Term{"c", {MfKind::Constant, {7.64}}, {}, {}});
  output.terms.push_back(Term{"l", {MfKind::Linear, {-1.5, 2}}, {}, {}});
  system.outputs.push_back(output);
  Rule rule;
  rule.connective = Connective::Or;
  rule.weight = 0.3;
  rule.antecedent.push_back(Clause{0, 1, true, Hedge::Extremely, {}});
  rule.consequent.push_back(Clause{0, 1, false, Hedge::None, {}});
  system.rules.push_back(rule);
  for (Hedge hedge : {Hedge::Somewhat, Hedge::Very, Hedge::VeryVery, Hedge::None}) {
    Rule hedged;
    hedged.antecedent.push_back(Clause{0, 0, false, hedge, {}});
    hedged.consequent.push_back(Clause{0, 0, false, Hedge::None, {}});
    system.rules.push_back(hedged);
  }

  DiagnosticList diagnostics;
  const std::string written = write_matlab_fis(system, diagnostics);
  CHECK(written.find("Name='it''s'\n") != std::string::npos);
  CHECK(written.find("Range=[0.30000000000000004 1e+300]\n") != std::string::npos);
  CHECK(written.find("MF1='lo':'gaussmf',[0.3333333333333333 0]\n") != std::string::npos);
  CHECK(written.find("MF2='hi':'sigmf',[2 5e-324]\n") != std::string::npos);
  CHECK(written.find("MF2='l':'linear',[-1.5 2]\n") != std::string::npos);
  CHECK(written.find("[Rules]\n-2.3, 2 (0.3) : 2\n1.05, 1 (1) : 1\n1.2, 1 (1) : 1\n1.4, 1 (1) : 1\n1, 1 (1) : 1\n") !=
        std::string::npos);
  REQUIRE(diagnostics.warning_count() == 1);
  CHECK(diagnostics.items()[0].message.find("hedges") != std::string::npos);

  DiagnosticList again;
  const RuleFile back = read_matlab_fis("back.fis", written, again);
  INFO(rendered(again, written));
  CHECK(again.error_count() == 0);
  REQUIRE(back.systems.size() == 1);
  CHECK(testing::first_difference(system, back.systems[0]) == "");
}

TEST_CASE("MATLAB .fis writer: warns naming every field MATLAB cannot hold", "[matlab-fis]") {
  FuzzySystem system = testing::random_system(7, [] {
    testing::RandomSystemOptions options;
    options.mamdani = true;
    options.sugeno = false;
    return options;
  }());
  system.description = "liver";
  system.inputs[0].unit = "kPa";
  system.inputs[0].description = "stiffness";
  system.samples = 0;
  system.no_fire = NoFirePolicy::Value;
  system.no_fire_value = 5.3;
  system.rules[0].label = "r1";
  system.and_method = TNorm::EinsteinProduct;
  DiagnosticList diagnostics;
  write_matlab_fis(system, diagnostics);
  // What changes the outputs of the file read back is matlab-lossy; what does not, matlab-export.
  std::string exported, lost;
  for (const Diagnostic& d : diagnostics.items()) {
    CHECK(d.severity == Severity::Warning);
    CHECK((d.code == kMatlabExport || d.code == kMatlabLossy));
    (d.code == kMatlabLossy ? lost : exported) += d.message + "\n";
  }
  INFO("export:\n" << exported << "lossy:\n" << lost);
  CHECK(exported.find("description of system") != std::string::npos);
  CHECK(exported.find("unit 'kPa' of input '" + system.inputs[0].name + "'") != std::string::npos);
  CHECK(exported.find("description of input") != std::string::npos);
  CHECK(lost.find("'samples exact'") != std::string::npos);
  CHECK(lost.find("no-fire value 5.3") != std::string::npos);
  CHECK(exported.find("rule labels") != std::string::npos);
  CHECK(exported.find("Einstein") != std::string::npos);

  system.no_fire = NoFirePolicy::Error;
  system.samples = 201;
  DiagnosticList more;
  write_matlab_fis(system, more);
  std::string messages;
  for (const Diagnostic& d : more.items()) messages += d.message + "\n";
  CHECK(messages.find("'samples 201'") != std::string::npos);
  CHECK(messages.find("no-fire policy 'error'") != std::string::npos);
}

TEST_CASE("MATLAB .fis writer: no loss is silent: a file that reads back computing otherwise carries -Wmatlab-lossy",
          "[heavy][matlab-fis]") {
  // 1,000 random systems with every fmpc feature a .fis cannot hold (units, sample counts, no-fire policies,
  // labels, type-2 footprints of every kind, Nie-Tan, interval constants): where the writer says nothing with
  // matlab-lossy, the written file, read back, computes the same settings and outputs at every probe point of
  // output_changes (about 1,300 per system). Where it does warn, a sample of the files is checked to differ, so
  // that the warning is not said of everything.
  std::size_t silent = 0, warned = 0, warned_and_checked = 0, warned_and_changed = 0;
  for (std::uint64_t seed = 1; seed <= 1000; ++seed) {
    testing::RandomSystemOptions options;
    options.interval_type2 = seed % 2 == 0;
    options.max_inputs = 3;
    options.max_rules = 8;
    const FuzzySystem system = testing::random_system(seed, options);
    DiagnosticList diagnostics;
    const std::string written = write_matlab_fis(system, diagnostics);
    std::size_t lossy = 0;
    for (const Diagnostic& d : diagnostics.items()) lossy += d.code == kMatlabLossy ? 1 : 0;
    DiagnosticList read;
    const RuleFile back = read_matlab_fis("back.fis", written, read);
    INFO("seed " << seed << "\n" << written);
    REQUIRE_FALSE(read.has_errors());
    if (lossy == 0) {
      ++silent;
      const std::vector<std::string> changes = output_changes(system, back.systems.front());
      std::string listed;
      for (const std::string& change : changes) listed += change + "\n";
      INFO(listed);
      CHECK(changes.empty());
    } else {
      ++warned;
      // Exact sampling with a maximum defuzzifier samples 100,001 points per evaluation: a sample of the warned
      // files, at the corners, centre and axis lines only, keeps this test within seconds.
      if (seed % 8 != 0) continue;
      ++warned_and_checked;
      warned_and_changed += output_changes(system, back.systems.front(), {{}, 0, true, {}}).empty() ? 0 : 1;
    }
  }
  CHECK(silent > 100);
  CHECK(warned > 100);
  CHECK(warned_and_changed * 10 > warned_and_checked * 7);
}

TEST_CASE("MATLAB .fis: every shared MATLAB and Octave file reads without errors", "[matlab-fis]") {
  const std::filesystem::path folder = std::filesystem::path(FMPC_SHARED_DATA_DIR) / "matlab-fis";
  if (!std::filesystem::is_directory(folder)) {
    WARN("skipped: " << folder.string() << " is absent");
    return;
  }
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.path().extension() != ".fis") continue;
    ++files;
    const std::string text = read_text(entry.path());
    DiagnosticList diagnostics;
    const RuleFile file = read_matlab_fis(entry.path().string(), text, diagnostics);
    SourceFiles sources;
    sources.add(entry.path().string(), text);
    INFO(entry.path().filename().string() << "\n" << render_all(diagnostics, sources));
    CHECK(diagnostics.error_count() == 0);
    REQUIRE(file.systems.size() == 1);
    for (const Diagnostic& d : diagnostics.items())
      CHECK((d.code == "extra-params" || d.code == "mf-index"));
  }
  CHECK(files == 28);
}

TEST_CASE("MATLAB .fis: details of the shared files", "[matlab-fis]") {
  const std::filesystem::path folder = std::filesystem::path(FMPC_SHARED_DATA_DIR) / "matlab-fis";
  if (!std::filesystem::is_directory(folder)) {
    WARN("skipped: " << folder.string() << " is absent");
    return;
  }
  auto load = [&](const std::string& name) {
    DiagnosticList diagnostics;
    RuleFile file = read_matlab_fis(name, read_text(folder / name), diagnostics);
    REQUIRE(file.systems.size() == 1);
    return file.systems[0];
  };
  const FuzzySystem fpeaks = load("takagi-sugeno_matlab_fpeaks.fis");
  CHECK(fpeaks.inputs[0].terms[0].mf.params == std::vector<double>{1.5782983484, 2.1513139249, -2.2325016054});
  CHECK(fpeaks.outputs[0].terms[0].mf.params == std::vector<double>{0.1545651008, -2.2282819965, -8.974452103});

  const FuzzySystem juggler = load("takagi-sugeno_matlab_juggler.fis");
  CHECK(juggler.inputs[1].max == 3.1415926);
  CHECK(juggler.inputs[1].terms[1].mf.params == std::vector<double>{0.785398, 4, 1.570796});

  const FuzzySystem portfolio = load("mamdani_octave_investment_portfolio.fis");
  CHECK(portfolio.and_method == TNorm::EinsteinProduct);
  CHECK(portfolio.or_method == SNorm::EinsteinSum);
  CHECK(portfolio.implication == TNorm::EinsteinProduct);
  CHECK(portfolio.aggregation == SNorm::EinsteinSum);
  const Rule& not_extremely = portfolio.rules[2];  // -2.3 -1.3, 2 (0.5) : 1
  CHECK(not_extremely.antecedent[0].negated);
  CHECK(not_extremely.antecedent[0].term == 1);
  CHECK(not_extremely.antecedent[0].hedge == Hedge::Extremely);
  CHECK(not_extremely.weight == 0.5);
  CHECK(portfolio.inputs[1].name == "Risk-Tolerance");

  const FuzzySystem tips = load("takagi-sugeno_octave_sugeno_tip_calculator.fis");
  REQUIRE(tips.outputs.size() == 3);
  CHECK(tips.rules[9].antecedent[0].hedge == Hedge::VeryVery);     // 2.40
  CHECK(tips.rules[9].consequent[2].hedge == Hedge::Extremely);    // 3.30
  CHECK(tips.rules[0].consequent[1].hedge == Hedge::Very);         // 1.20

  const FuzzySystem sltbu = load("takagi-sugeno_matlab_sltbu.fis");
  CHECK(sltbu.inputs[1].min == -0.78539816339744828);
  CHECK(sltbu.inputs[1].terms.empty());

  const FuzzySystem slcp1 = load("takagi-sugeno_matlab_slcp1.fis");
  CHECK(slcp1.inputs[4].terms[2].name == "large");
  CHECK(slcp1.outputs[0].terms[0].mf.params.size() == 6);
}

TEST_CASE("random_system: seeded, valid shapes, options respected", "[matlab-fis][random-system]") {
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    const FuzzySystem a = testing::random_system(seed);
    const FuzzySystem b = testing::random_system(seed);
    REQUIRE(testing::first_difference(a, b) == "");
    REQUIRE(a.inputs.size() >= 1);
    REQUIRE(a.inputs.size() <= 4);
    REQUIRE(a.outputs.size() >= 1);
    REQUIRE(a.outputs.size() <= 3);
    for (const Rule& rule : a.rules) {
      REQUIRE_FALSE(rule.antecedent.empty());
      REQUIRE_FALSE(rule.consequent.empty());
      REQUIRE(rule.weight > 0.0);
      REQUIRE(rule.weight <= 1.0);
    }
    for (const auto* variables : {&a.inputs, &a.outputs})
      for (const Variable& variable : *variables) {
        REQUIRE(variable.min < variable.max);
        for (const Term& term : variable.terms) {
          const int count = term.mf.kind == MfKind::Linear ? static_cast<int>(a.inputs.size()) + 1
                                                            : mf_param_count(term.mf.kind);
          REQUIRE(static_cast<int>(term.mf.params.size()) == count);
          for (double p : term.mf.params) REQUIRE(std::isfinite(p));
          if (term.mf.kind == MfKind::Triangle || term.mf.kind == MfKind::Trapezoid)
            REQUIRE(std::is_sorted(term.mf.params.begin(), term.mf.params.end()));
          if (term.mf.kind == MfKind::Gaussian || term.mf.kind == MfKind::GeneralizedBell)
            REQUIRE(term.mf.params[0] > 0.0);
          if (a.type == SystemType::Sugeno && variables == &a.outputs)
            REQUIRE((term.mf.kind == MfKind::Constant || term.mf.kind == MfKind::Linear));
        }
      }
  }
  CHECK(testing::first_difference(testing::random_system(1), testing::random_system(2)) != "");

  const testing::RandomSystemOptions matlab = testing::RandomSystemOptions::matlab();
  const testing::RandomSystemOptions fuzzylite = testing::RandomSystemOptions::fuzzylite();
  for (std::uint64_t seed = 1; seed <= 100; ++seed) {
    const FuzzySystem m = testing::random_system(seed, matlab);
    CHECK(m.samples == 101);
    CHECK(m.no_fire == NoFirePolicy::Midrange);
    CHECK(m.and_method != TNorm::EinsteinProduct);
    CHECK(m.aggregation != SNorm::EinsteinSum);
    for (const Rule& rule : m.rules) {
      CHECK(rule.label.empty());
      for (const Clause& clause : rule.antecedent) CHECK(clause.hedge == Hedge::None);
    }
    const FuzzySystem f = testing::random_system(seed, fuzzylite);
    for (const auto* variables : {&f.inputs, &f.outputs})
      for (const Variable& variable : *variables) {
        CHECK(variable.name.find_first_of(" -") == std::string::npos);
        for (const Term& term : variable.terms) CHECK(term.name.find_first_of(" -") == std::string::npos);
      }
  }

  testing::RandomSystemOptions rounded;
  rounded.decimals = 2;
  const FuzzySystem r = testing::random_system(11, rounded);
  for (const Term& term : r.inputs[0].terms)
    for (double p : term.mf.params) CHECK(std::round(p * 100.0) / 100.0 == p);

  const auto points = testing::random_inputs(r, 3, 50);
  REQUIRE(points.size() == 50);
  for (const auto& point : points) {
    REQUIRE(point.size() == r.inputs.size());
    for (std::size_t i = 0; i < point.size(); ++i) {
      CHECK(point[i] >= r.inputs[i].min);
      CHECK(point[i] <= r.inputs[i].max);
    }
  }
}

// Hostile inputs to the rule-file readers, one property per class of issue 30 (docs/limits.md): lines and words cut
// at one set of blanks in FLL and FCL, no key given twice, a byte order mark read as nothing, no name changed by a
// writer unsaid. tests/hostile runs the same classes through the fmpc command line, and
// tests/fuzz/fuzz_fll.cpp and fuzz_fcl.cpp fuzz both readers.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cctype>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "compiler/eval/output_comparison.h"
#include "compiler/frontend/fll.h"
#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/fuzzylite_vocabulary.h"
#include "compiler/frontend/matlab_fis.h"
#include "compiler/frontend/rule_file_loader.h"
#include "diagnostics/diagnostic.h"
#include "runtime/scene/scene_file.h"
#include "tests/support/system_comparison.h"

using namespace fmpc;

namespace {

const char* const kFcl =
    "FUNCTION_BLOCK demo\n"
    "VAR_INPUT\n  x : REAL;\nEND_VAR\n"
    "VAR_OUTPUT\n  z : REAL;\nEND_VAR\n"
    "FUZZIFY x\n  RANGE := (0 .. 10);\n  TERM low := Triangle 0 0 10;\n  TERM high := Triangle 0 10 10;\nEND_FUZZIFY\n"
    "DEFUZZIFY z\n  RANGE := (0 .. 1);\n  TERM small := Triangle 0 0 1;\n  TERM big := Triangle 0 1 1;\n"
    "  METHOD : COG;\n  ACCU : MAX;\n  DEFAULT := 0.5;\nEND_DEFUZZIFY\n"
    "RULEBLOCK rules\n  AND : MIN;\n  OR : MAX;\n  ACT : MIN;\n"
    "  RULE 1 : if x is low then z is small;\n  RULE 2 : if x is high then z is big;\nEND_RULEBLOCK\n"
    "END_FUNCTION_BLOCK\n";

const char* const kFll =
    "Engine: demo\n"
    "InputVariable: x\n  enabled: true\n  range: 0 10\n  term: low Triangle 0 0 10\n  term: high Triangle 0 10 10\n"
    "OutputVariable: z\n  enabled: true\n  range: 0 1\n  aggregation: Maximum\n  defuzzifier: Centroid 100\n"
    "  default: 0.5\n  term: small Triangle 0 0 1\n  term: big Triangle 0 1 1\n"
    "RuleBlock: rules\n  conjunction: Minimum\n  disjunction: Maximum\n  implication: Minimum\n"
    "  rule: if x is low then z is small\n  rule: if x is high then z is big\n";

// The lines of `text`, with `filler` inserted as a line of its own before line `at` (0-based).
std::string with_line(const std::string& text, std::size_t at, const std::string& filler) {
  std::size_t position = 0;
  for (std::size_t line = 0; line < at && position != std::string::npos; ++line) {
    position = text.find('\n', position);
    if (position != std::string::npos) ++position;
  }
  if (position == std::string::npos) position = text.size();
  return text.substr(0, position) + filler + "\n" + text.substr(position);
}

std::size_t line_count(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

struct Loaded {
  RuleFile file;
  DiagnosticList diagnostics;
};

Loaded load(const std::string& path, const std::string& text) {
  Loaded loaded;
  loaded.file = load_rule_file(path, text, loaded.diagnostics);
  return loaded;
}

}  // namespace

TEST_CASE("FLL and FCL cut lines and words at one set of blanks: std::isspace's", "[hostile][fuzzylite]") {
  for (int c = 1; c < 256; ++c)
    CHECK(is_fuzzylite_blank(static_cast<char>(c)) == (std::isspace(c) != 0));
  // A line of nothing but blanks is no line at all, wherever it stands, in either format: the file reads as it did
  // without it (a form feed or vertical tab alone on a line once crashed the FCL reader).
  for (const auto& [path, text] : {std::pair<std::string, std::string>{"x.fcl", kFcl}, {"x.fll", kFll}}) {
    const Loaded plain = load(path, text);
    REQUIRE_FALSE(plain.diagnostics.has_errors());
    for (const char blank : std::string(kFuzzyliteBlanks)) {
      if (blank == '\n') continue;
      for (std::size_t at = 0; at <= line_count(text); ++at) {
        for (const std::string& filler : {std::string(1, blank), std::string(3, blank) + " \t"}) {
          const Loaded read = load(path, with_line(text, at, filler));
          INFO(path << ": a line of byte " << static_cast<int>(blank) << " before line " << at + 1);
          CHECK_FALSE(read.diagnostics.has_errors());
          REQUIRE(read.file.systems.size() == 1);
          CHECK(read.file.systems[0].rules.size() == 2);
        }
      }
    }
  }
}

TEST_CASE("FLL and FCL readers take any line of bytes without crashing", "[hostile][fuzzylite]") {
  // Seeded: lines of random bytes (blanks, ';', ':', '(' and keywords among them) at random places of both files.
  // A crash fails the run; every line that is not blank must be read as something (an error or a meaning).
  std::mt19937 random(30);
  const std::vector<std::string> pieces = {"\f", "\v", "\r", "\t", " ", ";", ":", ":=", "(", ")", "..", "(*", "*)",
                                           "//", "#", "TERM", "RANGE", "FUZZIFY", "END_FUZZIFY", "VAR_INPUT",
                                           "range:", "term:", "rule:", "Engine:", "x", "1", "\x01", "\xff"};
  for (const auto& [path, text] : {std::pair<std::string, std::string>{"x.fcl", kFcl}, {"x.fll", kFll}}) {
    for (int round = 0; round < 400; ++round) {
      std::string line;
      const int count = 1 + static_cast<int>(random() % 6);
      for (int k = 0; k < count; ++k) line += pieces[random() % pieces.size()];
      const std::size_t at = 1 + random() % line_count(text);
      (void)load(path, with_line(text, at, line));
    }
  }
}

TEST_CASE("FLL and FCL: a line given twice is an error, never the last one winning", "[hostile][fuzzylite]") {
  // Every line of both samples, copied right after itself with its value changed where it has one: the file then
  // has an error. Rules may repeat (a duplicate rule is lint's), and so may FLL's rule blocks.
  for (const auto& [path, text] : {std::pair<std::string, std::string>{"x.fcl", kFcl}, {"x.fll", kFll}}) {
    std::vector<std::string> lines;
    for (std::size_t start = 0; start < text.size();) {
      const std::size_t end = text.find('\n', start);
      lines.push_back(text.substr(start, end - start));
      start = end + 1;
    }
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const std::string trimmed = fuzzylite_trimmed(lines[i]);
      if (trimmed.rfind("RULE ", 0) == 0 || trimmed.rfind("rule:", 0) == 0 || trimmed.rfind("RuleBlock:", 0) == 0)
        continue;
      std::string copy = lines[i];
      // Another value where the line has a number: "last wins" would change the system, not only repeat it.
      const std::size_t digit = copy.find_first_of("0123456789");
      if (digit != std::string::npos) copy[digit] = copy[digit] == '9' ? '8' : static_cast<char>(copy[digit] + 1);
      const Loaded read = load(path, with_line(text, i + 1, copy));
      INFO(path << ": line " << i + 1 << " given twice: " << copy);
      CHECK(read.diagnostics.has_errors());
    }
  }
}

TEST_CASE("a UTF-8 byte order mark changes nothing a reader reports", "[hostile]") {
  // Every rule format and the scene reader: the text with a BOM reads to the same systems and the same diagnostics
  // (message, line and column) as without (a BOM once made an FLL file read as the fmpc language).
  std::vector<std::pair<std::string, std::string>> files = {{"x.fcl", kFcl}, {"x.fll", kFll}};
  for (const char* name : {"tests/golden/lint_warnings/warnings.fis", "tests/golden/cli_three_mistakes/three.fis",
                           "tests/golden/fcl_check_errors/demo.fcl", "tests/golden/fll_eval/tipper.fll",
                           "rulesets/liver_fibrosis/it2.fis", "tests/fuzz/seeds/matlab_fis/type2.fis",
                           "tests/fuzz/seeds/fcl/features.fcl", "tests/fuzz/seeds/fll/features.fll"}) {
    std::ifstream in(std::string(FMPC_SOURCE_DIR) + "/" + name, std::ios::binary);
    REQUIRE(in);
    files.emplace_back(name, std::string(std::istreambuf_iterator<char>(in), {}));
  }
  const auto report = [](const DiagnosticList& diagnostics) {
    std::vector<std::string> lines;
    for (const Diagnostic& d : diagnostics.items())
      lines.push_back(std::to_string(d.range.line) + ":" + std::to_string(d.range.column) + ": " + d.message);
    return lines;
  };
  for (const auto& [path, text] : files) {
    INFO(path);
    const Loaded plain = load(path, text);
    const Loaded marked = load(path, "\xEF\xBB\xBF" + text);
    CHECK(report(marked.diagnostics) == report(plain.diagnostics));
    REQUIRE(marked.file.systems.size() == plain.file.systems.size());
    for (std::size_t s = 0; s < plain.file.systems.size(); ++s)
      CHECK(testing::first_difference(plain.file.systems[s], marked.file.systems[s]).empty());
  }
  const std::string scene = "mesh: {box: {size: [1, 1, 1], cells: [2, 2, 2]}}\nmaterial: {youngs_modulus: 5}\nnme: x\n";
  DiagnosticList plain, marked;
  (void)sim::parse_scene("/nonexistent/s.yaml", scene, plain);
  (void)sim::parse_scene("/nonexistent/s.yaml", "\xEF\xBB\xBF" + scene, marked);
  CHECK(report(marked) == report(plain));
  CHECK(plain.has_errors());
}

TEST_CASE("every writer keeps a name or its change is reported", "[hostile]") {
  // `fmpc convert` once turned '"' in names into '\'' without a word. Names holding each odd character are written
  // in every format and read back: either the text does not read back (convert refuses it), or every name is the
  // same, or name_changes names each that is not (convert warns with it, -Wrenamed-term).
  const Loaded sample = load("x.fll", kFll);
  REQUIRE(sample.file.systems.size() == 1);
  for (const char c : std::string("\"'\\#;:(),[]{}%=\t\x7f") + "\xc3\xa9") {
    FuzzySystem system = sample.file.systems[0];
    system.inputs[0].name = std::string("a") + c + "b";
    system.inputs[0].terms[0].name = std::string("lo") + c + "w";
    system.outputs[0].name = std::string("z") + c;
    for (const std::string format : {"fmpc", "matlab", "fll", "fcl"}) {
      DiagnosticList written_diagnostics;
      std::string text;
      if (format == "fmpc") text = write_fmpc(RuleFile{"x.fis", {system}});
      if (format == "matlab") text = write_matlab_fis(system, written_diagnostics);
      if (format == "fll") text = write_fll(system, written_diagnostics);
      if (format == "fcl") text = write_fcl(system, written_diagnostics);
      const Loaded back = load("back", text);
      INFO(format << " with byte " << static_cast<int>(static_cast<unsigned char>(c)) << ":\n" << text);
      if (back.diagnostics.has_errors() || back.file.systems.size() != 1) continue;
      const FuzzySystem& read = back.file.systems[0];
      const bool same = read.inputs[0].name == system.inputs[0].name &&
                        read.inputs[0].terms[0].name == system.inputs[0].terms[0].name &&
                        read.outputs[0].name == system.outputs[0].name;
      CHECK(same == name_changes(system, read).empty());
    }
  }
}

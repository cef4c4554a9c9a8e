// FCL (IEC 61131-7 Fuzzy Control Language) reader and writer, in the subset fuzzylite's FclImporter reads and its
// FclExporter writes (fl/imex/FclImporter.cpp): FUNCTION_BLOCK, VAR_INPUT/VAR_OUTPUT, FUZZIFY and DEFUZZIFY blocks
// with RANGE and TERM lines in fuzzylite's term syntax, METHOD/ACCU/DEFAULT, and RULEBLOCK with AND/OR/ACT and
// RULE lines. Comments: // to the end of the line and (* ... *).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "compiler/frontend/fll.h"
#include "compiler/frontend/fuzzylite_vocabulary.h"
#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

struct Line {
  std::string text;  // comments blanked, trailing ';' and spaces removed
  int number = 0;
  int column = 1;    // of the first non-blank character
};

// The text with comments replaced by spaces (columns kept), split into non-blank lines: each has a first word, as
// lines and words are cut at the same blanks (kFuzzyliteBlanks).
std::vector<Line> lines_of(std::string text) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text.compare(i, 2, "(*") == 0) {
      const std::size_t end = text.find("*)", i + 2);
      const std::size_t stop = end == std::string::npos ? text.size() : end + 2;
      for (std::size_t k = i; k < stop; ++k)
        if (text[k] != '\n') text[k] = ' ';
      i = stop - 1;
    } else if (text.compare(i, 2, "//") == 0) {
      while (i < text.size() && text[i] != '\n') text[i++] = ' ';
    }
  }
  std::vector<Line> lines;
  std::istringstream in(text);
  int number = 0;
  for (std::string line; std::getline(in, line);) {
    ++number;
    const std::size_t first = line.find_first_not_of(kFuzzyliteBlanks);
    if (first == std::string::npos) continue;
    std::size_t last = line.find_last_not_of(std::string(kFuzzyliteBlanks) + ";");
    if (last == std::string::npos || last < first) last = first;
    lines.push_back(Line{line.substr(first, last - first + 1), number, static_cast<int>(first) + 1});
  }
  return lines;
}

const std::pair<const char*, TNorm> kFclTNorms[] = {
    {"MIN", TNorm::Minimum}, {"PROD", TNorm::Product}, {"EPROD", TNorm::EinsteinProduct}};
// fuzzylite's FCL has no abbreviation for the unbounded sum: its exporter writes the class name, and so does fmpc's;
// "SUM" is read as well.
const std::pair<const char*, SNorm> kFclSNorms[] = {{"MAX", SNorm::Maximum},
                                                    {"ASUM", SNorm::ProbabilisticSum},
                                                    {"UnboundedSum", SNorm::Sum},
                                                    {"SUM", SNorm::Sum},
                                                    {"ESUM", SNorm::EinsteinSum}};
const std::pair<const char*, Defuzzifier> kFclMethods[] = {
    {"COG", Defuzzifier::Centroid},          {"COA", Defuzzifier::Bisector},
    {"MM", Defuzzifier::MeanOfMaximum},      {"LM", Defuzzifier::SmallestOfMaximum},
    {"RM", Defuzzifier::LargestOfMaximum},   {"COGS", Defuzzifier::WeightedAverage},
    {"COGSS", Defuzzifier::WeightedSum}};

template <typename Enum, std::size_t N>
std::optional<Enum> lookup(const std::pair<const char*, Enum> (&table)[N], const std::string& name) {
  for (const auto& [text, value] : table)
    if (name == text) return value;
  return std::nullopt;
}

template <typename Enum, std::size_t N>
const char* name_of(const std::pair<const char*, Enum> (&table)[N], Enum value) {
  for (const auto& [text, v] : table)
    if (v == value) return text;
  return "?";
}

template <typename Enum, std::size_t N>
std::string choices(const std::pair<const char*, Enum> (&table)[N]) {
  std::string list;
  for (const auto& entry : table) list += (list.empty() ? "" : ", ") + std::string(entry.first);
  return list;
}

class FclReader {
 public:
  FclReader(const std::string& path, DiagnosticList& diagnostics) : path_(path), diagnostics_(diagnostics) {}

  RuleFile read(const std::string& text) {
    RuleFile file;
    file.path = path_;
    for (const Line& line : lines_of(text)) read_line(line);
    if (block_ != Block::Done && block_ != Block::None)
      diagnostics_.error(SourceRange{path_, last_line_, 1, last_line_, 1},
                         "the file ends inside a block: close it (END_FUZZIFY, END_DEFUZZIFY, END_RULEBLOCK, END_VAR, "
                         "END_FUNCTION_BLOCK)");
    finish();
    if (!system_.inputs.empty() || !system_.outputs.empty()) file.systems.push_back(std::move(system_));
    return file;
  }

 private:
  enum class Block { None, FunctionBlock, VarInput, VarOutput, Fuzzify, Defuzzify, RuleBlock, Done };

  SourceRange at(const Line& line, std::size_t offset = 0, std::size_t length = 0) const {
    const int column = line.column + static_cast<int>(offset);
    return SourceRange{path_, line.number, column, line.number,
                       column + static_cast<int>(length ? length : line.text.size() - offset)};
  }

  Variable* find(std::vector<Variable>& variables, const std::string& name) {
    for (Variable& v : variables)
      if (v.name == name) return &v;
    return nullptr;
  }

  void read_line(const Line& line) {
    last_line_ = line.number;
    const std::vector<std::string> words = fuzzylite_words(line.text);
    const std::string& head = words[0];
    if (block_ == Block::None) {
      if (head != "FUNCTION_BLOCK") {
        diagnostics_.error(at(line, 0, head.size()), "an FCL file starts with FUNCTION_BLOCK NAME");
        block_ = Block::FunctionBlock;
        return;
      }
      system_.name = words.size() > 1 ? words[1] : "fcl";
      system_.range = at(line);
      block_ = Block::FunctionBlock;
      return;
    }
    const auto open = [&](Block block) {
      if (block_ != Block::FunctionBlock)
        diagnostics_.error(at(line, 0, head.size()), head + " inside another block: close that block first");
      block_ = block;
    };
    const auto close = [&](Block expected, const char* opener) {
      if (block_ != expected) diagnostics_.error(at(line, 0, head.size()), head + " without " + opener);
      block_ = Block::FunctionBlock;
    };
    if (head == "VAR_INPUT") return open(Block::VarInput);
    if (head == "VAR_OUTPUT") return open(Block::VarOutput);
    if (head == "END_VAR") {
      if (block_ != Block::VarInput && block_ != Block::VarOutput)
        diagnostics_.error(at(line, 0, head.size()), "END_VAR without VAR_INPUT or VAR_OUTPUT");
      block_ = Block::FunctionBlock;
      return;
    }
    if (head == "FUZZIFY" || head == "DEFUZZIFY") {
      open(head == "FUZZIFY" ? Block::Fuzzify : Block::Defuzzify);
      const std::string name = words.size() > 1 ? words[1] : "";
      current_ = find(head == "FUZZIFY" ? system_.inputs : system_.outputs, name);
      if (!current_)
        diagnostics_.error(at(line, head.size() + 1, name.size()),
                           "'" + name + "' is not declared in " + (head == "FUZZIFY" ? "VAR_INPUT" : "VAR_OUTPUT"));
      return;
    }
    if (head == "END_FUZZIFY") return close(Block::Fuzzify, "FUZZIFY");
    if (head == "END_DEFUZZIFY") return close(Block::Defuzzify, "DEFUZZIFY");
    if (head == "RULEBLOCK") return open(Block::RuleBlock);
    if (head == "END_RULEBLOCK") return close(Block::RuleBlock, "RULEBLOCK");
    if (head == "END_FUNCTION_BLOCK") {
      if (block_ != Block::FunctionBlock)
        diagnostics_.error(at(line, 0, head.size()), "END_FUNCTION_BLOCK inside an open block");
      block_ = Block::Done;
      return;
    }
    switch (block_) {
      case Block::VarInput:
      case Block::VarOutput: declare(line, words); return;
      case Block::Fuzzify:
      case Block::Defuzzify: variable_line(line, words); return;
      case Block::RuleBlock: rule_block_line(line, words); return;
      default: break;
    }
    diagnostics_.error(at(line, 0, head.size()), "'" + head + "' is not an FCL keyword here");
  }

  void declare(const Line& line, const std::vector<std::string>& words) {
    // NAME : REAL  (also NAME: REAL)
    std::string name = words[0];
    if (!name.empty() && name.back() == ':') name.pop_back();
    Variable variable;
    variable.name = name;
    variable.range = at(line);
    variable.name_range = at(line, 0, name.size());
    if (line.text.find("REAL") == std::string::npos)
      diagnostics_.error(at(line), "expected 'NAME : REAL;' (fmpc's variables are real numbers)");
    (block_ == Block::VarInput ? system_.inputs : system_.outputs).push_back(variable);
  }

  // The value after ':=' or ':' on a line such as "METHOD : COG" or "RANGE := (0 .. 1)".
  static std::string value_of(const std::string& text, std::size_t& offset) {
    std::size_t assign = text.find(":=");
    std::size_t skip = 2;
    if (assign == std::string::npos) {
      assign = text.find(':');
      skip = 1;
    }
    if (assign == std::string::npos) {
      offset = text.size();
      return {};
    }
    offset = text.find_first_not_of(kFuzzyliteBlanks, assign + skip);
    if (offset == std::string::npos) offset = text.size();
    return text.substr(offset);
  }

  void variable_line(const Line& line, const std::vector<std::string>& words) {
    if (!current_) return;
    const std::string& head = words[0];
    std::size_t offset = 0;
    const std::string value = value_of(line.text, offset);
    if (head == "RANGE") {
      // (MIN .. MAX)
      std::string inside = value;
      for (char& c : inside)
        if (c == '(' || c == ')') c = ' ';
      const std::size_t dots = inside.find("..");
      const auto end_of = [&](const std::string& part) {
        const std::vector<std::string> w = fuzzylite_words(part);
        return w.size() == 1 ? fuzzylite_number(w[0]) : std::nullopt;
      };
      const auto lo = dots == std::string::npos ? std::nullopt : end_of(inside.substr(0, dots));
      const auto hi = dots == std::string::npos ? std::nullopt : end_of(inside.substr(dots + 2));
      if (!lo || !hi) {
        diagnostics_.error(at(line, offset), "expected 'RANGE := (MIN .. MAX);'");
        return;
      }
      current_->min = *lo;
      current_->max = *hi;
      return;
    }
    if (head == "TERM") {
      // TERM NAME := Family numbers
      const std::size_t assign = line.text.find(":=");
      const std::vector<std::string> parts = fuzzylite_words(value);
      if (assign == std::string::npos || words.size() < 2 || parts.empty()) {
        diagnostics_.error(at(line), "expected 'TERM NAME := FAMILY NUMBERS...;'");
        return;
      }
      if (parts[0].front() == '(') {
        diagnostics_.error(at(line, offset), "point lists ('(x, y) ...', fuzzylite's Discrete) have no fmpc form: "
                                             "write the term as a Triangle, Trapezoid or another family");
        return;
      }
      Term term;
      term.name = words[1];
      term.range = at(line);
      if (parts.size() == 1 && fuzzylite_number(parts[0])) {  // "TERM NAME := 5;": an IEC singleton, a Constant
        term.name_range = at(line, line.text.find(words[1], 4), words[1].size());
        term.mf = MembershipFunction{MfKind::Constant, {*fuzzylite_number(parts[0])}};
        current_->terms.push_back(term);
        return;
      }
      term.name_range = at(line, line.text.find(words[1], 4), words[1].size());
      std::vector<double> numbers;
      for (std::size_t k = 1; k < parts.size(); ++k) {
        const auto n = fuzzylite_number(parts[k]);
        if (!n) {
          diagnostics_.error(at(line, offset), "'" + parts[k] + "' is not a number (term '" + term.name + "')");
          return;
        }
        numbers.push_back(*n);
      }
      std::string error;
      const auto mf = term_from_fuzzylite(parts[0], numbers, error);
      if (!mf) {
        diagnostics_.error(at(line, offset), error);
        return;
      }
      term.mf = *mf;
      current_->terms.push_back(term);
      return;
    }
    if (block_ == Block::Defuzzify && head == "METHOD") {
      if (const auto method = lookup(kFclMethods, value)) {
        method_ = *method;
      } else {
        diagnostics_.error(at(line, offset), "'" + value + "' is not a method fmpc has (" + choices(kFclMethods) + ")");
      }
      return;
    }
    if (block_ == Block::Defuzzify && head == "ACCU") {
      accumulation(line, value, offset);
      return;
    }
    if (block_ == Block::Defuzzify && head == "DEFAULT") {
      const std::string number = fuzzylite_words(value).empty() ? "" : fuzzylite_words(value)[0];
      const auto v = fuzzylite_number(number);
      if (!v) {
        diagnostics_.error(at(line, offset), "expected 'DEFAULT := NUMBER;' or 'DEFAULT := nan;'");
        return;
      }
      if (value.find("NC") != std::string::npos)
        diagnostics_.error(at(line, offset), "'NC' (keep the previous output) keeps a state fmpc's evaluators do not "
                                             "keep: give a number");
      defaults_.push_back({*v, at(line, offset), static_cast<std::size_t>(current_ - system_.outputs.data())});
      return;
    }
    if (head == "LOCK") {
      diagnostics_.warning(at(line), "format-difference",
                           "LOCK clamps values to the range in fuzzylite; fmpc evaluates values outside the range as "
                           "given, with a warning");
      return;
    }
    diagnostics_.error(at(line, 0, head.size()), "'" + head + "' is not a keyword of " +
                                                     (block_ == Block::Fuzzify ? "FUZZIFY" : "DEFUZZIFY"));
  }

  void accumulation(const Line& line, const std::string& value, std::size_t offset) {
    if (const auto norm = lookup(kFclSNorms, value)) {
      system_.aggregation = *norm;
    } else {
      diagnostics_.error(at(line, offset), "'" + value + "' is not an accumulation fmpc has (" + choices(kFclSNorms) + ")");
    }
  }

  void rule_block_line(const Line& line, const std::vector<std::string>& words) {
    const std::string& head = words[0];
    std::size_t offset = 0;
    const std::string value = value_of(line.text, offset);
    if (head == "AND" || head == "ACT") {
      if (const auto norm = lookup(kFclTNorms, value))
        (head == "AND" ? system_.and_method : system_.implication) = *norm;
      else
        diagnostics_.error(at(line, offset), "'" + value + "' is not a T-norm fmpc has (" + choices(kFclTNorms) + ")");
      return;
    }
    if (head == "OR") {
      if (const auto norm = lookup(kFclSNorms, value)) system_.or_method = *norm;
      else diagnostics_.error(at(line, offset), "'" + value + "' is not an S-norm fmpc has (" + choices(kFclSNorms) + ")");
      return;
    }
    if (head == "ACCU") {
      accumulation(line, value, offset);
      return;
    }
    if (head == "RULE") {
      rules_.push_back({value, at(line, offset)});
      return;
    }
    diagnostics_.error(at(line, 0, head.size()), "'" + head + "' is not a keyword of RULEBLOCK (AND, OR, ACT, ACCU, RULE)");
  }

  void finish() {
    system_.type = fuzzylite_system_type(system_, system_.range, diagnostics_);
    const bool sugeno = system_.type == SystemType::Sugeno;
    if (method_) {
      system_.defuzzifier = *method_;
      // fuzzylite reads FCL's COG with its default resolution of 100 (FclExporter writes none).
      if (system_.type == SystemType::Mamdani) system_.samples = 100;
    } else if (sugeno) {
      system_.defuzzifier = Defuzzifier::WeightedAverage;
    }
    // DEFAULT lines may come in any order of the outputs; an output without one defaults to NaN, as in fuzzylite.
    std::vector<double> values(system_.outputs.size(), std::nan(""));
    for (const Default& d : defaults_) values[d.output] = d.value;
    if (!defaults_.empty()) set_no_fire_from_defaults(system_, values, defaults_.back().at, diagnostics_);
    else system_.no_fire = NoFirePolicy::Error;
    for (const auto& [text, where] : rules_)
      if (auto rule = parse_fuzzylite_rule(text, where, system_, diagnostics_)) system_.rules.push_back(*rule);
  }

  std::string path_;
  DiagnosticList& diagnostics_;
  FuzzySystem system_;
  Block block_ = Block::None;
  Variable* current_ = nullptr;
  std::optional<Defuzzifier> method_;
  struct Default {
    double value;
    SourceRange at;
    std::size_t output;
  };
  std::vector<Default> defaults_;
  std::vector<std::pair<std::string, SourceRange>> rules_;
  int last_line_ = 1;
};

}  // namespace

RuleFile read_fcl(const std::string& path, const std::string& text, DiagnosticList& diagnostics) {
  return FclReader(path, diagnostics).read(text);
}

std::string write_fcl(const FuzzySystem& system, DiagnosticList& diagnostics) {
  if (system.interval_type2)
    diagnostics.error(system.range, "FCL holds type-1 systems; '" + system.name + "' is interval type-2");
  if (system.type == SystemType::Mamdani && system.samples != 100)
    diagnostics.warning(system.range, "format-difference",
                        "FCL has no defuzzification resolution: fuzzylite reads COG with 100 points, this system "
                        "samples " + (system.samples == 0 ? std::string("exactly") : std::to_string(system.samples)));
  std::ostringstream out;
  out << "// " << system.name << ", written by fmpc (IEC 61131-7 FCL)\n";
  out << "FUNCTION_BLOCK " << system.name << "\n\n";
  out << "VAR_INPUT\n";
  for (const Variable& v : system.inputs) out << "  " << v.name << ": REAL;\n";
  out << "END_VAR\n\nVAR_OUTPUT\n";
  for (const Variable& v : system.outputs) out << "  " << v.name << ": REAL;\n";
  out << "END_VAR\n\n";
  const auto terms = [&](const Variable& v) {
    if (!v.unit.empty() && v.unit != "dimensionless")
      diagnostics.warning(v.range, "format-difference",
                          "FCL has no units: '" + v.name + "' (" + v.unit + ") is written without its unit");
    out << "  RANGE := (" << format_number(v.min) << " .. " << format_number(v.max) << ");\n";
    for (const Term& term : v.terms) {
      out << "  TERM " << term.name << " := " << fuzzylite_term_name(term.mf.kind);
      for (double n : fuzzylite_term_numbers(term.mf)) out << ' ' << format_number(n);
      out << ";\n";
    }
  };
  for (const Variable& v : system.inputs) {
    out << "FUZZIFY " << v.name << '\n';
    terms(v);
    out << "END_FUZZIFY\n\n";
  }
  for (const Variable& v : system.outputs) {
    out << "DEFUZZIFY " << v.name << '\n';
    terms(v);
    out << "  METHOD : " << name_of(kFclMethods, system.defuzzifier) << ";\n";
    out << "  ACCU : " << name_of(kFclSNorms, system.aggregation) << ";\n";
    switch (system.no_fire) {
      case NoFirePolicy::Error: out << "  DEFAULT := nan;\n"; break;
      case NoFirePolicy::Value: out << "  DEFAULT := " << format_number(system.no_fire_value) << ";\n"; break;
      case NoFirePolicy::Midrange: out << "  DEFAULT := " << format_number((v.min + v.max) / 2) << ";\n"; break;
    }
    out << "END_DEFUZZIFY\n\n";
  }
  out << "RULEBLOCK rules\n";
  out << "  AND : " << name_of(kFclTNorms, system.and_method) << ";\n";
  out << "  OR : " << name_of(kFclSNorms, system.or_method) << ";\n";
  out << "  ACT : " << name_of(kFclTNorms, system.implication) << ";\n";
  for (std::size_t r = 0; r < system.rules.size(); ++r) {
    const std::string text = fuzzylite_rule_text(system, system.rules[r], system.rules[r].range, diagnostics);
    if (!text.empty()) out << "  RULE " << r + 1 << " : " << text << ";\n";
  }
  out << "END_RULEBLOCK\n\nEND_FUNCTION_BLOCK\n";
  return out.str();
}

}  // namespace fmpc

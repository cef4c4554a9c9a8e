// FCL (IEC 61131-7 Fuzzy Control Language) reader and writer, in the subset fuzzylite's FclImporter reads and its
// FclExporter writes (fl/imex/FclImporter.cpp): FUNCTION_BLOCK, VAR_INPUT/VAR_OUTPUT, FUZZIFY and DEFUZZIFY blocks
// with RANGE and TERM lines in fuzzylite's term syntax, METHOD/ACCU/DEFAULT, and RULEBLOCK with AND/OR/ACT and
// RULE lines. Comments: // to the end of the line and (* ... *).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
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
      if (words.size() > 2)
        diagnostics_.error(at(line, line.text.find(words[2], head.size() + words[1].size()), words[2].size()),
                           "unexpected '" + words[2] + "' after FUNCTION_BLOCK " + words[1] + "; remove it");
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
    // Block keywords take a name (FUZZIFY, DEFUZZIFY; FUNCTION_BLOCK and RULEBLOCK optionally) or nothing.
    static const std::map<std::string, std::size_t> block_words = {
        {"VAR_INPUT", 1},   {"VAR_OUTPUT", 1},    {"END_VAR", 1},       {"FUZZIFY", 2},
        {"DEFUZZIFY", 2},   {"END_FUZZIFY", 1},   {"END_DEFUZZIFY", 1}, {"RULEBLOCK", 2},
        {"END_RULEBLOCK", 1}, {"END_FUNCTION_BLOCK", 1}};
    if (const auto arity = block_words.find(head); arity != block_words.end() && words.size() > arity->second) {
      const std::size_t extra = line.text.find(words[arity->second], head.size());
      diagnostics_.error(at(line, extra, words[arity->second].size()),
                         "unexpected '" + words[arity->second] + "' after " +
                             (arity->second == 1 ? head : head + " " + words[1]) + "; remove it");
    }
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
      keys_.open_section();
      const std::string name = words.size() > 1 ? words[1] : "";
      block_title_ = head + " " + name;
      current_ = find(head == "FUZZIFY" ? system_.inputs : system_.outputs, name);
      const SourceRange name_at = at(line, name.empty() ? 0 : line.text.find(name, head.size()),
                                     name.empty() ? head.size() : name.size());
      if (!current_) {
        diagnostics_.error(name_at, name.empty() ? head + " needs the name of a variable"
                                                 : "'" + name + "' is not declared in " +
                                                       (head == "FUZZIFY" ? "VAR_INPUT" : "VAR_OUTPUT"));
        return;
      }
      // A second block for the same variable once added its terms to the first's and replaced its range.
      const auto [first, inserted] = blocks_.emplace(head + " " + name, name_at);
      if (!inserted) {
        diagnostics_.error(name_at, "'" + name + "' has a second " + head + " block; give each variable one",
                           {"the first is here: " + std::to_string(first->second.line) + ":" +
                            std::to_string(first->second.column)});
        current_ = nullptr;
      }
      return;
    }
    if (head == "END_FUZZIFY") return close(Block::Fuzzify, "FUZZIFY");
    if (head == "END_DEFUZZIFY") return close(Block::Defuzzify, "DEFUZZIFY");
    if (head == "RULEBLOCK") {
      keys_.open_section();
      block_title_ = "RULEBLOCK" + (words.size() > 1 ? " " + words[1] : std::string());
      return open(Block::RuleBlock);
    }
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
    // NAME : REAL  (also NAME: REAL, NAME :REAL, NAME:REAL), and nothing else on the line.
    const std::size_t colon = line.text.find(':');
    const std::string name = fuzzylite_trimmed(line.text.substr(0, colon));
    const std::vector<std::string> type =
        colon == std::string::npos ? std::vector<std::string>{} : fuzzylite_words(line.text.substr(colon + 1));
    Variable variable;
    variable.name = name.empty() ? words[0] : name;
    variable.range = at(line);
    variable.name_range = at(line, 0, variable.name.size());
    if (name.empty() || fuzzylite_words(name).size() != 1 || type != std::vector<std::string>{"REAL"})
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
    if (head != "TERM" && !keys_.once_in_section(head, at(line, 0, head.size()), block_title_, diagnostics_)) return;
    if (head == "RANGE") {
      // Exactly (MIN .. MAX): one parenthesis on each side, two numbers around "..", nothing else (the reader once
      // blanked every parenthesis, so that 100,000 unbalanced ones were a range).
      const std::string range = fuzzylite_trimmed(value);
      const std::size_t dots = range.find("..");
      const bool framed = range.size() >= 2 && range.front() == '(' && range.back() == ')' &&
                          range.find_first_of("()", 1) == range.size() - 1;
      const auto end_of = [&](const std::string& part) {
        const std::vector<std::string> w = fuzzylite_words(part);
        return w.size() == 1 ? fuzzylite_number(w[0]) : std::nullopt;
      };
      const auto lo = !framed || dots == std::string::npos ? std::nullopt : end_of(range.substr(1, dots - 1));
      const auto hi = !framed || dots == std::string::npos ? std::nullopt
                                                           : end_of(range.substr(dots + 2, range.size() - dots - 3));
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
      // The name is the one word between TERM and ':='.
      const std::vector<std::string> name_words = fuzzylite_words(line.text.substr(4, assign - 4));
      if (name_words.size() != 1) {
        diagnostics_.error(at(line), "expected 'TERM NAME := FAMILY NUMBERS...;' (one word for the name)");
        return;
      }
      Term term;
      term.name = name_words[0];
      term.range = at(line);
      if (parts.size() == 1 && fuzzylite_number(parts[0])) {  // "TERM NAME := 5;": an IEC singleton, a Constant
        term.name_range = at(line, line.text.find(term.name, 4), term.name.size());
        term.mf = MembershipFunction{MfKind::Constant, {*fuzzylite_number(parts[0])}};
        current_->terms.push_back(term);
        return;
      }
      term.name_range = at(line, line.text.find(term.name, 4), term.name.size());
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
      if (!keys_.one_value("METHOD", value, at(line, offset), diagnostics_)) return;
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
      // NUMBER, or NUMBER | NC (fuzzylite's lock-previous), and nothing else.
      const std::size_t bar = value.find('|');
      const std::vector<std::string> parts = fuzzylite_words(value.substr(0, bar));
      const bool keeps_previous = bar != std::string::npos;
      const auto v = parts.size() == 1 ? fuzzylite_number(parts[0]) : std::nullopt;
      if (!v || (keeps_previous && fuzzylite_words(value.substr(bar + 1)) != std::vector<std::string>{"NC"})) {
        diagnostics_.error(at(line, offset), "expected 'DEFAULT := NUMBER;' or 'DEFAULT := nan;'");
        return;
      }
      if (keeps_previous)
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
    if (!keys_.one_value("ACCU", value, at(line, offset), diagnostics_)) return;
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
    if (head == "AND" || head == "OR" || head == "ACT" || head == "ACCU") {
      if (!keys_.once_in_section(head, at(line, 0, head.size()), block_title_, diagnostics_)) return;
      if (head != "ACCU" && !keys_.one_value(head, value, at(line, offset), diagnostics_)) return;
    }
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
    const SystemNames names(system_);
    for (const auto& [text, where] : rules_)
      if (auto rule = parse_fuzzylite_rule(text, where, system_, names, diagnostics_)) system_.rules.push_back(*rule);
  }

  std::string path_;
  DiagnosticList& diagnostics_;
  FuzzySystem system_;
  Block block_ = Block::None;
  Variable* current_ = nullptr;
  std::optional<Defuzzifier> method_;
  std::string block_title_;                   // "FUZZIFY x", "RULEBLOCK rules": where a key was given twice
  std::map<std::string, SourceRange> blocks_;  // "FUZZIFY x" -> where the first block for x opened
  FuzzyliteKeys keys_;
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

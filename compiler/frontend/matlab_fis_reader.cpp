// MATLAB .fis reader: parse tree (grammar/MatlabFis.g4) -> FuzzySystem, with the meaning MATLAB gives each key and
// rule entry and Octave's hedge fractions. docs/matlab_fis.md describes every rule enforced here and its source.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "MatlabFisLexer.h"
#include "MatlabFisParser.h"
#include "grammar/parse_depth_limit.h"
#include "antlr4-runtime.h"
#include "compiler/frontend/matlab_fis.h"
#include "compiler/frontend/utf8.h"
#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

using grammar::MatlabFisLexer;
using grammar::MatlabFisParser;

constexpr double kPi = 3.141592653589793238462643383279502884;

// Byte positions of ANTLR tokens. ANTLR counts code points; SourceRange columns count bytes.
class SourcePositions {
 public:
  SourcePositions(std::string path, const std::string& text) : path_(std::move(path)) {
    line_starts_.push_back(0);
    for (std::size_t i = 0; i < text.size(); ++i) {
      const auto byte = static_cast<unsigned char>(text[i]);
      if ((byte & 0xC0U) != 0x80U) code_point_offsets_.push_back(i);
      if (text[i] == '\n' || (text[i] == '\r' && (i + 1 >= text.size() || text[i + 1] != '\n')))
        line_starts_.push_back(i + 1);
    }
    code_point_offsets_.push_back(text.size());
  }

  const std::string& path() const { return path_; }

  SourceRange token(const antlr4::Token* token) const {
    if (token == nullptr) return file_only();
    SourceRange range;
    range.file = path_;
    range.line = static_cast<int>(token->getLine());
    const std::size_t start = byte_offset(token->getStartIndex());
    const std::size_t stop =
        token->getStopIndex() >= token->getStartIndex() ? byte_offset(token->getStopIndex() + 1) : start;
    range.column = column_of(range.line, start);
    range.end_line = range.line;
    range.end_column = range.column + static_cast<int>(stop - start);
    return range;
  }

  // From the first token of `context` to the end of its last token.
  SourceRange span(antlr4::ParserRuleContext* context) const {
    if (context == nullptr) return file_only();
    SourceRange range = token(context->getStart());
    const SourceRange last = token(context->getStop());
    if (last.valid() && (last.line > range.line || (last.line == range.line && last.end_column > range.column))) {
      range.end_line = last.end_line;
      range.end_column = last.end_column;
    }
    return range;
  }

  // The text between the quotes of a STRING token.
  SourceRange string_inside(const antlr4::Token* token) const {
    SourceRange range = this->token(token);
    if (range.valid() && range.end_column - range.column >= 2) {
      range.column += 1;
      range.end_column -= 1;
    }
    return range;
  }

  SourceRange at(std::size_t line, std::size_t code_point_in_line_start, std::size_t code_point_index) const {
    SourceRange range;
    range.file = path_;
    range.line = static_cast<int>(line);
    const std::size_t start = byte_offset(code_point_index);
    range.column = line > 0 ? column_of(range.line, start) : static_cast<int>(code_point_in_line_start) + 1;
    range.end_line = range.line;
    range.end_column = range.column + 1;
    return range;
  }

  SourceRange file_only() const {
    SourceRange range;
    range.file = path_;
    return range;
  }

 private:
  std::size_t byte_offset(std::size_t code_point_index) const {
    return code_point_index < code_point_offsets_.size() ? code_point_offsets_[code_point_index]
                                                         : code_point_offsets_.back();
  }
  int column_of(int line, std::size_t byte) const {
    const std::size_t line_index = static_cast<std::size_t>(std::max(line, 1) - 1);
    const std::size_t line_start = line_index < line_starts_.size() ? line_starts_[line_index] : 0;
    return static_cast<int>(byte - std::min(byte, line_start)) + 1;
  }

  std::string path_;
  std::vector<std::size_t> line_starts_;
  std::vector<std::size_t> code_point_offsets_;
};

// Turns lexer and parser errors into diagnostics instead of console output.
class SyntaxErrorCollector : public antlr4::BaseErrorListener {
 public:
  SyntaxErrorCollector(const SourcePositions& positions, DiagnosticList& diagnostics)
      : positions_(positions), diagnostics_(diagnostics) {}

  void syntaxError(antlr4::Recognizer* recognizer, antlr4::Token* offending, std::size_t line,
                   std::size_t char_position, const std::string& message, std::exception_ptr) override {
    ++count_;
    // Error recovery repeats itself on the rest of a bad line; the first error of a line is the useful one.
    if (line == last_line_) return;
    last_line_ = line;
    SourceRange range;
    if (offending != nullptr && offending->getType() != antlr4::Token::EOF) {
      range = positions_.token(offending);
    } else if (auto* lexer = dynamic_cast<antlr4::Lexer*>(recognizer)) {
      range = positions_.at(line, char_position, lexer->tokenStartCharIndex);
    } else if (offending != nullptr) {
      range = positions_.token(offending);
      range.end_column = range.column + 1;
    } else {
      range = positions_.file_only();
    }
    std::string text = "syntax error: " + message;
    if (offending != nullptr && offending->getType() == MatlabFisLexer::UNTERMINATED_STRING)
      text = "this quoted text is not closed on its line: add the closing '";
    else if (offending != nullptr && offending->getType() == MatlabFisLexer::UNEXPECTED_CHARACTER)
      text = "unexpected character '" + offending->getText() + "'";
    diagnostics_.error(range, text,
                       {"a .fis line is a section header ([System], [Input1], [Output1], [Rules]), `Key = value`, "
                        "`MF1 = 'name' : 'trimf', [a b c]` or, under [Rules], `1 2, 1 (1) : 1`"});
  }

  int count() const { return count_; }

 private:
  const SourcePositions& positions_;
  DiagnosticList& diagnostics_;
  int count_ = 0;
  std::size_t last_line_ = 0;
};

std::string unquote(const std::string& quoted) {
  std::string text;
  for (std::size_t i = 1; i + 1 < quoted.size(); ++i) {
    text += quoted[i];
    if (quoted[i] == '\'' && i + 2 < quoted.size() && quoted[i + 1] == '\'') ++i;
  }
  return text;
}

std::string ordinal(std::size_t n) {
  const char* suffix = "th";
  if (n % 100 < 11 || n % 100 > 13) {
    if (n % 10 == 1) suffix = "st";
    else if (n % 10 == 2) suffix = "nd";
    else if (n % 10 == 3) suffix = "rd";
  }
  return std::to_string(n) + suffix;
}

std::string plural(std::size_t n, const std::string& singular, const std::string& plural_form) {
  return std::to_string(n) + " " + (n == 1 ? singular : plural_form);
}

enum class SectionKind { System, Input, Output, Rules };

struct Section {
  SectionKind kind = SectionKind::System;
  int index = 0;  // 1-based for [InputN] / [OutputN]
  SourceRange header;
  std::vector<MatlabFisParser::KeyLineContext*> keys;
  std::vector<MatlabFisParser::MfLineContext*> mfs;
  std::vector<MatlabFisParser::RuleLineContext*> rules;
};

const std::vector<std::string> kSystemKeys = {"Name",      "Type",      "Version",   "NumInputs",
                                              "NumOutputs", "NumRules", "AndMethod", "OrMethod",
                                              "ImpMethod", "AggMethod", "DefuzzMethod",
                                              "TypeRedMethod", "TypeReductionMethod"};
const std::vector<std::string> kVariableKeys = {"Name", "Range", "NumMFs"};

class SystemBuilder {
 public:
  SystemBuilder(const SourcePositions& positions, DiagnosticList& diagnostics)
      : positions_(positions), diagnostics_(diagnostics) {}

  std::optional<FuzzySystem> build(MatlabFisParser::FileContext* file) {
    collect_sections(file);
    if (!system_section_) {
      diagnostics_.error(positions_.file_only(), "no [System] section: a MATLAB .fis file starts with [System]");
      return std::nullopt;
    }
    FuzzySystem system;
    system.range = system_section_->header;
    read_system_keys(*system_section_, system);
    read_variables(system);
    read_rules(system);
    return system;
  }

 private:
  // ---- sections ---------------------------------------------------------------------------------------------

  void collect_sections(MatlabFisParser::FileContext* file) {
    Section* current = nullptr;
    for (MatlabFisParser::LineContext* line : file->line()) {
      if (auto* header = dynamic_cast<MatlabFisParser::SectionLineContext*>(line)) {
        current = open_section(header);
      } else if (current == nullptr) {
        diagnostics_.error(positions_.span(line), "this line comes before the [System] section",
                           {"a MATLAB .fis file starts with [System]"});
        current = &discarded_;
      } else if (auto* key = dynamic_cast<MatlabFisParser::KeyLineContext*>(line)) {
        if (current->kind == SectionKind::Rules)
          diagnostics_.error(positions_.span(key), "expected a rule line such as `1 2, 1 (1) : 1` in [Rules]");
        else
          current->keys.push_back(key);
      } else if (auto* mf = dynamic_cast<MatlabFisParser::MfLineContext*>(line)) {
        if (current->kind == SectionKind::Input || current->kind == SectionKind::Output)
          current->mfs.push_back(mf);
        else
          diagnostics_.error(positions_.span(mf), "membership functions belong in an [InputN] or [OutputN] section");
      } else if (auto* rule = dynamic_cast<MatlabFisParser::RuleLineContext*>(line)) {
        if (current->kind == SectionKind::Rules)
          current->rules.push_back(rule);
        else
          diagnostics_.error(positions_.span(rule), "rule lines belong in the [Rules] section");
      }
    }
  }

  Section* open_section(MatlabFisParser::SectionLineContext* header) {
    const std::string text = header->SECTION()->getText();  // "[Input12]"
    const std::string body = text.substr(1, text.size() - 2);
    Section section;
    section.header = positions_.token(header->SECTION()->getSymbol());
    std::map<int, Section>* numbered = nullptr;
    if (body == "System") {
      section.kind = SectionKind::System;
    } else if (body == "Rules") {
      section.kind = SectionKind::Rules;
    } else {
      const bool input = body.rfind("Input", 0) == 0;
      section.kind = input ? SectionKind::Input : SectionKind::Output;
      const std::string digits = body.substr(input ? 5 : 6);
      int index = 0;
      const auto result = std::from_chars(digits.data(), digits.data() + digits.size(), index);
      if (result.ec != std::errc() || index < 1) {
        diagnostics_.error(section.header, "section numbers start at 1: write [" +
                                               std::string(input ? "Input" : "Output") + "1]");
        return &discarded_;
      }
      section.index = index;
      numbered = input ? &inputs_ : &outputs_;
    }

    Section* existing = nullptr;
    if (section.kind == SectionKind::System && system_section_) existing = &*system_section_;
    if (section.kind == SectionKind::Rules && rules_section_) existing = &*rules_section_;
    if (numbered != nullptr) {
      auto found = numbered->find(section.index);
      if (found != numbered->end()) existing = &found->second;
    }
    if (existing != nullptr) {
      diagnostics_.error(section.header, "duplicate section " + text + ": MATLAB reads only one of them",
                         {"first defined here: " + std::to_string(existing->header.line) + ":" +
                          std::to_string(existing->header.column)});
      discarded_ = Section{};
      discarded_.kind = section.kind;
      return &discarded_;
    }
    if (section.kind == SectionKind::System) return &system_section_.emplace(std::move(section));
    if (section.kind == SectionKind::Rules) return &rules_section_.emplace(std::move(section));
    const int index = section.index;
    return &numbered->emplace(index, std::move(section)).first->second;
  }

  // ---- values -----------------------------------------------------------------------------------------------

  // Keys of `section` by name; a repeated key keeps the last value, as MATLAB's eval() of each line does.
  std::map<std::string, MatlabFisParser::KeyLineContext*> keyed(const Section& section,
                                                                const std::vector<std::string>& known,
                                                                const std::string& section_name) {
    std::map<std::string, MatlabFisParser::KeyLineContext*> keys;
    for (MatlabFisParser::KeyLineContext* line : section.keys) {
      const std::string key = line->key->getText();
      if (std::find(known.begin(), known.end(), key) == known.end()) {
        std::vector<std::string> notes;
        if (auto suggestion = closest_name(key, known)) notes.push_back("did you mean '" + *suggestion + "'?");
        if (key.size() > 2 && key.compare(0, 2, "MF") == 0 && section.kind != SectionKind::System)
          notes.push_back("a membership function is written MF1 = 'name' : 'type', [params]");
        diagnostics_.warning(positions_.token(line->key), "unknown-key",
                             "unknown key '" + key + "' in " + section_name + " is ignored", notes);
        continue;
      }
      auto found = keys.find(key);
      if (found != keys.end())
        diagnostics_.warning(positions_.token(line->key), "duplicate-key",
                             "'" + key + "' is given twice in " + section_name + "; the last value is used, as in "
                             "MATLAB",
                             {"first given here: " + std::to_string(found->second->key->getLine()) + ":" +
                              std::to_string(positions_.token(found->second->key).column)});
      keys[key] = line;
    }
    return keys;
  }

  std::optional<std::string> string_value(MatlabFisParser::KeyLineContext* line, SourceRange* inside = nullptr) {
    auto* value = dynamic_cast<MatlabFisParser::StringValueContext*>(line->value());
    if (value == nullptr) {
      diagnostics_.error(positions_.span(line->value()),
                         "'" + line->key->getText() + "' takes a quoted text such as 'name'");
      return std::nullopt;
    }
    if (inside != nullptr) *inside = positions_.string_inside(value->STRING()->getSymbol());
    return unquote(value->STRING()->getText());
  }

  std::optional<double> number_value(MatlabFisParser::KeyLineContext* line) {
    auto* value = dynamic_cast<MatlabFisParser::NumberValueContext*>(line->value());
    if (value == nullptr) {
      diagnostics_.error(positions_.span(line->value()), "'" + line->key->getText() + "' takes a number");
      return std::nullopt;
    }
    return evaluate(value->expression());
  }

  std::optional<int> count_value(MatlabFisParser::KeyLineContext* line) {
    const std::optional<double> value = number_value(line);
    if (!value) return std::nullopt;
    if (!(*value >= 0.0) || *value != std::floor(*value) || *value > 1e6) {
      diagnostics_.error(positions_.span(line->value()),
                         "'" + line->key->getText() + "' must be a whole number, 0 or more");
      return std::nullopt;
    }
    return static_cast<int>(*value);
  }

  std::optional<std::vector<double>> vector_value(MatlabFisParser::VectorContext* vector) {
    std::vector<double> values;
    bool ok = true;
    for (MatlabFisParser::ExpressionContext* element : vector->expression()) {
      const std::optional<double> value = evaluate(element);
      if (value) values.push_back(*value);
      else ok = false;
    }
    if (!ok) return std::nullopt;
    return values;
  }

  std::optional<double> parse_number(antlr4::Token* token) {
    const std::string text = token->getText();
    double value = 0.0;
    const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
    if (result.ec == std::errc::result_out_of_range) {
      diagnostics_.error(positions_.token(token), "the number " + text + " is out of the range of a double");
      return std::nullopt;
    }
    if (result.ec != std::errc() || result.ptr != text.data() + text.size()) {
      diagnostics_.error(positions_.token(token), "'" + text + "' is not a number");
      return std::nullopt;
    }
    return value;
  }

  // MATLAB evaluates values with eval(); fmpc evaluates the arithmetic such files use (`pi/4`, `2*pi`, `1e-3`).
  std::optional<double> evaluate(MatlabFisParser::ExpressionContext* expression) {
    std::optional<double> result;
    antlr4::Token* pending = nullptr;
    for (antlr4::tree::ParseTree* child : expression->children) {
      if (auto* terminal = dynamic_cast<antlr4::tree::TerminalNode*>(child)) {
        pending = terminal->getSymbol();
        continue;
      }
      const std::optional<double> operand = evaluate(dynamic_cast<MatlabFisParser::UnaryContext*>(child));
      if (!operand) return std::nullopt;
      if (!result) result = operand;
      else if (pending != nullptr && pending->getType() == MatlabFisLexer::SLASH) *result /= *operand;
      else *result *= *operand;
    }
    return result;
  }

  std::optional<double> evaluate(MatlabFisParser::UnaryContext* unary) {
    if (auto* signed_unary = dynamic_cast<MatlabFisParser::SignedUnaryContext*>(unary)) {
      const std::optional<double> value = evaluate(signed_unary->unary());
      if (!value) return std::nullopt;
      return signed_unary->sign->getType() == MatlabFisLexer::MINUS ? -*value : *value;
    }
    auto* power = dynamic_cast<MatlabFisParser::PowerUnaryContext*>(unary);
    if (power == nullptr) return std::nullopt;
    const std::optional<double> base = evaluate(power->atom());
    if (!base || power->exponent == nullptr) return base;
    const std::optional<double> exponent = evaluate(power->exponent);
    if (!exponent) return std::nullopt;
    return std::pow(*base, *exponent);
  }

  std::optional<double> evaluate(MatlabFisParser::AtomContext* atom) {
    if (auto* number = dynamic_cast<MatlabFisParser::NumberAtomContext*>(atom))
      return parse_number(number->NUMBER()->getSymbol());
    if (auto* group = dynamic_cast<MatlabFisParser::GroupAtomContext*>(atom)) {
      std::optional<double> result;
      antlr4::Token* pending = nullptr;
      for (antlr4::tree::ParseTree* child : group->sum()->children) {
        if (auto* terminal = dynamic_cast<antlr4::tree::TerminalNode*>(child)) {
          pending = terminal->getSymbol();
          continue;
        }
        const std::optional<double> operand = evaluate(dynamic_cast<MatlabFisParser::ExpressionContext*>(child));
        if (!operand) return std::nullopt;
        if (!result) result = operand;
        else if (pending != nullptr && pending->getType() == MatlabFisLexer::MINUS) *result -= *operand;
        else *result += *operand;
      }
      return result;
    }
    auto* name = dynamic_cast<MatlabFisParser::NameAtomContext*>(atom);
    if (name == nullptr) return std::nullopt;
    const std::string text = name->IDENT()->getText();
    if (text == "pi") return kPi;
    if (text == "inf" || text == "Inf") return std::numeric_limits<double>::infinity();
    if (text == "nan" || text == "NaN" || text == "NAN") return std::nan("");
    if (text == "eps") return 0x1.0p-52;
    std::vector<std::string> notes = {"fmpc evaluates numbers, + - * / ^, parentheses, pi, inf, nan and eps"};
    if (auto suggestion = closest_name(text, {"pi", "inf", "Inf", "nan", "NaN", "eps"}))
      notes.insert(notes.begin(), "did you mean '" + *suggestion + "'?");
    diagnostics_.error(positions_.token(name->IDENT()->getSymbol()), "unknown name '" + text + "' in a number",
                       notes);
    return std::nullopt;
  }

  // ---- [System] ---------------------------------------------------------------------------------------------

  template <typename Enum>
  void read_method(const std::map<std::string, MatlabFisParser::KeyLineContext*>& keys, const std::string& key,
                   std::optional<Enum> (*lookup)(const std::string&), const std::vector<std::string>& known,
                   Enum& target) {
    auto found = keys.find(key);
    if (found == keys.end()) return;  // MATLAB's default stays
    SourceRange range;
    const std::optional<std::string> name = string_value(found->second, &range);
    if (!name) return;
    if (const std::optional<Enum> value = lookup(*name)) {
      target = *value;
      return;
    }
    std::vector<std::string> notes;
    if (auto suggestion = closest_name(*name, known)) notes.push_back("did you mean '" + *suggestion + "'?");
    std::string list;
    for (const std::string& candidate : known) list += (list.empty() ? "" : ", ") + candidate;
    notes.push_back(key + " takes one of: " + list);
    diagnostics_.error(range, "unsupported " + key + " '" + *name + "'", notes);
  }

  void read_system_keys(const Section& section, FuzzySystem& system) {
    const auto keys = keyed(section, kSystemKeys, "[System]");
    // MATLAB's readfis defaults for omitted keys.
    system.name = "Untitled";
    if (auto found = keys.find("Name"); found != keys.end()) {
      if (auto name = string_value(found->second)) system.name = *name;
    }
    if (auto found = keys.find("Type"); found != keys.end()) {
      SourceRange range;
      if (auto type = string_value(found->second, &range)) {
        if (*type == "mamdani" || *type == "mamdanitype2") {
          system.type = SystemType::Mamdani;
          system.interval_type2 = *type == "mamdanitype2";
        } else if (*type == "sugeno" || *type == "sugenotype2") {
          system.type = SystemType::Sugeno;
          system.interval_type2 = *type == "sugenotype2";
        } else {
          std::vector<std::string> notes;
          if (auto suggestion = closest_name(*type, {"mamdani", "sugeno", "mamdanitype2", "sugenotype2"}))
            notes.push_back("did you mean '" + *suggestion + "'?");
          diagnostics_.error(range,
                             "unknown system type '" + *type +
                                 "': expected 'mamdani', 'sugeno', 'mamdanitype2' or 'sugenotype2'",
                             notes);
        }
      }
    }
    if (auto found = keys.find("Version"); found != keys.end()) {
      // Version 3.0 may be what MATLAB writes for type-2 systems (docs/matlab_fis.md); it is read as 2.0.
      if (auto version = number_value(found->second); version && *version != 1.0 && *version != 2.0 &&
                                                      *version != 3.0)
        diagnostics_.warning(positions_.span(found->second->value()), "unknown-version",
                             "version " + format_number(*version) + " is not a known .fis version (1.0 or 2.0); "
                             "reading it as version 2.0");
    }
    // MATLAB's mamfistype2 / sugfistype2 keep Type 'mamdani' / 'sugeno'; the TypeReductionMethod key, which only
    // type-2 systems have, marks them (docs/matlab_fis.md). fmpc's earlier 'mamdanitype2' spelling is read too.
    for (const char* key : {"TypeRedMethod", "TypeReductionMethod"})
      if (keys.count(key) != 0) system.interval_type2 = true;
    if (system.type == SystemType::Sugeno) system.defuzzifier = Defuzzifier::WeightedAverage;

    read_method<TNorm>(keys, "AndMethod", tnorm_from_string, {"min", "prod", "einstein_product"}, system.and_method);
    read_method<SNorm>(keys, "OrMethod", snorm_from_string, {"max", "probor", "sum", "einstein_sum"},
                       system.or_method);
    read_method<TNorm>(keys, "ImpMethod", tnorm_from_string, {"min", "prod", "einstein_product"},
                       system.implication);
    read_method<SNorm>(keys, "AggMethod", snorm_from_string, {"max", "probor", "sum", "einstein_sum"},
                       system.aggregation);
    read_method<Defuzzifier>(keys, "DefuzzMethod", defuzzifier_from_string,
                             {"centroid", "bisector", "mom", "som", "lom", "wtaver", "wtsum"}, system.defuzzifier);

    read_type_reduction(keys, system);

    num_inputs_ = declared_count(keys, "NumInputs");
    num_outputs_ = declared_count(keys, "NumOutputs");
    num_rules_ = declared_count(keys, "NumRules");
  }

  // MATLAB's TypeReductionMethod: karnikmendel (default), ekm, iasc, eiasc. IASC computes the same interval as
  // EIASC (both are exact), so it is read as EIASC with a note.
  void read_type_reduction(const std::map<std::string, MatlabFisParser::KeyLineContext*>& keys,
                           FuzzySystem& system) {
    for (const char* key : {"TypeRedMethod", "TypeReductionMethod"}) {
      auto found = keys.find(key);
      if (found == keys.end()) continue;
      SourceRange range;
      const std::optional<std::string> name = string_value(found->second, &range);
      if (!name) continue;
      if (*name == "karnikmendel") {
        system.type_reduction = TypeReduction::KarnikMendel;
      } else if (*name == "ekm") {
        system.type_reduction = TypeReduction::EnhancedKarnikMendel;
      } else if (*name == "eiasc") {
        system.type_reduction = TypeReduction::Eiasc;
      } else if (*name == "iasc") {
        system.type_reduction = TypeReduction::Eiasc;
        diagnostics_.warning(range, "iasc-as-eiasc",
                             "type reduction 'iasc' is read as 'eiasc': both compute the exact interval, so the "
                             "outputs agree to rounding");
      } else {
        const std::vector<std::string> known = {"karnikmendel", "ekm", "iasc", "eiasc"};
        std::vector<std::string> notes;
        if (auto suggestion = closest_name(*name, known)) notes.push_back("did you mean '" + *suggestion + "'?");
        notes.push_back(std::string(key) + " takes one of: karnikmendel, ekm, iasc, eiasc");
        diagnostics_.error(range, "unsupported type reduction '" + *name + "'", notes);
      }
    }
  }

  struct DeclaredCount {
    std::optional<int> value;
    SourceRange range;
    bool present = false;
  };

  DeclaredCount declared_count(const std::map<std::string, MatlabFisParser::KeyLineContext*>& keys,
                               const std::string& key) {
    DeclaredCount count;
    auto found = keys.find(key);
    if (found == keys.end()) return count;
    count.present = true;
    count.range = positions_.span(found->second->value());
    count.value = count_value(found->second);
    return count;
  }

  // Checks a declared count against what the file holds; a missing count is inferred with a warning.
  void check_count(const DeclaredCount& declared, std::size_t actual, const std::string& key,
                   const std::string& what, const SourceRange& where_missing) {
    if (!declared.present) {
      diagnostics_.warning(where_missing, "missing-key",
                           key + " is missing; MATLAB needs it: add " + key + "=" + std::to_string(actual));
      return;
    }
    if (declared.value && static_cast<std::size_t>(*declared.value) != actual)
      diagnostics_.error(declared.range, key + " is " + std::to_string(*declared.value) + " but the file has " +
                                             plural(actual, what, what + "s"),
                         {"set " + key + "=" + std::to_string(actual) + " or add the missing " + what + "s"});
  }

  // ---- [InputN] / [OutputN] ---------------------------------------------------------------------------------

  void read_variables(FuzzySystem& system) {
    check_numbering(inputs_, num_inputs_, "Input", "NumInputs");
    check_numbering(outputs_, num_outputs_, "Output", "NumOutputs");
    check_count(num_inputs_, inputs_.size(), "NumInputs", "[InputN] section", system_section_->header);
    check_count(num_outputs_, outputs_.size(), "NumOutputs", "[OutputN] section", system_section_->header);
    // Rules refer to variables by position, so the variables are kept in section-number order.
    for (auto& [index, section] : inputs_) system.inputs.push_back(read_variable(section, "input", system, false));
    for (auto& [index, section] : outputs_) system.outputs.push_back(read_variable(section, "output", system, true));
  }

  void check_numbering(const std::map<int, Section>& sections, const DeclaredCount& declared,
                       const std::string& name, const std::string& key) {
    int expected = 1;
    for (const auto& [index, section] : sections) {
      if (index != expected) {
        diagnostics_.error(section.header, "[" + name + std::to_string(index) + "] follows [" + name +
                                               std::to_string(expected - 1) + "]: [" + name +
                                               std::to_string(expected) + "] is missing",
                           {"sections are numbered 1, 2, 3, ... without gaps"});
        expected = index;
      }
      if (declared.value && index > *declared.value && index == expected)
        diagnostics_.error(section.header, "[" + name + std::to_string(index) + "] is beyond " + key + "=" +
                                               std::to_string(*declared.value));
      ++expected;
    }
  }

  Variable read_variable(const Section& section, const std::string& role, const FuzzySystem& system,
                         bool is_output) {
    const std::string section_name = "[" + std::string(is_output ? "Output" : "Input") +
                                     std::to_string(section.index) + "]";
    const auto keys = keyed(section, kVariableKeys, section_name);
    Variable variable;
    variable.range = section.header;
    if (auto found = keys.find("Name"); found != keys.end()) {
      if (auto name = string_value(found->second, &variable.name_range)) variable.name = *name;
    } else {
      diagnostics_.error(section.header, section_name + " has no Name: add Name='...'");
    }
    if (auto found = keys.find("Range"); found != keys.end()) {
      auto* value = dynamic_cast<MatlabFisParser::VectorValueContext*>(found->second->value());
      std::optional<std::vector<double>> range;
      if (value != nullptr) range = vector_value(value->vector());
      if (value == nullptr || (range && range->size() != 2)) {
        diagnostics_.error(positions_.span(found->second->value()),
                           "Range takes two numbers, the lower and the upper bound: Range=[0 10]");
      } else if (range) {
        variable.min = (*range)[0];
        variable.max = (*range)[1];
      }
    } else {
      diagnostics_.error(section.header, section_name + " has no Range: add Range=[min max]");
    }

    DeclaredCount num_mfs;
    if (auto found = keys.find("NumMFs"); found != keys.end()) {
      num_mfs.present = true;
      num_mfs.range = positions_.span(found->second->value());
      num_mfs.value = count_value(found->second);
    }
    check_count(num_mfs, section.mfs.size(), "NumMFs", "MF line", section.header);

    for (std::size_t position = 0; position < section.mfs.size(); ++position)
      variable.terms.push_back(read_term(section.mfs[position], position, role, variable, system));
    return variable;
  }

  Term read_term(MatlabFisParser::MfLineContext* line, std::size_t position, const std::string& role,
                 const Variable& variable, const FuzzySystem& system) {
    Term term;
    term.range = positions_.span(line);
    term.name = unquote(line->name->getText());
    term.name_range = positions_.string_inside(line->name);

    // MATLAB reads MF lines in order and ignores the number after "MF"; Octave insists that it matches.
    const std::string key = line->key->getText();
    const std::string expected_key = "MF" + std::to_string(position + 1);
    if (key != expected_key)
      diagnostics_.warning(positions_.token(line->key), "mf-index",
                           "'" + key + "' is the " + ordinal(position + 1) + " MF line of " + role + " '" +
                               variable.name + "'; MATLAB reads MF lines in order, so it is " + expected_key,
                           {"Octave rejects this file; rename it " + expected_key});

    const std::string kind_name = unquote(line->kind->getText());
    const SourceRange kind_range = positions_.string_inside(line->kind);
    const std::optional<MfKind> kind = mf_kind_from_matlab_name(kind_name);
    if (!kind) {
      std::vector<std::string> known = {"trimf", "trapmf", "gaussmf", "gauss2mf", "gbellmf", "sigmf", "dsigmf",
                                        "psigmf", "zmf", "smf", "pimf", "linsmf", "linzmf", "constant", "linear"};
      std::vector<std::string> notes;
      if (auto suggestion = closest_name(kind_name, known)) notes.push_back("did you mean '" + *suggestion + "'?");
      notes.push_back("custom membership functions cannot be evaluated outside MATLAB");
      diagnostics_.error(kind_range, "unknown membership function type '" + kind_name + "'", notes);
      return term;
    }
    term.mf.kind = *kind;

    const SourceRange params_range = positions_.span(line->params);
    std::optional<std::vector<double>> params = vector_value(line->params);
    if (!params) return term;
    const int needed = *kind == MfKind::Linear ? static_cast<int>(system.inputs.size()) + 1 : mf_param_count(*kind);
    const auto count = static_cast<int>(params->size());
    if (count < needed) {
      diagnostics_.error(params_range, "'" + kind_name + "' takes " + plural(static_cast<std::size_t>(needed),
                                                                            "parameter", "parameters") +
                                           " but " + std::to_string(count) + " " +
                                           (count == 1 ? "is" : "are") + " given",
                         {*kind == MfKind::Linear ? "a linear output takes one coefficient per input and a constant"
                                                  : "see docs/matlab_fis.md for the order of each family"});
    } else if (count > needed) {
      // Old MATLAB versions stored every MF in 4 columns padded with zeros, and MATLAB ignores the extra columns.
      diagnostics_.warning(params_range, "extra-params",
                           "'" + kind_name + "' takes " +
                               plural(static_cast<std::size_t>(needed), "parameter", "parameters") + "; the " +
                               plural(static_cast<std::size_t>(count - needed), "extra value is", "extra values are") +
                               " ignored, as MATLAB does");
      params->resize(static_cast<std::size_t>(needed));
    }
    term.mf.params = std::move(*params);
    read_lower_scale_lag(line, term, system, role);
    return term;
  }

  // `,LowerScale,LowerLag` after the parameters of a type-2 MF line. Lenient: a missing pair reads as zero width
  // (with a warning); a scalar or a 2-vector lag are both accepted, the latter only with equal sides.
  void read_lower_scale_lag(MatlabFisParser::MfLineContext* line, Term& term, const FuzzySystem& system,
                            const std::string& role) {
    const bool sugeno_output = role == "output" && system.type == SystemType::Sugeno;
    if (!system.interval_type2 || sugeno_output) {
      if (line->lowerScale != nullptr)
        diagnostics_.warning(positions_.span(line->lowerScale), "lower-mf-ignored",
                             std::string("LowerScale and LowerLag belong to type-2 MFs ") +
                                 (sugeno_output ? "(a type-2 Sugeno system's outputs are type-1)"
                                                : "(this system is type-1)") +
                                 " and are ignored",
                             sugeno_output ? std::vector<std::string>{}
                                           : std::vector<std::string>{"a type-2 system names its type reduction in "
                                                                      "[System]: TypeReductionMethod='karnikmendel'"});
      return;
    }
    if (line->lowerScale == nullptr) {
      diagnostics_.warning(positions_.span(line), "missing-lower-mf",
                           "this type-2 MF line has no LowerScale and LowerLag; it is read with zero width "
                           "(lower MF = upper MF)",
                           {"MATLAB writes them after the parameters: MF1='name':'trimf',[0 1 2],1,[0.2 0.2]"});
      return;
    }
    Footprint footprint;
    footprint.kind = FootprintKind::ScaleLag;
    footprint.range = positions_.span(line->lowerScale);
    const std::optional<std::vector<double>> scale = numbers_of(line->lowerScale);
    if (!scale) return;
    if (scale->size() != 1) {
      diagnostics_.error(positions_.span(line->lowerScale), "LowerScale is one number in (0, 1]");
      return;
    }
    footprint.first = scale->front();
    if (line->lowerLag != nullptr) {
      const std::optional<std::vector<double>> lag = numbers_of(line->lowerLag);
      if (!lag) return;
      if (lag->empty() || lag->size() > 2) {
        diagnostics_.error(positions_.span(line->lowerLag), "LowerLag is one number or two in [0, 1)");
        return;
      }
      if (lag->size() == 2 && (*lag)[0] != (*lag)[1]) {
        diagnostics_.error(positions_.span(line->lowerLag),
                           "LowerLag [" + format_number((*lag)[0]) + " " + format_number((*lag)[1]) +
                               "] lags the two sides differently, which fmpc does not support",
                           {"use one lag for both sides, or write the lower MF explicitly in the fmpc language: "
                            "upper F(...) lower G(...)"});
        return;
      }
      footprint.second = lag->front();
    }
    term.footprint = footprint;
  }

  // A scalar or a vector value as numbers; nullopt after reporting a string or a bad number.
  std::optional<std::vector<double>> numbers_of(MatlabFisParser::ValueContext* value) {
    if (auto* vector = dynamic_cast<MatlabFisParser::VectorValueContext*>(value)) return vector_value(vector->vector());
    if (auto* number = dynamic_cast<MatlabFisParser::NumberValueContext*>(value)) {
      const std::optional<double> result = evaluate(number->expression());
      if (!result) return std::nullopt;
      return std::vector<double>{*result};
    }
    diagnostics_.error(positions_.span(value), "expected a number or a vector such as [0.2 0.2]");
    return std::nullopt;
  }

  // ---- [Rules] ----------------------------------------------------------------------------------------------

  void read_rules(FuzzySystem& system) {
    const std::size_t rule_lines = rules_section_ ? rules_section_->rules.size() : 0;
    check_count(num_rules_, rule_lines, "NumRules", "rule line", system_section_->header);
    if (!rules_section_) return;
    for (std::size_t r = 0; r < rules_section_->rules.size(); ++r)
      if (auto rule = read_rule(rules_section_->rules[r], r, system)) system.rules.push_back(std::move(*rule));
  }

  std::optional<double> signed_number(MatlabFisParser::SignedNumberContext* number) {
    const std::optional<double> value = parse_number(number->NUMBER()->getSymbol());
    if (!value) return std::nullopt;
    return number->sign != nullptr && number->sign->getType() == MatlabFisLexer::MINUS ? -*value : *value;
  }

  // One antecedent or consequent column: 0 = not part of the rule, negative = NOT, integer part = MF index,
  // fractional part = hedge, decoded as Octave's get_mf_index_and_hedge does: round(100 * fraction) / 10 is the
  // power the grade is raised to. Returns false on an error; `clause` stays empty for a column that is 0.
  bool read_clause(MatlabFisParser::SignedNumberContext* entry, int variable_index, const Variable& variable,
                   const std::string& role, std::size_t rule_index, std::optional<Clause>& clause) {
    const std::optional<double> value = signed_number(entry);
    if (!value) return false;
    const SourceRange range = positions_.span(entry);
    const double magnitude = std::fabs(*value);
    const double index = std::trunc(magnitude);
    if (index == 0.0) {
      if (magnitude != 0.0 || *value < 0.0)
        diagnostics_.warning(range, "dont-care-hedge",
                             "MF index 0 means " + role + " '" + variable.name + "' is not part of rule " +
                                 std::to_string(rule_index + 1) + "; the fraction and sign are ignored");
      return true;
    }
    if (index > static_cast<double>(variable.terms.size())) {
      diagnostics_.error(range, "MF index " + format_number(index) + " is out of range: " + role + " '" +
                                    variable.name + "' has " +
                                    plural(variable.terms.size(), "membership function", "membership functions"),
                         {"use 1 to " + std::to_string(variable.terms.size()) + ", 0 to leave the " + role +
                          " out of the rule, or a negative index for NOT"});
      return false;
    }
    Clause result;
    result.range = range;
    result.variable = variable_index;
    result.term = static_cast<int>(index) - 1;
    result.negated = *value < 0.0;
    const double power = std::round(100.0 * (magnitude - index)) / 10.0;
    if (power == 0.0) {
      result.hedge = Hedge::None;
    } else if (power == 0.5) {
      result.hedge = Hedge::Somewhat;
    } else if (power == 2.0) {
      result.hedge = Hedge::Very;
    } else if (power == 3.0) {
      result.hedge = Hedge::Extremely;
    } else if (power == 4.0) {
      result.hedge = Hedge::VeryVery;
    } else if (power == 1.0) {
      diagnostics_.warning(range, "identity-hedge",
                           "the fraction .1 raises the grade to the power 1, which changes nothing");
    } else {
      diagnostics_.error(range, "the fraction of " + entry->getText() + " is a hedge (power " +
                                    format_number(power) + ") that fmpc does not support",
                         {"Octave's hedges: .05 somewhat (power 0.5), .2 very (2), .3 extremely (3), "
                          ".4 very very (4)"});
      return false;
    }
    clause = result;
    return true;
  }

  std::optional<Rule> read_rule(MatlabFisParser::RuleLineContext* line, std::size_t rule_index,
                                const FuzzySystem& system) {
    Rule rule;
    rule.range = positions_.span(line);
    bool ok = true;
    const auto antecedent = line->antecedent->signedNumber();
    const auto consequent = line->consequent->signedNumber();
    ok &= check_columns(antecedent, system.inputs.size(), "input", line->COMMA()->getSymbol(), rule_index);
    ok &= check_columns(consequent, system.outputs.size(), "output", line->LPAREN()->getSymbol(), rule_index);

    for (std::size_t i = 0; i < std::min(antecedent.size(), system.inputs.size()); ++i) {
      std::optional<Clause> clause;
      ok &= read_clause(antecedent[i], static_cast<int>(i), system.inputs[i], "input", rule_index, clause);
      if (clause) rule.antecedent.push_back(std::move(*clause));
    }
    for (std::size_t o = 0; o < std::min(consequent.size(), system.outputs.size()); ++o) {
      std::optional<Clause> clause;
      ok &= read_clause(consequent[o], static_cast<int>(o), system.outputs[o], "output", rule_index, clause);
      if (clause) rule.consequent.push_back(std::move(*clause));
    }

    if (auto weight = signed_number(line->weight)) rule.weight = *weight;
    else ok = false;
    const std::optional<double> connective = signed_number(line->connective);
    if (connective && *connective == 1.0) {
      rule.connective = Connective::And;
    } else if (connective && *connective == 2.0) {
      rule.connective = Connective::Or;
    } else {
      if (connective)
        diagnostics_.error(positions_.span(line->connective),
                           "the connective after ':' is 1 (AND) or 2 (OR), not " + line->connective->getText());
      ok = false;
    }
    if (!ok) return std::nullopt;

    if (rule.antecedent.empty() && !system.inputs.empty()) {
      diagnostics_.error(positions_.span(line->antecedent),
                         "rule " + std::to_string(rule_index + 1) + " has no antecedent: every input is 0 (not part "
                         "of the rule)",
                         {"MATLAB rejects such a rule; give at least one input an MF index"});
      return std::nullopt;
    }
    if (rule.consequent.empty()) {
      diagnostics_.warning(positions_.span(line->consequent), "empty-consequent",
                           "rule " + std::to_string(rule_index + 1) + " has no consequent: every output is 0, so the "
                           "rule changes no output and is dropped");
      return std::nullopt;
    }
    return rule;
  }

  bool check_columns(const std::vector<MatlabFisParser::SignedNumberContext*>& columns, std::size_t expected,
                     const std::string& role, antlr4::Token* after, std::size_t rule_index) {
    if (columns.size() == expected) return true;
    const std::string message = "rule " + std::to_string(rule_index + 1) + " has " +
                                plural(columns.size(), role + " column", role + " columns") + " but the system has " +
                                plural(expected, role, role + "s");
    const std::string note = "write one MF index per " + role + ", 0 for an " + role + " not in the rule";
    if (columns.size() > expected) {
      diagnostics_.error(positions_.span(columns[expected]), message, {note});
    } else {
      SourceRange range = positions_.token(after);
      diagnostics_.error(range, message, {note});
    }
    return false;
  }

  const SourcePositions& positions_;
  DiagnosticList& diagnostics_;
  std::optional<Section> system_section_;
  std::optional<Section> rules_section_;
  std::map<int, Section> inputs_;
  std::map<int, Section> outputs_;
  Section discarded_;
  DeclaredCount num_inputs_;
  DeclaredCount num_outputs_;
  DeclaredCount num_rules_;
};

}  // namespace

RuleFile read_matlab_fis(const std::string& path, const std::string& text, DiagnosticList& diagnostics) {
  RuleFile file;
  file.path = path;

  if (report_invalid_utf8(path, text, diagnostics)) return file;
  const std::string source = blank_byte_order_mark(text);

  const SourcePositions positions(path, source);
  SyntaxErrorCollector errors(positions, diagnostics);
  antlr4::ANTLRInputStream input(source);
  MatlabFisLexer lexer(&input);
  lexer.removeErrorListeners();
  lexer.addErrorListener(&errors);
  antlr4::CommonTokenStream tokens(&lexer);
  MatlabFisParser parser(&tokens);
  parser.removeErrorListeners();
  parser.addErrorListener(&errors);
  const antlr4::Token* too_deep = nullptr;
  MatlabFisParser::FileContext* tree = grammar::parse_file_within_depth_limit(parser, &too_deep);
  if (!tree) {
    diagnostics.error(positions.token(too_deep), grammar::parse_depth_message(),
                      {"nesting is limited so that the parser cannot run off the end of its stack"});
    return file;
  }
  // A tree repaired by error recovery has missing children; only a clean parse is lowered.
  if (errors.count() > 0) return file;

  SystemBuilder builder(positions, diagnostics);
  if (std::optional<FuzzySystem> system = builder.build(tree)) file.systems.push_back(std::move(*system));
  return file;
}

}  // namespace fmpc

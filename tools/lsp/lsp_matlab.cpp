// The language server's answers for MATLAB .fis text (docs/matlab_fis.md): hover, completion, go to definition and
// formatting, read from the lines of the text (tools/lsp/matlab_lines.h) and, for names, numbers and grades, from
// the system the file loads into. A rule line, all numbers in MATLAB's format, is read back as the rule it means.
#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "compiler/frontend/fmpc_ast.h"
#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/matlab_fis.h"
#include "diagnostics/number_format.h"
#include "tools/lsp/completion_list.h"
#include "tools/lsp/hover_text.h"
#include "tools/lsp/lsp_document.h"
#include "tools/lsp/matlab_lines.h"

namespace fmpc::lsp {

namespace {

using Section = MatlabLine::Section;

// The [System] keys fmpc reads and what each means (docs/matlab_fis.md, "[System]").
struct SystemKey {
  const char* key;
  const char* meaning;
  std::vector<const char*> values;
};

const std::vector<SystemKey>& system_keys() {
  static const std::vector<SystemKey> keys{
      {"Name", "the system's name", {}},
      {"Type", "`mamdani` (output terms are sets) or `sugeno` (output terms are constants or linear functions)",
       {"mamdani", "sugeno"}},
      {"Version", "the file format's version (`2.0` is what MATLAB writes)", {}},
      {"NumInputs", "how many [Input] sections follow", {}},
      {"NumOutputs", "how many [Output] sections follow", {}},
      {"NumRules", "how many rule lines [Rules] holds", {}},
      {"AndMethod", "how `and` joins the grades of a rule's conditions", {"min", "prod", "einstein_product"}},
      {"OrMethod", "how `or` joins the grades of a rule's conditions", {"max", "probor", "sum", "einstein_sum"}},
      {"ImpMethod", "implication: how a rule's firing strength shapes its output term (min clips it, prod scales it)",
       {"min", "prod", "einstein_product"}},
      {"AggMethod", "aggregation: how the rules' output sets are combined into one", {"max", "probor", "sum", "einstein_sum"}},
      {"DefuzzMethod", "defuzzification: the crisp output drawn from the aggregated set (Sugeno: wtaver or wtsum)",
       {"centroid", "bisector", "mom", "som", "lom", "wtaver", "wtsum"}},
      {"TypeReductionMethod", "interval type-2 systems: how the output interval is reduced",
       {"karnikmendel", "ekm", "iasc", "eiasc"}},
  };
  return keys;
}

const SystemKey* system_key(const std::string& key) {
  for (const SystemKey& entry : system_keys())
    if (key == entry.key) return &entry;
  return nullptr;
}

Json position_json(const Position& position) { return Json{{"line", position.line}, {"character", position.character}}; }

// The token at `offset` (or ending at it), if any.
std::optional<std::size_t> token_at(const MatlabLine& line, std::size_t offset) {
  for (std::size_t i = 0; i < line.tokens.size(); ++i)
    if (line.tokens[i].begin <= offset && offset < line.tokens[i].end) return i;
  for (std::size_t i = 0; i < line.tokens.size(); ++i)
    if (line.tokens[i].end == offset) return i;
  return std::nullopt;
}

// Where a token of a rule line stands: `1 2, 3 (1) : 1` is antecedent entries, consequent entries, weight,
// connective.
struct RuleEntry {
  enum class Part { Antecedent, Consequent, Weight, Connective };
  Part part = Part::Antecedent;
  std::size_t index = 0;  // which entry of its part
  double value = 0;       // with its sign
};

// The entry that token `token` is (a number), or, with `token` == the line's size, where the next entry would go
// after the tokens ending at or before `limit`.
std::optional<RuleEntry> rule_entry(const MatlabLine& line, std::size_t token, std::size_t limit) {
  RuleEntry entry;
  for (std::size_t j = 0; j < line.tokens.size(); ++j) {
    const MatlabToken& t = line.tokens[j];
    if (token == line.tokens.size() && t.end > limit) break;
    if (t.text == ",") entry = RuleEntry{RuleEntry::Part::Consequent, 0, 0};
    else if (t.text == "(") entry = RuleEntry{RuleEntry::Part::Weight, 0, 0};
    else if (t.text == ":") entry = RuleEntry{RuleEntry::Part::Connective, 0, 0};
    if (t.kind != MatlabToken::Kind::Number) continue;
    if (j == token) {
      entry.value = std::strtod(t.text.c_str(), nullptr);
      if (j > 0 && line.tokens[j - 1].text == "-") entry.value = -entry.value;
      return entry;
    }
    ++entry.index;
  }
  if (token == line.tokens.size()) return entry;
  return std::nullopt;
}

// The variable whose section holds `line`.
const Variable* section_variable(const FuzzySystem& system, const MatlabLine& line, bool& is_output) {
  if (line.section != Section::Input && line.section != Section::Output) return nullptr;
  is_output = line.section == Section::Output;
  for (const Variable& variable : is_output ? system.outputs : system.inputs)
    if (variable.range.line == line.header_line + 1) return &variable;
  return nullptr;
}

std::string term_title(const Term& term, const Variable& variable, bool is_output) {
  return "**" + term.name + "**, a term of " + (is_output ? "output" : "input") + " **" + variable.name + "**";
}

// The term a rule entry names: the entry's magnitude counts the variable's terms from 1 (MATLAB's format; a
// fraction is Octave's hedge).
const Term* entry_term(const Variable& variable, double value) {
  const long index = static_cast<long>(std::fabs(value));
  if (index < 1 || static_cast<std::size_t>(index) > variable.terms.size()) return nullptr;
  return &variable.terms[static_cast<std::size_t>(index - 1)];
}

}  // namespace

const FuzzySystem* Document::matlab_system() const {
  if (diagnostics_.has_errors() || rules_.systems.size() != 1) return nullptr;
  return &rules_.systems.front();
}

Json Document::matlab_hover(const Position& position) const {
  const std::vector<MatlabLine> lines = read_matlab_lines(text_);
  if (position.line < 0 || static_cast<std::size_t>(position.line) >= lines.size()) return nullptr;
  const MatlabLine& line = lines[static_cast<std::size_t>(position.line)];
  const std::optional<std::size_t> found = token_at(line, positions_.offset(position));
  if (!found) return nullptr;
  const MatlabToken& token = line.tokens[*found];
  const Json range{{"start", position_json(positions_.at_offset(token.begin))},
                   {"end", position_json(positions_.at_offset(token.end))}};
  const std::string key = line.key();
  if (line.section == Section::System && !key.empty()) {
    const SystemKey* entry = system_key(key);
    return entry ? markdown_hover("**" + key + "**: " + entry->meaning, range) : Json(nullptr);
  }
  // An MF line's type needs no loaded system.
  const bool mf_line = key.size() > 2 && key.compare(0, 2, "MF") == 0;
  if (mf_line && token.kind == MatlabToken::Kind::String && *found >= 3 && line.tokens[*found - 1].text == ":") {
    const std::string text = family_hover_text(token.unquoted());
    return text.empty() ? Json(nullptr) : markdown_hover(text, range);
  }
  const FuzzySystem* system = matlab_system();
  if (!system) return nullptr;
  if (line.section == Section::Rules) {
    for (std::size_t r = 0; r < system->rules.size(); ++r) {
      if (system->rules[r].range.line != line.line + 1) continue;
      const std::string& label = system->rules[r].label;
      std::string text = "**" + (label.empty() ? system->rule_display_name(r) : "rule " + label) + "**: `" +
                         format_rule_body(*system, r) + "`";
      const std::optional<RuleEntry> entry = rule_entry(line, *found, 0);
      if (entry && (entry->part == RuleEntry::Part::Antecedent || entry->part == RuleEntry::Part::Consequent)) {
        const bool is_output = entry->part == RuleEntry::Part::Consequent;
        const std::vector<Variable>& variables = is_output ? system->outputs : system->inputs;
        if (entry->index < variables.size()) {
          const Variable& variable = variables[entry->index];
          const Term* term = entry_term(variable, entry->value);
          if (!term)
            text += "\n\n" + format_number(entry->value) + ": " + (is_output ? "output" : "input") + " **" +
                    variable.name + "** takes no part in this rule";
          else
            text += "\n\n" + std::string(entry->value < 0 ? "(negative: `not`) " : "") +
                    term_title(*term, variable, is_output) + " is " + term_hover_text(variable, *term);
        }
      } else if (entry && entry->part == RuleEntry::Part::Connective) {
        text += std::string("\n\nconnective ") + (entry->value == 1 ? "1: the conditions are joined by `and`"
                                                                    : "2: the conditions are joined by `or`");
      } else if (entry && entry->part == RuleEntry::Part::Weight) {
        text += "\n\nweight " + format_number(entry->value) + ": the rule's firing strength is multiplied by it";
      }
      return markdown_hover(text, range);
    }
    return nullptr;
  }
  bool is_output = false;
  const Variable* variable = section_variable(*system, line, is_output);
  if (!variable) return nullptr;
  if (line.is_header || key == "Name") return markdown_hover(variable_hover_text(*system, *variable, is_output), range);
  if (token.kind != MatlabToken::Kind::Number && !(mf_line && token.kind == MatlabToken::Kind::String)) return nullptr;
  double value = std::strtod(token.text.c_str(), nullptr);
  if (*found > 0 && line.tokens[*found - 1].text == "-") value = -value;
  if (key == "Range" && token.kind == MatlabToken::Kind::Number)
    return markdown_hover(value_hover_text(*variable, value), range);
  if (!mf_line) return nullptr;
  for (const Term& term : variable->terms) {
    if (term.range.line != line.line + 1) continue;
    if (token.kind == MatlabToken::Kind::String)
      return markdown_hover(term_title(term, *variable, is_output) + " is " + term_hover_text(*variable, term), range);
    if (term.mf.kind == MfKind::Constant || term.mf.kind == MfKind::Linear) return nullptr;
    return markdown_hover(value_hover_text(*variable, value), range);
  }
  return nullptr;
}

Json Document::matlab_definition(const Position& position) const {
  const FuzzySystem* system = matlab_system();
  const std::vector<MatlabLine> lines = read_matlab_lines(text_);
  if (!system || position.line < 0 || static_cast<std::size_t>(position.line) >= lines.size()) return nullptr;
  const MatlabLine& line = lines[static_cast<std::size_t>(position.line)];
  const std::optional<std::size_t> found = token_at(line, positions_.offset(position));
  if (line.section != Section::Rules || !found) return nullptr;
  const std::optional<RuleEntry> entry = rule_entry(line, *found, 0);
  if (!entry || (entry->part != RuleEntry::Part::Antecedent && entry->part != RuleEntry::Part::Consequent))
    return nullptr;
  const std::vector<Variable>& variables =
      entry->part == RuleEntry::Part::Consequent ? system->outputs : system->inputs;
  if (entry->index >= variables.size()) return nullptr;
  const Term* term = entry_term(variables[entry->index], entry->value);
  if (!term) return nullptr;
  return Json{{"uri", uri_}, {"range", range_json(term->name_range.valid() ? term->name_range : term->range)}};
}

Json Document::matlab_completion(const Position& position, bool snippets) const {
  Completions out;
  const std::vector<MatlabLine> lines = read_matlab_lines(text_);
  if (position.line < 0 || static_cast<std::size_t>(position.line) >= lines.size()) return out.list();
  const MatlabLine& line = lines[static_cast<std::size_t>(position.line)];
  const std::size_t offset = positions_.offset(position);
  // The word being typed is not context: the tokens before it are.
  std::size_t limit = offset;
  std::vector<const MatlabToken*> before;
  for (const MatlabToken& token : line.tokens) {
    if (token.end < offset || (token.end == offset && token.kind == MatlabToken::Kind::Symbol)) before.push_back(&token);
    else if (token.begin < offset) limit = token.begin;
  }
  if (line.section == Section::Rules && !line.is_header) {
    // From the lines, not the loaded system: a rule being typed leaves the file with errors.
    const std::optional<RuleEntry> entry = rule_entry(line, line.tokens.size(), limit);
    if (entry->part == RuleEntry::Part::Connective) {
      out.add("1", kItemValue, "and: every condition");
      out.add("2", kItemValue, "or: any condition");
    }
    if (entry->part != RuleEntry::Part::Antecedent && entry->part != RuleEntry::Part::Consequent) return out.list();
    const Section wanted = entry->part == RuleEntry::Part::Consequent ? Section::Output : Section::Input;
    std::string variable;
    std::vector<std::string> terms;
    for (const MatlabLine& other : lines) {
      if (other.section != wanted || other.section_number != static_cast<int>(entry->index) + 1 || other.is_header ||
          other.tokens.size() < 3 || other.tokens[2].kind != MatlabToken::Kind::String)
        continue;
      if (other.key() == "Name") variable = other.tokens[2].unquoted();
      else if (other.key().compare(0, 2, "MF") == 0) terms.push_back(other.tokens[2].unquoted());
    }
    if (variable.empty()) return out.list();
    for (std::size_t k = 0; k < terms.size(); ++k)
      out.add(std::to_string(k + 1), kItemEnumMember, variable + " is " + terms[k]);
    out.add("0", kItemValue, variable + " takes no part");
    return out.list();
  }
  const bool after_equals = before.size() >= 2 && before[0]->kind == MatlabToken::Kind::Name && before[1]->text == "=";
  if (!after_equals) {
    // A key or a section header.
    int inputs = 0, outputs = 0;
    bool system_header = false, rules_header = false;
    std::vector<std::string> keys_here;
    int mf_lines = 0;
    for (const MatlabLine& other : lines) {
      if (other.is_header) {
        system_header |= other.section == Section::System;
        rules_header |= other.section == Section::Rules;
        if (other.section == Section::Input) inputs = std::max(inputs, other.section_number);
        if (other.section == Section::Output) outputs = std::max(outputs, other.section_number);
      } else if (other.header_line == line.header_line && other.line != line.line && !other.key().empty()) {
        keys_here.push_back(other.key());
        if (other.key().compare(0, 2, "MF") == 0) ++mf_lines;
      }
    }
    const auto unused = [&](const std::string& key) {
      return std::find(keys_here.begin(), keys_here.end(), key) == keys_here.end();
    };
    if (line.is_header) {
      // A key belongs under the header, not on its line.
    } else if (line.section == Section::System) {
      for (const SystemKey& key : system_keys())
        if (unused(key.key)) out.add(key.key, kItemProperty, key.meaning, std::string(key.key) + "=", false);
    } else if (line.section == Section::Input || line.section == Section::Output) {
      if (unused("Name")) out.add("Name", kItemProperty, "the variable's name", "Name='", false);
      if (unused("Range")) out.add("Range", kItemProperty, "[min max]", "Range=[", false);
      if (unused("NumMFs")) out.add("NumMFs", kItemProperty, "how many MF lines follow", "NumMFs=", false);
      const std::string mf = "MF" + std::to_string(mf_lines + 1);
      out.add(mf, kItemProperty, "membership function: 'name':'type',[parameters]", mf + "='", false);
    }
    if (!system_header) out.add("[System]", kItemKeyword, "section");
    out.add("[Input" + std::to_string(inputs + 1) + "]", kItemKeyword, "section: the next input");
    out.add("[Output" + std::to_string(outputs + 1) + "]", kItemKeyword, "section: the next output");
    if (!rules_header) out.add("[Rules]", kItemKeyword, "section: one rule a line");
    return out.list();
  }
  const std::string key = before[0]->text;
  if (line.section == Section::System) {
    if (const SystemKey* entry = system_key(key))
      for (const char* value : entry->values) out.add(std::string("'") + value + "'", kItemValue, key);
    return out.list();
  }
  // An MF line's type, after `MFk='name':`.
  if (key.compare(0, 2, "MF") == 0 && before.size() >= 4 && before[2]->kind == MatlabToken::Kind::String &&
      before[3]->text == ":" && before.size() == 4) {
    for (const std::string& name : ast::family_names()) {
      const ast::FamilySignature* family = ast::find_family(name);
      const std::string matlab = matlab_name(family->kind);
      std::string parameters, snippet;
      int field = 1;
      for (const char* parameter : family->matlab_parameters) {
        parameters += (parameters.empty() ? "" : " ") + std::string(parameter);
        snippet += (snippet.empty() ? "" : " ") + std::string("${") + std::to_string(field++) + ":" + parameter + "}";
      }
      if (family->kind == MfKind::Linear) parameters = "p1 ... pN c", snippet = "$1";
      out.add("'" + matlab + "'", kItemFunction, "[" + parameters + "]: fmpc's " + name,
              snippets ? "'" + matlab + "',[" + snippet + "]" : "", true);
    }
  }
  return out.list();
}

std::optional<Json> Document::matlab_formatting(std::string& why) const {
  const FuzzySystem* system = matlab_system();
  if (!system) {
    why = "the file has errors: fix them first (the layout is written from the system the file describes)";
    return std::nullopt;
  }
  for (const MatlabLine& line : read_matlab_lines(text_))
    if (line.has_comment) {
      why = "line " + std::to_string(line.line + 1) +
            " has a comment, which MATLAB's writefis layout has no place for: formatting would drop it";
      return std::nullopt;
    }
  DiagnosticList writing;
  const std::string formatted = write_matlab_fis(*system, writing);
  if (!writing.items().empty()) {
    why = "MATLAB's layout cannot hold everything this file says: " + writing.items().front().message;
    return std::nullopt;
  }
  Json edits = Json::array();
  if (formatted != text_)
    edits.push_back(Json{{"range", {{"start", position_json(Position{})}, {"end", position_json(positions_.end())}}},
                         {"newText", formatted}});
  return edits;
}

}  // namespace fmpc::lsp

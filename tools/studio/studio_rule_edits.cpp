#include "tools/studio/studio_rule_edits.h"

#include <cmath>
#include <variant>

#include "compiler/frontend/fmpc_ast.h"
#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/rule_file_loader.h"
#include "diagnostics/number_format.h"

namespace fmpc::studio {

namespace {

// The file read both ways: the IR (names resolved, for printing rules) and the syntax tree (positions of every
// number and label). Only a file without errors is edited, so that the two line up system by system and rule by
// rule.
struct EditableFile {
  RuleFile rules;
  ast::File tree;
  std::size_t system = 0;  // the system edited, in both
};

std::optional<EditableFile> read_for_edit(const std::string& path, const std::string& text, const std::string& system,
                                          std::string& error) {
  if (detect_dialect(text) != Dialect::Fmpc) {
    error = std::string("this is a ") + dialect_name(detect_dialect(text)) +
            " file; the table and the membership editor change fmpc files (convert it: fmpc convert FILE --to fmpc)";
    return std::nullopt;
  }
  EditableFile file;
  DiagnosticList diagnostics;
  file.rules = load_rule_file(path, text, diagnostics);
  std::optional<ast::File> tree;
  if (!diagnostics.has_errors()) tree = ast::parse_fmpc(path, text, diagnostics);
  if (diagnostics.has_errors() || !tree || tree->systems.size() != file.rules.systems.size()) {
    error = "the text has errors: fix them first (they are listed under the editor)";
    return std::nullopt;
  }
  file.tree = std::move(*tree);
  for (std::size_t s = 0; s < file.rules.systems.size(); ++s)
    if (system.empty() || file.rules.systems[s].name == system) {
      file.system = s;
      return file;
    }
  error = "there is no system '" + system + "' in the text";
  return std::nullopt;
}

std::vector<const ast::Rule*> rules_of(const ast::System& system) {
  std::vector<const ast::Rule*> rules;
  for (const ast::Item& item : system.items)
    if (const auto* rule = std::get_if<ast::Rule>(&item)) rules.push_back(rule);
  return rules;
}

std::optional<std::pair<std::size_t, std::size_t>> offsets(const std::string& text, const SourceRange& range) {
  const std::optional<std::size_t> begin = offset_of(text, range.line, range.column);
  const std::optional<std::size_t> end = offset_of(text, range.end_line, range.end_column);
  if (!begin || !end || *end < *begin) return std::nullopt;
  return std::make_pair(*begin, *end);
}

std::optional<Hedge> hedge_named(const std::string& name) {
  for (Hedge hedge : {Hedge::None, Hedge::Somewhat, Hedge::Very, Hedge::Extremely, Hedge::VeryVery})
    if (name == to_string(hedge)) return hedge;
  return std::nullopt;
}

// The IR clauses of `specs`; nullopt with `error` naming what does not resolve.
std::optional<std::vector<Clause>> clauses_of(const FuzzySystem& system, const std::vector<ClauseSpec>& specs,
                                              bool consequent, std::string& error) {
  std::vector<Clause> clauses;
  const std::vector<Variable>& variables = consequent ? system.outputs : system.inputs;
  for (const ClauseSpec& spec : specs) {
    Clause clause;
    clause.variable = consequent ? system.find_output(spec.variable) : system.find_input(spec.variable);
    if (clause.variable < 0) {
      error = "'" + spec.variable + "' is not an " + (consequent ? "output" : "input") + " of '" + system.name + "'";
      return std::nullopt;
    }
    clause.term = variables[static_cast<std::size_t>(clause.variable)].find_term(spec.term);
    if (clause.term < 0) {
      error = "'" + spec.variable + "' has no term '" + spec.term + "'";
      return std::nullopt;
    }
    const std::optional<Hedge> hedge = hedge_named(spec.hedge);
    if (!hedge) {
      error = "'" + spec.hedge + "' is not a hedge (somewhat, very, extremely, very very)";
      return std::nullopt;
    }
    clause.hedge = *hedge;
    clause.negated = spec.negated;
    clauses.push_back(clause);
  }
  return clauses;
}

std::optional<Rule> rule_of(const FuzzySystem& system, const RuleSpec& spec, std::string& error) {
  Rule rule;
  const std::optional<std::vector<Clause>> antecedent = clauses_of(system, spec.antecedent, false, error);
  if (!antecedent) return std::nullopt;
  const std::optional<std::vector<Clause>> consequent = clauses_of(system, spec.consequent, true, error);
  if (!consequent) return std::nullopt;
  if (antecedent->empty() || consequent->empty()) {
    error = "a rule needs at least one condition and one conclusion";
    return std::nullopt;
  }
  if (!(spec.weight >= 0.0 && spec.weight <= 1.0)) {
    error = "a weight lies between 0 and 1";
    return std::nullopt;
  }
  rule.antecedent = *antecedent;
  rule.consequent = *consequent;
  rule.connective = spec.conjunction ? Connective::And : Connective::Or;
  rule.weight = spec.weight;
  return rule;
}

// The offset just past the end of the line holding `offset` (after its '\n'; the text's end on the last line).
std::size_t after_line(const std::string& text, std::size_t offset) {
  const std::size_t newline = text.find('\n', offset);
  return newline == std::string::npos ? text.size() : newline + 1;
}

}  // namespace

std::optional<std::size_t> offset_of(const std::string& text, int line, int column) {
  if (line < 1 || column < 1) return std::nullopt;
  std::size_t offset = 0;
  for (int l = 1; l < line; ++l) {
    const std::size_t newline = text.find('\n', offset);
    if (newline == std::string::npos) return std::nullopt;
    offset = newline + 1;
  }
  const std::size_t line_end = std::min(text.find('\n', offset), text.size());
  const std::size_t at = offset + static_cast<std::size_t>(column - 1);
  if (at > line_end) return std::nullopt;
  return at;
}

std::optional<std::string> set_term_parameter(const std::string& path, const std::string& text,
                                              const std::string& system, const std::string& variable,
                                              const std::string& term, const std::string& parameter, double value,
                                              std::string& error) {
  if (!std::isfinite(value)) {
    error = "give a finite number";
    return std::nullopt;
  }
  std::optional<EditableFile> file = read_for_edit(path, text, system, error);
  if (!file) return std::nullopt;
  for (const ast::Item& item : file->tree.systems[file->system].items) {
    const auto* v = std::get_if<ast::Variable>(&item);
    if (!v || v->name.text != variable) continue;
    for (const ast::Term& t : v->terms) {
      if (t.name.text != term) continue;
      for (const ast::Argument& argument : t.arguments) {
        if (argument.name.text != parameter) continue;
        if (argument.high) {
          error = "'" + parameter + "' of '" + term + "' is an interval: change it in the text";
          return std::nullopt;
        }
        const bool keep_unit = argument.unit && v->unit && argument.unit->text == v->unit->text;
        SourceRange span = argument.value.range;
        if (argument.unit) {
          span.end_line = argument.unit->range.end_line;
          span.end_column = argument.unit->range.end_column;
        }
        const auto at = offsets(text, span);
        if (!at) break;
        std::string edited = text;
        edited.replace(at->first, at->second - at->first,
                       format_number(value) + (keep_unit ? " " + argument.unit->text : ""));
        return edited;
      }
      error = "term '" + term + "' of '" + variable + "' has no parameter '" + parameter + "'";
      return std::nullopt;
    }
    error = "'" + variable + "' has no term '" + term + "'";
    return std::nullopt;
  }
  error = "there is no variable '" + variable + "'";
  return std::nullopt;
}

std::optional<std::string> set_rule(const std::string& path, const std::string& text, const std::string& system,
                                    std::size_t rule, const RuleSpec& spec, std::string& error) {
  std::optional<EditableFile> file = read_for_edit(path, text, system, error);
  if (!file) return std::nullopt;
  FuzzySystem copy = file->rules.systems[file->system];
  const std::vector<const ast::Rule*> rules = rules_of(file->tree.systems[file->system]);
  if (rule >= copy.rules.size() || rule >= rules.size()) {
    error = "there is no rule " + std::to_string(rule + 1);
    return std::nullopt;
  }
  std::optional<Rule> replacement = rule_of(copy, spec, error);
  if (!replacement) return std::nullopt;
  replacement->label = copy.rules[rule].label;
  copy.rules[rule] = *replacement;
  const auto at = offsets(text, rules[rule]->range);
  if (!at) {
    error = "the rule's place in the text was not found";
    return std::nullopt;
  }
  // "rule LABEL:" as written (a quoted label keeps its quotes), then the new body.
  const std::size_t label_end = rules[rule]->label ? offset_of(text, rules[rule]->label->range.end_line,
                                                               rules[rule]->label->range.end_column)
                                                         .value_or(at->first)
                                                   : at->first;
  const std::size_t colon = text.find(':', label_end);
  if (colon == std::string::npos || colon >= at->second) {
    error = "the rule's label was not found";
    return std::nullopt;
  }
  std::string edited = text;
  edited.replace(at->first, at->second - at->first,
                 text.substr(at->first, colon + 1 - at->first) + " " + format_rule_body(copy, rule));
  return edited;
}

std::optional<std::string> add_rule(const std::string& path, const std::string& text, const std::string& system,
                                    const RuleSpec& spec, std::string& error) {
  std::optional<EditableFile> file = read_for_edit(path, text, system, error);
  if (!file) return std::nullopt;
  FuzzySystem copy = file->rules.systems[file->system];
  RuleSpec wanted = spec;
  if (wanted.antecedent.empty() && wanted.consequent.empty()) {
    if (copy.inputs.empty() || copy.outputs.empty() || copy.inputs.front().terms.empty() ||
        copy.outputs.front().terms.empty()) {
      error = "the system needs an input and an output with terms before it can have a rule";
      return std::nullopt;
    }
    wanted.antecedent.push_back({copy.inputs.front().name, copy.inputs.front().terms.front().name, false, ""});
    wanted.consequent.push_back({copy.outputs.front().name, copy.outputs.front().terms.front().name, false, ""});
  }
  std::optional<Rule> rule = rule_of(copy, wanted, error);
  if (!rule) return std::nullopt;
  for (std::size_t n = copy.rules.size() + 1;; ++n) {
    const std::string label = "r" + std::to_string(n);
    bool taken = false;
    for (const Rule& existing : copy.rules) taken = taken || existing.label == label;
    if (!taken) {
      rule->label = label;
      break;
    }
  }
  copy.rules.push_back(*rule);
  const std::string line = "rule " + rule->label + ": " + format_rule_body(copy, copy.rules.size() - 1);
  // After the system's last rule, or after everything the system holds when it has none (with a blank line).
  const ast::System& tree = file->tree.systems[file->system];
  const std::vector<const ast::Rule*> rules = rules_of(tree);
  SourceRange last = tree.range;
  const auto later = [&](const SourceRange& range) {
    if (range.end_line > last.end_line || (range.end_line == last.end_line && range.end_column > last.end_column))
      last = range;
  };
  if (!rules.empty()) {
    last = rules.back()->range;
  } else {
    for (const ast::Setting& setting : tree.settings) later(setting.range);
    for (const ast::Item& item : tree.items)
      if (const auto* v = std::get_if<ast::Variable>(&item)) {
        later(v->range);
        for (const ast::Term& t : v->terms) later(t.range);
      }
  }
  const std::optional<std::size_t> end = offset_of(text, last.end_line, last.end_column);
  if (!end) {
    error = "the place for the new rule was not found";
    return std::nullopt;
  }
  const std::size_t insert = after_line(text, *end);
  std::string edited = text;
  std::string addition = (rules.empty() ? "\n" : "") + line + "\n";
  if (insert == text.size() && !text.empty() && text.back() != '\n') addition = "\n" + addition;
  edited.insert(insert, addition);
  return edited;
}

std::optional<std::string> delete_rule(const std::string& path, const std::string& text, const std::string& system,
                                       std::size_t rule, std::string& error) {
  std::optional<EditableFile> file = read_for_edit(path, text, system, error);
  if (!file) return std::nullopt;
  const std::vector<const ast::Rule*> rules = rules_of(file->tree.systems[file->system]);
  if (rule >= rules.size()) {
    error = "there is no rule " + std::to_string(rule + 1);
    return std::nullopt;
  }
  const auto at = offsets(text, rules[rule]->range);
  if (!at) {
    error = "the rule's place in the text was not found";
    return std::nullopt;
  }
  std::size_t begin = at->first, end = at->second;
  const std::size_t line_start = text.rfind('\n', begin == 0 ? 0 : begin - 1);
  const std::size_t first = begin == 0 || line_start == std::string::npos ? 0 : line_start + 1;
  const std::size_t line_end = after_line(text, end);
  const std::string before = text.substr(first, begin - first);
  std::string after = text.substr(end, line_end - end);
  const bool blank_before = before.find_first_not_of(" \t") == std::string::npos;
  const std::size_t rest = after.find_first_not_of(" \t\r\n");
  // The rule has its line to itself (a comment at its end goes with it).
  if (blank_before && (rest == std::string::npos || after[rest] == '#')) {
    begin = first;
    end = line_end;
  }
  std::string edited = text;
  edited.erase(begin, end - begin);
  return edited;
}

}  // namespace fmpc::studio

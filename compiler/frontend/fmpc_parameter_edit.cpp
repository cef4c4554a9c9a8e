// edit_fmpc_parameters (fmpc_language.h): numbers rewritten in place, found through the AST's source ranges.
#include <algorithm>

#include "compiler/frontend/fmpc_ast.h"
#include "compiler/frontend/fmpc_language.h"
#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

struct Replacement {
  std::size_t begin = 0;
  std::size_t end = 0;
  std::string text;
};

const ast::Term* find_term(const ast::File& file, const ParameterEdit& edit, const ast::Variable** variable) {
  for (const ast::System& system : file.systems) {
    if (system.name.text != edit.system) continue;
    for (const ast::Item& item : system.items) {
      const auto* candidate = std::get_if<ast::Variable>(&item);
      if (!candidate || candidate->name.text != edit.variable) continue;
      for (const ast::Term& term : candidate->terms) {
        if (term.name.text != edit.term) continue;
        *variable = candidate;
        return &term;
      }
    }
  }
  return nullptr;
}

}  // namespace

std::optional<std::string> edit_fmpc_parameters(const std::string& path, const std::string& text,
                                                const std::vector<ParameterEdit>& edits,
                                                DiagnosticList& diagnostics) {
  DiagnosticList syntax;
  const std::optional<ast::File> file = ast::parse_fmpc(path, text, syntax);
  if (!file || syntax.has_errors()) {
    diagnostics.append(syntax);
    return std::nullopt;
  }
  std::vector<std::size_t> line_starts{0};
  for (std::size_t i = 0; i < text.size(); ++i)
    if (text[i] == '\n') line_starts.push_back(i + 1);
  const auto offset = [&](int line, int column) {
    return line_starts[static_cast<std::size_t>(line - 1)] + static_cast<std::size_t>(column - 1);
  };
  std::vector<Replacement> replacements;
  DiagnosticList problems;
  for (const ParameterEdit& edit : edits) {
    const ast::Variable* variable = nullptr;
    const ast::Term* term = find_term(*file, edit, &variable);
    if (!term) {
      problems.error(SourceRange{path, 0, 0, 0, 0}, "no term '" + edit.term + "' of '" + edit.variable +
                                                           "' in system '" + edit.system + "' to write into");
      continue;
    }
    const std::string unit = variable->unit ? variable->unit->text : "";
    const std::string number = format_number(edit.value);
    const auto found = std::find_if(term->arguments.begin(), term->arguments.end(), [&](const ast::Argument& a) {
      return a.name.text == edit.parameter && !(edit.parameter == "offset" && a.name.quoted);
    });
    if (found != term->arguments.end()) {
      Replacement replacement;
      replacement.begin = offset(found->value.range.line, found->value.range.column);
      replacement.end = offset(found->value.range.end_line, found->value.range.end_column);
      replacement.text = number;
      // Written in another unit: the number and its unit become the value in the variable's unit.
      if (found->unit && found->unit->text != unit) {
        replacement.end = offset(found->unit->range.end_line, found->unit->range.end_column);
        if (!unit.empty()) replacement.text += (unit == "%" ? "" : " ") + unit;
      }
      replacements.push_back(replacement);
      continue;
    }
    if (term->family.text != "linear" || !term->call_range.valid()) {
      problems.error(term->range, "term '" + edit.term + "' has no parameter '" + edit.parameter + "' to write");
      continue;
    }
    // A linear coefficient left out (0): added before the closing parenthesis.
    const std::size_t close = offset(term->call_range.end_line, term->call_range.end_column) - 1;
    const std::string name = edit.parameter == "offset" ? edit.parameter : ast::name_as_written(edit.parameter);
    replacements.push_back(
        Replacement{close, close, (term->arguments.empty() ? "" : ", ") + name + " " + number});
  }
  diagnostics.append(problems);
  if (problems.has_errors()) return std::nullopt;
  std::sort(replacements.begin(), replacements.end(),
            [](const Replacement& a, const Replacement& b) { return a.begin > b.begin; });
  std::string result = text;
  for (const Replacement& replacement : replacements)
    result.replace(replacement.begin, replacement.end - replacement.begin, replacement.text);
  return result;
}

}  // namespace fmpc

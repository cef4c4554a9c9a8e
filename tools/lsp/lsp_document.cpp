#include "tools/lsp/lsp_document.h"

#include <cctype>

#include "compiler/frontend/fmpc_language.h"
#include "compiler/sema/lint.h"
#include "diagnostics/number_format.h"
#include "runtime/io/input_file.h"

namespace fmpc::lsp {

namespace {

// LSP 3.17 enumerations (DiagnosticSeverity, SymbolKind).
constexpr int kSeverityError = 1;
constexpr int kSeverityWarning = 2;
constexpr int kSeverityInformation = 3;
constexpr int kSymbolNamespace = 3;
constexpr int kSymbolFunction = 12;
constexpr int kSymbolVariable = 13;
constexpr int kSymbolEnumMember = 22;

Json position_json(const Position& position) { return Json{{"line", position.line}, {"character", position.character}}; }

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool before(const Position& a, const Position& b) {
  return a.line < b.line || (a.line == b.line && a.character < b.character);
}

}  // namespace

std::string path_of_uri(const std::string& uri) {
  const std::string scheme = "file://";
  if (uri.compare(0, scheme.size(), scheme) != 0) return uri;
  std::string path;
  for (std::size_t i = scheme.size(); i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && hex_value(uri[i + 1]) >= 0 && hex_value(uri[i + 2]) >= 0) {
      path += static_cast<char>(hex_value(uri[i + 1]) * 16 + hex_value(uri[i + 2]));
      i += 2;
    } else {
      path += uri[i];
    }
  }
  return path;
}

Document::Document(std::string uri, std::string path, std::string text, PositionEncoding encoding)
    : uri_(std::move(uri)),
      path_(std::move(path)),
      text_(std::move(text)),
      encoding_(encoding),
      positions_(text_, encoding) {
  // The same bound as a rule file read from disk (docs/limits.md): past it nothing is parsed.
  if (text_.size() > sim::kMaxRuleFileBytes) {
    diagnostics_.error(SourceRange{path_, 1, 1, 1, 1},
                       "the document is " + std::to_string(text_.size()) + " bytes; rule files are read up to " +
                           std::to_string(sim::kMaxRuleFileBytes) + " bytes (docs/limits.md)");
    return;
  }
  dialect_ = detect_dialect(text_);
  rules_ = load_rule_file(path_, text_, diagnostics_);
  if (!diagnostics_.has_errors()) {
    LintOptions options;
    options.require_units = dialect_ == Dialect::Fmpc;
    for (const FuzzySystem& system : rules_.systems) lint_system(system, options, diagnostics_);
  }
  diagnostics_.sort_by_position();
  if (dialect_ == Dialect::Fmpc) outline_.emplace(path_, text_);
}

Json Document::range_json(const SourceRange& range) const {
  const auto [start, end] = positions_.range(range);
  return Json{{"start", position_json(start)}, {"end", position_json(end)}};
}

Json Document::diagnostics() const {
  Json list = Json::array();
  for (const Diagnostic& diagnostic : diagnostics_.items()) {
    std::string message = diagnostic.message;
    for (const std::string& note : diagnostic.notes) message += "\nnote: " + note;
    Json item{{"range", range_json(diagnostic.range)},
              {"severity", diagnostic.severity == Severity::Error     ? kSeverityError
                           : diagnostic.severity == Severity::Warning ? kSeverityWarning
                                                                      : kSeverityInformation},
              {"source", "fmpc"},
              {"message", message}};
    if (!diagnostic.code.empty()) item["code"] = diagnostic.code;
    list.push_back(std::move(item));
  }
  if (diagnostics_.dropped_count() > 0)
    list.push_back(Json{{"range", range_json(SourceRange{})},
                        {"severity", kSeverityInformation},
                        {"source", "fmpc"},
                        {"message", std::to_string(diagnostics_.dropped_count()) + " more diagnostics not shown"}});
  return list;
}

const FuzzySystem* Document::lowered_system(const std::string& name) const {
  for (const FuzzySystem& system : rules_.systems)
    if (system.name == name) return &system;
  return nullptr;
}

Json Document::definition(const Position& position) const {
  if (dialect_ == Dialect::Matlab) return matlab_definition(position);
  if (!outline_) return nullptr;
  const std::optional<std::size_t> token = outline_->token_at(positions_.offset(position), true);
  if (!token) return nullptr;
  const TokenRole role = outline_->role_of(*token);
  std::optional<std::size_t> target;
  if (role.kind == TokenRole::Kind::VariableReference || role.kind == TokenRole::Kind::VariableName) {
    if (role.variable) target = role.variable->name_token;
  } else if (role.kind == TokenRole::Kind::TermReference || role.kind == TokenRole::Kind::TermName) {
    if (role.term) target = role.term->name_token;
  }
  if (!target) return nullptr;
  return Json{{"uri", uri_}, {"range", range_json(outline_->tokens()[*target].range)}};
}

Json Document::symbols() const {
  Json result = Json::array();
  const auto symbol = [&](const std::string& name, const std::string& detail, int kind, const SourceRange& range,
                          const SourceRange& selection) {
    SourceRange whole = range;
    // The selection must lie inside the range.
    if (!whole.valid()) whole = selection;
    return Json{{"name", name.empty() ? std::string("(unnamed)") : name},
                {"detail", detail},
                {"kind", kind},
                {"range", range_json(whole)},
                {"selectionRange", range_json(selection.valid() ? selection : whole)},
                {"children", Json::array()}};
  };
  if (!outline_) {
    // Other dialects: from the IR, when the file loaded.
    for (const FuzzySystem& system : rules_.systems) {
      Json item = symbol(system.name, to_string(system.type), kSymbolNamespace, system.range, system.range);
      for (const auto* variables : {&system.inputs, &system.outputs}) {
        for (const Variable& variable : *variables) {
          Json child = symbol(variable.name, std::string(variables == &system.inputs ? "input" : "output") + " in [" +
                                                 format_number(variable.min) + ", " + format_number(variable.max) + "]",
                              kSymbolVariable, variable.range, variable.name_range);
          for (const Term& term : variable.terms)
            child["children"].push_back(
                symbol(term.name, matlab_name(term.mf.kind), kSymbolEnumMember, term.range, term.name_range));
          item["children"].push_back(std::move(child));
        }
      }
      for (std::size_t r = 0; r < system.rules.size(); ++r)
        item["children"].push_back(symbol(system.rule_display_name(r), "", kSymbolFunction, system.rules[r].range,
                                          system.rules[r].range));
      result.push_back(std::move(item));
    }
    return result;
  }
  const std::vector<FmpcToken>& tokens = outline_->tokens();
  const auto span = [&](std::size_t first, std::size_t last) {
    SourceRange range = tokens[first].range;
    range.end_line = tokens[last].range.end_line;
    range.end_column = tokens[last].range.end_column;
    return range;
  };
  // The text of tokens first..last as written, blanks between them kept to one space.
  const auto text_of = [&](std::size_t first, std::size_t last) {
    std::string text;
    for (std::size_t i = first; i <= last && i < tokens.size(); ++i) {
      if (tokens[i].kind == FmpcTokenKind::Comment) continue;
      if (!text.empty() && tokens[i].begin > tokens[i - 1].end) text += ' ';
      text += tokens[i].text;
    }
    return text;
  };
  for (const OutlineSystem& system : outline_->systems()) {
    Json item = symbol(system.name, "system", kSymbolNamespace, span(system.first_token, system.last_token),
                       tokens[system.name_token].range);
    for (const OutlineVariable& variable : system.variables) {
      std::size_t last = variable.last_token;
      for (const OutlineTerm& term : variable.terms) last = std::max(last, term.last_token);
      const std::string detail = (variable.is_output ? "output " : "input ") +
                                 (variable.last_token > variable.name_token
                                      ? text_of(variable.name_token + 1, variable.last_token)
                                      : std::string());
      Json child = symbol(variable.name, detail, kSymbolVariable, span(variable.first_token, last),
                          tokens[variable.name_token].range);
      for (const OutlineTerm& term : variable.terms) {
        const std::string shape =
            term.family_token != term.name_token ? text_of(term.family_token, term.last_token) : std::string();
        child["children"].push_back(symbol(term.name, shape, kSymbolEnumMember, span(term.first_token, term.last_token),
                                           tokens[term.name_token].range));
      }
      item["children"].push_back(std::move(child));
    }
    for (std::size_t r = 0; r < system.rules.size(); ++r) {
      const OutlineRule& rule = system.rules[r];
      std::size_t body = rule.first_token + 1;
      while (body <= rule.last_token && tokens[body].text != ":") ++body;
      const std::string detail = body < rule.last_token ? text_of(body + 1, rule.last_token) : std::string();
      const std::string name = rule.label.empty() ? "rule " + std::to_string(r + 1) : rule.label;
      const SourceRange selection = rule.label_token ? tokens[*rule.label_token].range : tokens[rule.first_token].range;
      item["children"].push_back(
          symbol(name, detail, kSymbolFunction, span(rule.first_token, rule.last_token), selection));
    }
    result.push_back(std::move(item));
  }
  return result;
}

std::optional<Json> Document::formatting(std::string& why) const {
  if (dialect_ == Dialect::Matlab) return matlab_formatting(why);
  if (dialect_ != Dialect::Fmpc) {
    why = std::string("fmpc formats its own language and MATLAB .fis; this is ") + dialect_name(dialect_) +
          " (fmpc convert --to fmpc turns it into fmpc text)";
    return std::nullopt;
  }
  DiagnosticList syntax;
  const std::optional<std::string> formatted = format_fmpc(path_, text_, syntax);
  if (!formatted) {
    why = "the file has syntax errors: fix them first (fmpc fmt needs a file that parses)";
    return std::nullopt;
  }
  Json edits = Json::array();
  if (*formatted != text_)
    edits.push_back(Json{{"range", {{"start", position_json(Position{})}, {"end", position_json(positions_.end())}}},
                         {"newText", *formatted}});
  return edits;
}

Json Document::code_actions(const Position& start, const Position& end) const {
  Json actions = Json::array();
  for (const Diagnostic& diagnostic : diagnostics_.items()) {
    if (!diagnostic.fix) continue;
    const auto [from, to] = positions_.range(diagnostic.range);
    if (before(end, from) || before(to, start)) continue;
    const FixIt& fix = *diagnostic.fix;
    const auto [fix_from, fix_to] = positions_.range(fix.range);
    const bool insertion = fix_from.line == fix_to.line && fix_from.character == fix_to.character;
    std::string title;
    if (insertion) title = "Insert '" + fix.replacement + "'";
    else if (fix.replacement.find_first_not_of(' ') == std::string::npos) title = "Remove it";
    else title = "Write " + fix.replacement;
    std::string message = diagnostic.message;
    for (const std::string& note : diagnostic.notes) message += "\nnote: " + note;
    Json edit{{"range", range_json(fix.range)}, {"newText", fix.replacement}};
    actions.push_back(Json{{"title", title},
                           {"kind", "quickfix"},
                           {"isPreferred", true},
                           {"diagnostics", Json::array({Json{{"range", range_json(diagnostic.range)},
                                                             {"severity", kSeverityError},
                                                             {"source", "fmpc"},
                                                             {"message", message}}})},
                           {"edit", {{"changes", {{uri_, Json::array({edit})}}}}}});
  }
  return actions;
}

}  // namespace fmpc::lsp

#pragma once
// One open document as the language server sees it: its text read and checked exactly as `fmpc check` does
// (load_rule_file and lint, every dialect), and for fmpc-language text the token outline (rule_outline.h) that
// symbols, definitions, hover and completion stand on; MATLAB .fis text is read line by line (lsp_matlab.cpp). Each feature returns the LSP 3.17 JSON shape of its answer
// (https://microsoft.github.io/language-server-protocol/specifications/lsp/3.17/specification/).
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "compiler/frontend/rule_file_loader.h"
#include "diagnostics/diagnostic.h"
#include "tools/lsp/rule_outline.h"
#include "tools/lsp/text_positions.h"

namespace fmpc::lsp {

using Json = nlohmann::json;

class Document {
 public:
  // `path` names the document in messages (the file path of a file: URI, else the URI itself).
  Document(std::string uri, std::string path, std::string text, PositionEncoding encoding);
  // Held in place: positions_ and outline_ refer to text_.
  Document(const Document&) = delete;
  Document& operator=(const Document&) = delete;

  const std::string& uri() const { return uri_; }
  const std::string& text() const { return text_; }
  Dialect dialect() const { return dialect_; }

  // PublishDiagnosticsParams.diagnostics: every error and lint warning, notes in the message, codes as `code`.
  Json diagnostics() const;
  // Hover at `position` (a term: its shape, parameters and grades; a number: every term's grade there; a
  // variable, a family, a hedge, a rule label), or null.
  Json hover(const Position& position) const;
  // CompletionList at `position`: the names, keywords and values the text allows there.
  Json completion(const Position& position, bool snippets) const;
  // Location of the declaration of the variable or term at `position`, or null.
  Json definition(const Position& position) const;
  // DocumentSymbol[]: systems, their variables and terms, and rules.
  Json symbols() const;
  // TextEdit[] giving `fmpc fmt`'s canonical layout (MATLAB .fis: MATLAB's writefis layout, as `fmpc convert --to
  // matlab` writes it), or nullopt with `why` (errors; comments in MATLAB text; FLL and FCL).
  std::optional<Json> formatting(std::string& why) const;
  // CodeAction[]: the fix-its of the diagnostics that touch `range`.
  Json code_actions(const Position& start, const Position& end) const;

  // LSP range JSON of a SourceRange or a token of the outline.
  Json range_json(const SourceRange& range) const;

 private:
  const FuzzySystem* lowered_system(const std::string& name) const;
  Json hover_term(const TokenRole& role) const;
  Json hover_number(const TokenRole& role) const;
  Json hover_variable(const TokenRole& role) const;
  // MATLAB .fis text (lsp_matlab.cpp). The system it loads into, or nullptr while it has errors.
  const FuzzySystem* matlab_system() const;
  Json matlab_hover(const Position& position) const;
  Json matlab_definition(const Position& position) const;
  Json matlab_completion(const Position& position, bool snippets) const;
  std::optional<Json> matlab_formatting(std::string& why) const;

  std::string uri_;
  std::string path_;
  std::string text_;
  PositionEncoding encoding_;
  TextPositions positions_;
  Dialect dialect_ = Dialect::Fmpc;
  RuleFile rules_;
  DiagnosticList diagnostics_;
  std::optional<RuleOutline> outline_;
};

// The file path of a `file://` URI (percent-escapes decoded), or the URI itself when it is another scheme.
std::string path_of_uri(const std::string& uri);

}  // namespace fmpc::lsp

#pragma once
// Lexical repairs of the fmpc language (docs/language.md, "Diagnostics"): character sequences that a newcomer writes
// and whose meaning is clear (`.5`, `==`, `mL/min`, `F0-F1`, `- 20`, an unclosed quote) are reported as errors that
// name the fix, with a fix-it, and handed to the parser as the fixed token, so that parsing goes on as if the fix
// were made and the later errors, syntax and semantic, are still reported. A character with no clear meaning stays
// an ERROR_CHARACTER token (the parser then reports nothing more on its line).
#include <memory>
#include <vector>

#include "antlr4-runtime.h"
#include "compiler/frontend/fmpc_source_map.h"
#include "diagnostics/diagnostic.h"

namespace fmpc::ast {

struct RepairedTokens {
  std::vector<std::unique_ptr<antlr4::Token>> tokens;  // every channel, ending with EOF
  bool unrepaired = false;  // an error was left in the tokens (the file then yields no AST)
};

// The lexer's tokens (`lexed`, filled) with every repair made; each repair and each unrepairable character is an
// error in `diagnostics`.
RepairedTokens repair_tokens(const SourceMap& source, antlr4::BufferedTokenStream& lexed, DiagnosticList& diagnostics);

}  // namespace fmpc::ast

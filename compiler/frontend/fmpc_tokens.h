#pragma once
// The tokens of fmpc-language text as the lexer sees them (grammar/Fmpc.g4), comments included, for tools that
// work on text that may not parse: the language server's outline, completion and hover (tools/lsp). Positions
// are SourceRanges (1-based lines, byte columns). Nothing is repaired or reported here; parse_fmpc does that.
#include <string>
#include <vector>

#include "diagnostics/source_range.h"

namespace fmpc {

enum class FmpcTokenKind {
  ReservedWord,     // system input output rule if then is not and or weight somewhat very extremely interval_type2
  ContextualWord,   // type implication ... lag: a keyword where a setting expects it, a name elsewhere
  Identifier,
  QuotedName,       // "F0-F1" (text keeps the quotes; an unterminated one runs to the line end)
  Number,
  Punctuation,      // : [ ] , ( ) %
  Comment,
  Unknown,          // a character the lexer cannot use
};

struct FmpcToken {
  FmpcTokenKind kind = FmpcTokenKind::Unknown;
  std::string text;
  SourceRange range;
  std::size_t begin = 0;  // byte offsets in the text
  std::size_t end = 0;
};

// The tokens of `text`, in order (blanks left out). Text that is not valid UTF-8 gives the tokens before the first
// bad byte.
std::vector<FmpcToken> tokenize_fmpc(const std::string& path, const std::string& text);

// A name's text without its quotes ("F0-F1" -> F0-F1); other tokens' text unchanged.
std::string unquoted_name(const FmpcToken& token);

// Whether `token` can stand where a name is expected (an identifier, a quoted name or a contextual word).
bool is_name_token(const FmpcToken& token);

}  // namespace fmpc

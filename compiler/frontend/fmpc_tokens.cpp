#include "compiler/frontend/fmpc_tokens.h"

#include "FmpcLexer.h"
#include "antlr4-runtime.h"
#include "compiler/frontend/fmpc_source_map.h"
#include "compiler/frontend/utf8.h"

namespace fmpc {

namespace {

using grammar::FmpcLexer;

FmpcTokenKind kind_of(std::size_t type, const std::string& text) {
  if (type >= FmpcLexer::SYSTEM && type <= FmpcLexer::EXTREMELY) return FmpcTokenKind::ReservedWord;
  if (type >= FmpcLexer::TYPE && type <= FmpcLexer::LAG) return FmpcTokenKind::ContextualWord;
  switch (type) {
    case FmpcLexer::IDENTIFIER: return FmpcTokenKind::Identifier;
    case FmpcLexer::STRING: return FmpcTokenKind::QuotedName;
    case FmpcLexer::NUMBER: return FmpcTokenKind::Number;
    case FmpcLexer::COMMENT: return FmpcTokenKind::Comment;
    case FmpcLexer::ERROR_CHARACTER: return FmpcTokenKind::Unknown;
    default: break;
  }
  return text.empty() ? FmpcTokenKind::Unknown : FmpcTokenKind::Punctuation;
}

}  // namespace

std::vector<FmpcToken> tokenize_fmpc(const std::string& path, const std::string& text) {
  const std::size_t bad_byte = first_invalid_utf8(text);
  const std::string valid = bad_byte == std::string::npos ? text : text.substr(0, bad_byte);
  const ast::SourceMap source(path, valid);
  antlr4::ANTLRInputStream input(valid);
  FmpcLexer lexer(&input);
  lexer.removeErrorListeners();
  antlr4::CommonTokenStream tokens(&lexer);
  tokens.fill();
  std::vector<FmpcToken> result;
  result.reserve(tokens.size());
  for (std::size_t i = 0; i < tokens.size(); ++i) {
    const antlr4::Token* token = tokens.get(i);
    if (token->getType() == antlr4::Token::EOF) break;
    FmpcToken out;
    out.text = token->getText();
    out.kind = kind_of(token->getType(), out.text);
    out.range = source.token(token);
    out.begin = source.byte_offset(token->getStartIndex());
    out.end = source.byte_offset(token->getStopIndex() + 1);
    result.push_back(std::move(out));
  }
  return result;
}

std::string unquoted_name(const FmpcToken& token) {
  if (token.kind != FmpcTokenKind::QuotedName || token.text.empty()) return token.text;
  const bool closed = token.text.size() >= 2 && token.text.back() == '"';
  return token.text.substr(1, token.text.size() - (closed ? 2 : 1));
}

bool is_name_token(const FmpcToken& token) {
  return token.kind == FmpcTokenKind::Identifier || token.kind == FmpcTokenKind::QuotedName ||
         token.kind == FmpcTokenKind::ContextualWord;
}

}  // namespace fmpc

#pragma once
// The generated ANTLR parsers recurse once per grammar rule they enter, on the C++ stack: MatlabFis.g4's
// `unary` and `expression` nest as deep as the text does (30,000 opening parentheses or minus signs overflow an
// 8 MiB stack). ParseDepthLimit is attached to a parser as a parse listener; it counts rule entries and exits and
// throws ParseDepthExceeded when a rule would be entered deeper than the limit, before the parser recurses
// further. The readers catch it and report the position (docs/limits.md).
#include <cstddef>
#include <exception>
#include <string>

#include "antlr4-runtime.h"

namespace fmpc::grammar {

// Grammar rule levels, not parentheses: in MatlabFis.g4 one parenthesis costs four levels (atom, sum,
// expression, unary), one sign or power one; a file of ordinary lines needs fewer than 10. At this depth the
// parser uses well under 1 MiB of stack, sanitizers included.
inline constexpr std::size_t kMaxParseDepth = 400;

// The error the readers report at the token where the limit was hit.
inline std::string parse_depth_message() {
  return "the text nests deeper than the parser's limit of " + std::to_string(kMaxParseDepth) +
         " grammar levels (about " + std::to_string(kMaxParseDepth / 4) +
         " parentheses, or as many signs or powers in a row); simplify the expression";
}

struct ParseDepthExceeded : std::exception {
  const antlr4::Token* token = nullptr;  // where the too-deep rule starts
  const char* what() const noexcept override { return "parse nesting too deep"; }
};

class ParseDepthLimit : public antlr4::tree::ParseTreeListener {
 public:
  explicit ParseDepthLimit(std::size_t limit = kMaxParseDepth) : limit_(limit) {}
  void enterEveryRule(antlr4::ParserRuleContext* context) override {
    if (++depth_ > limit_) {
      ParseDepthExceeded exceeded;
      exceeded.token = context->getStart();
      throw exceeded;
    }
  }
  void exitEveryRule(antlr4::ParserRuleContext*) override {
    if (depth_ > 0) --depth_;
  }
  void visitTerminal(antlr4::tree::TerminalNode*) override {}
  void visitErrorNode(antlr4::tree::ErrorNode*) override {}

 private:
  std::size_t limit_;
  std::size_t depth_ = 0;
};

// Parses the start rule `file` of `parser` within the limit: the tree, or nullptr with `*too_deep` set to the token
// where the limit was hit.
template <typename Parser>
auto parse_file_within_depth_limit(Parser& parser, const antlr4::Token** too_deep) -> decltype(parser.file()) {
  ParseDepthLimit depth_limit;
  parser.addParseListener(&depth_limit);
  try {
    auto* tree = parser.file();
    parser.removeParseListener(&depth_limit);
    return tree;
  } catch (const ParseDepthExceeded& exceeded) {
    parser.removeParseListener(&depth_limit);
    *too_deep = exceeded.token;
    return nullptr;
  }
}

}  // namespace fmpc::grammar

#pragma once
// The outline of fmpc-language text read from its tokens alone, so that it exists while the text is being typed and
// does not parse: systems, variables with their terms, rules, and what a token in a rule refers to. The language
// server's symbols, definitions, hover and completion stand on it; numbers and grades come from the IR when the
// system lowers without errors (tools/lsp/language_features.h).
#include <optional>
#include <string>
#include <vector>

#include "compiler/frontend/fmpc_tokens.h"

namespace fmpc::lsp {

struct OutlineTerm {
  std::string name;
  std::size_t name_token = 0;    // index into RuleOutline::tokens
  std::size_t family_token = 0;  // the family after `is` (after `upper`); == name_token when missing
  std::size_t first_token = 0, last_token = 0;
};

struct OutlineVariable {
  bool is_output = false;
  std::string name;
  std::size_t name_token = 0;
  std::size_t first_token = 0, last_token = 0;  // the header line
  std::vector<OutlineTerm> terms;
};

struct OutlineRule {
  std::string label;  // empty when unlabelled
  std::size_t first_token = 0, last_token = 0;
  std::optional<std::size_t> label_token;
};

struct OutlineSystem {
  std::string name;
  std::size_t name_token = 0;
  std::size_t first_token = 0, last_token = 0;  // the whole system, its items included
  std::vector<OutlineVariable> variables;
  std::vector<OutlineRule> rules;
  const OutlineVariable* find_variable(const std::string& name) const;
};

// What the token at some place is, read from its neighbours.
struct TokenRole {
  enum class Kind { None, SystemName, VariableName, TermName, Family, VariableReference, TermReference, RuleLabel,
                    Number, Hedge, Keyword };
  Kind kind = Kind::None;
  std::size_t token = 0;
  const OutlineSystem* system = nullptr;
  const OutlineVariable* variable = nullptr;  // the variable named or owning the term / number
  const OutlineTerm* term = nullptr;          // TermName: the declaration; TermReference: the one it names, if any
  const OutlineRule* rule = nullptr;          // the rule the token is in
  bool after_then = false;                    // in a rule: after `then` (a reference to an output)
};

class RuleOutline {
 public:
  RuleOutline(const std::string& path, const std::string& text);

  const std::vector<FmpcToken>& tokens() const { return tokens_; }
  const std::vector<OutlineSystem>& systems() const { return systems_; }

  // The visible token (not a comment) whose bytes hold `offset`, or end at it when `touching_end`; nullopt between
  // tokens.
  std::optional<std::size_t> token_at(std::size_t offset, bool touching_end = false) const;
  // The last visible token that ends at or before `offset`.
  std::optional<std::size_t> token_before(std::size_t offset) const;
  const OutlineSystem* system_of(std::size_t token) const;
  const OutlineVariable* variable_of(std::size_t token) const;  // whose header or terms hold the token
  const OutlineRule* rule_of(std::size_t token) const;
  TokenRole role_of(std::size_t token) const;

  // In a rule, the variable named before `is` for a term token at `token` (the clause's subject), if any.
  std::optional<std::size_t> clause_subject(std::size_t token) const;
  // Whether `token` lies after its rule's `then`.
  bool after_then(std::size_t token) const;

 private:
  void build();
  bool starts_line(std::size_t token) const;
  std::optional<std::size_t> next_visible(std::size_t token) const;
  std::optional<std::size_t> previous_visible(std::size_t token) const;

  std::vector<FmpcToken> tokens_;
  std::vector<OutlineSystem> systems_;
};

// Hedge words and their exponent as docs/language.md gives them.
bool is_hedge_word(const std::string& word);

}  // namespace fmpc::lsp

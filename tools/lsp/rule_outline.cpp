#include "tools/lsp/rule_outline.h"

#include <algorithm>

namespace fmpc::lsp {

namespace {

bool is_word(const FmpcToken& token, const char* word) {
  return (token.kind == FmpcTokenKind::ReservedWord || token.kind == FmpcTokenKind::ContextualWord) &&
         token.text == word;
}

bool is_setting_word(const FmpcToken& token) {
  for (const char* word : {"type", "type_reduction", "and", "or", "implication", "aggregation", "defuzzify", "when"})
    if (is_word(token, word)) return true;
  return false;
}

}  // namespace

bool is_hedge_word(const std::string& word) {
  return word == "somewhat" || word == "very" || word == "extremely";
}

const OutlineVariable* OutlineSystem::find_variable(const std::string& variable_name) const {
  for (const OutlineVariable& variable : variables)
    if (variable.name == variable_name) return &variable;
  return nullptr;
}

RuleOutline::RuleOutline(const std::string& path, const std::string& text) : tokens_(tokenize_fmpc(path, text)) {
  // Comments are kept in tokens_ (their positions matter to nobody here): the outline skips them.
  build();
}

std::optional<std::size_t> RuleOutline::next_visible(std::size_t token) const {
  for (std::size_t i = token + 1; i < tokens_.size(); ++i)
    if (tokens_[i].kind != FmpcTokenKind::Comment) return i;
  return std::nullopt;
}

std::optional<std::size_t> RuleOutline::previous_visible(std::size_t token) const {
  for (std::size_t i = token; i-- > 0;)
    if (tokens_[i].kind != FmpcTokenKind::Comment) return i;
  return std::nullopt;
}

bool RuleOutline::starts_line(std::size_t token) const {
  const std::optional<std::size_t> previous = previous_visible(token);
  return !previous || tokens_[*previous].range.end_line < tokens_[token].range.line;
}

void RuleOutline::build() {
  enum class Open { Nothing, SystemHeader, Setting, VariableHeader, Term, Rule };
  Open open = Open::Nothing;
  const auto ensure_system = [&](std::size_t i) {
    if (systems_.empty()) {
      OutlineSystem system;
      system.first_token = system.name_token = i;
      systems_.push_back(system);
    }
    return &systems_.back();
  };
  const auto name_after = [&](std::size_t i, std::string& name) -> std::optional<std::size_t> {
    const std::optional<std::size_t> next = next_visible(i);
    if (!next || !is_name_token(tokens_[*next])) return std::nullopt;
    name = unquoted_name(tokens_[*next]);
    return next;
  };
  for (std::size_t i = 0; i < tokens_.size(); ++i) {
    const FmpcToken& token = tokens_[i];
    if (token.kind == FmpcTokenKind::Comment) continue;
    // Indices of the next two visible tokens (tokens_.size() when there is none).
    const std::size_t none = tokens_.size();
    const std::size_t next = next_visible(i).value_or(none);
    const std::size_t after_next = next < none ? next_visible(next).value_or(none) : none;
    const bool next_is_is = next < none && is_word(tokens_[next], "is");
    OutlineVariable* variable =
        systems_.empty() || systems_.back().variables.empty() ? nullptr : &systems_.back().variables.back();
    if (is_word(token, "system")) {
      OutlineSystem system;
      system.first_token = system.name_token = i;
      if (auto name = name_after(i, system.name)) system.name_token = *name;
      systems_.push_back(system);
      open = Open::SystemHeader;
    } else if (is_word(token, "input") || is_word(token, "output")) {
      OutlineSystem* system = ensure_system(i);
      OutlineVariable added;
      added.is_output = token.text == "output";
      added.first_token = added.name_token = i;
      if (auto name = name_after(i, added.name)) added.name_token = *name;
      system->variables.push_back(added);
      open = Open::VariableHeader;
    } else if (is_word(token, "rule")) {
      OutlineSystem* system = ensure_system(i);
      OutlineRule rule;
      rule.first_token = i;
      if (next < none && is_name_token(tokens_[next]) && after_next < none && tokens_[after_next].text == ":") {
        rule.label = unquoted_name(tokens_[next]);
        rule.label_token = next;
      }
      system->rules.push_back(rule);
      open = Open::Rule;
    } else if (starts_line(i) && is_name_token(token) && next_is_is && variable &&
               (open == Open::VariableHeader || open == Open::Term)) {
      OutlineTerm term;
      term.name = unquoted_name(token);
      term.first_token = term.name_token = term.family_token = i;
      if (after_next < none) {
        std::size_t family = after_next;
        if (is_word(tokens_[family], "upper")) family = next_visible(family).value_or(family);
        if (is_name_token(tokens_[family])) term.family_token = family;
      }
      variable->terms.push_back(term);
      open = Open::Term;
    } else if (starts_line(i) && is_setting_word(token) &&
               !(open == Open::Rule && after_next < none && is_word(tokens_[after_next], "is"))) {
      ensure_system(i);
      open = Open::Setting;
    }
    // The token belongs to the item open now (and to its system).
    if (systems_.empty()) continue;
    OutlineSystem& system = systems_.back();
    system.last_token = i;
    if (open == Open::VariableHeader && !system.variables.empty()) system.variables.back().last_token = i;
    if (open == Open::Term && !system.variables.empty() && !system.variables.back().terms.empty())
      system.variables.back().terms.back().last_token = i;
    if (open == Open::Rule && !system.rules.empty()) system.rules.back().last_token = i;
  }
}

std::optional<std::size_t> RuleOutline::token_at(std::size_t offset, bool touching_end) const {
  // Tokens are in text order: the first one ending after `offset` (or at it) is the candidate.
  const auto it = std::lower_bound(tokens_.begin(), tokens_.end(), offset, [&](const FmpcToken& token, std::size_t at) {
    return touching_end ? token.end < at : token.end <= at;
  });
  if (it == tokens_.end() || it->begin > offset || it->kind == FmpcTokenKind::Comment) return std::nullopt;
  return static_cast<std::size_t>(it - tokens_.begin());
}

std::optional<std::size_t> RuleOutline::token_before(std::size_t offset) const {
  std::optional<std::size_t> found;
  for (std::size_t i = 0; i < tokens_.size() && tokens_[i].end <= offset; ++i)
    if (tokens_[i].kind != FmpcTokenKind::Comment) found = i;
  return found;
}

const OutlineSystem* RuleOutline::system_of(std::size_t token) const {
  for (const OutlineSystem& system : systems_)
    if (system.first_token <= token && token <= system.last_token) return &system;
  return nullptr;
}

const OutlineVariable* RuleOutline::variable_of(std::size_t token) const {
  const OutlineSystem* system = system_of(token);
  if (!system) return nullptr;
  for (const OutlineVariable& variable : system->variables) {
    if (variable.first_token <= token && token <= variable.last_token) return &variable;
    for (const OutlineTerm& term : variable.terms)
      if (term.first_token <= token && token <= term.last_token) return &variable;
  }
  return nullptr;
}

const OutlineRule* RuleOutline::rule_of(std::size_t token) const {
  const OutlineSystem* system = system_of(token);
  if (!system) return nullptr;
  for (const OutlineRule& rule : system->rules)
    if (rule.first_token <= token && token <= rule.last_token) return &rule;
  return nullptr;
}

bool RuleOutline::after_then(std::size_t token) const {
  const OutlineRule* rule = rule_of(token);
  if (!rule) return false;
  for (std::size_t i = rule->first_token; i < token && i < tokens_.size(); ++i)
    if (is_word(tokens_[i], "then")) return true;
  return false;
}

std::optional<std::size_t> RuleOutline::clause_subject(std::size_t token) const {
  // Back over `not` and the hedges to `is`; the name before it is the clause's variable.
  std::optional<std::size_t> at = previous_visible(token);
  while (at && (is_word(tokens_[*at], "not") || is_hedge_word(tokens_[*at].text))) at = previous_visible(*at);
  if (!at || !is_word(tokens_[*at], "is")) return std::nullopt;
  const std::optional<std::size_t> subject = previous_visible(*at);
  if (!subject || !is_name_token(tokens_[*subject])) return std::nullopt;
  return subject;
}

TokenRole RuleOutline::role_of(std::size_t token) const {
  TokenRole role;
  role.token = token;
  if (token >= tokens_.size()) return role;
  role.system = system_of(token);
  role.rule = rule_of(token);
  role.variable = variable_of(token);
  const FmpcToken& t = tokens_[token];
  if (role.system && role.system->name_token == token && token != role.system->first_token) {
    role.kind = TokenRole::Kind::SystemName;
    return role;
  }
  if (role.variable) {
    if (role.variable->name_token == token && token != role.variable->first_token) {
      role.kind = TokenRole::Kind::VariableName;
      return role;
    }
    for (const OutlineTerm& term : role.variable->terms) {
      if (term.name_token == token) {
        role.kind = TokenRole::Kind::TermName;
        role.term = &term;
        return role;
      }
      if (term.family_token == token && term.family_token != term.name_token) {
        role.kind = TokenRole::Kind::Family;
        role.term = &term;
        return role;
      }
    }
  }
  if (t.kind == FmpcTokenKind::Number) {
    role.kind = TokenRole::Kind::Number;
    return role;
  }
  if (role.rule && role.rule->label_token && *role.rule->label_token == token) {
    role.kind = TokenRole::Kind::RuleLabel;
    return role;
  }
  if (is_hedge_word(t.text) && t.kind == FmpcTokenKind::ReservedWord) {
    role.kind = TokenRole::Kind::Hedge;
    return role;
  }
  if (role.rule && is_name_token(t) && role.system) {
    role.after_then = after_then(token);
    const std::optional<std::size_t> next = next_visible(token);
    if (next && is_word(tokens_[*next], "is")) {
      role.kind = TokenRole::Kind::VariableReference;
      role.variable = role.system->find_variable(unquoted_name(t));
      return role;
    }
    if (const std::optional<std::size_t> subject = clause_subject(token)) {
      role.kind = TokenRole::Kind::TermReference;
      role.variable = role.system->find_variable(unquoted_name(tokens_[*subject]));
      if (role.variable)
        for (const OutlineTerm& term : role.variable->terms)
          if (term.name == unquoted_name(t)) role.term = &term;
      return role;
    }
  }
  if (t.kind == FmpcTokenKind::ReservedWord || t.kind == FmpcTokenKind::ContextualWord)
    role.kind = TokenRole::Kind::Keyword;
  return role;
}

}  // namespace fmpc::lsp

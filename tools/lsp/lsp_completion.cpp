// Completion (LSP 3.17 textDocument/completion): from the tokens before the cursor, what the grammar allows next,
// with the names of the system being edited (its variables, a variable's terms, a family's parameters). The word
// being typed is left to the client to filter by.
#include <algorithm>

#include "compiler/frontend/fmpc_ast.h"
#include "tools/lsp/completion_list.h"
#include "tools/lsp/lsp_document.h"

namespace fmpc::lsp {

namespace {

bool is(const FmpcToken& token, const char* word) {
  return token.kind != FmpcTokenKind::QuotedName && token.kind != FmpcTokenKind::Comment && token.text == word;
}

}  // namespace

Json Document::completion(const Position& position, bool snippets) const {
  if (dialect_ == Dialect::Matlab) return matlab_completion(position, snippets);
  Completions out;
  if (!outline_) return out.list();
  const std::vector<FmpcToken>& tokens = outline_->tokens();
  const std::size_t offset = positions_.offset(position);
  // The word being typed (a name or keyword ending at the cursor) is not context: the token before it is.
  std::size_t limit = offset;
  if (const std::optional<std::size_t> typed = outline_->token_at(offset, true)) {
    const FmpcToken& word = tokens[*typed];
    if (word.end == offset && (is_name_token(word) || word.kind == FmpcTokenKind::ReservedWord)) limit = word.begin;
  }
  const std::optional<std::size_t> previous = outline_->token_before(limit);
  const auto item_keywords = [&] {
    out.keywords({"system", "input", "output", "rule"});
    for (const char* setting : {"type", "and", "or", "implication", "aggregation", "defuzzify", "type_reduction"})
      out.add(setting, kItemProperty, "setting");
    out.add("when no rule fires:", kItemProperty, "setting: midrange, value X or error");
  };
  if (!previous) {
    out.keywords({"system"});
    return out.list();
  }
  const FmpcToken& p = tokens[*previous];
  const TokenRole role = outline_->role_of(*previous);
  const OutlineSystem* system = outline_->system_of(*previous);
  const auto add_variables = [&](bool outputs) {
    if (!system) return;
    for (const OutlineVariable& variable : system->variables)
      if (variable.is_output == outputs)
        out.add(ast::name_as_written(variable.name), kItemVariable, outputs ? "output" : "input");
  };
  const auto add_terms = [&](std::optional<std::size_t> subject) {
    if (!subject || !system) return;
    if (const OutlineVariable* variable = system->find_variable(unquoted_name(tokens[*subject])))
      for (const OutlineTerm& term : variable->terms)
        out.add(ast::name_as_written(term.name), kItemEnumMember, "term of " + variable->name);
  };
  const bool next_line = positions_.at_offset(limit).line > positions_.at_offset(p.end).line;

  // Inside a rule.
  if (const OutlineRule* rule = outline_->rule_of(*previous)) {
    const bool then_seen = outline_->after_then(*previous) || is(p, "then");
    if (is(p, ":")) {
      out.keywords({"if"});
    } else if (is(p, "if") || ((is(p, "and") || is(p, "or")) && !then_seen)) {
      add_variables(false);
    } else if (is(p, "then") || (is(p, "and") && then_seen)) {
      add_variables(true);
    } else if (is(p, "is") || is(p, "not") || (p.kind == FmpcTokenKind::ReservedWord && is_hedge_word(p.text))) {
      add_terms(outline_->clause_subject(*previous + 1));
      if (is(p, "is")) out.keywords({"not"});
      if (is(p, "is") || is(p, "not")) out.keywords({"somewhat", "very", "extremely"});
      if (is(p, "very")) out.keywords({"very"});
    } else if (role.kind == TokenRole::Kind::TermReference) {
      if (!then_seen) out.keywords({"and", "or", "then"});
      else out.keywords({"and", "weight"});
      if (next_line) item_keywords();
    } else if (is_name_token(p) && *previous > rule->first_token) {
      out.keywords({"is"});
    } else if (p.kind == FmpcTokenKind::Number && next_line) {
      item_keywords();
    }
    return out.list();
  }

  // A term's membership function, its parameters.
  if (is(p, "is") || is(p, "upper") || is(p, "lower")) {
    for (const std::string& name : ast::family_names()) {
      const ast::FamilySignature* family = ast::find_family(name);
      std::string signature, snippet;
      int field = 1;
      for (const char* parameter : family->parameters) {
        signature += (signature.empty() ? "" : ", ") + std::string(parameter);
        snippet += (snippet.empty() ? "" : ", ") + std::string(parameter) + " ${" + std::to_string(field++) + "}";
      }
      out.add(name, kItemFunction, name + "(" + signature + "), MATLAB " + matlab_name(family->kind),
              snippets && family->kind != MfKind::Linear ? name + "(" + snippet + ")" : "");
    }
    if (is(p, "is")) out.keywords({"upper"});
    if (is(p, "lower")) out.keywords({"scale", "lag"});
    return out.list();
  }
  if (is(p, "(") || is(p, ",")) {
    // Back to the call's family: the name before the '(' that opens it.
    std::size_t open = *previous;
    while (open > 0 && !is(tokens[open], "(")) --open;
    if (open > 0 && is(tokens[open], "(")) {
      const std::string family_name = tokens[open - 1].text;
      std::vector<std::string> given;
      for (std::size_t i = open + 1; i < *previous; ++i)
        if ((is(tokens[i - 1], "(") || is(tokens[i - 1], ",")) && is_name_token(tokens[i]))
          given.push_back(unquoted_name(tokens[i]));
      const auto unused = [&](const std::string& name) {
        return std::find(given.begin(), given.end(), name) == given.end();
      };
      if (family_name == "linear") {
        add_variables(false);
        if (unused("offset")) out.add("offset", kItemProperty, "the constant term");
      } else if (const ast::FamilySignature* family = ast::find_family_or_alias(family_name)) {
        for (const char* parameter : family->parameters)
          if (unused(parameter)) out.add(parameter, kItemProperty, "parameter of " + std::string(family->name));
      }
    }
    return out.list();
  }

  // Settings.
  if (is(p, "type")) {
    out.values({"mamdani", "sugeno"}, "system type");
    out.keywords({"interval_type2"});
  } else if (is(p, "interval_type2")) {
    out.values({"mamdani", "sugeno"}, "system type");
  } else if (is(p, "and") || is(p, "implication")) {
    out.values({"min", "prod", "einstein_product"}, "t-norm");
  } else if (is(p, "or") || is(p, "aggregation")) {
    out.values({"max", "probor", "sum", "einstein_sum"}, "s-norm");
  } else if (is(p, "defuzzify")) {
    out.values({"centroid", "bisector", "mom", "som", "lom"}, "Mamdani defuzzifier");
    out.values({"wtaver", "wtsum"}, "Sugeno defuzzifier");
  } else if (is(p, "samples")) {
    out.values({"101", "exact"}, "output samples");
  } else if (is(p, "type_reduction")) {
    out.values({"karnik_mendel", "enhanced_karnik_mendel", "eiasc", "nie_tan"}, "type reduction");
  } else if (is(p, "when")) {
    out.add("no rule fires:", kItemKeyword);
  } else if (is(p, "fires")) {
    out.add(":", kItemKeyword);
  } else if (is(p, ":")) {
    out.values({"midrange", "value", "error"}, "when no rule fires");
  } else if (is(p, "]") && !next_line) {
    for (const char* unit : {"kPa", "Pa", "MPa", "mm", "cm", "m", "s", "ms", "N", "kg", "g", "%", "dimensionless"})
      out.add(unit, kItemUnit, "unit");
  } else if (is(p, "input") || is(p, "output") || is(p, "system") || is(p, "rule")) {
    // A new name: nothing to offer.
  } else if (next_line || p.kind == FmpcTokenKind::Comment) {
    item_keywords();
  }
  return out.list();
}

}  // namespace fmpc::lsp

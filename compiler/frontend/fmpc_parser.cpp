// Text -> ANTLR parse tree -> ast::File. Syntax errors become Diagnostics through FmpcErrorStrategy (ANTLR's
// console listeners are removed); comments are attached to the printed line they belong to.
#include <algorithm>
#include <charconv>
#include <memory>
#include <set>

#include "FmpcLexer.h"
#include "FmpcParser.h"
#include "grammar/parse_depth_limit.h"
#include "antlr4-runtime.h"
#include "compiler/frontend/fmpc_ast.h"
#include "compiler/frontend/fmpc_source_map.h"
#include "compiler/frontend/fmpc_token_repair.h"
#include "compiler/frontend/utf8.h"

namespace fmpc::ast {

namespace {

using grammar::FmpcLexer;
using grammar::FmpcParser;

bool is_name_token(std::size_t type) {
  switch (type) {
    case FmpcLexer::IDENTIFIER:
    case FmpcLexer::STRING:
    case FmpcLexer::TYPE:
    case FmpcLexer::IMPLICATION:
    case FmpcLexer::AGGREGATION:
    case FmpcLexer::DEFUZZIFY:
    case FmpcLexer::SAMPLES:
    case FmpcLexer::EXACT:
    case FmpcLexer::WHEN:
    case FmpcLexer::NO:
    case FmpcLexer::FIRES:
    case FmpcLexer::MIDRANGE:
    case FmpcLexer::VALUE:
    case FmpcLexer::ERROR:
    case FmpcLexer::IN:
    case FmpcLexer::TYPE_REDUCTION:
    case FmpcLexer::UPPER:
    case FmpcLexer::LOWER:
    case FmpcLexer::SCALE:
    case FmpcLexer::LAG: return true;
    default: return false;
  }
}

const antlr4::Token* previous_visible_token(antlr4::TokenStream* tokens, const antlr4::Token* token) {
  for (std::size_t i = token->getTokenIndex(); i-- > 0;) {
    const antlr4::Token* candidate = tokens->get(i);
    if (candidate->getChannel() == antlr4::Token::DEFAULT_CHANNEL) return candidate;
  }
  return nullptr;
}

// Whether the clause being parsed lies after `then` in its rule (an output is expected) or before (an input).
bool after_then(antlr4::TokenStream* tokens, const antlr4::Token* token) {
  for (std::size_t i = token->getTokenIndex() + 1; i-- > 0;) {
    const std::size_t type = tokens->get(i)->getType();
    if (type == FmpcLexer::THEN) return true;
    if (type == FmpcLexer::IF || type == FmpcLexer::RULE) return false;
  }
  return false;
}

const char* kTNormChoices = "a t-norm (min, prod or einstein_product)";
const char* kSNormChoices = "an s-norm (max, probor, sum or einstein_sum)";

// What a name at this point would be, for "expected ... after ..." messages.
std::string expected_name_noun(antlr4::TokenStream* tokens, const antlr4::Token* previous,
                               antlr4::RuleContext* context) {
  const std::size_t file_rule = FmpcParser::RuleFile;
  std::size_t rule = context ? context->getRuleIndex() : file_rule;
  while (context && (rule == FmpcParser::RuleName || rule == FmpcParser::RuleUnit)) {
    context = dynamic_cast<antlr4::RuleContext*>(context->parent);
    rule = context ? context->getRuleIndex() : file_rule;
  }
  if (!previous) return "a name";
  switch (previous->getType()) {
    case FmpcLexer::SYSTEM: return "a system name";
    case FmpcLexer::INPUT:
    case FmpcLexer::OUTPUT: return "a variable name";
    case FmpcLexer::IF: return "an input name";
    case FmpcLexer::THEN: return "an output name";
    case FmpcLexer::AND:
      if (rule == FmpcParser::RuleSetting || rule == FmpcParser::RuleItem) return kTNormChoices;
      return after_then(tokens, previous) ? "an output name" : "an input name";
    case FmpcLexer::OR:
      if (rule == FmpcParser::RuleSetting || rule == FmpcParser::RuleItem) return kSNormChoices;
      return "an input name";
    case FmpcLexer::IMPLICATION: return kTNormChoices;
    case FmpcLexer::AGGREGATION: return kSNormChoices;
    case FmpcLexer::TYPE: return "a system type (mamdani or sugeno)";
    case FmpcLexer::INTERVAL_TYPE2: return "a system type (mamdani or sugeno)";
    case FmpcLexer::TYPE_REDUCTION:
      return "a type reduction (karnik_mendel, enhanced_karnik_mendel, eiasc or nie_tan)";
    case FmpcLexer::UPPER: return "a membership function such as 'gauss'";
    case FmpcLexer::LOWER: return "a membership function such as 'gauss', or 'scale' or 'lag'";
    case FmpcLexer::DEFUZZIFY: return "a defuzzifier (centroid, bisector, mom, som, lom, wtaver or wtsum)";
    case FmpcLexer::IS:
      return rule == FmpcParser::RuleTermDecl || rule == FmpcParser::RuleMfCall ? "a membership function such as 'gauss'"
                                                                               : "a term name";
    case FmpcLexer::NOT:
    case FmpcLexer::SOMEWHAT:
    case FmpcLexer::VERY:
    case FmpcLexer::EXTREMELY: return "a term name";
    case FmpcLexer::RULE: return "a rule label";
    case FmpcLexer::NUMBER:
      if (rule == FmpcParser::RuleArgument || rule == FmpcParser::RuleTermDecl || rule == FmpcParser::RuleMfCall)
        return "a unit";
      break;
    default: break;
  }
  if (previous->getText() == "(" || previous->getText() == ",") {
    if (rule == FmpcParser::RuleTermDecl || rule == FmpcParser::RuleArgument || rule == FmpcParser::RuleMfCall)
      return "a parameter name";
  }
  if (previous->getText() == "]") return "a unit or a term name";
  if (rule == FmpcParser::RuleVariableDecl || rule == FmpcParser::RuleTermDecl || rule == FmpcParser::RuleMfCall)
    return "a term name";
  return "a name";
}

// Between items: the contextual setting words make the raw token set read badly, so say it in words.
std::vector<std::string> expected_items(antlr4::TokenStream* tokens, const antlr4::Token* found, bool end_expected) {
  std::size_t last_item_keyword = 0;
  for (std::size_t i = found->getTokenIndex(); i-- > 0 && last_item_keyword == 0;) {
    const std::size_t type = tokens->get(i)->getType();
    if (type == FmpcLexer::SYSTEM || type == FmpcLexer::INPUT || type == FmpcLexer::OUTPUT || type == FmpcLexer::RULE)
      last_item_keyword = type;
  }
  if (last_item_keyword == 0) return {"'system'"};
  std::vector<std::string> items;
  if (last_item_keyword == FmpcLexer::INPUT || last_item_keyword == FmpcLexer::OUTPUT) items.push_back("a term");
  else if (last_item_keyword == FmpcLexer::SYSTEM) items.push_back("a setting");
  for (const char* keyword : {"'input'", "'output'", "'rule'", "'system'"}) items.push_back(keyword);
  if (end_expected) items.push_back("end of file");
  return items;
}

std::string describe_found(const antlr4::Token* token) {
  if (token->getType() == antlr4::Token::EOF) return "end of file";
  return "'" + token->getText() + "'";
}

std::string join_alternatives(const std::vector<std::string>& alternatives) {
  std::string text;
  for (std::size_t i = 0; i < alternatives.size(); ++i) {
    if (i > 0) text += i + 1 == alternatives.size() ? " or " : ", ";
    text += alternatives[i];
  }
  return text;
}

// Reports syntax errors as "expected X after 'P', found 'T'" instead of ANTLR's "mismatched input"; recovery
// stays ANTLR's (single-token insertion and deletion, then resynchronisation), so every error is reported.
// A missing ':' or ',' (the only token the parser could take there) is inserted with a fix-it, and the parse goes
// on as if it were written: such an error is a repair, and a file whose every syntax error is a repair still
// yields its AST, so that the errors of the later steps are reported too.
class FmpcErrorStrategy : public antlr4::DefaultErrorStrategy {
 public:
  FmpcErrorStrategy(const SourceMap& source, DiagnosticList& diagnostics)
      : source_(source), diagnostics_(diagnostics) {}

  // Whether a syntax error was met that the parser did not repair.
  bool unrepaired() const { return unrepaired_; }

 protected:
  void reportNoViableAlternative(antlr4::Parser* parser, const antlr4::NoViableAltException& e) override {
    report(parser, e.getOffendingToken(), e.getExpectedTokens(), e.getCtx());
  }

  void reportInputMismatch(antlr4::Parser* parser, const antlr4::InputMismatchException& e) override {
    report(parser, e.getOffendingToken(), e.getExpectedTokens(), e.getCtx());
  }

  void reportFailedPredicate(antlr4::Parser* parser, const antlr4::FailedPredicateException& e) override {
    report(parser, e.getOffendingToken(), e.getExpectedTokens(), e.getCtx());
  }

  void reportUnwantedToken(antlr4::Parser* parser) override {
    if (inErrorRecoveryMode(parser)) return;
    beginErrorCondition(parser);
    report(parser, parser->getCurrentToken(), getExpectedTokens(parser), parser->getContext());
  }

  // Panic mode to the next item: skip to the next `system`, `input`, `output` or `rule`, or to a line that starts
  // with a term ("NAME is") or a setting word. ANTLR's own resynchronisation stops at the first token that could
  // follow, which inside a rule is almost anything and produced cascades of errors.
  void recover(antlr4::Parser* parser, std::exception_ptr) override {
    unrepaired_ = true;
    antlr4::TokenStream* tokens = parser->getTokenStream();
    const std::size_t index = tokens->index();
    if (index != recovered_at_index_) {
      recovered_at_index_ = index;
      recovered_in_states_.clear();
    }
    // Called again at the same token in the same state: nothing can match it here, so step over it.
    if (!recovered_in_states_.insert(parser->getState()).second && tokens->LA(1) != antlr4::Token::EOF)
      parser->consume();
    while (!starts_item(tokens, tokens->index())) parser->consume();
  }

  // ANTLR drops one token when the next one fits; dropping a keyword (`then`, `is`, `rule`) makes the rest of the
  // line mean something else and the errors that follow point at the wrong thing, so only other tokens go.
  antlr4::Token* singleTokenDeletion(antlr4::Parser* parser) override {
    const std::size_t type = parser->getCurrentToken()->getType();
    if (type >= FmpcLexer::SYSTEM && type <= FmpcLexer::EXTREMELY) return nullptr;
    return DefaultErrorStrategy::singleTokenDeletion(parser);
  }

  void reportMissingToken(antlr4::Parser* parser) override {
    if (inErrorRecoveryMode(parser)) return;
    beginErrorCondition(parser);
    const antlr4::misc::IntervalSet expected = getExpectedTokens(parser);
    const std::string inserted =
        expected.size() == 1 ? parser->getVocabulary().getLiteralName(static_cast<std::size_t>(expected.getMinElement()))
                             : std::string();
    if (inserted == "':'" || inserted == "','") {
      report(parser, parser->getCurrentToken(), expected, parser->getContext(), inserted.substr(1, 1));
      return;
    }
    report(parser, parser->getCurrentToken(), expected, parser->getContext());
  }

 private:
  // `insertion`: the text the parser inserted to go on (a repair, reported with its fix-it); empty otherwise.
  void report(antlr4::Parser* parser, const antlr4::Token* found, const antlr4::misc::IntervalSet& expected,
              antlr4::RuleContext* context, const std::string& insertion = "") {
    if (insertion.empty()) unrepaired_ = true;
    if (!found) return;
    antlr4::TokenStream* tokens = parser->getTokenStream();
    const antlr4::Token* previous = previous_visible_token(tokens, found);
    // An error right after a character the lexer rejected is a consequence of it (already reported); so is a
    // second error on the line of the previous one, which ANTLR's resynchronisation tends to produce.
    if (found->getType() == FmpcLexer::ERROR_CHARACTER) return;
    if (previous && previous->getType() == FmpcLexer::ERROR_CHARACTER) return;
    // What is missing at the end of a line is reported there, not at the first token of the next line.
    SourceRange range = source_.token(found);
    if (previous && previous->getLine() != found->getLine()) {
      range = source_.token(previous);
      range.line = range.end_line;
      range.column = range.end_column;
      range.end_column = range.column + 1;
    }
    if (static_cast<std::size_t>(range.line) == last_error_line_) return;
    last_error_line_ = static_cast<std::size_t>(range.line);
    std::vector<std::string> alternatives;
    bool name_expected = false;
    bool end_expected = false;
    bool modifiers_expected = false;
    std::vector<std::string> keywords;
    // Positional parameters and MATLAB's `[...]` vector are read only to be refused with the named spelling:
    // messages do not offer them.
    const std::size_t rule = context ? context->getRuleIndex() : static_cast<std::size_t>(FmpcParser::RuleFile);
    const bool in_call = rule == FmpcParser::RuleMfCall || rule == FmpcParser::RuleArgument;
    const bool parameter_expected = in_call && previous && (previous->getText() == "(" || previous->getText() == ",");
    bool call_expected = false;
    for (const ssize_t type : expected.toList())
      call_expected = call_expected || parser->getVocabulary().getLiteralName(static_cast<std::size_t>(type)) == "'('";
    for (const ssize_t type : expected.toList()) {
      if (parameter_expected && type == FmpcLexer::NUMBER) continue;
      if ((call_expected || parameter_expected) &&
          parser->getVocabulary().getLiteralName(static_cast<std::size_t>(type)) == "'['")
        continue;
      if (type == static_cast<ssize_t>(antlr4::Token::EOF)) {
        end_expected = true;
      } else if (is_name_token(static_cast<std::size_t>(type))) {
        name_expected = true;
      } else if (type == FmpcLexer::NOT || type == FmpcLexer::SOMEWHAT || type == FmpcLexer::VERY ||
                 type == FmpcLexer::EXTREMELY) {
        modifiers_expected = true;
      } else if (type == FmpcLexer::NUMBER) {
        alternatives.push_back("a number");
      } else {
        const std::string literal = parser->getVocabulary().getLiteralName(static_cast<std::size_t>(type));
        if (literal == "'%'" && name_expected) continue;
        keywords.push_back(literal.empty() ? parser->getVocabulary().getDisplayName(static_cast<std::size_t>(type))
                                           : literal);
      }
    }
    // "not" and the hedges are optional before a term name; listing them only lengthens the message.
    if (modifiers_expected && !name_expected) keywords.insert(keywords.begin(), "'not' or a hedge");
    if (name_expected) alternatives.insert(alternatives.begin(), expected_name_noun(tokens, previous, context));
    alternatives.insert(alternatives.end(), keywords.begin(), keywords.end());
    if (end_expected) alternatives.push_back("end of file");
    if (expected.contains(static_cast<ssize_t>(FmpcLexer::INPUT)) && expected.contains(static_cast<ssize_t>(FmpcLexer::RULE)))
      alternatives = expected_items(tokens, found, end_expected);

    std::string message = "expected " + (alternatives.empty() ? std::string("something else")
                                                              : join_alternatives(alternatives));
    if (previous) message += " after '" + previous->getText() + "'";
    message += ", found " + describe_found(found);
    for (const Diagnostic& existing : diagnostics_.items())
      if (existing.range.line == range.line && existing.range.column == range.column) return;
    Diagnostic diagnostic;
    diagnostic.range = range;
    diagnostic.message = std::move(message);
    if (!insertion.empty() && previous) {
      SourceRange after_previous = source_.token(previous);
      after_previous.line = after_previous.end_line;
      after_previous.column = after_previous.end_column;
      diagnostic.fix = FixIt{after_previous, insertion};
    }
    diagnostics_.add(std::move(diagnostic));
  }

  static bool starts_item(antlr4::TokenStream* tokens, std::size_t index) {
    const antlr4::Token* token = tokens->get(index);
    switch (token->getType()) {
      case antlr4::Token::EOF:
      case FmpcLexer::SYSTEM:
      case FmpcLexer::INPUT:
      case FmpcLexer::OUTPUT:
      case FmpcLexer::RULE: return true;
      default: break;
    }
    const antlr4::Token* previous = previous_visible_token(tokens, token);
    if (previous && previous->getLine() == token->getLine()) return false;
    switch (token->getType()) {
      case FmpcLexer::TYPE:
      case FmpcLexer::TYPE_REDUCTION:
      case FmpcLexer::AND:
      case FmpcLexer::OR:
      case FmpcLexer::IMPLICATION:
      case FmpcLexer::AGGREGATION:
      case FmpcLexer::DEFUZZIFY:
      case FmpcLexer::WHEN: return true;
      default: break;
    }
    return is_name_token(token->getType()) && tokens->get(index + 1)->getType() == FmpcLexer::IS;
  }

  const SourceMap& source_;
  DiagnosticList& diagnostics_;
  std::size_t last_error_line_ = 0;
  bool unrepaired_ = false;
  std::size_t recovered_at_index_ = static_cast<std::size_t>(-1);
  std::set<std::size_t> recovered_in_states_;
};

// ---------------------------------------------------------------------------------------------------------------
// Parse tree -> AST.

class AstBuilder {
 public:
  AstBuilder(const SourceMap& source, antlr4::CommonTokenStream& tokens, DiagnosticList& diagnostics)
      : source_(source), tokens_(tokens), diagnostics_(diagnostics) {}

  File build(FmpcParser::FileContext* tree) {
    File file;
    file.path = source_.path();
    bool previous_was_variable = false;  // the item before is a variable line or one of its terms
    for (FmpcParser::ItemContext* item : tree->item()) {
      if (FmpcParser::SystemHeaderContext* header = item->systemHeader()) {
        file.systems.push_back(build_system(header, file.systems.size()));
        previous_was_variable = false;
        continue;
      }
      if (file.systems.empty()) {
        const char* what = item->setting()        ? "a setting"
                           : item->variableDecl() ? "a variable"
                           : item->termDecl()     ? "a term"
                                                  : "a rule";
        diagnostics_.error(source_.token(item->getStart()),
                           std::string(what) + " before the first 'system' line; start the file with: system NAME");
        continue;
      }
      const std::size_t system_index = file.systems.size() - 1;
      System& system = file.systems.back();
      Variable* open_variable = previous_was_variable ? std::get_if<Variable>(&system.items.back()) : nullptr;
      previous_was_variable = false;
      if (FmpcParser::SettingContext* setting = item->setting()) {
        system.settings.push_back(build_setting(setting, LineRef{system_index, system.settings.size(), kNone, kNone}));
      } else if (FmpcParser::VariableDeclContext* variable = item->variableDecl()) {
        system.items.emplace_back(build_variable(variable, system_index, system.items.size()));
        previous_was_variable = true;
      } else if (FmpcParser::TermDeclContext* term = item->termDecl()) {
        if (!open_variable) {
          diagnostics_.error(source_.context(term->name()),
                             "term " + quoted_name(term->name()) +
                                 " is not under an 'input' or 'output' line; a variable's terms follow its line, "
                                 "before any rule or setting");
          continue;
        }
        open_variable->terms.push_back(
            build_term(term, LineRef{system_index, kNone, system.items.size() - 1, open_variable->terms.size()}));
        previous_was_variable = true;
      } else if (FmpcParser::RuleDeclContext* rule = item->ruleDecl()) {
        system.items.emplace_back(build_rule(rule, LineRef{system_index, kNone, system.items.size(), kNone}));
      }
    }
    attach_comments(file);
    return file;
  }

 private:
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);

  // Where a printed line's Comments live in the File; resolved once the File's vectors stop growing.
  struct LineRef {
    std::size_t system;
    std::size_t setting;
    std::size_t item;
    std::size_t term;
  };

  struct Line {
    std::size_t first_token;
    std::size_t last_token;
    LineRef ref;
    Comments* comments = nullptr;
  };

  Name name(FmpcParser::NameContext* context) const {
    const antlr4::Token* token = context->getStart();
    std::string text = token->getText();
    const bool quoted = token->getType() == FmpcLexer::STRING;
    if (quoted) text = text.substr(1, text.size() - 2);
    return Name{text, source_.token(token), quoted};
  }

  Name unit(FmpcParser::UnitContext* context) const {
    if (context->name()) return name(context->name());
    return Name{context->getStart()->getText(), source_.token(context->getStart()), false};
  }

  static std::string unquote(const antlr4::Token* token) {
    const std::string text = token->getText();
    return text.substr(1, text.size() - 2);
  }

  Number number(const antlr4::Token* token) {
    Number result;
    result.range = source_.token(token);
    const std::string text = token->getText();
    const auto parsed = std::from_chars(text.data(), text.data() + text.size(), result.value);
    if (parsed.ec == std::errc::result_out_of_range) {
      // from_chars leaves the value unchanged on overflow and underflow; tell them apart by the exponent's sign.
      const std::size_t e = text.find_first_of("eE");
      const bool tiny = e != std::string::npos && e + 1 < text.size() && text[e + 1] == '-';
      if (tiny) {
        result.value = 0.0;
      } else {
        diagnostics_.error(result.range, "number " + text + " is too large (a double holds up to about 1.8e308)");
      }
    }
    return result;
  }

  System build_system(FmpcParser::SystemHeaderContext* context, std::size_t system_index) {
    System system;
    system.name = name(context->name());
    if (context->description) system.description = unquote(context->description);
    system.range = source_.context(context);
    add_line(context->getStart(), context->getStop(), LineRef{system_index, kNone, kNone, kNone});
    return system;
  }

  Setting build_setting(FmpcParser::SettingContext* context, const LineRef& ref) {
    Setting setting;
    setting.range = source_.context(context);
    if (auto* type = dynamic_cast<FmpcParser::TypeSettingContext*>(context)) {
      setting.kind = SettingKind::Type;
      setting.value = name(type->value);
      setting.interval_type2 = type->INTERVAL_TYPE2() != nullptr;
    } else if (auto* reduction = dynamic_cast<FmpcParser::TypeReductionSettingContext*>(context)) {
      setting.kind = SettingKind::TypeReduction;
      setting.value = name(reduction->value);
    } else if (auto* and_setting = dynamic_cast<FmpcParser::AndSettingContext*>(context)) {
      setting.kind = SettingKind::And;
      setting.value = name(and_setting->value);
    } else if (auto* or_setting = dynamic_cast<FmpcParser::OrSettingContext*>(context)) {
      setting.kind = SettingKind::Or;
      setting.value = name(or_setting->value);
    } else if (auto* implication = dynamic_cast<FmpcParser::ImplicationSettingContext*>(context)) {
      setting.kind = SettingKind::Implication;
      setting.value = name(implication->value);
    } else if (auto* aggregation = dynamic_cast<FmpcParser::AggregationSettingContext*>(context)) {
      setting.kind = SettingKind::Aggregation;
      setting.value = name(aggregation->value);
    } else if (auto* defuzzify = dynamic_cast<FmpcParser::DefuzzifySettingContext*>(context)) {
      setting.kind = SettingKind::Defuzzify;
      setting.value = name(defuzzify->value);
      if (defuzzify->count) setting.samples = number(defuzzify->count);
      setting.samples_exact = defuzzify->EXACT() != nullptr;
    } else if (auto* no_fire = dynamic_cast<FmpcParser::NoFireSettingContext*>(context)) {
      setting.kind = SettingKind::NoFire;
      FmpcParser::NoFireActionContext* action = no_fire->noFireAction();
      setting.value = Name{action->getStart()->getText(), source_.token(action->getStart()), false};
      if (action->NUMBER()) setting.no_fire_value = number(action->NUMBER()->getSymbol());
    }
    add_line(context->getStart(), context->getStop(), ref);
    return setting;
  }

  std::string quoted_name(FmpcParser::NameContext* context) const { return "'" + name(context).text + "'"; }

  Variable build_variable(FmpcParser::VariableDeclContext* context, std::size_t system_index,
                          std::size_t item_index) {
    Variable variable;
    variable.is_output = context->direction->getType() == FmpcLexer::OUTPUT;
    variable.name = name(context->name());
    if (context->description) variable.description = unquote(context->description);
    variable.min = number(context->low);
    variable.max = number(context->high);
    if (context->unit()) variable.unit = unit(context->unit());
    variable.range = source_.context(context);
    add_line(context->getStart(), context->getStop(), LineRef{system_index, kNone, item_index, kNone});
    return variable;
  }

  std::vector<Argument> build_arguments(FmpcParser::MfCallContext* call) {
    std::vector<Argument> arguments;
    // MATLAB's vector `gaussmf [0.91 7.64]`: positional arguments, refused by sema with the named spelling.
    for (antlr4::tree::TerminalNode* number_node : call->NUMBER()) {
      Argument argument;
      argument.value = number(number_node->getSymbol());
      argument.range = argument.value.range;
      arguments.push_back(std::move(argument));
    }
    for (FmpcParser::ArgumentContext* argument_context : call->argument()) {
      Argument argument;
      if (argument_context->name()) argument.name = name(argument_context->name());
      if (FmpcParser::IntervalContext* interval = argument_context->interval()) {
        argument.value = number(interval->low);
        argument.high = number(interval->high);
      } else {
        argument.value = number(argument_context->NUMBER()->getSymbol());
      }
      if (argument_context->unit()) argument.unit = unit(argument_context->unit());
      argument.range = source_.context(argument_context);
      arguments.push_back(std::move(argument));
    }
    return arguments;
  }

  Term build_term(FmpcParser::TermDeclContext* context, const LineRef& ref) {
    Term term;
    term.name = name(context->name());
    FmpcParser::MfCallContext* upper = context->mfCall(0);
    term.family = name(upper->family);
    term.arguments = build_arguments(upper);
    term.call_range = source_.context(upper);
    term.explicit_upper = context->UPPER() != nullptr;
    if (context->lowerMf) {
      LowerCall lower;
      lower.family = name(context->lowerMf->family);
      lower.arguments = build_arguments(context->lowerMf);
      lower.range = source_.context(context->lowerMf);
      term.lower = std::move(lower);
    } else if (FmpcParser::LowerScaleLagContext* scale_lag = context->lowerScaleLag()) {
      if (scale_lag->scale) term.lower_scale = number(scale_lag->scale);
      if (scale_lag->lag) term.lower_lag = number(scale_lag->lag);
      term.lower_range = source_.span(context->LOWER()->getSymbol(), scale_lag->getStop());
    }
    if (context->LOWER() && context->lowerMf) term.lower_range = source_.span(context->LOWER()->getSymbol(), context->getStop());
    term.range = source_.context(context);
    add_line(context->getStart(), context->getStop(), ref);
    return term;
  }

  Clause build_clause(FmpcParser::ClauseContext* context) const {
    Clause clause;
    clause.variable = name(context->variableName);
    clause.negated = context->NOT() != nullptr;
    if (FmpcParser::HedgeContext* hedge = context->hedge()) {
      if (hedge->SOMEWHAT()) clause.hedge = Hedge::Somewhat;
      else if (hedge->EXTREMELY()) clause.hedge = Hedge::Extremely;
      else clause.hedge = hedge->VERY().size() == 2 ? Hedge::VeryVery : Hedge::Very;
    }
    clause.term = name(context->termName);
    clause.range = source_.context(context);
    return clause;
  }

  Rule build_rule(FmpcParser::RuleDeclContext* context, const LineRef& ref) {
    Rule rule;
    if (context->label) rule.label = name(context->label);
    const std::size_t then_index = context->THEN()->getSymbol()->getTokenIndex();
    for (FmpcParser::ClauseContext* clause : context->clause()) {
      if (clause->getStart()->getTokenIndex() < then_index) rule.antecedent.push_back(build_clause(clause));
      else rule.consequent.push_back(build_clause(clause));
    }
    for (FmpcParser::ConnectiveContext* connective : context->connective())
      rule.connectives.push_back(ConnectiveToken{connective->OR() ? Connective::Or : Connective::And,
                                                 source_.context(connective)});
    if (context->weight) rule.weight = number(context->weight);
    rule.range = source_.context(context);
    add_line(context->getStart(), context->getStop(), ref);
    return rule;
  }

  void add_line(const antlr4::Token* first, const antlr4::Token* last, const LineRef& ref) {
    lines_.push_back(Line{first->getTokenIndex(), last->getTokenIndex(), ref, nullptr});
  }

  static Comments& comments_of(File& file, const LineRef& ref) {
    System& system = file.systems[ref.system];
    if (ref.setting != kNone) return system.settings[ref.setting].comments;
    if (ref.item == kNone) return system.comments;
    Item& item = system.items[ref.item];
    if (auto* variable = std::get_if<Variable>(&item))
      return ref.term == kNone ? variable->comments : variable->terms[ref.term].comments;
    return std::get<Rule>(item).comments;
  }

  void attach_comments(File& file) {
    for (Line& line : lines_) line.comments = &comments_of(file, line.ref);
    // Comments, and the token index where each line's block (its leading comments, then itself) starts.
    std::vector<std::size_t> block_start(lines_.size());
    for (std::size_t i = 0; i < lines_.size(); ++i) block_start[i] = lines_[i].first_token;
    std::size_t end_block_start = std::string::npos;
    // Each line's last own-line comment (token index) and how many entries of its block reach it: a blank line
    // between a comment block and its line is part of the layout (a file's header comment, then `system`).
    std::vector<std::size_t> last_comment(lines_.size(), std::string::npos), block_entries(lines_.size(), 0);
    const std::size_t count = tokens_.size();
    for (std::size_t index = 0; index < count; ++index) {
      const antlr4::Token* token = tokens_.get(index);
      if (token->getType() != FmpcLexer::COMMENT) continue;
      std::string text = token->getText();
      while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r')) text.pop_back();
      const antlr4::Token* previous = previous_visible_token(&tokens_, token);
      bool attached = false;
      if (previous && previous->getLine() == token->getLine()) {
        for (Line& line : lines_) {
          if (line.first_token <= previous->getTokenIndex() && previous->getTokenIndex() <= line.last_token) {
            // A line printed as one may have held several end-of-line comments; the later ones move above it.
            if (line.comments->trailing.empty()) line.comments->trailing = text;
            else line.comments->leading.push_back(text);
            attached = true;
            break;
          }
        }
      }
      if (attached) continue;
      std::size_t owner = 0;
      while (owner < lines_.size() && lines_[owner].first_token < index) ++owner;
      std::vector<std::string>& block = owner < lines_.size() ? lines_[owner].comments->leading
                                                               : file.end_comments.leading;
      // A blank line between two own-line comments is kept (as an empty entry).
      if (!block.empty() && blank_line_before(index)) block.emplace_back();
      block.push_back(text);
      if (owner < lines_.size()) {
        block_start[owner] = std::min(block_start[owner], index);
        last_comment[owner] = index;
        block_entries[owner] = block.size();
      } else {
        end_block_start = std::min(end_block_start, index);
      }
    }
    for (std::size_t i = 0; i < lines_.size(); ++i)
      if (last_comment[i] != std::string::npos &&
          tokens_.get(lines_[i].first_token)->getLine() >= tokens_.get(last_comment[i])->getLine() + 2) {
        std::vector<std::string>& leading = lines_[i].comments->leading;
        leading.insert(leading.begin() + static_cast<std::ptrdiff_t>(block_entries[i]), std::string());
      }
    for (std::size_t i = 0; i < lines_.size(); ++i)
      lines_[i].comments->blank_line_before = blank_line_before(block_start[i]);
    if (end_block_start != std::string::npos) file.end_comments.blank_line_before = blank_line_before(end_block_start);
  }

  bool blank_line_before(std::size_t token_index) {
    if (token_index == 0) return false;
    const antlr4::Token* previous = tokens_.get(token_index - 1);
    return tokens_.get(token_index)->getLine() >= previous->getLine() + 2;
  }

  const SourceMap& source_;
  antlr4::CommonTokenStream& tokens_;
  DiagnosticList& diagnostics_;
  std::vector<Line> lines_;
};

}  // namespace

std::optional<File> parse_fmpc(const std::string& path, const std::string& text, DiagnosticList& diagnostics) {
  const std::size_t bad_byte = first_invalid_utf8(text);
  if (bad_byte != std::string::npos) {
    const SourceMap source(path, text.substr(0, bad_byte));
    SourceRange range = source.bytes(bad_byte, bad_byte);
    range.end_column = range.column + 1;
    diagnostics.error(range, "the file is not valid UTF-8 (save it as UTF-8)");
    return std::nullopt;
  }
  const SourceMap source(path, text);
  DiagnosticList syntax;

  antlr4::ANTLRInputStream input(text);
  FmpcLexer lexer(&input);
  lexer.removeErrorListeners();
  antlr4::CommonTokenStream lexed(&lexer);
  lexed.fill();
  RepairedTokens repaired = repair_tokens(source, lexed, syntax);
  const bool lexically_repaired = !repaired.unrepaired;
  antlr4::ListTokenSource token_source(std::move(repaired.tokens), path);
  antlr4::CommonTokenStream tokens(&token_source);
  tokens.fill();

  FmpcParser parser(&tokens);
  parser.removeErrorListeners();
  auto strategy = std::make_shared<FmpcErrorStrategy>(source, syntax);
  parser.setErrorHandler(strategy);
  // Fmpc.g4 is flat (a file is a list of items, a rule a list of clauses), so no text nests deeply; the limit
  // stays as a guard should the grammar ever gain a recursive rule.
  const antlr4::Token* too_deep = nullptr;
  FmpcParser::FileContext* tree = grammar::parse_file_within_depth_limit(parser, &too_deep);
  if (!tree) syntax.error(source.token(too_deep), grammar::parse_depth_message());

  // Errors the tokens or the parser could not repair leave no tree worth reading: report them and stop.
  if (!tree || !lexically_repaired || strategy->unrepaired()) {
    syntax.sort_by_position();
    diagnostics.append(syntax);
    return std::nullopt;
  }
  const std::size_t repairs = syntax.error_count();
  AstBuilder builder(source, tokens, syntax);
  File file = builder.build(tree);
  const bool built = syntax.error_count() == repairs;
  syntax.sort_by_position();
  diagnostics.append(syntax);
  if (!built) return std::nullopt;
  return file;
}

}  // namespace fmpc::ast

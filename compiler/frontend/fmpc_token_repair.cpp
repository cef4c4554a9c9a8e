#include "compiler/frontend/fmpc_token_repair.h"

#include <cctype>
#include <string>

#include "FmpcLexer.h"

namespace fmpc::ast {

namespace {

using grammar::FmpcLexer;

bool is_word(const antlr4::Token* token) {
  const std::size_t type = token->getType();
  return type == FmpcLexer::IDENTIFIER || (type >= FmpcLexer::SYSTEM && type <= FmpcLexer::LAG);
}

bool is_error_character(const antlr4::Token* token, const char* text) {
  return token->getType() == FmpcLexer::ERROR_CHARACTER && token->getText() == text;
}

bool is_non_ascii(const antlr4::Token* token) {
  return token->getType() == FmpcLexer::ERROR_CHARACTER && static_cast<unsigned char>(token->getText()[0]) >= 0x80;
}

// A character that may sit inside an unquoted-looking name (`F0-F1`, `mL/min`, `kg/m^3`, `Young's`). Operators a
// newcomer may mean as such (`=`, `!`, `&`, `|`, `<`, `>`, `;`) are not: they are repaired or reported apart.
bool is_name_character(const antlr4::Token* token) {
  if (token->getType() != FmpcLexer::ERROR_CHARACTER) return false;
  const std::string text = token->getText();
  return text.find_first_of("=!&|<>;") == std::string::npos;
}

// The first character of `text` that an identifier cannot hold (a whole UTF-8 sequence).
std::string first_foreign_character(const std::string& text) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if (std::isalnum(byte) || byte == '_') continue;
    std::size_t length = 1;
    while (i + length < text.size() && (static_cast<unsigned char>(text[i + length]) & 0xC0) == 0x80) ++length;
    return text.substr(i, length);
  }
  return "";
}

class TokenRepair {
 public:
  TokenRepair(const SourceMap& source, antlr4::BufferedTokenStream& lexed, DiagnosticList& diagnostics)
      : source_(source), diagnostics_(diagnostics) {
    for (std::size_t i = 0; i < lexed.size(); ++i) tokens_.push_back(lexed.get(i));
    // ',' is an implicit token of the grammar: its type is looked up by its literal.
    if (const auto* lexer = dynamic_cast<const antlr4::Lexer*>(lexed.getTokenSource()))
      for (std::size_t type = 1; type <= lexer->getVocabulary().getMaxTokenType(); ++type)
        if (lexer->getVocabulary().getLiteralName(type) == "','") comma_type_ = type;
  }

  RepairedTokens run() {
    std::size_t i = 0;
    while (i < tokens_.size()) {
      const antlr4::Token* token = tokens_[i];
      if (token->getChannel() != antlr4::Token::DEFAULT_CHANNEL) {
        keep(i++);
        continue;
      }
      track_parentheses(token);
      const std::size_t next = repair_at(i);
      if (next > i) {
        previous_ = tokens_[next - 1];
        i = next;
        continue;
      }
      if (token->getType() == FmpcLexer::ERROR_CHARACTER) report_unrepairable(i);
      previous_ = token;
      keep(i++);
    }
    return std::move(result_);
  }

 private:
  // The visible token after `index` when it touches it (no blank or comment between), else nullptr.
  const antlr4::Token* glued_after(std::size_t index) const {
    if (index + 1 >= tokens_.size()) return nullptr;
    const antlr4::Token* next = tokens_[index + 1];
    if (next->getChannel() != antlr4::Token::DEFAULT_CHANNEL || next->getType() == antlr4::Token::EOF) return nullptr;
    return next->getStartIndex() == tokens_[index]->getStopIndex() + 1 ? next : nullptr;
  }

  const antlr4::Token* next_visible(std::size_t index) const {
    for (std::size_t i = index + 1; i < tokens_.size(); ++i)
      if (tokens_[i]->getChannel() == antlr4::Token::DEFAULT_CHANNEL) return tokens_[i];
    return nullptr;
  }

  bool glued_to_previous_name(const antlr4::Token* token) const {
    return previous_ && previous_->getStopIndex() + 1 == token->getStartIndex() &&
           (is_word(previous_) || previous_->getType() == FmpcLexer::NUMBER);
  }

  void track_parentheses(const antlr4::Token* token) {
    const std::string text = token->getText();
    if (text == "(") ++parenthesis_depth_;
    else if (text == ")" && parenthesis_depth_ > 0) --parenthesis_depth_;
    else if (token->getType() >= FmpcLexer::SYSTEM && token->getType() <= FmpcLexer::RULE) parenthesis_depth_ = 0;
    if (parenthesis_depth_ == 0) comma_reported_ = false;
  }

  // Tries every repair at token `i`; returns the index after what it consumed, or `i` when none applies.
  std::size_t repair_at(std::size_t i) {
    const antlr4::Token* token = tokens_[i];
    if (token->getType() == FmpcLexer::STRING) return close_quote(i);
    if (token->getType() == FmpcLexer::ERROR_CHARACTER) {
      if (std::size_t next = repair_number(i); next > i) return next;
      if (std::size_t next = repair_operator(i); next > i) return next;
    }
    if (std::size_t next = insert_comma(i); next > i) return next;
    const antlr4::Token* before = last_emitted();
    if (is_word(token) || is_non_ascii(token) ||
        (token->getType() == FmpcLexer::NUMBER && before && before->getText() == "]"))
      return quote_name(i);
    return i;
  }

  // MATLAB's vector written inside a call, `trimf(0 5 10)`: a number after a number in parentheses is read as if
  // the comma between them were written (the parser then asks for the parameters' names).
  std::size_t insert_comma(std::size_t i) {
    const antlr4::Token* token = tokens_[i];
    if (comma_type_ == 0 || parenthesis_depth_ == 0 || token->getType() != FmpcLexer::NUMBER || !previous_ ||
        previous_->getType() != FmpcLexer::NUMBER || previous_->getLine() != token->getLine() ||
        glued_to_previous_name(token))
      return i;
    // One error a call (its first gap); the commas of the others are inserted too.
    if (!comma_reported_) {
      SourceRange after = source_.token(previous_);
      after.line = after.end_line;
      after.column = after.end_column;
      error(source_.token(token), "parameters are separated by ',': write " + previous_->getText() + ", " +
                                      token->getText(), FixIt{after, ","});
      comma_reported_ = true;
    }
    emit(token, comma_type_, ",", token, token);
    keep(i);
    return i + 1;
  }

  // An unterminated quoted name is read as if closed at the end of its line.
  std::size_t close_quote(std::size_t i) {
    const antlr4::Token* token = tokens_[i];
    const std::string text = token->getText();
    if (text.size() >= 2 && text.back() == '"') return i;
    SourceRange range = source_.token(token);
    SourceRange end = range;
    end.column = end.end_column;
    error(range, "unterminated quoted name: close it with '\"' on the same line", FixIt{end, "\""});
    emit(token, FmpcLexer::STRING, text + "\"", token, token);
    return i + 1;
  }

  // `.5`, `-.5`, `+5` and `- 20` (a number that only lacks its leading digit, has a sign fmpc does not write, or a
  // space after its minus), and `12.` (a trailing point).
  std::size_t repair_number(std::size_t i) {
    const antlr4::Token* token = tokens_[i];
    const antlr4::Token* second = glued_after(i);
    const antlr4::Token* third = second ? glued_after(i + 1) : nullptr;
    const auto plain_number = [](const antlr4::Token* t) {
      return t && t->getType() == FmpcLexer::NUMBER && t->getText().find_first_of(".-") == std::string::npos;
    };
    const bool ends_number = !second || (!is_word(second) && second->getType() != FmpcLexer::NUMBER &&
                                         second->getType() != FmpcLexer::ERROR_CHARACTER);
    if (is_error_character(token, ".") && previous_ && previous_->getType() == FmpcLexer::NUMBER &&
        previous_->getStopIndex() + 1 == token->getStartIndex() && ends_number) {
      // The number before was already handed on; the point is dropped with an error on both.
      const std::string number = previous_->getText();
      SourceRange range = source_.span(previous_, token);
      error(range, "a number does not end with '.': write " + number, FixIt{range, number});
      return i + 1;
    }
    if (glued_to_previous_name(token)) return i;
    if (is_error_character(token, ".") && plain_number(second)) {
      const std::string number = "0." + second->getText();
      number_fix(token, second, number, "a number starts with a digit: write " + number);
      return i + 2;
    }
    if (is_error_character(token, "-") && second && is_error_character(second, ".") && plain_number(third)) {
      const std::string number = "-0." + third->getText();
      number_fix(token, third, number, "a number starts with a digit: write " + number);
      return i + 3;
    }
    if (is_error_character(token, "+") && second && second->getType() == FmpcLexer::NUMBER &&
        second->getText()[0] != '-') {
      number_fix(token, second, second->getText(), "a number has no leading '+': write " + second->getText());
      return i + 2;
    }
    const antlr4::Token* after = next_visible(i);
    if (is_error_character(token, "-") && !second && after && after->getType() == FmpcLexer::NUMBER &&
        after->getLine() == token->getLine() && after->getText()[0] != '-') {
      const std::string number = "-" + after->getText();
      number_fix(token, after, number, "a negative number is written without a space: write " + number);
      std::size_t j = i + 1;
      while (tokens_[j] != after) ++j;
      return j + 1;
    }
    return i;
  }

  // `==` or `=` (is), `!=` (is not), `&&` or `&` (and), `||` or `|` (or); `=` between a parameter or a setting and
  // its value (`mean=7.64`, `weight = 0.5`) is dropped.
  std::size_t repair_operator(std::size_t i) {
    const antlr4::Token* token = tokens_[i];
    const std::string text = token->getText();
    const antlr4::Token* second = glued_after(i);
    const bool doubled = second && second->getText() == text;
    const antlr4::Token* last = doubled ? second : token;
    const std::string written = doubled ? text + text : text;
    const SourceRange range = source_.span(token, last);
    if (text == "=") {
      if (parenthesis_depth_ > 0 || setting_word(previous_)) {
        const antlr4::Token* value = next_visible(doubled ? i + 1 : i);
        const std::string example = (previous_ ? previous_->getText() : std::string("mean")) + " " +
                                    (value ? value->getText() : std::string("0.5"));
        // Removed, or replaced by a space where it joins the name and the value (`mean=5`).
        const antlr4::Token* after = glued_after(doubled ? i + 1 : i);
        const bool joins = previous_ && previous_->getStopIndex() + 1 == token->getStartIndex() && after;
        error(range, "no '" + written + "' between a name and its value: write " + example,
              FixIt{range, joins ? " " : ""});
        return doubled ? i + 2 : i + 1;
      }
      error(range, "write 'is' instead of '" + written + "'", FixIt{range, "is"});
      emit(token, FmpcLexer::IS, "is", token, last);
      return doubled ? i + 2 : i + 1;
    }
    if (text == "!" && second && second->getText() == "=") {
      const SourceRange both = source_.span(token, second);
      error(both, "write 'is not' instead of '!='", FixIt{both, "is not"});
      emit(token, FmpcLexer::IS, "is", token, token);
      emit(second, FmpcLexer::NOT, "not", second, second);
      return i + 2;
    }
    if (text == "&" || text == "|") {
      const std::string word = text == "&" ? "and" : "or";
      error(range, "write '" + word + "' instead of '" + written + "'", FixIt{range, word});
      emit(token, text == "&" ? FmpcLexer::AND : FmpcLexer::OR, word, token, last);
      return doubled ? i + 2 : i + 1;
    }
    return i;
  }

  static bool setting_word(const antlr4::Token* token) {
    if (!token) return false;
    switch (token->getType()) {
      case FmpcLexer::TYPE:
      case FmpcLexer::TYPE_REDUCTION:
      case FmpcLexer::IMPLICATION:
      case FmpcLexer::AGGREGATION:
      case FmpcLexer::DEFUZZIFY:
      case FmpcLexer::SAMPLES:
      case FmpcLexer::WEIGHT:
      case FmpcLexer::VALUE:
      case FmpcLexer::SCALE:
      case FmpcLexer::LAG: return true;
      default: return false;
    }
  }

  // A name or unit written with a character an identifier cannot hold, all in one piece (`F0-F1`, `mL/min`, `µm`,
  // `kg/m^3`): read as the quoted name it must be.
  std::size_t quote_name(std::size_t i) {
    std::size_t end = i;
    bool foreign = is_non_ascii(tokens_[i]);
    bool word = is_word(tokens_[i]);
    while (const antlr4::Token* next = glued_after(end)) {
      if (is_name_character(next)) foreign = true;
      else if (next->getType() == FmpcLexer::NUMBER && next->getText().find_first_of(".-") != std::string::npos)
        foreign = true;
      else if (is_word(next)) word = true;
      else if (next->getType() != FmpcLexer::NUMBER) break;
      ++end;
    }
    if (!foreign || !word) return i;
    const antlr4::Token* first = tokens_[i];
    const antlr4::Token* last = tokens_[end];
    std::string text;
    for (std::size_t k = i; k <= end; ++k) text += tokens_[k]->getText();
    const SourceRange range = source_.span(first, last);
    // A unit follows a variable's range or a parameter's value, on its line.
    const antlr4::Token* before = last_emitted();
    const bool unit = before && before->getLine() == first->getLine() &&
                      (before->getText() == "]" || before->getType() == FmpcLexer::NUMBER);
    const std::string quoted = "\"" + text + "\"";
    error(range, std::string(unit ? "a unit" : "a name") + " with '" + first_foreign_character(text) +
                     "' must be quoted: write " + quoted,
          FixIt{range, quoted});
    emit(first, FmpcLexer::STRING, quoted, first, last);
    return end + 1;
  }

  void report_unrepairable(std::size_t i) {
    const antlr4::Token* token = tokens_[i];
    const std::string text = token->getText();
    std::string message = "unexpected character '" + text + "'";
    if (text == "-" && !glued_to_previous_name(token)) message += "; a negative number is written without a space: -20";
    else message += "; a name with this character must be quoted: \"F0-F1\"";
    diagnostics_.error(source_.token(token), message);
    result_.unrepaired = true;
  }

  void number_fix(const antlr4::Token* first, const antlr4::Token* last, const std::string& number,
                  const std::string& message) {
    const SourceRange range = source_.span(first, last);
    error(range, message, FixIt{range, number});
    emit(first, FmpcLexer::NUMBER, number, first, last);
  }

  void error(const SourceRange& range, std::string message, FixIt fix) {
    Diagnostic diagnostic;
    diagnostic.range = range;
    diagnostic.message = std::move(message);
    diagnostic.fix = std::move(fix);
    diagnostics_.add(std::move(diagnostic));
  }

  const antlr4::Token* last_emitted() const {
    for (auto it = result_.tokens.rbegin(); it != result_.tokens.rend(); ++it)
      if ((*it)->getChannel() == antlr4::Token::DEFAULT_CHANNEL) return it->get();
    return nullptr;
  }

  void keep(std::size_t i) { result_.tokens.push_back(std::make_unique<antlr4::CommonToken>(tokens_[i])); }

  // A token of `type` and `text` in place of the source from `first` to `last`.
  void emit(const antlr4::Token* model, std::size_t type, const std::string& text, const antlr4::Token* first,
            const antlr4::Token* last) {
    auto token = std::make_unique<antlr4::CommonToken>(const_cast<antlr4::Token*>(model));
    token->setType(type);
    token->setText(text);
    token->setStartIndex(first->getStartIndex());
    token->setStopIndex(last->getStopIndex());
    token->setLine(first->getLine());
    token->setCharPositionInLine(first->getCharPositionInLine());
    result_.tokens.push_back(std::move(token));
  }

  const SourceMap& source_;
  DiagnosticList& diagnostics_;
  std::vector<antlr4::Token*> tokens_;
  const antlr4::Token* previous_ = nullptr;  // the last visible source token handled
  int parenthesis_depth_ = 0;
  std::size_t comma_type_ = 0;
  bool comma_reported_ = false;  // in the call open now
  RepairedTokens result_;
};

}  // namespace

RepairedTokens repair_tokens(const SourceMap& source, antlr4::BufferedTokenStream& lexed,
                             DiagnosticList& diagnostics) {
  return TokenRepair(source, lexed, diagnostics).run();
}

}  // namespace fmpc::ast

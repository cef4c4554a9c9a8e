#include "runtime/mesh/text_cursor.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace fmpc::sim {

namespace {
bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }
}  // namespace

void TextCursor::skip_blanks_within_line() {
  while (position_ < text_.size() && is_blank(text_[position_])) ++position_;
}

std::string_view TextCursor::next_token() {
  while (position_ < text_.size()) {
    const char c = text_[position_];
    if (c == '\n') {
      ++line_;
      ++position_;
      line_start_ = position_;
    } else if (is_blank(c)) {
      ++position_;
    } else {
      break;
    }
  }
  const std::size_t start = position_;
  while (position_ < text_.size() && !is_blank(text_[position_]) && text_[position_] != '\n') ++position_;
  token_line_ = line_;
  token_column_ = static_cast<int>(start - line_start_) + 1;
  return text_.substr(start, position_ - start);
}

std::optional<std::string_view> TextCursor::next_token_on_line() {
  skip_blanks_within_line();
  if (position_ >= text_.size() || text_[position_] == '\n') return std::nullopt;
  return next_token();
}

std::string_view TextCursor::rest_of_line() {
  skip_blanks_within_line();
  const std::size_t start = position_;
  while (position_ < text_.size() && text_[position_] != '\n') ++position_;
  std::size_t end = position_;
  while (end > start && is_blank(text_[end - 1])) --end;
  if (position_ < text_.size()) {
    ++position_;
    ++line_;
    line_start_ = position_;
  }
  return text_.substr(start, end - start);
}

void TextCursor::skip_line() { (void)rest_of_line(); }

bool TextCursor::at_end() {
  while (position_ < text_.size() && (is_blank(text_[position_]) || text_[position_] == '\n')) {
    if (text_[position_] == '\n') {
      ++line_;
      line_start_ = position_ + 1;
    }
    ++position_;
  }
  return position_ >= text_.size();
}

void TextCursor::advance_bytes(std::size_t count) {
  for (std::size_t i = 0; i < count && position_ < text_.size(); ++i, ++position_) {
    if (text_[position_] == '\n') {
      ++line_;
      line_start_ = position_ + 1;
    }
  }
}

SourceRange TextCursor::range_here() const {
  SourceRange range;
  range.file = file_;
  range.line = token_line_;
  range.column = token_column_;
  return range;
}

bool parse_integer(std::string_view token, std::int64_t& value) {
  if (token.empty() || token.size() > 30) return false;
  const std::string copy(token);
  char* end = nullptr;
  errno = 0;
  const long long parsed = std::strtoll(copy.c_str(), &end, 10);
  if (errno != 0 || end != copy.c_str() + copy.size()) return false;
  value = parsed;
  return true;
}

bool parse_real(std::string_view token, double& value) {
  if (token.empty() || token.size() > 64) return false;
  const std::string copy(token);
  char* end = nullptr;
  const double parsed = std::strtod(copy.c_str(), &end);
  if (end != copy.c_str() + copy.size()) return false;
  value = parsed;
  return true;
}

std::optional<std::int64_t> TextCursor::read_integer(DiagnosticList& diagnostics, std::string_view what) {
  const std::string_view token = next_token();
  std::int64_t value = 0;
  if (parse_integer(token, value)) return value;
  diagnostics.error(range_here(), token.empty()
                                      ? "the file ends where " + std::string(what) +
                                            " (an integer) was expected; the file is truncated: export it again"
                                      : "expected " + std::string(what) + " (an integer) but found '" +
                                            std::string(token.substr(0, 40)) + "'; fix or re-export the file");
  return std::nullopt;
}

std::optional<double> TextCursor::read_real(DiagnosticList& diagnostics, std::string_view what) {
  const std::string_view token = next_token();
  double value = 0.0;
  if (parse_real(token, value)) {
    if (!std::isfinite(value)) {
      diagnostics.error(range_here(), std::string(what) + " is '" + std::string(token) +
                                          "', which is not a finite number; replace it with a coordinate");
      return std::nullopt;
    }
    return value;
  }
  diagnostics.error(range_here(), token.empty()
                                      ? "the file ends where " + std::string(what) +
                                            " (a number) was expected; the file is truncated: export it again"
                                      : "expected " + std::string(what) + " (a number) but found '" +
                                            std::string(token.substr(0, 40)) + "'; fix or re-export the file");
  return std::nullopt;
}

}  // namespace fmpc::sim

#pragma once
// Reads whitespace-separated tokens from a mesh file held in memory, keeping the 1-based line number of each
// token so that readers can name file:line in their diagnostics. Binary blocks (legacy VTK) are read as raw bytes.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "diagnostics/diagnostic.h"

namespace fmpc::sim {

class TextCursor {
 public:
  TextCursor(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {}

  // The next token on any line; empty at the end of the text. token_line() is its line.
  std::string_view next_token();
  // The next token only if it is on the current line (used for variable-length records such as OBJ faces).
  std::optional<std::string_view> next_token_on_line();
  // The rest of the current line after the last token, trimmed, and moves to the next line.
  std::string_view rest_of_line();
  void skip_line();
  bool at_end();  // skips blank space first
  bool at_end_of_text() const { return position_ >= text_.size(); }

  // The current position in bytes and raw access for binary payloads.
  std::size_t position() const { return position_; }
  std::size_t remaining() const { return text_.size() - position_; }
  const char* data_here() const { return text_.data() + position_; }
  void advance_bytes(std::size_t count);

  int line() const { return line_; }
  int token_line() const { return token_line_; }
  const std::string& file() const { return file_; }
  SourceRange range_here() const;  // the last token's line

  // Reads a number token; on failure appends an error naming file:line, what was found and what was expected.
  std::optional<std::int64_t> read_integer(DiagnosticList& diagnostics, std::string_view what);
  std::optional<double> read_real(DiagnosticList& diagnostics, std::string_view what);

 private:
  void skip_blanks_within_line();
  std::string_view text_;
  std::string file_;
  std::size_t position_ = 0;
  int line_ = 1;
  int token_line_ = 0;
  int token_column_ = 0;
  std::size_t line_start_ = 0;
};

bool parse_integer(std::string_view token, std::int64_t& value);
bool parse_real(std::string_view token, double& value);

}  // namespace fmpc::sim

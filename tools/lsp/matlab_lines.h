#pragma once
// MATLAB .fis text seen line by line, as the language server needs it while the file is typed (and may not load):
// the section each line belongs to and each line's tokens, in the shapes of grammar/MatlabFis.g4's lexer (strings,
// numbers, names, single characters; `%` and `#` comments dropped). docs/matlab_fis.md describes the format.
#include <cstddef>
#include <string>
#include <vector>

namespace fmpc::lsp {

struct MatlabToken {
  enum class Kind { String, Number, Name, Symbol };
  Kind kind = Kind::Symbol;
  std::size_t begin = 0, end = 0;  // byte offsets in the text
  std::string text;                // as written (a string with its quotes)
  // A string's text without its quotes (doubled quotes made single); an unterminated one up to the line's end.
  std::string unquoted() const;
};

struct MatlabLine {
  enum class Section { None, System, Input, Output, Rules };
  Section section = Section::None;  // of the header above it (or its own, for a header)
  int section_number = 0;           // N of [InputN] / [OutputN]
  int header_line = -1;             // 0-based line of that header; -1 before any
  bool is_header = false;
  bool has_comment = false;
  int line = 0;  // 0-based
  std::size_t begin = 0, end = 0;  // byte offsets of the line, its end before "\r\n" or "\n"
  std::vector<MatlabToken> tokens;
  // The key of a `Key = ...` or MF line (the name before its first '='), or "".
  std::string key() const;
};

// Every line of `text`, in order (a last line without its line end included).
std::vector<MatlabLine> read_matlab_lines(const std::string& text);

}  // namespace fmpc::lsp

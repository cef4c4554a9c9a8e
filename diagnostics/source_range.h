#pragma once
#include <string>

namespace fmpc {

// A span of source text. Lines and columns are 1-based; columns count bytes (tabs count as one), which is what
// the caret renderer assumes. A default-constructed range (line 0) means "no source position" (e.g. a system built
// in code or converted from another format), and diagnostics then name only the file or the field.
struct SourceRange {
  std::string file;
  int line = 0;
  int column = 0;
  int end_line = 0;
  int end_column = 0;  // one past the last character

  bool valid() const { return line > 0; }
};

inline bool operator<(const SourceRange& a, const SourceRange& b) {
  if (a.file != b.file) return a.file < b.file;
  if (a.line != b.line) return a.line < b.line;
  return a.column < b.column;
}

}  // namespace fmpc

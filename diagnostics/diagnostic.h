#pragma once
// Diagnostics are data: every stage appends to a DiagnosticList and returns; only tools/ prints. The renderer
// produces the compiler-style text that golden tests compare byte for byte.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/source_range.h"

namespace fmpc {

enum class Severity { Note, Warning, Error };

struct FixIt {
  SourceRange range;        // the text to replace
  std::string replacement;  // what to put there
};

struct Diagnostic {
  Severity severity = Severity::Error;
  SourceRange range;         // where; file-only (line 0) when there is no position
  std::string message;       // one sentence, lower case start, no trailing period
  std::string code;          // lint name for warnings ("unused-term"), empty for errors
  std::vector<std::string> notes;  // extra lines ("did you mean 'F4'?", "first defined here: 3:5")
  std::optional<FixIt> fix;
};

class DiagnosticList {
 public:
  void add(Diagnostic diagnostic) { items_.push_back(std::move(diagnostic)); }
  void error(const SourceRange& range, std::string message, std::vector<std::string> notes = {});
  void warning(const SourceRange& range, std::string code, std::string message, std::vector<std::string> notes = {});
  void append(const DiagnosticList& other);

  bool has_errors() const;
  std::size_t error_count() const;
  std::size_t warning_count() const;
  bool empty() const { return items_.empty(); }
  const std::vector<Diagnostic>& items() const { return items_; }

  // Stable sort by file, line, column (diagnostics without a position first within their file).
  void sort_by_position();

 private:
  std::vector<Diagnostic> items_;
};

// Source text by file path, so the renderer can show the offending line.
class SourceFiles {
 public:
  void add(const std::string& path, std::string text) { texts_[path] = std::move(text); }
  // The 1-based line of `path`, without its newline; nullopt when unknown.
  std::optional<std::string> line(const std::string& path, int line_number) const;

 private:
  std::map<std::string, std::string> texts_;
};

// Renders one diagnostic:
//   FILE:LINE:COL: error: MESSAGE
//      LINE | source text
//           |      ^~~~
//           |      FIXIT            (when there is a fix-it)
//   note: NOTE                      (one line per note)
// Warnings end their first line with " [-WCODE]". Without a position: "FILE: error: MESSAGE".
std::string render(const Diagnostic& diagnostic, const SourceFiles& sources);
std::string render_all(const DiagnosticList& diagnostics, const SourceFiles& sources);

// The closest candidate by edit distance, if it is close enough to suggest (distance <= max(1, len/3)).
std::optional<std::string> closest_name(const std::string& name, const std::vector<std::string>& candidates);

}  // namespace fmpc

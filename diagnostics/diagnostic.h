#pragma once
// Diagnostics are data: every stage appends to a DiagnosticList and returns; only tools/ prints. The renderer
// produces the compiler-style text that golden tests compare byte for byte.
#include <cstddef>
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

// Bounds on what a list keeps (docs/limits.md): hostile input can ask for millions of diagnostics, each quoting a
// megabyte-long name. A message or note longer than kMaxDiagnosticTextBytes keeps its start and end around
// "[... N bytes ...]" (a longer fix-it is dropped: cut, it would no longer be a fix); past kMaxStoredDiagnostics
// the list only counts what it drops, by severity.
inline constexpr std::size_t kMaxDiagnosticTextBytes = 1024;
inline constexpr std::size_t kMaxStoredDiagnostics = 100000;

class DiagnosticList {
 public:
  void add(Diagnostic diagnostic);
  void error(const SourceRange& range, std::string message, std::vector<std::string> notes = {});
  void warning(const SourceRange& range, std::string code, std::string message, std::vector<std::string> notes = {});
  void append(const DiagnosticList& other);

  bool has_errors() const;
  std::size_t error_count() const;
  std::size_t warning_count() const;
  bool empty() const { return items_.empty() && dropped_errors_ + dropped_warnings_ + dropped_notes_ == 0; }
  // The diagnostics kept (at most kMaxStoredDiagnostics); the counts above include the dropped ones.
  const std::vector<Diagnostic>& items() const { return items_; }
  std::size_t dropped_count() const { return dropped_errors_ + dropped_warnings_ + dropped_notes_; }

  // Stable sort by file, line, column (diagnostics without a position first within their file).
  void sort_by_position();

 private:
  std::vector<Diagnostic> items_;
  std::size_t dropped_errors_ = 0;
  std::size_t dropped_warnings_ = 0;
  std::size_t dropped_notes_ = 0;
};

// Source text by file path, so the renderer can show the offending line. Line starts are indexed once per file,
// so rendering N diagnostics costs N lookups, not N scans of the file.
class SourceFiles {
 public:
  void add(const std::string& path, std::string text);
  // The 1-based line of `path`, without its newline; nullopt when unknown.
  std::optional<std::string> line(const std::string& path, int line_number) const;

 private:
  struct Text {
    std::string text;
    std::vector<std::size_t> line_starts;  // byte offset of each line's first byte
  };
  std::map<std::string, Text> texts_;
};

// How much of a source line a diagnostic shows: a longer line is cut to a window of this many bytes around the
// caret, marked with "..." at the cut ends.
inline constexpr std::size_t kMaxExcerptBytes = 160;
// How many diagnostics render_all prints before it summarises the rest ("... and 9,990 more: 9,990 errors").
inline constexpr std::size_t kMaxRenderedDiagnostics = 100;

// "error", "warning" or "note", as the rendered text and the studio's diagnostics name them.
const char* severity_name(Severity severity);

// Renders one diagnostic:
//   FILE:LINE:COL: error: MESSAGE
//      LINE | source text
//           |      ^~~~
//           |      FIXIT            (when there is a fix-it)
//   note: NOTE                      (one line per note)
// Warnings end their first line with " [-WCODE]". Without a position: "FILE: error: MESSAGE".
std::string render(const Diagnostic& diagnostic, const SourceFiles& sources);
// The first kMaxRenderedDiagnostics diagnostics, then one line counting the rest by severity.
std::string render_all(const DiagnosticList& diagnostics, const SourceFiles& sources);

// "did you mean" stays cheap on hostile names: names longer than kMaxSuggestedNameBytes are not compared, at most
// kMaxSuggestionCandidates candidates are examined, and the edit distance is computed in a band of width
// 2 * cap + 1 that stops as soon as every entry of a row exceeds the cap (O(length * cap) per candidate).
inline constexpr std::size_t kMaxSuggestedNameBytes = 64;
inline constexpr std::size_t kMaxSuggestionCandidates = 4096;

// The closest candidate by edit distance, if it is close enough to suggest (distance <= max(1, len/3)).
std::optional<std::string> closest_name(const std::string& name, const std::vector<std::string>& candidates);

}  // namespace fmpc

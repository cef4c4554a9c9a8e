#include "diagnostics/diagnostic.h"

#include <algorithm>
#include <cctype>
#include <sstream>

namespace fmpc {

namespace {

// Cuts `text` to at most `limit` bytes on UTF-8 character boundaries: its start and end around a marker that
// says how many bytes were left out.
std::string shortened(std::string text, std::size_t limit) {
  if (text.size() <= limit) return text;
  const auto boundary = [&](std::size_t i) {
    while (i > 0 && i < text.size() && (static_cast<unsigned char>(text[i]) & 0xC0) == 0x80) --i;
    return i;
  };
  const std::size_t keep = limit / 2;
  const std::size_t head = boundary(keep);
  const std::size_t tail = boundary(text.size() - keep);
  return text.substr(0, head) + "[... " + std::to_string(tail - head) + " bytes ...]" + text.substr(tail);
}

// 9990 -> "9,990".
std::string format_count(std::size_t n) {
  std::string digits = std::to_string(n);
  for (std::size_t i = digits.size(); i > 3; i -= 3) digits.insert(i - 3, ",");
  return digits;
}

}  // namespace

void DiagnosticList::add(Diagnostic diagnostic) {
  if (items_.size() >= kMaxStoredDiagnostics) {
    switch (diagnostic.severity) {
      case Severity::Error: ++dropped_errors_; break;
      case Severity::Warning: ++dropped_warnings_; break;
      case Severity::Note: ++dropped_notes_; break;
    }
    return;
  }
  diagnostic.message = shortened(std::move(diagnostic.message), kMaxDiagnosticTextBytes);
  for (std::string& note : diagnostic.notes) note = shortened(std::move(note), kMaxDiagnosticTextBytes);
  // A fix-it is text to put in the file: dropped rather than cut when it is too long to be a fix.
  if (diagnostic.fix && diagnostic.fix->replacement.size() > kMaxDiagnosticTextBytes) diagnostic.fix.reset();
  items_.push_back(std::move(diagnostic));
}

void DiagnosticList::error(const SourceRange& range, std::string message, std::vector<std::string> notes) {
  add(Diagnostic{Severity::Error, range, std::move(message), {}, std::move(notes), std::nullopt});
}

void DiagnosticList::warning(const SourceRange& range, std::string code, std::string message,
                             std::vector<std::string> notes) {
  add(Diagnostic{Severity::Warning, range, std::move(message), std::move(code), std::move(notes), std::nullopt});
}

void DiagnosticList::append(const DiagnosticList& other) {
  for (const Diagnostic& d : other.items_) add(d);
  dropped_errors_ += other.dropped_errors_;
  dropped_warnings_ += other.dropped_warnings_;
  dropped_notes_ += other.dropped_notes_;
}

bool DiagnosticList::has_errors() const { return error_count() > 0; }

std::size_t DiagnosticList::error_count() const {
  return dropped_errors_ + static_cast<std::size_t>(std::count_if(
                               items_.begin(), items_.end(),
                               [](const Diagnostic& d) { return d.severity == Severity::Error; }));
}

std::size_t DiagnosticList::warning_count() const {
  return dropped_warnings_ + static_cast<std::size_t>(std::count_if(
                                 items_.begin(), items_.end(),
                                 [](const Diagnostic& d) { return d.severity == Severity::Warning; }));
}

void DiagnosticList::sort_by_position() {
  std::stable_sort(items_.begin(), items_.end(),
                   [](const Diagnostic& a, const Diagnostic& b) { return a.range < b.range; });
}

void SourceFiles::add(const std::string& path, std::string text) {
  Text& entry = texts_[path];
  entry.text = std::move(text);
  entry.line_starts.assign(1, 0);
  for (std::size_t i = 0; i < entry.text.size(); ++i)
    if (entry.text[i] == '\n') entry.line_starts.push_back(i + 1);
}

std::optional<std::string> SourceFiles::line(const std::string& path, int line_number) const {
  auto it = texts_.find(path);
  if (it == texts_.end() || line_number < 1) return std::nullopt;
  const std::string& text = it->second.text;
  const std::vector<std::size_t>& starts = it->second.line_starts;
  if (static_cast<std::size_t>(line_number) > starts.size()) return std::nullopt;
  const std::size_t start = starts[static_cast<std::size_t>(line_number - 1)];
  if (start > text.size()) return std::nullopt;
  std::size_t end = text.find('\n', start);
  std::string result = text.substr(start, end == std::string::npos ? std::string::npos : end - start);
  if (!result.empty() && result.back() == '\r') result.pop_back();
  return result;
}

const char* severity_name(Severity severity) {
  switch (severity) {
    case Severity::Note: return "note";
    case Severity::Warning: return "warning";
    case Severity::Error: return "error";
  }
  return "error";
}

std::string render(const Diagnostic& diagnostic, const SourceFiles& sources) {
  std::ostringstream out;
  const SourceRange& r = diagnostic.range;
  out << (r.file.empty() ? "<input>" : r.file);
  if (r.valid()) out << ':' << r.line << ':' << r.column;
  out << ": " << severity_name(diagnostic.severity) << ": " << diagnostic.message;
  if (!diagnostic.code.empty()) out << " [-W" << diagnostic.code << ']';
  out << '\n';
  if (r.valid()) {
    if (auto text = sources.line(r.file, r.line)) {
      const std::string number = std::to_string(r.line);
      const std::string gutter(number.size(), ' ');
      // A long line is shown as a window around the caret; `first` is the byte of the line the window starts at.
      const std::size_t caret = static_cast<std::size_t>(std::max(r.column, 1) - 1);
      std::size_t first = 0;
      std::string excerpt = *text;
      std::string lead;
      if (text->size() > kMaxExcerptBytes) {
        const std::size_t half = kMaxExcerptBytes / 2;
        first = caret > half ? std::min(caret - half, text->size() - std::min(text->size(), kMaxExcerptBytes)) : 0;
        while (first > 0 && (static_cast<unsigned char>((*text)[first]) & 0xC0) == 0x80) --first;
        std::size_t last = std::min(text->size(), first + kMaxExcerptBytes);
        while (last < text->size() && (static_cast<unsigned char>((*text)[last]) & 0xC0) == 0x80) --last;
        excerpt = text->substr(first, last - first);
        if (first > 0) lead = "...";
        if (last < text->size()) excerpt += "...";
      }
      out << ' ' << number << " | " << lead << excerpt << '\n';
      // Tabs in the source are echoed in the caret line so that the caret stays under the column.
      const auto pad_to = [&](std::size_t byte) {
        std::string pad(lead.size(), ' ');
        for (std::size_t c = first; c < byte && c < text->size() && c < first + kMaxExcerptBytes; ++c)
          pad += (*text)[c] == '\t' ? '\t' : ' ';
        return pad;
      };
      const std::string pad = pad_to(caret);
      std::size_t width = 1;
      if (r.end_line == r.line && r.end_column > r.column) width = static_cast<std::size_t>(r.end_column - r.column);
      width = std::min(width, kMaxExcerptBytes);
      out << ' ' << gutter << " | " << pad << '^' << std::string(width - 1, '~') << '\n';
      // The fix-it's text starts where it goes (an insertion after the previous token, not under the caret).
      if (diagnostic.fix && diagnostic.fix->range.line == r.line &&
          diagnostic.fix->replacement.find_first_not_of(' ') != std::string::npos) {
        const std::size_t at = static_cast<std::size_t>(std::max(diagnostic.fix->range.column, 1) - 1);
        out << ' ' << gutter << " | " << (at >= first ? pad_to(at) : pad)
            << shortened(diagnostic.fix->replacement, kMaxExcerptBytes) << '\n';
      }
    }
  }
  for (const std::string& note : diagnostic.notes) out << "note: " << note << '\n';
  return out.str();
}

std::string render_all(const DiagnosticList& diagnostics, const SourceFiles& sources) {
  std::string out;
  const std::vector<Diagnostic>& items = diagnostics.items();
  const std::size_t shown = std::min(items.size(), kMaxRenderedDiagnostics);
  for (std::size_t i = 0; i < shown; ++i) out += render(items[i], sources);
  const std::size_t hidden = items.size() - shown + diagnostics.dropped_count();
  if (hidden == 0) return out;
  std::size_t errors = diagnostics.error_count(), warnings = diagnostics.warning_count();
  for (std::size_t i = 0; i < shown; ++i) {
    if (items[i].severity == Severity::Error) --errors;
    if (items[i].severity == Severity::Warning) --warnings;
  }
  out += "... and " + format_count(hidden) + " more not shown: " + format_count(errors) + " error" +
         (errors == 1 ? "" : "s") + ", " + format_count(warnings) + " warning" + (warnings == 1 ? "" : "s") +
         " (fix the first ones and run again)\n";
  return out;
}

// Optimal string alignment distance (Levenshtein plus adjacent transpositions, case-insensitive): "HVC" is one
// edit from "HCV", the typo a clinician actually makes. Only the band |i - j| <= cap is computed (a cell outside
// it costs more than cap edits), and the search stops once a whole row exceeds the cap: nullopt means "more than
// cap". Three rolling rows, as the transposition looks two rows back.
static std::optional<std::size_t> bounded_edit_distance(const std::string& a, const std::string& b, std::size_t cap) {
  const std::size_t n = a.size(), m = b.size();
  if ((n > m ? n - m : m - n) > cap) return std::nullopt;
  auto same = [](char x, char y) {
    return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
  };
  const std::size_t beyond = cap + 1;
  std::vector<std::size_t> two_back(m + 1, beyond), previous(m + 1, beyond), current(m + 1, beyond);
  for (std::size_t j = 0; j <= std::min(m, cap); ++j) previous[j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    const std::size_t from = i > cap ? i - cap : 1;
    const std::size_t to = std::min(m, i + cap);
    std::fill(current.begin(), current.end(), beyond);
    if (i <= cap) current[0] = i;
    std::size_t row_minimum = current[0];
    for (std::size_t j = from; j <= to; ++j) {
      std::size_t d = std::min({previous[j] + 1, current[j - 1] + 1,
                                previous[j - 1] + (same(a[i - 1], b[j - 1]) ? 0 : 1)});
      if (i > 1 && j > 1 && same(a[i - 1], b[j - 2]) && same(a[i - 2], b[j - 1])) d = std::min(d, two_back[j - 2] + 1);
      current[j] = std::min(d, beyond);
      row_minimum = std::min(row_minimum, current[j]);
    }
    if (row_minimum > cap) return std::nullopt;
    std::swap(two_back, previous);
    std::swap(previous, current);
  }
  return previous[m] <= cap ? std::optional<std::size_t>(previous[m]) : std::nullopt;
}

std::optional<std::string> closest_name(const std::string& name, const std::vector<std::string>& candidates) {
  if (name.size() > kMaxSuggestedNameBytes) return std::nullopt;
  std::optional<std::string> best;
  std::size_t cap = std::max<std::size_t>(1, name.size() / 3);
  const std::size_t examined = std::min(candidates.size(), kMaxSuggestionCandidates);
  for (std::size_t c = 0; c < examined; ++c) {
    const std::string& candidate = candidates[c];
    if (candidate.size() > kMaxSuggestedNameBytes) continue;
    const std::optional<std::size_t> d = bounded_edit_distance(name, candidate, cap);
    if (!d) continue;
    best = candidate;
    if (*d == 0) break;
    cap = *d - 1;  // a later candidate must be strictly closer
  }
  return best;
}

}  // namespace fmpc

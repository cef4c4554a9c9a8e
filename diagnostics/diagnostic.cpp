#include "diagnostics/diagnostic.h"

#include <algorithm>
#include <cctype>
#include <sstream>

namespace fmpc {

void DiagnosticList::error(const SourceRange& range, std::string message, std::vector<std::string> notes) {
  add(Diagnostic{Severity::Error, range, std::move(message), {}, std::move(notes), std::nullopt});
}

void DiagnosticList::warning(const SourceRange& range, std::string code, std::string message,
                             std::vector<std::string> notes) {
  add(Diagnostic{Severity::Warning, range, std::move(message), std::move(code), std::move(notes), std::nullopt});
}

void DiagnosticList::append(const DiagnosticList& other) {
  items_.insert(items_.end(), other.items_.begin(), other.items_.end());
}

bool DiagnosticList::has_errors() const { return error_count() > 0; }

std::size_t DiagnosticList::error_count() const {
  return static_cast<std::size_t>(std::count_if(items_.begin(), items_.end(),
                                                [](const Diagnostic& d) { return d.severity == Severity::Error; }));
}

std::size_t DiagnosticList::warning_count() const {
  return static_cast<std::size_t>(std::count_if(items_.begin(), items_.end(),
                                                [](const Diagnostic& d) { return d.severity == Severity::Warning; }));
}

void DiagnosticList::sort_by_position() {
  std::stable_sort(items_.begin(), items_.end(),
                   [](const Diagnostic& a, const Diagnostic& b) { return a.range < b.range; });
}

std::optional<std::string> SourceFiles::line(const std::string& path, int line_number) const {
  auto it = texts_.find(path);
  if (it == texts_.end() || line_number < 1) return std::nullopt;
  const std::string& text = it->second;
  std::size_t start = 0;
  for (int l = 1; l < line_number; ++l) {
    start = text.find('\n', start);
    if (start == std::string::npos) return std::nullopt;
    ++start;
  }
  if (start > text.size()) return std::nullopt;
  std::size_t end = text.find('\n', start);
  std::string result = text.substr(start, end == std::string::npos ? std::string::npos : end - start);
  if (!result.empty() && result.back() == '\r') result.pop_back();
  return result;
}

static const char* severity_name(Severity severity) {
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
      out << ' ' << number << " | " << *text << '\n';
      // Tabs in the source are echoed in the caret line so that the caret stays under the column.
      std::string pad;
      for (int c = 1; c < r.column && static_cast<std::size_t>(c - 1) < text->size(); ++c)
        pad += (*text)[static_cast<std::size_t>(c - 1)] == '\t' ? '\t' : ' ';
      int width = 1;
      if (r.end_line == r.line && r.end_column > r.column) width = r.end_column - r.column;
      out << ' ' << gutter << " | " << pad << '^' << std::string(static_cast<std::size_t>(width - 1), '~') << '\n';
      if (diagnostic.fix && diagnostic.fix->range.line == r.line)
        out << ' ' << gutter << " | " << pad << diagnostic.fix->replacement << '\n';
    }
  }
  for (const std::string& note : diagnostic.notes) out << "note: " << note << '\n';
  return out.str();
}

std::string render_all(const DiagnosticList& diagnostics, const SourceFiles& sources) {
  std::string out;
  for (const Diagnostic& d : diagnostics.items()) out += render(d, sources);
  return out;
}

// Optimal string alignment distance (Levenshtein plus adjacent transpositions, case-insensitive): "HVC" is one
// edit from "HCV", the typo a clinician actually makes.
static std::size_t edit_distance(const std::string& a, const std::string& b) {
  auto same = [](char x, char y) {
    return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
  };
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (same(a[i - 1], b[j - 1]) ? 0 : 1)});
      if (i > 1 && j > 1 && same(a[i - 1], b[j - 2]) && same(a[i - 2], b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

std::optional<std::string> closest_name(const std::string& name, const std::vector<std::string>& candidates) {
  std::optional<std::string> best;
  std::size_t best_distance = std::max<std::size_t>(1, name.size() / 3) + 1;
  for (const std::string& candidate : candidates) {
    const std::size_t d = edit_distance(name, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  return best;
}

}  // namespace fmpc

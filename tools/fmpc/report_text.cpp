#include "tools/fmpc/report_text.h"

#include <cstdio>

namespace fmpc::cli {

std::string four_digits(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

std::string four_digits_with_unit(double value, const std::string& unit) {
  return four_digits(value) + (unit.empty() || unit == "dimensionless" ? "" : " " + unit);
}

std::string markdown_table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
  const auto line = [](const std::vector<std::string>& cells) {
    std::string text = "|";
    for (const std::string& cell : cells) {
      std::string escaped;
      for (char c : cell) {
        if (c == '|') escaped += '\\';
        escaped += c == '\n' ? ' ' : c;
      }
      text += " " + escaped + " |";
    }
    return text + "\n";
  };
  std::string text = line(header);
  text += "|";
  for (std::size_t c = 0; c < header.size(); ++c) text += " --- |";
  text += "\n";
  for (const auto& row : rows) text += line(row);
  return text;
}

void append_capped(const DiagnosticList& from, std::size_t max_warnings, const std::string& file, DiagnosticList& to) {
  std::size_t warnings = 0, dropped = 0;
  for (const Diagnostic& d : from.items()) {
    if (d.severity == Severity::Warning && ++warnings > max_warnings) {
      ++dropped;
      continue;
    }
    to.add(d);
  }
  if (dropped > 0)
    to.add(Diagnostic{Severity::Note, SourceRange{file, 0, 0, 0, 0},
                      std::to_string(dropped) + " more warnings not shown (--max-warnings)", {}, {}, {}});
}

}  // namespace fmpc::cli

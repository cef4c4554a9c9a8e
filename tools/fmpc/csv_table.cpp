#include "tools/fmpc/csv_table.h"

#include "compiler/frontend/utf8.h"
#include "tools/fmpc/text_files.h"

#include <algorithm>
#include <cctype>

namespace fmpc::cli {

namespace {

std::string trimmed(const std::string& s) {
  const std::size_t first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

}  // namespace

CsvTable parse_csv(const std::string& path, const std::string& original, DiagnosticList& diagnostics,
                   const std::string& header_example) {
  const std::string text = blank_byte_order_mark(original);
  CsvTable table;
  table.path = path;
  std::vector<CsvCell> row;
  CsvCell cell;
  bool quoted = false, was_quoted = false, row_has_content = false;
  int line = 1, column = 1, cell_line = 1, cell_column = 1;
  auto finish_cell = [&] {
    cell.text = was_quoted ? cell.text : trimmed(cell.text);
    cell.range = SourceRange{path, cell_line, cell_column, line, column};
    row.push_back(cell);
    cell = CsvCell{};
    was_quoted = false;
  };
  auto finish_row = [&] {
    if (row_has_content) {
      finish_cell();
      if (table.header.empty() && table.rows.empty())
        table.header = std::move(row);
      else
        table.rows.push_back(std::move(row));
    }
    row.clear();
    cell = CsvCell{};
    was_quoted = false;
    row_has_content = false;
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (table.rows.size() * std::max<std::size_t>(table.header.size(), 1) + row.size() > kMaxCsvCells) {
      diagnostics.error(SourceRange{path, line, 1, line, 2},
                        "the CSV has more than " + std::to_string(kMaxCsvCells) +
                            " cells, the limit (docs/limits.md); split it into several files");
      return table;
    }
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        cell.text += '"';
        ++i;
        ++column;
      } else if (c == '"') {
        quoted = false;
      } else {
        cell.text += c;
        if (c == '\n') {
          ++line;
          column = 0;
        }
      }
    } else if (c == '"' && trimmed(cell.text).empty()) {
      quoted = was_quoted = row_has_content = true;
      cell.text.clear();
    } else if (c == ',') {
      row_has_content = true;
      finish_cell();
      cell_line = line;
      cell_column = column + 1;
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      finish_row();
      ++line;
      column = 0;
      cell_line = line;
      cell_column = 1;
    } else {
      if (c != ' ' && c != '\t') row_has_content = true;
      if (cell.text.empty() && (c == ' ' || c == '\t')) cell_column = column + 1;
      cell.text += c;
    }
    ++column;
  }
  if (quoted)
    diagnostics.error(SourceRange{path, cell_line, cell_column, cell_line, cell_column + 1},
                      "unterminated quoted field", {"close the field with a double quote"});
  finish_row();
  if (table.header.empty())
    diagnostics.error(SourceRange{path, 0, 0, 0, 0}, "no header row: the CSV is empty",
                      {header_example.empty() ? std::string("the first row names the columns")
                                              : "the first row names the columns: " + header_example});
  return table;
}

std::string format_csv_row(const std::vector<std::string>& fields) {
  std::string line;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const std::string& f = fields[i];
    if (i) line += ',';
    const bool needs_quotes =
        f.find_first_of(",\"\n\r") != std::string::npos || (!f.empty() && (f.front() == ' ' || f.back() == ' '));
    if (!needs_quotes) {
      line += f;
      continue;
    }
    line += '"';
    for (char c : f) line += c == '"' ? std::string("\"\"") : std::string(1, c);
    line += '"';
  }
  return line + '\n';
}

std::optional<CsvTable> read_csv_file(const std::string& path, const std::string& name, std::size_t limit,
                                      const std::string& what, const SourceRange& unreadable, SourceFiles& sources,
                                      DiagnosticList& diagnostics, const std::string& header_example) {
  std::string error;
  const std::optional<std::string> text = read_text_file(path, limit, what, error);
  if (!text) {
    diagnostics.error(unreadable, error);
    return std::nullopt;
  }
  sources.add(name, *text);
  const std::size_t errors_before = diagnostics.error_count();
  CsvTable table = parse_csv(name, *text, diagnostics, header_example);
  if (diagnostics.error_count() > errors_before) return std::nullopt;
  return table;
}

HeaderColumn split_header_unit(const CsvCell& cell) {
  HeaderColumn column{cell.text, "", cell.range};
  const std::string& text = cell.text;
  if (text.size() < 3) return column;
  const char close = text.back();
  const char open = close == ')' ? '(' : close == ']' ? '[' : '\0';
  if (open == '\0') return column;
  const std::size_t start = text.rfind(open);
  if (start == std::string::npos || start == 0) return column;
  std::string name = text.substr(0, start);
  while (!name.empty() && std::isspace(static_cast<unsigned char>(name.back()))) name.pop_back();
  std::string unit = text.substr(start + 1, text.size() - start - 2);
  if (name.empty() || unit.empty()) return column;
  column.name = name;
  column.unit = unit;
  return column;
}

}  // namespace fmpc::cli

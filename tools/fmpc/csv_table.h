#pragma once
// RFC 4180 CSV as the CLI reads and writes it: a header row, comma separators, double-quoted fields with ""
// escapes, LF or CRLF line ends. Every cell keeps its position so that errors point at it.
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"

namespace fmpc::cli {

struct CsvCell {
  std::string text;  // unquoted, surrounding spaces trimmed
  SourceRange range;
};

struct CsvTable {
  std::string path;
  std::vector<CsvCell> header;
  std::vector<std::vector<CsvCell>> rows;  // blank lines skipped
};

// Every cell keeps its text and position (about 100 bytes each); a table of more cells is refused.
inline constexpr std::size_t kMaxCsvCells = std::size_t{1} << 20;  // 1,048,576

// `header_example` (e.g. "label,HCV,HBV", from the file's own inputs) is shown when the text has no header row. A
// leading UTF-8 byte order mark is read as three spaces (compiler/frontend/utf8.h).
CsvTable parse_csv(const std::string& path, const std::string& text, DiagnosticList& diagnostics,
                   const std::string& header_example = "");

// Reads the file at `path` ("-": standard input; at most `limit` bytes, `what` names it in the error when it cannot
// be read, located at `unreadable`), keeps its text in `sources` under `name` (what the cells' positions say) and
// parses it (`header_example` as for parse_csv); nullopt after errors.
std::optional<CsvTable> read_csv_file(const std::string& path, const std::string& name, std::size_t limit,
                                      const std::string& what, const SourceRange& unreadable, SourceFiles& sources,
                                      DiagnosticList& diagnostics, const std::string& header_example = "");

// A header cell that states a unit, "HCV (kPa)" or "stiffness [Pa]": the name without it and the unit (empty when
// none is stated).
struct HeaderColumn {
  std::string name;
  std::string unit;
  SourceRange range;
};
HeaderColumn split_header_unit(const CsvCell& cell);

// One CSV line (with its '\n'); fields are quoted only when they need it.
std::string format_csv_row(const std::vector<std::string>& fields);

}  // namespace fmpc::cli

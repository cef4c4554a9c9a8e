// libFuzzer target: the CLI's CSV reader (tools/fmpc/csv_table.cpp), as `fmpc eval --csv` uses it.
#include <cstdint>
#include <string>

#include "tools/fmpc/csv_table.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  fmpc::DiagnosticList diagnostics;
  const fmpc::cli::CsvTable table = fmpc::cli::parse_csv("fuzz.csv", text, diagnostics);
  std::string written;
  for (const auto& row : table.rows) {
    std::vector<std::string> fields;
    for (const auto& cell : row) fields.push_back(cell.text);
    written += fmpc::cli::format_csv_row(fields);
  }
  return 0;
}

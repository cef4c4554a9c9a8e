#pragma once
// Measured data for `fmpc tune` (docs/cli.md): a CSV (csv_table.h) with a header row, read by the conventions of
// `fmpc validate` so that one file serves both: one column per input of the system, matched by name (or mapped with
// `--column INPUT=COLUMN`); the measured values of one output from the column `measured_column` when given, else
// the first of OUTPUT, measured, measured_OUTPUT, OUTPUT_measured that the header has; an optional label column
// (`label`, `patient` or `id`); other columns listed, not refused. Values are taken in the variables' units (a
// unit in a header is not read here). Every message points at its cell. When validate's reader
// (patient_data.h on the studio branch) lands on main, this becomes a call to it.
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"
#include "tools/fmpc/csv_table.h"

namespace fmpc::cli {

struct MeasuredData {
  std::vector<std::string> labels;          // the label column's text, or "row N" (the CSV line) without one
  std::vector<std::vector<double>> inputs;  // per patient, in the system's input order
  std::vector<double> measured;             // per patient
  std::string measured_column;
  std::vector<std::string> unused_columns;  // header cells nothing asked for
  std::size_t skipped_rows = 0;             // rows whose measured cell is empty (each a warning)
};

// Errors: a missing input or measured column, a column named twice, a cell that is not a finite number, a row with
// another number of fields than the header, fewer than 2 patients. Inputs outside their range are warnings
// (`input-out-of-range`), evaluated as given; an empty measured cell skips its row with `missing-measurement`.
// nullopt after errors.
std::optional<MeasuredData> read_measured_data(const CsvTable& table, const FuzzySystem& system, std::size_t output,
                                               const std::map<std::string, std::string>& input_columns,
                                               const std::string& measured_column, DiagnosticList& diagnostics);

// `--column INPUT=COLUMN` arguments -> a map; errors name the argument.
bool parse_input_columns(const std::vector<std::string>& arguments, const FuzzySystem& system,
                         std::map<std::string, std::string>& columns, DiagnosticList& diagnostics);

}  // namespace fmpc::cli

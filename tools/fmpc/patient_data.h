#pragma once
// Patients for `fmpc validate` and `fmpc diff` (and the studio's validation and comparison panels): a CSV with a
// header row, one column per input of the rule systems (matched by name; `--column INPUT=COLUMN` maps another
// name), an optional label column (`label`, `patient` or `id`) and, for validation, a column of measured values of
// one output. A header cell may state its unit, `HCV (kPa)` or `stiffness [Pa]`: values are then converted into the
// variable's unit (compiler/ir/units.h), and a unit that does not convert is an error naming both. Columns nothing
// asks for are listed, not refused (a measured-data file often carries age, sex, ...). Every message points at its
// cell (tools/fmpc/csv_table.h).
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"
#include "tools/fmpc/csv_table.h"

namespace fmpc::cli {

struct PatientDataRequest {
  std::vector<const FuzzySystem*> systems;  // every input of each is read (one column serves every system)
  std::map<std::string, std::string> input_columns;  // input name -> column name, where they differ
  // Validation: the output of systems[0] whose measured values are read; its column is `measured_column` when given,
  // else the first of OUTPUT, measured, measured_OUTPUT, OUTPUT_measured that the header has.
  std::optional<std::size_t> measured_output;
  std::string measured_column;
};

struct PatientData {
  std::vector<std::string> labels;  // the label column's text, or "row N" (the CSV line) without one
  std::vector<int> lines;           // each patient's CSV line
  // Per system, per patient: the input vector in the system's input order, in the system's units.
  std::vector<std::vector<std::vector<double>>> points;
  // Per system, per patient, per input: the cell each value came from (for located evaluation warnings).
  std::vector<std::vector<std::vector<SourceRange>>> origins;
  std::vector<SourceRange> rows;  // each patient's whole row
  std::vector<double> measured;   // per patient, in the output's unit (validation only)
  std::string measured_column;    // the header cell it came from
  // What a reader should know: unit conversions, columns not used, rows skipped for an empty measured cell.
  std::vector<std::string> notes;
  std::size_t skipped_rows = 0;
};

// Reads the table (parsed by parse_csv) for the request. Errors (located): a missing input or measured column, a
// column named twice, a unit that does not convert, a cell that is not a finite number, a row with another number
// of fields than the header, no patient left. A row whose measured cell is empty is skipped with a warning.
// nullopt after errors.
std::optional<PatientData> read_patient_data(const CsvTable& table, const PatientDataRequest& request,
                                             DiagnosticList& diagnostics);

// The output called `name` (the first when `name` is empty); an error naming the outputs otherwise
// (`--output-variable`).
std::optional<std::size_t> output_named(const FuzzySystem& system, const std::string& name,
                                        DiagnosticList& diagnostics);

// The file `-o/--output` names ("" when not given). It names a file in every command; `fmpc tune`, `validate` and
// `plot` once took `--output NAME` for an output variable beside another option for the file, so the option collects
// every value: one that is the name of an output of `system` is refused with an error naming --output-variable (the
// old spelling never writes a file called `stiffness`), and two files are an error.
std::string output_file_argument(const std::vector<std::string>& values, const FuzzySystem& system,
                                 DiagnosticList& diagnostics);

// `--column INPUT=COLUMN` arguments -> the request's map; errors name the argument.
bool parse_column_mappings(const std::vector<std::string>& arguments, std::map<std::string, std::string>& mappings,
                           DiagnosticList& diagnostics);

}  // namespace fmpc::cli

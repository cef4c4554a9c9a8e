#pragma once
// Points to evaluate, from NAME=VALUE arguments or a CSV table with a column per input, each value keeping where it
// came from so that messages point at it (fmpc eval; fmpc thesis-benchmark reads its patients the same way).
#include <optional>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"
#include "tools/fmpc/csv_table.h"

namespace fmpc::cli {

// One point to evaluate, with where each value came from (for located messages).
struct EvaluationPoint {
  std::vector<double> inputs;
  std::vector<SourceRange> origins;  // per input
  SourceRange where;                 // the CSV row, or "command line"
  std::string label;                 // "point 3 (patients.csv:4)", "P03 (patients.csv:4)", "point 1 (command line)"
  std::string name;                  // the row's text in the label column; empty without one
};

// The names a CSV column of row labels may have (`label`, as `fmpc simulate --patients` requires, or `patient`).
bool is_label_column(const std::string& header);

// The names of the variables, in order.
std::vector<std::string> variable_names(const std::vector<Variable>& variables);

// The header a CSV of points for `system` has: its inputs, comma-separated ("service,food").
std::string csv_header_of(const FuzzySystem& system);

// The whole text as a number (strtod), or nullopt.
std::optional<double> parse_number(const std::string& text);

// A number for `input`, or an error: text that is not a number, or NaN (fmpc never turns NaN into a silent
// output).
std::optional<double> parse_input_value(const std::string& text, const Variable& input, const SourceRange& where,
                                        DiagnosticList& diagnostics);

// NAME=VALUE arguments -> one point. Every input must be given exactly once.
std::optional<EvaluationPoint> point_from_assignments(const std::vector<std::string>& assignments,
                                                      const FuzzySystem& system, DiagnosticList& diagnostics);

// A CSV table with a header row -> points. Columns naming outputs are ignored (so a golden file with inputs and
// outputs can be fed back in); one column named `label` or `patient` (unless the system has an input of that name)
// names the rows: its header goes to `label_column` (left empty without one) and each row's text to the point's
// `name`. Any other unknown column is an error.
std::vector<EvaluationPoint> points_from_csv(const CsvTable& table, const FuzzySystem& system,
                                             DiagnosticList& diagnostics, std::string* label_column = nullptr);

}  // namespace fmpc::cli

#pragma once
// What an evaluation flagged (compiler/eval/interpreter.h EvaluationFlags), and what a lookup table does with inputs
// beyond its axes, as located diagnostics. `fmpc eval` and the Python module (python/) both report through here, so
// a point gets the same messages wherever it was evaluated.
#include <string>
#include <vector>

#include "compiler/backend/table/lookup_table.h"
#include "compiler/eval/interpreter.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

// "7.5 kPa"; no unit for "" and "dimensionless".
std::string value_with_unit(double value, const std::string& unit);

// NaN inputs and the no-fire policy `error` are errors; inputs outside their range and the other no-fire policies
// are warnings. `origins` (one per input) locates each input's value, `where` the point as a whole.
void report_evaluation_flags(const FuzzySystem& system, const std::vector<double>& inputs,
                             const std::vector<SourceRange>& origins, const SourceRange& where,
                             const Evaluation& evaluation, DiagnosticList& diagnostics);

// The inputs of one point of `table` (laid out as table_interface(table).inputs): NaN is an error (a table would
// return a number for it), a value beyond an axis a warning (the table clamps; it never extrapolates).
void report_table_inputs(const FuzzySystem& table_interface, const std::vector<double>& inputs,
                         const std::vector<SourceRange>& origins, DiagnosticList& diagnostics);

}  // namespace fmpc

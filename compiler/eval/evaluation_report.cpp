#include "compiler/eval/evaluation_report.h"

#include <cmath>

#include "diagnostics/number_format.h"

namespace fmpc {

std::string value_with_unit(double value, const std::string& unit) {
  return format_number(value) + (unit.empty() || unit == "dimensionless" ? "" : " " + unit);
}

void report_evaluation_flags(const FuzzySystem& system, const std::vector<double>& inputs,
                             const std::vector<SourceRange>& origins, const SourceRange& where,
                             const Evaluation& evaluation, DiagnosticList& diagnostics) {
  const EvaluationFlags& flags = evaluation.flags;
  for (int i : flags.inputs_nan) {
    const Variable& v = system.inputs[static_cast<std::size_t>(i)];
    diagnostics.error(origins[static_cast<std::size_t>(i)], "input '" + v.name + "' is NaN",
                      {"give a number within [" + format_number(v.min) + ", " + format_number(v.max) + "]"});
  }
  for (int i : flags.inputs_out_of_range) {
    const Variable& v = system.inputs[static_cast<std::size_t>(i)];
    diagnostics.warning(origins[static_cast<std::size_t>(i)], "input-out-of-range",
                        "input '" + v.name + "' = " + format_number(inputs[static_cast<std::size_t>(i)]) +
                            " is outside its range [" + format_number(v.min) + ", " + format_number(v.max) +
                            "]; evaluated as given");
  }
  for (int o : flags.outputs_no_rule_fired) {
    const Variable& v = system.outputs[static_cast<std::size_t>(o)];
    if (flags.no_fire_error)
      diagnostics.error(where, "no rule fired for output '" + v.name + "' (policy: error)",
                        {"add rules covering this point or choose another 'when no rule fires' policy"});
    else
      diagnostics.warning(where, "no-rule-fired",
                          "no rule fired for output '" + v.name + "'; output set to " +
                              value_with_unit(evaluation.outputs[static_cast<std::size_t>(o)], v.unit) +
                              (system.no_fire == NoFirePolicy::Midrange ? " (mid-range)" : " (policy value)"));
  }
}

void report_table_inputs(const FuzzySystem& table_interface, const std::vector<double>& inputs,
                         const std::vector<SourceRange>& origins, DiagnosticList& diagnostics) {
  for (std::size_t i = 0; i < table_interface.inputs.size(); ++i) {
    const Variable& v = table_interface.inputs[i];
    if (std::isnan(inputs[i])) {
      diagnostics.error(origins[i], "input '" + v.name + "' is NaN",
                        {"give a number within the table's axis [" + format_number(v.min) + ", " +
                         format_number(v.max) + "]"});
      continue;
    }
    if (inputs[i] >= v.min && inputs[i] <= v.max) continue;
    diagnostics.warning(origins[i], "input-out-of-range",
                        "input '" + v.name + "' = " + format_number(inputs[i]) + " is outside the table's axis [" +
                            format_number(v.min) + ", " + format_number(v.max) + "]; the table holds the value at " +
                            format_number(inputs[i] < v.min ? v.min : v.max));
  }
}

}  // namespace fmpc

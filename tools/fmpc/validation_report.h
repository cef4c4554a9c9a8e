#pragma once
// `fmpc validate` and the studio's validation panel: a rule system's predictions for patients with measured
// values (tools/fmpc/patient_data.h), how well they agree (compiler/eval/agreement.h), the patients predicted worst
// with the rule that fired most strongly for each, as markdown, CSV and two pictures (predicted against measured;
// Bland-Altman).
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "compiler/eval/agreement.h"
#include "compiler/eval/interpreter.h"
#include "compiler/ir/fuzzy_system.h"
#include "tools/fmpc/patient_data.h"
#include "tools/plot/canvas.h"

namespace fmpc::cli {

struct ValidationPatient {
  std::string label;
  int line = 0;  // in the CSV
  std::vector<double> inputs;
  double measured = 0.0;
  double predicted = 0.0;
  double difference = 0.0;  // predicted - measured
  bool no_rule_fired = false;
  int strongest_rule = -1;  // the rule that fired most strongly (the first of equals); -1 when none fired
  std::string strongest_rule_name;  // "r7" or "rule 7"; "none" when none fired
  double strongest_firing = 0.0;
};

struct ValidationReport {
  std::string rules_path;
  std::string data_path;
  std::string system_name;
  std::size_t output = 0;
  std::string output_name;
  std::string output_unit;
  std::string measured_column;
  std::vector<ValidationPatient> patients;
  Agreement agreement;
  std::vector<std::size_t> worst;  // patients by |difference|, largest first, at most kWorstPatients
  std::vector<std::string> notes;  // from reading the data
};

inline constexpr std::size_t kWorstPatients = 10;

// Evaluates every patient (the interpreter, as `fmpc eval`) and measures the agreement. Evaluation warnings (inputs
// out of range, no rule fired) and errors (no rule fired under the policy `error`) are appended, located at the
// patients' cells; nullopt after errors.
std::optional<ValidationReport> validate_rules(const FuzzySystem& system, std::size_t output, const PatientData& data,
                                               const EvaluationOptions& options, DiagnosticList& diagnostics);

std::string validation_markdown(const ValidationReport& report);
// label, line, the inputs, measured, predicted, difference, no_rule_fired, strongest_rule, strongest_firing; numbers
// in their shortest exact form.
std::string validation_csv(const ValidationReport& report, const FuzzySystem& system);
std::string predicted_against_measured_plot(const ValidationReport& report, plot::ImageFormat format);
std::string bland_altman_plot(const ValidationReport& report, plot::ImageFormat format);

}  // namespace fmpc::cli

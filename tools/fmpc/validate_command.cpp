// fmpc validate FILE --data MEASURED.csv: how well a rule system predicts measured values (MATLAB's System
// Validation): MAE, RMSE, bias and Bland-Altman limits, the patients predicted worst with their strongest rule, as
// markdown (stdout and --markdown), a per-patient table (--table) and two pictures (--plots DIR).
#include <CLI/CLI.hpp>

#include <iostream>

#include "runtime/io/input_file.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/csv_table.h"
#include "tools/fmpc/report_output.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/validation_report.h"

namespace fmpc::cli {

namespace {

struct ValidateOptions {
  std::string file;
  std::string data;
  std::string output_variable;
  std::string measured;
  ReportOptions report;
};

int run_validate(const ValidateOptions& options) {
  LoadedRuleFile file = load_rule_file_from_disk(options.file);
  DiagnosticList& diagnostics = file.diagnostics;
  const FuzzySystem* system =
      diagnostics.has_errors() ? nullptr : select_system(file, options.report.system, diagnostics);
  std::optional<std::size_t> output;
  std::string markdown;
  if (system) {
    output = output_named(*system, options.output_variable, diagnostics);
    markdown = output_file_argument(options.report.markdown, *system, diagnostics);
  }
  PatientDataRequest request;
  parse_column_mappings(options.report.columns, request.input_columns, diagnostics);
  std::optional<CsvTable> table;
  if (!diagnostics.has_errors())
    table = read_csv_file(options.data, options.data, sim::kMaxCsvFileBytes, "data file",
                          SourceRange{"argument --data", 0, 0, 0, 0}, file.sources, diagnostics);
  std::optional<PatientData> data;
  if (table && !diagnostics.has_errors()) {
    request.systems = {system};
    request.measured_output = output;
    request.measured_column = options.measured;
    data = read_patient_data(*table, request, diagnostics);
  }
  std::optional<ValidationReport> report;
  if (data) report = validate_rules(*system, *output, *data, options.report.evaluation(), diagnostics);
  print_diagnostics(diagnostics, file.sources, std::cerr);
  if (!report || diagnostics.has_errors()) return kExitErrors;
  report->rules_path = options.file;
  report->data_path = options.data;
  return write_report(
      options.report, markdown, "validate", validation_markdown(*report), [&] { return validation_csv(*report, *system); },
      [&] {
        return std::vector<std::pair<std::string, std::string>>{
            {"predicted_against_measured.png", predicted_against_measured_plot(*report, plot::ImageFormat::Png)},
            {"bland_altman.png", bland_altman_plot(*report, plot::ImageFormat::Png)}};
      });
}

}  // namespace

void register_validate_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<ValidateOptions>();
  CLI::App* command = app.add_subcommand(
      "validate",
      "Hold a rule file against measured data (MATLAB's System Validation): MAE, RMSE, bias, Bland-Altman limits\n"
      "and the patients predicted worst. The CSV has a column per input (named after it, or mapped with --column),\n"
      "a column of measured values of one output, and optionally 'label'; a header may state a unit, 'HCV (kPa)'.\n"
      "Prints markdown; --markdown, --table and --plots write files (docs/cli.md).");
  command->add_option("file", options->file, "Rule file")->required();
  command->add_option("--data", options->data, "CSV of patients with measured values")->required();
  command->add_option("--output-variable", options->output_variable,
                      "The output the measurements are of (default: the first)");
  command->add_option("--measured", options->measured,
                      "The measured column (default: the first of OUTPUT, measured, measured_OUTPUT, OUTPUT_measured)");
  add_report_options(*command, options->report,
                     "Write every patient (inputs, measured, predicted, difference) as CSV",
                     "Write predicted_against_measured.png and bland_altman.png into this folder");
  command->callback([options, &exit_code] { exit_code = run_validate(*options); });
}

}  // namespace fmpc::cli

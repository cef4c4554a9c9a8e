// fmpc diff A B --csv PATIENTS.csv: what differs between two versions of a rule system (settings, variables,
// terms, rules) and what that does to every patient's outputs and stages, as markdown (stdout and --markdown), a
// per-patient table (--table) and a histogram of the changes per output (--plots DIR).
#include <CLI/CLI.hpp>

#include <cctype>
#include <iostream>

#include "runtime/io/input_file.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/csv_table.h"
#include "tools/fmpc/report_output.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/version_diff_report.h"

namespace fmpc::cli {

namespace {

struct DiffOptions {
  std::string first;
  std::string second;
  std::string patients;
  ReportOptions report;
};

// A file name for an output's histogram: its name where that is a safe file name, else its position.
std::string histogram_file(const std::string& output, std::size_t index) {
  bool safe = !output.empty() && output.size() <= 64 && output[0] != '.';
  for (char c : output) safe = safe && (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.');
  return "differences_" + (safe ? output : std::to_string(index + 1)) + ".png";
}

int run_diff(const DiffOptions& options) {
  LoadedRuleFile first = load_rule_file_from_disk(options.first);
  LoadedRuleFile second = load_rule_file_from_disk(options.second);
  const FuzzySystem* a =
      first.diagnostics.has_errors() ? nullptr : select_system(first, options.report.system, first.diagnostics);
  const FuzzySystem* b =
      second.diagnostics.has_errors() ? nullptr : select_system(second, options.report.system, second.diagnostics);
  // Each file's diagnostics quote its own lines; the patient file's text joins the first file's sources.
  print_diagnostics(first.diagnostics, first.sources, std::cerr);
  if (options.second != options.first) print_diagnostics(second.diagnostics, second.sources, std::cerr);
  if (!a || !b) return kExitErrors;
  DiagnosticList diagnostics;
  const std::string markdown = output_file_argument(options.report.markdown, *a, diagnostics);
  SourceFiles& sources = first.sources;
  PatientDataRequest request;
  parse_column_mappings(options.report.columns, request.input_columns, diagnostics);
  std::optional<CsvTable> table;
  if (!diagnostics.has_errors())
    table = read_csv_file(options.patients, options.patients, sim::kMaxCsvFileBytes, "patient file",
                          SourceRange{"argument --csv", 0, 0, 0, 0}, sources, diagnostics);
  std::optional<PatientData> data;
  if (table && !diagnostics.has_errors()) {
    request.systems = {a, b};
    data = read_patient_data(*table, request, diagnostics);
  }
  std::optional<VersionDiffReport> report;
  if (data) report = compare_versions(*a, *b, *data, options.report.evaluation(), diagnostics);
  print_diagnostics(diagnostics, sources, std::cerr);
  if (!report || diagnostics.has_errors()) return kExitErrors;
  report->path_a = options.first;
  report->path_b = options.second;
  report->data_path = options.patients;
  return write_report(
      options.report, markdown, "diff", version_diff_markdown(*report, *a, *b), [&] { return version_diff_csv(*report, *a, *b); },
      [&] {
        std::vector<std::pair<std::string, std::string>> plots;
        for (std::size_t o = 0; o < report->outputs.size(); ++o)
          plots.emplace_back(histogram_file(report->outputs[o].name, o),
                             difference_histogram_plot(*report, o, plot::ImageFormat::Png));
        return plots;
      });
}

}  // namespace

void register_diff_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<DiffOptions>();
  CLI::App* command = app.add_subcommand(
      "diff",
      "Compare two versions of a rule file over a cohort: the settings, variables, terms and rules that differ, and\n"
      "each output's change per patient (second - first), with the patients whose stage (the output term that\n"
      "describes the output best) changes. Prints markdown; --markdown, --table and --plots write files.");
  command->add_option("first", options->first, "The first version (the reference)")->required();
  command->add_option("second", options->second, "The second version")->required();
  command->add_option("--csv", options->patients, "CSV of patients: a column per input, optionally 'label'")
      ->required();
  add_report_options(*command, options->report, "Write every patient's outputs, changes and stages as CSV",
                     "Write differences_OUTPUT.png (a histogram) into this folder");
  command->callback([options, &exit_code] { exit_code = run_diff(*options); });
}

}  // namespace fmpc::cli

// fmpc tune: fits the named membership-function parameters of a rule file to measured data (compiler/eval/tuning.h,
// docs/cli.md), writes the tuned file beside it and prints what changed.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "compiler/eval/evaluation_report.h"
#include "compiler/eval/interpreter.h"
#include "compiler/eval/output_comparison.h"
#include "compiler/eval/tuning.h"
#include "compiler/frontend/fll.h"
#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/matlab_fis.h"
#include "compiler/sema/check.h"
#include "diagnostics/number_format.h"
#include "runtime/io/input_file.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/csv_table.h"
#include "tools/fmpc/evaluation_points.h"
#include "tools/fmpc/patient_data.h"
#include "tools/fmpc/report_text.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"

namespace fmpc::cli {

namespace {

struct TuneOptions {
  std::string file;
  std::string data;
  std::vector<std::string> parameters;
  std::string output_variable;
  std::string measured;
  std::vector<std::string> columns;
  int folds = 5;
  std::uint64_t seed = 1;
  int max_evaluations = 0;
  int digits = 4;
  std::vector<std::string> output;  // -o/--output: the tuned file (output_file_argument)
  std::string former_tuned;  // --tuned, the old spelling of -o/--output
  bool in_place = false;
  std::string system;
};

// `value` to `digits` significant digits, as the shortest text that reads back as it.
double tune_rounded(double value, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*g", digits, value);
  return std::strtod(text, nullptr);
}

// `dir/stem.tuned.ext` beside the input.
std::string tune_default_path(const std::string& file) {
  const std::filesystem::path path(file);
  return (path.parent_path() / (path.stem().string() + ".tuned" + path.extension().string())).string();
}

bool tune_same_file(const std::string& a, const std::string& b) {
  std::error_code error;
  if (std::filesystem::exists(b, error) && std::filesystem::equivalent(a, b, error)) return true;
  return std::filesystem::weakly_canonical(a, error) == std::filesystem::weakly_canonical(b, error);
}

// The changed lines of two texts with the same lines, in unified-diff form (hunks of one line each, merged when
// adjacent); `old_name` and `new_name` head it.
std::string tune_line_diff(const std::string& before, const std::string& after, const std::string& old_name,
                           const std::string& new_name) {
  const auto lines = [](const std::string& text) {
    std::vector<std::string> result;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) result.push_back(line);
    return result;
  };
  const std::vector<std::string> a = lines(before), b = lines(after);
  std::string diff = "--- " + old_name + "\n+++ " + new_name + "\n";
  for (std::size_t i = 0; i < a.size() && i < b.size();) {
    if (a[i] == b[i]) {
      ++i;
      continue;
    }
    std::size_t end = i;
    while (end < a.size() && end < b.size() && a[end] != b[end]) ++end;
    diff += "@@ -" + std::to_string(i + 1) + "," + std::to_string(end - i) + " +" + std::to_string(i + 1) + "," +
            std::to_string(end - i) + " @@\n";
    for (std::size_t k = i; k < end; ++k) diff += "-" + a[k] + "\n";
    for (std::size_t k = i; k < end; ++k) diff += "+" + b[k] + "\n";
    i = end;
  }
  return diff;
}

int run_tune(const TuneOptions& options) {
  LoadedRuleFile file = load_rule_file_from_disk(options.file);
  if (file.diagnostics.has_errors()) {
    print_diagnostics(file.diagnostics, file.sources, std::cerr);
    return kExitErrors;
  }
  DiagnosticList diagnostics;
  SourceFiles& sources = file.sources;
  std::string read_error;
  const std::string original =
      read_text_file(options.file, sim::kMaxRuleFileBytes, "rule file", read_error).value_or("");
  const FuzzySystem* system = select_system(file, options.system, diagnostics);
  std::optional<std::size_t> output;
  std::string output_path;
  if (system) {
    output = output_named(*system, options.output_variable, diagnostics);
    output_path = output_file_argument(options.output, *system, diagnostics);
  }
  if (!options.former_tuned.empty())
    diagnostics.error(SourceRange{"argument --tuned", 0, 0, 0, 0},
                      "--tuned is now -o/--output: -o " + options.former_tuned,
                      {"-o/--output names the file a command writes in every fmpc command"});
  if (options.folds == 1 || options.folds < 0)
    diagnostics.error(SourceRange{"argument --folds", 0, 0, 0, 0},
                      "--folds is " + std::to_string(options.folds) + "; give 2 or more, or 0 to skip cross-validation");
  if (options.digits < 1 || options.digits > 17)
    diagnostics.error(SourceRange{"argument --digits", 0, 0, 0, 0}, "--digits takes 1 to 17 significant digits");
  if (options.in_place && !output_path.empty())
    diagnostics.error(kCommandLine, "give -o/--output FILE or --in-place, not both");
  const std::string tuned_path = options.in_place ? options.file
                                 : output_path.empty() ? tune_default_path(options.file) : output_path;
  if (!options.in_place && tune_same_file(options.file, tuned_path))
    diagnostics.error(SourceRange{"argument --output", 0, 0, 0, 0},
                      "'" + tuned_path + "' is the input file; fmpc tune writes a new file",
                      {"give another -o/--output FILE, or --in-place to overwrite the input"});
  std::vector<TunableParameter> parameters;
  std::optional<PatientData> data;
  // Every mistake at once: the parameters and the data are read whatever the options' errors were. The data are
  // read as `fmpc validate` reads them (patient_data.h), so one file serves both, units in its header included.
  if (system && output) {
    parameters = select_parameters(*system, options.parameters, SourceRange{"argument --parameters", 0, 0, 0, 0},
                                   diagnostics);
    PatientDataRequest request;
    request.systems = {system};
    request.measured_output = output;
    request.measured_column = options.measured;
    parse_column_mappings(options.columns, request.input_columns, diagnostics);
    const std::string header = csv_header_of(*system) + "," + system->outputs[*output].name;
    if (const std::optional<CsvTable> table =
            read_csv_file(options.data, options.data, sim::kMaxCsvFileBytes, "measured data",
                          SourceRange{"argument --data", 0, 0, 0, 0}, sources, diagnostics, header))
      data = read_patient_data(*table, request, diagnostics);
  }
  TuningData tuning;
  if (data && !diagnostics.has_errors()) {
    tuning.inputs = data->points.front();
    tuning.measured = data->measured;
    tuning.output = *output;
    if (data->measured.size() < 2)
      diagnostics.error(SourceRange{options.data, 0, 0, 0, 0},
                        "the data has " + std::to_string(data->measured.size()) +
                            " patient with a measured value; tuning needs at least 2");
    else if (options.folds > 0 && data->measured.size() < static_cast<std::size_t>(options.folds))
      diagnostics.error(SourceRange{"argument --folds", 0, 0, 0, 0},
                        std::to_string(options.folds) + " folds need at least " + std::to_string(options.folds) +
                            " patients; the data has " + std::to_string(data->measured.size()),
                        {"give fewer --folds, or 0 to skip cross-validation"});
    // Each patient as `fmpc validate` reports it (inputs out of range, no rule fired), the first 20 warnings shown;
    // and the file's own system must predict every patient: a search cannot start from no value.
    Interpreter interpreter(*system);
    DiagnosticList flags;
    bool no_value_reported = false;
    for (std::size_t p = 0; p < tuning.inputs.size(); ++p) {
      const Evaluation evaluation = interpreter.evaluate(tuning.inputs[p]);
      const std::size_t flagged = flags.error_count();
      report_evaluation_flags(*system, tuning.inputs[p], data->origins.front()[p], data->rows[p], evaluation, flags);
      // The policy `error` has said so already; one message is enough for the other ways to no value.
      if (!std::isfinite(evaluation.outputs[*output]) && flags.error_count() == flagged && !no_value_reported) {
        no_value_reported = true;
        diagnostics.error(data->rows[p],
                          "the rule file predicts no value for " + data->labels[p] + " (no rule fires there)",
                          {"give the system a `when no rule fires:` value, or leave the patient out"});
      }
    }
    append_capped(flags, 20, options.data, diagnostics);
  }
  if (!system || !output || !data || diagnostics.has_errors()) {
    print_diagnostics(diagnostics, sources, std::cerr);
    return kExitErrors;
  }

  TuningOptions tuning_options;
  tuning_options.folds = options.folds;
  tuning_options.seed = options.seed;
  tuning_options.search.max_evaluations = options.max_evaluations;
  const TuningResult result = tune_system(*system, parameters, tuning, tuning_options);

  // Written with `digits` significant digits, unless rounding would leave the bounds or the terms' order.
  std::vector<double> written = result.values;
  for (std::size_t i = 0; i < written.size(); ++i)
    written[i] = std::clamp(tune_rounded(written[i], options.digits), parameters[i].lower, parameters[i].upper);
  FuzzySystem tuned = with_parameters(*system, parameters, written);
  std::vector<std::size_t> everyone(tuning.measured.size());
  for (std::size_t i = 0; i < everyone.size(); ++i) everyone[i] = i;
  {
    // Rounding that breaks a check or loses more than 0.1% of the fit is not taken: the values go out in full.
    DiagnosticList problems;
    check_system(tuned, problems);
    const double rounded_rmse = problems.has_errors() ? HUGE_VAL : prediction_rmse(tuned, tuning, everyone);
    if (!(rounded_rmse <= result.rmse_after * (1 + 1e-3) + 1e-12)) {
      written = result.values;
      tuned = with_parameters(*system, parameters, written);
    }
  }
  const double written_rmse = prediction_rmse(tuned, tuning, everyone);

  // The new text: numbers rewritten in place for the fmpc language (comments and layout kept), the dialect's
  // writer otherwise.
  std::string text;
  if (file.dialect == Dialect::Fmpc) {
    std::vector<ParameterEdit> edits;
    for (std::size_t i = 0; i < parameters.size(); ++i) {
      const TunableParameter& parameter = parameters[i];
      const Variable& variable = parameter.output ? system->outputs[parameter.variable] : system->inputs[parameter.variable];
      const std::string name = parameter.name.substr(parameter.name.rfind('.') + 1);
      edits.push_back(ParameterEdit{system->name, variable.name, variable.terms[parameter.term].name, name, written[i]});
    }
    const std::optional<std::string> edited = edit_fmpc_parameters(file.path, original, edits, diagnostics);
    if (!edited) {
      print_diagnostics(diagnostics, sources, std::cerr);
      return kExitErrors;
    }
    text = *edited;
  } else if (file.dialect == Dialect::Matlab) {
    text = write_matlab_fis(tuned, diagnostics);
  } else if (file.dialect == Dialect::Fll) {
    text = write_fll(tuned, diagnostics);
  } else {
    text = write_fcl(tuned, diagnostics);
  }
  // Read back as fmpc will read it: the written file must compute what the tuned system computes.
  {
    DiagnosticList back_diagnostics;
    const RuleFile back = load_rule_file(tuned_path, text, back_diagnostics);
    const FuzzySystem* back_system = nullptr;
    for (const FuzzySystem& candidate : back.systems)
      if (candidate.name == tuned.name) back_system = &candidate;
    std::vector<std::string> changes;
    if (back_diagnostics.has_errors() || !back_system) changes.push_back("the written text does not read back");
    else changes = output_changes(tuned, *back_system);
    if (!changes.empty()) {
      std::cerr << "fmpc: internal error: the tuned file would not compute the tuned system: " << changes.front()
                << "\nplease report this with the input that caused it\n";
      return 70;
    }
  }

  const Variable& fitted = system->outputs[*output];
  const std::string unit = fitted.unit.empty() || fitted.unit == "dimensionless" ? "" : " " + fitted.unit;
  std::ostringstream out;
  out << "# fmpc tune " << options.file << "\n\n";
  out << "Fitted: output `" << fitted.name << "` against column `" << data->measured_column << "` of "
      << options.data << ", " << tuning.measured.size() << " patients";
  out << ".\n";
  if (!data->notes.empty()) out << "\n";
  for (const std::string& note : data->notes) out << "- " << note << "\n";
  out << "\nMethod: bounded Nelder-Mead simplex search (Nelder and Mead 1965; coefficients 1, 2, 1/2, 1/2 as "
         "MATLAB's fminsearch) minimising the RMSE, from the file's values, at most "
      << (options.max_evaluations > 0 ? options.max_evaluations : 200 * static_cast<int>(parameters.size()))
      << " evaluations a search. Rules, weights and settings are not changed.\n";
  if (!result.folds.empty()) {
    out << "\n## Held-out error (" << result.folds.size() << "-fold cross-validation, folds from seed " << options.seed
        << ")\n\n| fold | patients | RMSE before | RMSE after | evaluations |\n|---:|---:|---:|---:|---:|\n";
    for (std::size_t f = 0; f < result.folds.size(); ++f) {
      const FoldResult& fold = result.folds[f];
      out << "| " << f + 1 << " | " << fold.patients << " | " << four_digits(fold.rmse_before) << unit << " | "
          << four_digits(fold.rmse_after) << unit << " | " << fold.evaluations << (fold.converged ? "" : " (cap)")
          << " |\n";
    }
    out << "| all | " << tuning.measured.size() << " | " << four_digits(result.held_out_rmse_before) << unit << " | "
        << four_digits(result.held_out_rmse_after) << unit << " | |\n";
  }
  out << "\n## Parameters (fitted on all " << tuning.measured.size() << " patients: RMSE "
      << four_digits(result.rmse_before) << unit << " before, " << four_digits(written_rmse) << unit
      << " as written)\n\n| parameter | before | after | bounds |\n|---|---:|---:|---|\n";
  for (std::size_t i = 0; i < parameters.size(); ++i)
    out << "| " << parameters[i].name << " | " << format_number(parameters[i].value) << " | "
        << format_number(written[i])
        << (written[i] != parameters[i].value &&
                    (written[i] == parameters[i].lower || written[i] == parameters[i].upper)
                ? " (at its bound)"
                : "")
        << " | [" << format_number(parameters[i].lower) << ", "
        << format_number(parameters[i].upper) << "]: " << parameters[i].bound << " |\n";
  if (!result.search.converged)
    out << "\nThe search stopped at its cap of " << result.search.evaluations
        << " evaluations, the simplex's RMSE values still " << four_digits(result.search.value_spread)
        << unit << " apart: raise --max-evaluations for a closer fit.\n";
  else
    out << "\nThe search converged after " << result.search.evaluations << " evaluations.\n";
  out << "\n## Changes\n\n";
  // The writers of the other formats lay a file out their own way: a line diff means something only where the
  // input was laid out the same (a file fmpc wrote, for one).
  const auto line_count = [](const std::string& t) { return std::count(t.begin(), t.end(), '\n'); };
  if (file.dialect == Dialect::Fmpc || line_count(original) == line_count(text))
    out << "```diff\n" << tune_line_diff(original, text, options.file, tuned_path) << "```\n";
  else
    out << "(written by fmpc's " << dialect_name(file.dialect)
        << " writer in its own layout; the table above lists every change)\n";

  std::string error;
  if (!write_text_file_atomically(tuned_path, text, error)) {
    diagnostics.error(SourceRange{tuned_path, 0, 0, 0, 0}, error);
    print_diagnostics(diagnostics, sources, std::cerr);
    return kExitErrors;
  }
  out << "\nWrote " << tuned_path << ".\n";
  print_diagnostics(diagnostics, sources, std::cerr);
  std::cout << out.str();
  return kExitOk;
}

}  // namespace

void register_tune_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<TuneOptions>();
  CLI::App* command = app.add_subcommand(
      "tune", "Fit the named membership-function parameters to measured data (MATLAB's tunefis): bounded "
              "Nelder-Mead, k-fold held-out error before and after; writes a new file and prints the diff");
  command->add_option("file", options->file, "Rule file")->required();
  command->add_option("--data", options->data, "CSV of patients: a column per input and one of measured values")
      ->required();
  command->add_option("--parameters", options->parameters,
                      "VARIABLE.TERM.PARAMETER patterns (* and ? allowed): HCV.F2.mean, HCV.*.sd, stiffness.*")
      ->required()
      ->expected(1, -1);
  command->add_option("--output-variable", options->output_variable,
                      "The output fitted to the measured values (default: the first)");
  command->add_option("--measured", options->measured,
                      "The column of measured values (default OUTPUT, measured, measured_OUTPUT or OUTPUT_measured)");
  command->add_option("--column", options->columns, "INPUT=COLUMN: read an input from a column of another name");
  command->add_option("--folds", options->folds, "k of the k-fold cross-validation; 0 skips it");
  command->add_option("--seed", options->seed, "Seed of the folds' assignment");
  command->add_option("--max-evaluations", options->max_evaluations,
                      "Cap on objective evaluations per search; 0: 200 per parameter");
  command->add_option("--digits", options->digits, "Significant digits of the numbers written");
  command->add_option("-o,--output", options->output,
                      "Where to write the tuned file, atomically (default: FILE's stem + .tuned beside it)")
      ->allow_extra_args(false);
  command->add_option("--tuned", options->former_tuned)->group("");  // the old spelling: an error naming -o
  command->add_flag("--in-place", options->in_place, "Overwrite the input file instead");
  command->add_option("--system", options->system, "The system to tune, in a file that holds several");
  command->callback([options, &exit_code] { exit_code = run_tune(*options); });
}

}  // namespace fmpc::cli

#include "tools/studio/studio_cohorts.h"

#include "diagnostics/number_format.h"
#include "tools/fmpc/csv_table.h"
#include "tools/fmpc/patient_data.h"
#include "tools/fmpc/report_text.h"
#include "tools/fmpc/validation_report.h"
#include "tools/fmpc/version_diff_report.h"

namespace fmpc::studio {

namespace {

Json rendered(const DiagnosticList& diagnostics, const SourceFiles& sources, Severity severity) {
  Json list = Json::array();
  for (const Diagnostic& d : diagnostics.items())
    if (d.severity == severity) list.push_back(render(d, sources));
  return list;
}

Json failure(const DiagnosticList& diagnostics, const SourceFiles& sources) {
  return Json{{"ok", false},
              {"errors", rendered(diagnostics, sources, Severity::Error)},
              {"warnings", rendered(diagnostics, sources, Severity::Warning)}};
}

// A number with its 4-digit text, as the CLI's report prints it.
Json number_json(double value, const std::string& unit) {
  return Json{{"value", value}, {"text", cli::four_digits_with_unit(value, unit)}};
}

Json agreement_json(const Agreement& a, const std::string& unit) {
  return Json{{"count", a.count},
              {"mae", number_json(a.mean_absolute_error, unit)},
              {"rmse", number_json(a.root_mean_square_error, unit)},
              {"bias", number_json(a.bias, unit)},
              {"sd", number_json(a.difference_sd, unit)},
              {"lower_limit", number_json(a.lower_limit, unit)},
              {"upper_limit", number_json(a.upper_limit, unit)},
              {"largest", number_json(a.largest_absolute_error, unit)},
              {"largest_index", a.largest_error_index},
              {"correlation", number_json(a.correlation, "")}};
}

// Reads the CSV for `systems` (and a measured output of the first); nullopt after errors, which land in
// `diagnostics` with the CSV's text in `sources`.
std::optional<cli::PatientData> read_table(const CohortTable& table, const std::vector<const FuzzySystem*>& systems,
                                           std::optional<std::size_t> measured_output,
                                           const std::string& measured_column, SourceFiles& sources,
                                           DiagnosticList& diagnostics) {
  sources.add(table.name, table.text);
  const cli::CsvTable csv = cli::parse_csv(table.name, table.text, diagnostics);
  if (diagnostics.has_errors()) return std::nullopt;
  cli::PatientDataRequest request;
  request.systems = systems;
  request.input_columns = table.input_columns;
  request.measured_output = measured_output;
  request.measured_column = measured_column;
  return cli::read_patient_data(csv, request, diagnostics);
}

}  // namespace

Json validation_json(const FuzzySystem& system, const std::string& output, const std::string& measured_column,
                     const CohortTable& table) {
  SourceFiles sources;
  DiagnosticList diagnostics;
  const std::optional<std::size_t> index = cli::output_named(system, output, diagnostics);
  std::optional<cli::PatientData> data;
  if (index) data = read_table(table, {&system}, index, measured_column, sources, diagnostics);
  std::optional<cli::ValidationReport> report;
  if (data) report = cli::validate_rules(system, *index, *data, EvaluationOptions{}, diagnostics);
  if (!report) return failure(diagnostics, sources);
  const std::string& unit = report->output_unit;
  Json patients = Json::array();
  for (const cli::ValidationPatient& p : report->patients)
    patients.push_back(Json{{"label", p.label},
                            {"line", p.line},
                            {"inputs", p.inputs},
                            {"measured", p.measured},
                            {"predicted", p.predicted},
                            {"predicted_text", format_number(p.predicted)},
                            {"difference", p.difference},
                            {"mean", p.predicted / 2 + p.measured / 2},
                            {"no_rule_fired", p.no_rule_fired},
                            {"strongest_rule", p.strongest_rule},
                            {"strongest_rule_name", p.strongest_rule_name},
                            {"strongest_firing", p.strongest_firing}});
  return Json{{"ok", true},
              {"output", report->output_name},
              {"unit", unit},
              {"measured_column", report->measured_column},
              {"agreement", agreement_json(report->agreement, unit)},
              {"patients", patients},
              {"worst", report->worst},
              {"notes", report->notes},
              {"warnings", rendered(diagnostics, sources, Severity::Warning)}};
}

Json differences_json(const FuzzySystem& a, const FuzzySystem& b) {
  return Json(cli::describe_differences(a, b, system_differences(a, b)));
}

Json comparison_json(const FuzzySystem& a, const std::string& name_a, const FuzzySystem& b, const std::string& name_b,
                     const CohortTable& table) {
  SourceFiles sources;
  DiagnosticList diagnostics;
  const std::optional<cli::PatientData> data = read_table(table, {&a, &b}, std::nullopt, "", sources, diagnostics);
  std::optional<cli::VersionDiffReport> report;
  if (data) report = cli::compare_versions(a, b, *data, EvaluationOptions{}, diagnostics);
  if (!report) return failure(diagnostics, sources);
  Json outputs = Json::array();
  for (std::size_t o = 0; o < report->outputs.size(); ++o) {
    const OutputComparisonOverPoints& out = report->outputs[o];
    const std::string& unit = report->units[o];
    std::vector<std::string> stage_a, stage_b;
    for (std::size_t k = 0; k < out.a.size(); ++k) {
      stage_a.push_back(cli::stage_name(a, out.in_a, out.stage_a[k]));
      stage_b.push_back(cli::stage_name(b, out.in_b, out.stage_b[k]));
    }
    const Histogram& h = report->histograms[o];
    Json item{{"name", out.name},
              {"unit", unit},
              {"a", out.a},
              {"b", out.b},
              {"difference", out.difference},
              {"stage_a", stage_a},
              {"stage_b", stage_b},
              {"stage_changes", out.stage_changes},
              {"histogram", Json{{"lo", h.lo}, {"hi", h.hi}, {"counts", h.counts}}}};
    if (out.agreement.count > 0) item["agreement"] = agreement_json(out.agreement, unit);
    outputs.push_back(item);
  }
  return Json{{"ok", true},
              {"first", name_a},
              {"second", name_b},
              {"differences", report->differences},
              {"labels", report->labels},
              {"lines", report->lines},
              {"outputs", outputs},
              {"notes", report->notes},
              {"warnings", rendered(diagnostics, sources, Severity::Warning)}};
}

}  // namespace fmpc::studio

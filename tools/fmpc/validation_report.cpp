#include "tools/fmpc/validation_report.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "compiler/eval/evaluation_report.h"
#include "diagnostics/number_format.h"
#include "tools/fmpc/csv_table.h"
#include "tools/fmpc/report_text.h"
#include "tools/plot/line_chart.h"

namespace fmpc::cli {

namespace {

std::string axis_title(const std::string& what, const ValidationReport& report) {
  const bool unit = !report.output_unit.empty() && report.output_unit != "dimensionless";
  return what + (unit ? " (" + report.output_unit + ")" : "");
}

std::string rule_name(const FuzzySystem& system, int rule) {
  return rule < 0 ? std::string("none") : system.rule_display_name(static_cast<std::size_t>(rule));
}

// [lo, hi] widened by 5% on each side, so that no point sits on the frame.
void pad(double& lo, double& hi) {
  if (!(hi > lo)) hi = lo + 1;
  const double margin = (hi - lo) * 0.05;
  lo -= margin;
  hi += margin;
}

// A horizontal line across [lo, hi] as a series.
plot::Series level(const std::string& name, double lo, double hi, double y, plot::Colour colour,
                   std::vector<double> dashes) {
  plot::Series series;
  series.name = name;
  series.x = {lo, hi};
  series.y = {y, y};
  series.colour = colour;
  series.width = 1.5;
  series.dashes = std::move(dashes);
  return series;
}

}  // namespace

std::optional<ValidationReport> validate_rules(const FuzzySystem& system, std::size_t output, const PatientData& data,
                                               const EvaluationOptions& options, DiagnosticList& diagnostics) {
  ValidationReport report;
  report.system_name = system.name;
  report.output = output;
  report.output_name = system.outputs[output].name;
  report.output_unit = system.outputs[output].unit;
  report.measured_column = data.measured_column;
  report.notes = data.notes;
  Interpreter interpreter(system, options);
  DiagnosticList flags;
  for (std::size_t k = 0; k < data.labels.size(); ++k) {
    const std::vector<double>& inputs = data.points.front()[k];
    const Evaluation evaluation = interpreter.evaluate(inputs);
    report_evaluation_flags(system, inputs, data.origins.front()[k], data.rows[k], evaluation, flags);
    ValidationPatient patient;
    patient.label = data.labels[k];
    patient.line = data.lines[k];
    patient.inputs = inputs;
    patient.measured = data.measured[k];
    patient.predicted = evaluation.outputs[output];
    patient.difference = patient.predicted - patient.measured;
    const auto& fired = evaluation.flags.outputs_no_rule_fired;
    patient.no_rule_fired = std::find(fired.begin(), fired.end(), static_cast<int>(output)) != fired.end();
    for (std::size_t r = 0; r < evaluation.firing_strengths.size(); ++r)
      if (evaluation.firing_strengths[r] > patient.strongest_firing) {
        patient.strongest_firing = evaluation.firing_strengths[r];
        patient.strongest_rule = static_cast<int>(r);
      }
    patient.strongest_rule_name = rule_name(system, patient.strongest_rule);
    report.patients.push_back(std::move(patient));
  }
  append_capped(flags, 20, data.rows.empty() ? "" : data.rows.front().file, diagnostics);
  if (flags.has_errors()) return std::nullopt;
  std::vector<double> predicted, measured;
  for (const ValidationPatient& p : report.patients) {
    predicted.push_back(p.predicted);
    measured.push_back(p.measured);
  }
  report.agreement = measure_agreement(predicted, measured);
  std::vector<std::size_t> order(report.patients.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::fabs(report.patients[a].difference) > std::fabs(report.patients[b].difference);
  });
  order.resize(std::min(order.size(), kWorstPatients));
  report.worst = order;
  return report;
}

std::string validation_markdown(const ValidationReport& report) {
  const Agreement& a = report.agreement;
  const std::string& unit = report.output_unit;
  std::string text = "# Validation of " + report.system_name + " (" + report.rules_path + ") against " +
                     report.data_path + "\n\n";
  text += "Output '" + report.output_name + "' predicted by the rules against the measured column '" +
          report.measured_column + "', " + std::to_string(a.count) + " patient" + (a.count == 1 ? "" : "s") +
          ". Differences are predicted - measured.\n\n";
  const ValidationPatient& largest = report.patients[a.largest_error_index];
  std::vector<std::vector<std::string>> rows = {
      {"patients", std::to_string(a.count)},
      {"mean absolute error (MAE)", four_digits_with_unit(a.mean_absolute_error, unit)},
      {"root mean square error (RMSE)", four_digits_with_unit(a.root_mean_square_error, unit)},
      {"bias (mean difference)", four_digits_with_unit(a.bias, unit)},
      {"SD of the differences", a.count < 2 ? "undefined (one patient)" : four_digits_with_unit(a.difference_sd, unit)},
      {"95% limits of agreement (bias -/+ 1.96 SD)",
       a.count < 2 ? "undefined (one patient)"
                   : four_digits(a.lower_limit) + " to " + four_digits_with_unit(a.upper_limit, unit)},
      {"largest error", four_digits_with_unit(largest.difference, unit) + " (" + largest.label + ")"},
      {"Pearson r (predicted, measured)", std::isnan(a.correlation) ? "undefined (constant values)"
                                                                    : four_digits(a.correlation)},
  };
  text += markdown_table({"measure", "value"}, rows) + "\n";
  text += "## The patients predicted worst\n\n";
  std::vector<std::vector<std::string>> worst;
  for (std::size_t k : report.worst) {
    const ValidationPatient& p = report.patients[k];
    worst.push_back({p.label, std::to_string(p.line), four_digits(p.measured), four_digits(p.predicted),
                     four_digits(p.difference),
                     p.strongest_rule < 0 ? "none fired"
                                          : p.strongest_rule_name + " (" + four_digits(p.strongest_firing) + ")",
                     p.no_rule_fired ? "no rule fired: the policy's value" : ""});
  }
  text += markdown_table({"patient", "line", "measured", "predicted", "difference", "strongest rule (firing)", "note"},
                         worst);
  if (!report.notes.empty()) {
    text += "\n";
    for (const std::string& note : report.notes) text += "- " + note + "\n";
  }
  return text;
}

std::string validation_csv(const ValidationReport& report, const FuzzySystem& system) {
  std::vector<std::string> header = {"label", "line"};
  for (const Variable& input : system.inputs) header.push_back(input.name);
  for (const char* column : {"measured", "predicted", "difference", "no_rule_fired", "strongest_rule",
                             "strongest_firing"})
    header.emplace_back(column);
  std::string text = format_csv_row(header);
  for (const ValidationPatient& p : report.patients) {
    std::vector<std::string> row = {p.label, std::to_string(p.line)};
    for (double v : p.inputs) row.push_back(format_number(v));
    row.push_back(format_number(p.measured));
    row.push_back(format_number(p.predicted));
    row.push_back(format_number(p.difference));
    row.push_back(p.no_rule_fired ? "true" : "false");
    row.push_back(p.strongest_rule_name);
    row.push_back(format_number(p.strongest_firing));
    text += format_csv_row(row);
  }
  return text;
}

std::string predicted_against_measured_plot(const ValidationReport& report, plot::ImageFormat format) {
  const Agreement& a = report.agreement;
  plot::LineChart chart;
  chart.title.push_back(report.system_name + ": predicted against measured " + report.output_name);
  chart.title.push_back(std::to_string(a.count) + " patients from " + report.data_path + "; MAE " +
                        four_digits_with_unit(a.mean_absolute_error, report.output_unit) + ", RMSE " +
                        four_digits_with_unit(a.root_mean_square_error, report.output_unit) + ", bias " +
                        four_digits_with_unit(a.bias, report.output_unit));
  double lo = report.patients.front().measured, hi = lo;
  plot::Series patients;
  patients.name = "patients";
  patients.markers = true;
  patients.line = false;
  for (const ValidationPatient& p : report.patients) {
    patients.x.push_back(p.measured);
    patients.y.push_back(p.predicted);
    lo = std::min({lo, p.measured, p.predicted});
    hi = std::max({hi, p.measured, p.predicted});
  }
  pad(lo, hi);
  chart.x = plot::Axis{lo, hi, false, axis_title("measured " + report.output_name, report)};
  chart.y = plot::Axis{lo, hi, false, axis_title("predicted " + report.output_name, report)};
  plot::Series identity;
  identity.name = "predicted = measured";
  const plot::Axis shown = plot::rounded(chart.x);
  identity.x = identity.y = {shown.lo, shown.hi};
  identity.colour = plot::kTextGrey;
  identity.width = 1.5;
  identity.dashes = {6, 4};
  chart.series.push_back(identity);
  chart.series.push_back(patients);
  for (std::size_t n = 0; n < report.worst.size() && n < 3; ++n) {
    const ValidationPatient& p = report.patients[report.worst[n]];
    chart.notes.push_back("worst " + std::to_string(n + 1) + ": " + p.label + " (" +
                          four_digits_with_unit(p.difference, report.output_unit) + ")");
  }
  return plot::render_line_chart(chart, format);
}

std::string bland_altman_plot(const ValidationReport& report, plot::ImageFormat format) {
  const Agreement& a = report.agreement;
  const std::string& unit = report.output_unit;
  plot::LineChart chart;
  chart.title.push_back(report.system_name + ": Bland-Altman plot of " + report.output_name);
  chart.title.push_back(std::to_string(a.count) + " patients from " + report.data_path +
                        "; difference = predicted - measured");
  plot::Series patients;
  patients.name = "patients";
  patients.markers = true;
  patients.line = false;
  double x_lo = 0, x_hi = 0, y_lo = std::min(0.0, a.bias), y_hi = std::max(0.0, a.bias);
  for (std::size_t k = 0; k < report.patients.size(); ++k) {
    const ValidationPatient& p = report.patients[k];
    const double mean = p.predicted / 2 + p.measured / 2;
    patients.x.push_back(mean);
    patients.y.push_back(p.difference);
    x_lo = k == 0 ? mean : std::min(x_lo, mean);
    x_hi = k == 0 ? mean : std::max(x_hi, mean);
    y_lo = std::min(y_lo, p.difference);
    y_hi = std::max(y_hi, p.difference);
  }
  if (a.count >= 2) {
    y_lo = std::min(y_lo, a.lower_limit);
    y_hi = std::max(y_hi, a.upper_limit);
  }
  pad(x_lo, x_hi);
  pad(y_lo, y_hi);
  chart.x = plot::Axis{x_lo, x_hi, false, axis_title("mean of predicted and measured", report)};
  chart.y = plot::Axis{y_lo, y_hi, false, axis_title("predicted - measured", report)};
  const plot::Axis shown = plot::rounded(chart.x);
  chart.series.push_back(level("", shown.lo, shown.hi, 0.0, plot::kGridGrey, {}));
  chart.series.push_back(level("bias " + four_digits_with_unit(a.bias, unit), shown.lo, shown.hi, a.bias,
                               plot::categorical_colour(1), {}));
  if (a.count >= 2) {
    chart.series.push_back(level("95% limits of agreement", shown.lo, shown.hi, a.upper_limit,
                                 plot::categorical_colour(3), {6, 4}));
    chart.series.push_back(level("", shown.lo, shown.hi, a.lower_limit, plot::categorical_colour(3), {6, 4}));
    chart.notes.push_back("limits: " + four_digits(a.lower_limit) + " to " + four_digits_with_unit(a.upper_limit, unit));
  } else {
    chart.notes.push_back("one patient: no limits of agreement");
  }
  chart.series.push_back(patients);
  return plot::render_line_chart(chart, format);
}

}  // namespace fmpc::cli

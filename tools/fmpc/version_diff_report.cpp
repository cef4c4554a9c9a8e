#include "tools/fmpc/version_diff_report.h"

#include <cmath>

#include "compiler/eval/evaluation_report.h"
#include "compiler/frontend/fmpc_ast.h"
#include "compiler/frontend/fmpc_language.h"
#include "diagnostics/number_format.h"
#include "tools/fmpc/csv_table.h"
#include "tools/fmpc/report_text.h"
#include "tools/plot/line_chart.h"

namespace fmpc::cli {

namespace {

const char* role(bool output) { return output ? "output" : "input"; }

std::string rule_text(const FuzzySystem& system, int rule) {
  return system.rule_display_name(static_cast<std::size_t>(rule)) + ": " +
         format_rule_body(system, static_cast<std::size_t>(rule));
}

const Variable& variable_of(const FuzzySystem& system, bool output, int index) {
  return (output ? system.outputs : system.inputs)[static_cast<std::size_t>(index)];
}

}  // namespace

std::string term_shape_text(const Term& term, const FuzzySystem& system) {
  const ast::FamilySignature& family = ast::family_of(term.mf.kind);
  std::string text = std::string(family.name) + "(";
  if (term.mf.kind == MfKind::Linear) {
    for (std::size_t i = 0; i < term.mf.params.size(); ++i)
      text += (i ? ", " : "") + (i < system.inputs.size() ? system.inputs[i].name : std::string("offset")) + " " +
              format_number(term.mf.params[i]);
  } else {
    for (std::size_t p = 0; p < family.parameters.size(); ++p) {
      const auto index = static_cast<std::size_t>(family.matlab_index[p]);
      text += (p ? ", " : "") + std::string(family.parameters[p]) + " " +
              (index < term.mf.params.size() ? format_number(term.mf.params[index]) : std::string("?"));
    }
  }
  return text + ")" + (term.footprint ? " with a footprint of uncertainty" : "");
}

std::vector<std::string> describe_differences(const FuzzySystem& a, const FuzzySystem& b,
                                              const SystemDifferences& differences) {
  std::vector<std::string> lines = differences.settings;
  for (const VariableChange& change : differences.variables) {
    if (change.kind == ChangeKind::Added) {
      lines.push_back(std::string(role(change.output)) + " '" + variable_of(b, change.output, change.in_b).name +
                      "' is added");
    } else if (change.kind == ChangeKind::Removed) {
      lines.push_back(std::string(role(change.output)) + " '" + variable_of(a, change.output, change.in_a).name +
                      "' is removed");
    } else {
      std::string what;
      for (const std::string& item : change.what) what += (what.empty() ? "" : ", ") + item;
      lines.push_back(std::string(role(change.output)) + " '" + variable_of(a, change.output, change.in_a).name +
                      "': " + what);
    }
  }
  for (const TermChange& change : differences.terms) {
    const std::string where = "term '%' of " + std::string(role(change.output)) + " '" + change.variable + "'";
    const auto named = [&](const std::string& name) {
      std::string text = where;
      text.replace(text.find('%'), 1, name);
      return text;
    };
    if (change.kind == ChangeKind::Added) {
      const Term& term = variable_of(b, change.output, change.variable_in_b).terms[static_cast<std::size_t>(change.in_b)];
      lines.push_back(named(term.name) + " is added: " + term_shape_text(term, b));
    } else if (change.kind == ChangeKind::Removed) {
      const Term& term = variable_of(a, change.output, change.variable_in_a).terms[static_cast<std::size_t>(change.in_a)];
      lines.push_back(named(term.name) + " is removed (was " + term_shape_text(term, a) + ")");
    } else {
      const Term& x = variable_of(a, change.output, change.variable_in_a).terms[static_cast<std::size_t>(change.in_a)];
      const Term& y = variable_of(b, change.output, change.variable_in_b).terms[static_cast<std::size_t>(change.in_b)];
      std::string text = named(x.name) + ": " + term_shape_text(x, a) + " -> " + term_shape_text(y, b);
      if (change.footprint_changed && !change.family_changed && !change.parameters_changed)
        text = named(x.name) + ": its footprint of uncertainty changes";
      lines.push_back(text);
    }
  }
  for (const RuleChange& change : differences.rules) {
    if (change.kind == ChangeKind::Added) {
      lines.push_back("rule added: " + rule_text(b, change.in_b));
    } else if (change.kind == ChangeKind::Removed) {
      lines.push_back("rule removed: " + rule_text(a, change.in_a));
    } else {
      lines.push_back("rule changed: " + rule_text(a, change.in_a) + " -> " + rule_text(b, change.in_b));
    }
  }
  return lines;
}

std::string stage_name(const FuzzySystem& system, int output, int stage) {
  if (stage < 0 || output < 0) return "";
  return system.outputs[static_cast<std::size_t>(output)].terms[static_cast<std::size_t>(stage)].name;
}

std::optional<VersionDiffReport> compare_versions(const FuzzySystem& a, const FuzzySystem& b, const PatientData& data,
                                                  const EvaluationOptions& options, DiagnosticList& diagnostics) {
  VersionDiffReport report;
  report.differences = describe_differences(a, b, system_differences(a, b));
  report.labels = data.labels;
  report.lines = data.lines;
  report.notes = data.notes;
  std::vector<Evaluation> evaluations[2];
  const FuzzySystem* systems[2] = {&a, &b};
  bool errors = false;
  for (std::size_t s = 0; s < 2; ++s) {
    Interpreter interpreter(*systems[s], options);
    DiagnosticList flags;
    for (std::size_t k = 0; k < data.labels.size(); ++k) {
      evaluations[s].push_back(interpreter.evaluate(data.points[s][k]));
      report_evaluation_flags(*systems[s], data.points[s][k], data.origins[s][k], data.rows[k], evaluations[s].back(),
                              flags);
    }
    append_capped(flags, 20, data.rows.empty() ? "" : data.rows.front().file, diagnostics);
    errors = errors || flags.has_errors();
  }
  if (errors) return std::nullopt;
  report.outputs = compare_evaluations(a, b, evaluations[0], evaluations[1]);
  for (const Variable& output : a.outputs)
    if (b.find_output(output.name) < 0) report.notes.push_back("output '" + output.name + "' is only in the first version");
  for (const Variable& output : b.outputs)
    if (a.find_output(output.name) < 0) report.notes.push_back("output '" + output.name + "' is only in the second version");
  for (const OutputComparisonOverPoints& output : report.outputs) {
    report.units.push_back(a.outputs[static_cast<std::size_t>(output.in_a)].unit);
    std::vector<double> finite;
    for (double d : output.difference)
      if (std::isfinite(d)) finite.push_back(d);
    report.histograms.push_back(finite.empty() ? Histogram{} : histogram(finite, sturges_bins(finite.size())));
  }
  return report;
}

std::string version_diff_markdown(const VersionDiffReport& report, const FuzzySystem& a, const FuzzySystem& b) {
  std::string text = "# " + report.path_b + " against " + report.path_a + " over " + report.data_path + "\n\n";
  text += "## What differs in the rules\n\n";
  if (report.differences.empty()) text += "Nothing: the two versions define the same system.\n";
  for (const std::string& line : report.differences) text += "- " + line + "\n";
  text += "\n## Outputs over " + std::to_string(report.labels.size()) + " patients\n\n";
  text += "Changes are second - first (" + report.path_b + " - " + report.path_a + ").\n\n";
  std::vector<std::vector<std::string>> rows;
  for (const OutputComparisonOverPoints& output : report.outputs) {
    const Agreement& g = output.agreement;
    const std::string& unit = a.outputs[static_cast<std::size_t>(output.in_a)].unit;
    if (g.count == 0) {
      rows.push_back({output.name, "no patient with two finite values", "", "", "", ""});
      continue;
    }
    std::size_t where = 0, seen = 0;
    for (std::size_t k = 0; k < output.difference.size(); ++k)
      if (std::isfinite(output.difference[k]) && seen++ == g.largest_error_index) where = k;
    rows.push_back({output.name, four_digits_with_unit(g.mean_absolute_error, unit),
                    four_digits_with_unit(output.difference[where], unit) + " (" + report.labels[where] + ")",
                    four_digits_with_unit(g.bias, unit),
                    std::to_string(output.stage_changes.size()) + " of " + std::to_string(output.a.size()),
                    std::to_string(g.count)});
  }
  text += markdown_table({"output", "mean |change|", "largest change", "mean change", "stage changes", "patients compared"},
                         rows);
  for (const OutputComparisonOverPoints& output : report.outputs) {
    if (output.stage_changes.empty()) continue;
    text += "\n### Patients whose '" + output.name + "' stage changes\n\n";
    std::vector<std::vector<std::string>> changes;
    for (std::size_t k : output.stage_changes) {
      const std::string from = stage_name(a, output.in_a, output.stage_a[k]);
      const std::string to = stage_name(b, output.in_b, output.stage_b[k]);
      changes.push_back({report.labels[k], std::to_string(report.lines[k]), four_digits(output.a[k]),
                         from.empty() ? "(none)" : from, four_digits(output.b[k]), to.empty() ? "(none)" : to});
    }
    text += markdown_table({"patient", "line", "first", "stage", "second", "stage"}, changes);
  }
  if (!report.notes.empty()) {
    text += "\n";
    for (const std::string& note : report.notes) text += "- " + note + "\n";
  }
  return text;
}

std::string version_diff_csv(const VersionDiffReport& report, const FuzzySystem& a, const FuzzySystem& b) {
  std::vector<std::string> header = {"label", "line"};
  for (const OutputComparisonOverPoints& output : report.outputs)
    for (const char* suffix : {".a", ".b", ".difference", ".stage_a", ".stage_b"}) header.push_back(output.name + suffix);
  std::string text = format_csv_row(header);
  for (std::size_t k = 0; k < report.labels.size(); ++k) {
    std::vector<std::string> row = {report.labels[k], std::to_string(report.lines[k])};
    for (const OutputComparisonOverPoints& output : report.outputs) {
      row.push_back(format_number(output.a[k]));
      row.push_back(format_number(output.b[k]));
      row.push_back(format_number(output.difference[k]));
      row.push_back(stage_name(a, output.in_a, output.stage_a[k]));
      row.push_back(stage_name(b, output.in_b, output.stage_b[k]));
    }
    text += format_csv_row(row);
  }
  return text;
}

std::string difference_histogram_plot(const VersionDiffReport& report, std::size_t index, plot::ImageFormat format) {
  const OutputComparisonOverPoints& output = report.outputs[index];
  const Histogram& h = report.histograms[index];
  plot::LineChart chart;
  chart.title.push_back("Change of '" + output.name + "': " + report.path_b + " - " + report.path_a);
  const std::size_t changes = output.stage_changes.size();
  chart.title.push_back(std::to_string(output.agreement.count) + " patients from " + report.data_path + "; " +
                        (changes == 0 ? std::string("no patient changes stage")
                                      : std::to_string(changes) + (changes == 1 ? " patient changes" : " patients change") +
                                            " stage"));
  plot::Series bars;
  bars.name = "patients per bin";
  std::size_t highest = 1;
  for (std::size_t k = 0; k < h.counts.size(); ++k) {
    const double left = h.lo + h.bin_width() * static_cast<double>(k);
    const double right = k + 1 == h.counts.size() ? h.hi : left + h.bin_width();
    const auto count = static_cast<double>(h.counts[k]);
    bars.x.insert(bars.x.end(), {left, left, right, right});
    bars.y.insert(bars.y.end(), {0, count, count, 0});
    highest = std::max(highest, h.counts[k]);
  }
  bars.y_lower.assign(bars.y.size(), 0.0);
  const std::string& unit = report.units[index];
  const bool unit_shown = !unit.empty() && unit != "dimensionless";
  chart.x = plot::Axis{h.counts.empty() ? -0.5 : h.lo, h.counts.empty() ? 0.5 : h.hi, false,
                       "change of " + output.name + (unit_shown ? " (" + unit + ")" : "")};
  chart.y = plot::Axis{0, static_cast<double>(highest) * 1.1, false, "patients"};
  chart.series.push_back(bars);
  if (output.agreement.count > 0) {
    chart.markers.push_back(plot::VerticalMarker{0.0, "no change", plot::kTextGrey});
    chart.notes.push_back("mean change " + four_digits_with_unit(output.agreement.bias, unit));
    chart.notes.push_back("mean |change| " + four_digits_with_unit(output.agreement.mean_absolute_error, unit));
  }
  return plot::render_line_chart(chart, format);
}

}  // namespace fmpc::cli

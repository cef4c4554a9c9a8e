#include "tools/fmpc/measured_data.h"

#include <cmath>

#include "diagnostics/number_format.h"
#include "tools/fmpc/evaluation_points.h"

namespace fmpc::cli {

namespace {

bool is_measured_label_column(const std::string& header) {
  return header == "label" || header == "patient" || header == "id";
}

}  // namespace

bool parse_input_columns(const std::vector<std::string>& arguments, const FuzzySystem& system,
                         std::map<std::string, std::string>& columns, DiagnosticList& diagnostics) {
  bool ok = true;
  for (const std::string& argument : arguments) {
    const SourceRange where{"argument --column " + argument, 0, 0, 0, 0};
    const std::size_t eq = argument.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == argument.size()) {
      diagnostics.error(where, "expected INPUT=COLUMN", {"for example: --column HCV=fibroscan_hcv"});
      ok = false;
      continue;
    }
    const std::string input = argument.substr(0, eq);
    if (system.find_input(input) < 0) {
      std::vector<std::string> notes;
      if (auto closest = closest_name(input, variable_names(system.inputs)))
        notes.push_back("did you mean '" + *closest + "'?");
      diagnostics.error(where, "'" + input + "' is not an input of system '" + system.name + "'", notes);
      ok = false;
      continue;
    }
    if (!columns.emplace(input, argument.substr(eq + 1)).second) {
      diagnostics.error(where, "input '" + input + "' is mapped twice");
      ok = false;
    }
  }
  return ok;
}

std::optional<MeasuredData> read_measured_data(const CsvTable& table, const FuzzySystem& system, std::size_t output,
                                               const std::map<std::string, std::string>& input_columns,
                                               const std::string& measured_column, DiagnosticList& diagnostics) {
  const std::size_t errors_before = diagnostics.error_count();
  const SourceRange header_range{table.path, 1, 1, 1, 1};
  const auto find_column = [&](const std::string& name) -> std::optional<std::size_t> {
    std::optional<std::size_t> found;
    for (std::size_t c = 0; c < table.header.size(); ++c) {
      if (table.header[c].text != name) continue;
      if (found) diagnostics.error(table.header[c].range, "column '" + name + "' appears twice");
      else found = c;
    }
    return found;
  };
  MeasuredData data;
  std::vector<bool> used(table.header.size(), false);
  std::vector<std::size_t> input_column(system.inputs.size());
  for (std::size_t i = 0; i < system.inputs.size(); ++i) {
    const auto mapped = input_columns.find(system.inputs[i].name);
    const std::string name = mapped == input_columns.end() ? system.inputs[i].name : mapped->second;
    if (const std::optional<std::size_t> column = find_column(name)) {
      input_column[i] = *column;
      used[*column] = true;
    } else {
      diagnostics.error(header_range, "the header has no column '" + name + "' for input '" + system.inputs[i].name + "'",
                        {"name the column after the input, or map it: --column " + system.inputs[i].name + "=COLUMN"});
    }
  }
  const std::string output_name = system.outputs[output].name;
  std::optional<std::size_t> measured;
  if (!measured_column.empty()) {
    measured = find_column(measured_column);
    if (!measured)
      diagnostics.error(SourceRange{"argument --measured", 0, 0, 0, 0},
                        "the header has no column '" + measured_column + "'");
  } else {
    for (const std::string& name : {output_name, std::string("measured"), "measured_" + output_name,
                                    output_name + "_measured"})
      if (!measured) measured = find_column(name);
    if (!measured)
      diagnostics.error(header_range, "the header has no column of measured '" + output_name + "'",
                        {"name it " + output_name + " or measured, or give --measured COLUMN"});
  }
  if (measured) {
    used[*measured] = true;
    data.measured_column = table.header[*measured].text;
  }
  std::optional<std::size_t> label;
  for (std::size_t c = 0; c < table.header.size(); ++c)
    if (!used[c] && !label && is_measured_label_column(table.header[c].text)) {
      label = c;
      used[c] = true;
    }
  for (std::size_t c = 0; c < table.header.size(); ++c)
    if (!used[c]) data.unused_columns.push_back(table.header[c].text);
  if (diagnostics.error_count() > errors_before) return std::nullopt;

  for (const auto& row : table.rows) {
    const int line = row.front().range.line;
    if (row.size() != table.header.size()) {
      diagnostics.error(row.front().range, "this row has " + std::to_string(row.size()) + " fields, the header " +
                                               std::to_string(table.header.size()));
      continue;
    }
    const CsvCell& measured_cell = row[*measured];
    if (measured_cell.text.empty()) {
      diagnostics.warning(measured_cell.range, "missing-measurement",
                          "no measured value in this row; the patient is left out");
      ++data.skipped_rows;
      continue;
    }
    std::vector<double> inputs(system.inputs.size(), 0.0);
    bool ok = true;
    for (std::size_t i = 0; i < system.inputs.size(); ++i) {
      const CsvCell& cell = row[input_column[i]];
      const std::optional<double> value = parse_input_value(cell.text, system.inputs[i], cell.range, diagnostics);
      if (!value || !std::isfinite(*value)) {
        if (value) diagnostics.error(cell.range, "input '" + system.inputs[i].name + "' is " + format_number(*value));
        ok = false;
        continue;
      }
      if (*value < system.inputs[i].min || *value > system.inputs[i].max)
        diagnostics.warning(cell.range, "input-out-of-range",
                            "input '" + system.inputs[i].name + "' = " + format_number(*value) +
                                " is outside its range [" + format_number(system.inputs[i].min) + ", " +
                                format_number(system.inputs[i].max) + "]; evaluated as given");
      inputs[i] = *value;
    }
    const std::optional<double> value = parse_number(measured_cell.text);
    if (!value || !std::isfinite(*value)) {
      diagnostics.error(measured_cell.range, "the measured value '" + measured_cell.text + "' is not a finite number");
      ok = false;
    }
    if (!ok) continue;
    data.labels.push_back(label ? row[*label].text : "row " + std::to_string(line));
    data.inputs.push_back(std::move(inputs));
    data.measured.push_back(*value);
  }
  if (diagnostics.error_count() == errors_before && data.measured.size() < 2)
    diagnostics.error(SourceRange{table.path, 0, 0, 0, 0},
                      "the data has " + std::to_string(data.measured.size()) +
                          " patient(s) with a measured value; tuning needs at least 2");
  if (diagnostics.error_count() > errors_before) return std::nullopt;
  return data;
}

}  // namespace fmpc::cli

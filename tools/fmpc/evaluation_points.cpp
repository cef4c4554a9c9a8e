#include "tools/fmpc/evaluation_points.h"
#include "tools/fmpc/commands.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "compiler/ir/units.h"
#include "diagnostics/number_format.h"

namespace fmpc::cli {

std::optional<double> parse_number(const std::string& text) {
  if (text.empty()) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) return std::nullopt;
  return value;
}

// A number for `input`, or an error: text that is not a number, or NaN (fmpc never turns NaN into a silent
// output).
std::optional<double> parse_input_value(const std::string& text, const Variable& input, const SourceRange& where,
                                        DiagnosticList& diagnostics) {
  const std::optional<double> value = parse_number(text);
  if (!value) {
    diagnostics.error(where, "'" + text + "' is not a number (input '" + input.name + "')");
    return std::nullopt;
  }
  if (std::isnan(*value)) {
    diagnostics.error(where, "input '" + input.name + "' is NaN",
                      {"give a number within [" + format_number(input.min) + ", " + format_number(input.max) + "]"});
    return std::nullopt;
  }
  return value;
}

std::vector<std::string> variable_names(const std::vector<Variable>& variables) {
  std::vector<std::string> names;
  for (const Variable& v : variables) names.push_back(v.name);
  return names;
}

std::string csv_header_of(const FuzzySystem& system) {
  std::string header;
  for (const Variable& v : system.inputs) header += (header.empty() ? "" : ",") + v.name;
  return header;
}

namespace {

// `csv_column`: the name is a CSV header, where a label column may stand too.
void report_unknown_input(const std::string& name, const FuzzySystem& system, const SourceRange& where,
                          DiagnosticList& diagnostics, bool csv_column = false) {
  std::vector<std::string> notes;
  std::vector<std::string> candidates = variable_names(system.inputs);
  if (csv_column) candidates.insert(candidates.end(), {"label", "patient"});
  if (auto suggestion = closest_name(name, candidates)) notes.push_back("did you mean '" + *suggestion + "'?");
  std::string inputs;
  for (const Variable& v : system.inputs) inputs += (inputs.empty() ? "" : ", ") + v.name;
  notes.push_back("the inputs of '" + system.name + "' are: " + inputs);
  if (csv_column) notes.push_back("a column 'label' or 'patient' names the rows; columns named after outputs are ignored");
  diagnostics.error(where, "'" + name + "' is not an input of system '" + system.name + "'", notes);
}

}  // namespace

// NAME=VALUE arguments -> one point. Every input must be given exactly once.
std::optional<EvaluationPoint> point_from_assignments(const std::vector<std::string>& assignments,
                                                      const FuzzySystem& system, DiagnosticList& diagnostics) {
  EvaluationPoint point;
  point.label = "point 1 (command line)";
  point.where = kCommandLine;
  point.inputs.assign(system.inputs.size(), std::nan(""));
  point.origins.assign(system.inputs.size(), SourceRange{});
  std::vector<bool> given(system.inputs.size(), false);
  for (const std::string& assignment : assignments) {
    const SourceRange where{"argument '" + assignment + "'", 0, 0, 0, 0};
    const std::size_t eq = assignment.find('=');
    if (eq == std::string::npos) {
      diagnostics.error(where, "expected NAME=VALUE", {"for example: " + system.inputs.front().name + "=7.5"});
      continue;
    }
    const std::string name = assignment.substr(0, eq);
    const int index = system.find_input(name);
    if (index < 0) {
      report_unknown_input(name, system, where, diagnostics);
      continue;
    }
    if (given[static_cast<std::size_t>(index)]) diagnostics.error(where, "input '" + name + "' is given twice");
    given[static_cast<std::size_t>(index)] = true;
    const std::optional<double> value = parse_input_value(
        assignment.substr(eq + 1), system.inputs[static_cast<std::size_t>(index)], where, diagnostics);
    if (!value) continue;
    point.inputs[static_cast<std::size_t>(index)] = *value;
    point.origins[static_cast<std::size_t>(index)] = where;
  }
  for (std::size_t i = 0; i < system.inputs.size(); ++i)
    if (!given[i])
      diagnostics.error(kCommandLine, "no value for input '" + system.inputs[i].name + "'",
                        {"add " + system.inputs[i].name + "=VALUE (range [" + format_number(system.inputs[i].min) +
                         ", " + format_number(system.inputs[i].max) + "])"});
  if (diagnostics.has_errors()) return std::nullopt;
  return point;
}

namespace {

// OUTPUT.lower / OUTPUT.upper: the type-reduced interval columns `fmpc eval` writes for interval type-2 systems.
bool is_output_interval_column(const std::string& name, const FuzzySystem& system) {
  if (!system.interval_type2) return false;
  for (const char* suffix : {".lower", ".upper"}) {
    const std::string end = suffix;
    if (name.size() > end.size() && name.compare(name.size() - end.size(), end.size(), end) == 0 &&
        system.find_output(name.substr(0, name.size() - end.size())) >= 0)
      return true;
  }
  return false;
}

}  // namespace

// A CSV table with a header row -> points. Columns naming outputs are ignored (so a golden file with inputs and
// outputs, or fmpc validate's measured data, can be fed back in); any other unknown column is an error. A header
// may state a unit, "HCV (Pa)", as fmpc validate's CSV does: values are converted into the input's.
bool is_label_column(const std::string& header) { return header == "label" || header == "patient"; }

std::vector<EvaluationPoint> points_from_csv(const CsvTable& table, const FuzzySystem& system,
                                             DiagnosticList& diagnostics, std::string* label_column) {
  std::vector<EvaluationPoint> points;
  std::vector<int> column_input(table.header.size(), -1);
  // A header's stated unit ("HCV (Pa)", as fmpc validate reads it) where it differs from the input's: converted.
  std::vector<std::string> column_unit(table.header.size());
  std::vector<bool> seen(system.inputs.size(), false);
  std::optional<std::size_t> label;
  for (std::size_t c = 0; c < table.header.size(); ++c) {
    const CsvCell& cell = table.header[c];
    const HeaderColumn named = split_header_unit(cell);
    int index = system.find_input(cell.text);
    if (index < 0 && !named.unit.empty() && (index = system.find_input(named.name)) >= 0) {
      const Variable& input = system.inputs[static_cast<std::size_t>(index)];
      if (!input.unit.empty() && named.unit != input.unit) {
        if (!convert_unit(1.0, named.unit, input.unit)) {
          diagnostics.error(cell.range, "column '" + cell.text + "' is in " + named.unit + ", which does not convert to " +
                                            input.unit + ", the unit of '" + input.name + "'",
                            {"give the values in " + input.unit +
                             " (or a unit fmpc converts: docs/language.md, \"Units\")"});
          seen[static_cast<std::size_t>(index)] = true;  // located above; not also "no column for input"
          continue;
        }
        column_unit[c] = named.unit;
      }
    }
    if (index < 0 && is_label_column(cell.text)) {
      if (label)
        diagnostics.error(cell.range, "two label columns ('" + table.header[*label].text + "' and '" + cell.text + "')",
                          {"keep one: it names the rows"});
      else label = c;
    } else if (index >= 0) {
      if (seen[static_cast<std::size_t>(index)])
        diagnostics.error(cell.range, "column '" + cell.text + "' appears twice");
      seen[static_cast<std::size_t>(index)] = true;
      column_input[c] = index;
    } else if (system.find_output(cell.text) < 0 && system.find_output(named.name) < 0 &&
               !is_output_interval_column(cell.text, system)) {
      report_unknown_input(cell.text, system, cell.range, diagnostics, true);
    }
  }
  for (std::size_t i = 0; i < system.inputs.size(); ++i)
    if (!seen[i])
      diagnostics.error(SourceRange{table.path, 1, 1, 1, 1},
                        "the header has no column for input '" + system.inputs[i].name + "'");
  if (diagnostics.has_errors()) return points;
  for (const auto& row : table.rows) {
    EvaluationPoint point;
    point.label = "point " + std::to_string(points.size() + 1) + " (" + table.path + ":" +
                  std::to_string(row.front().range.line) + ")";
    point.where = row.front().range;
    point.where.end_line = point.where.line;
    point.where.end_column = row.back().range.end_column;
    point.inputs.assign(system.inputs.size(), 0.0);
    point.origins.assign(system.inputs.size(), SourceRange{});
    if (label && *label < row.size()) {
      point.name = row[*label].text;
      point.label = point.name + " (" + table.path + ":" + std::to_string(row.front().range.line) + ")";
    }
    if (row.size() != table.header.size()) {
      diagnostics.error(row.front().range, "this row has " + std::to_string(row.size()) + " fields, the header " +
                                               std::to_string(table.header.size()));
      continue;
    }
    for (std::size_t c = 0; c < row.size(); ++c) {
      if (column_input[c] < 0) continue;
      const std::optional<double> value = parse_input_value(
          row[c].text, system.inputs[static_cast<std::size_t>(column_input[c])], row[c].range, diagnostics);
      if (!value) continue;
      const Variable& input = system.inputs[static_cast<std::size_t>(column_input[c])];
      point.inputs[static_cast<std::size_t>(column_input[c])] =
          column_unit[c].empty() ? *value : convert_unit(*value, column_unit[c], input.unit).value_or(*value);
      point.origins[static_cast<std::size_t>(column_input[c])] = row[c].range;
    }
    points.push_back(std::move(point));
  }
  if (label_column) *label_column = label ? table.header[*label].text : std::string();
  return points;
}

}  // namespace fmpc::cli

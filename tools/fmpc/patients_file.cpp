#include "tools/fmpc/patients_file.h"

#include <cmath>
#include <map>

#include "diagnostics/number_format.h"
#include "runtime/io/input_file.h"
#include "runtime/scene/cohort.h"
#include "tools/fmpc/csv_table.h"
#include "tools/fmpc/evaluation_points.h"

namespace fmpc::cli {

namespace {

constexpr const char* kLabelColumn = "label";

const sim::InputBinding* binding_of(const sim::Scene& scene, const std::string& input) {
  for (const sim::InputBinding& binding : scene.material.bindings)
    if (binding.input == input) return &binding;
  return nullptr;
}

// The header: the label's column and each input column's input index; errors for every column that cannot be one.
bool read_header(const CsvTable& table, const sim::Scene& scene, const FuzzySystem& system, std::size_t& label_column,
                 std::vector<int>& column_input, PatientsFile& file, DiagnosticList& diagnostics) {
  const std::size_t errors_before = diagnostics.error_count();
  std::optional<std::size_t> label;
  column_input.assign(table.header.size(), -1);
  std::vector<bool> seen(system.inputs.size(), false);
  for (std::size_t c = 0; c < table.header.size(); ++c) {
    const CsvCell& cell = table.header[c];
    if (cell.text == kLabelColumn) {
      if (label) diagnostics.error(cell.range, "column 'label' appears twice");
      label = c;
      continue;
    }
    const int index = system.find_input(cell.text);
    if (index < 0) {
      std::vector<std::string> names = variable_names(system.inputs);
      names.push_back(kLabelColumn);
      std::vector<std::string> notes;
      if (auto suggestion = closest_name(cell.text, names)) notes.push_back("did you mean '" + *suggestion + "'?");
      std::string inputs;
      for (const Variable& v : system.inputs) inputs += (inputs.empty() ? "" : ", ") + v.name;
      notes.push_back("the columns are 'label' and inputs of system '" + system.name + "': " + inputs);
      diagnostics.error(cell.range, "'" + cell.text + "' is not an input of system '" + system.name + "'", notes);
      continue;
    }
    if (seen[static_cast<std::size_t>(index)]) {
      diagnostics.error(cell.range, "column '" + cell.text + "' appears twice");
      continue;
    }
    seen[static_cast<std::size_t>(index)] = true;
    const sim::InputBinding* binding = binding_of(scene, cell.text);
    if (binding != nullptr && binding->kind != sim::InputBinding::Kind::Constant) {
      const char* how = binding->kind == sim::InputBinding::Kind::Strain ? "by strain" : "per region";
      const SourceRange bound = scene.range_of("material.inputs." + cell.text);
      diagnostics.error(cell.range,
                        "input '" + cell.text + "' is bound " + how + " in the scene (" + bound.file + ":" +
                            std::to_string(bound.line) + ":" + std::to_string(bound.column) +
                            "); a patient's column replaces a constant binding only",
                        {"bind it to a number in the scene's material.inputs, or drop the column"});
      continue;
    }
    column_input[c] = index;
    file.inputs.push_back(cell.text);
  }
  if (!label)
    diagnostics.error(SourceRange{table.path, 1, 1, 1, 1}, "the header has no 'label' column",
                      {"add a column 'label': it names each patient's output folder"});
  for (const sim::InputBinding& binding : scene.material.bindings) {
    const int index = system.find_input(binding.input);
    if (binding.kind != sim::InputBinding::Kind::Constant || index < 0 || seen[static_cast<std::size_t>(index)])
      continue;
    diagnostics.error(SourceRange{table.path, 1, 1, 1, 1},
                      "the header has no column for input '" + binding.input + "', which the scene binds to " +
                          format_number(binding.value),
                      {"add a column '" + binding.input + "': every patient gives every input the scene binds"});
  }
  if (label) label_column = *label;
  return diagnostics.error_count() == errors_before;
}

}  // namespace

std::optional<PatientsFile> read_patients_file(const std::string& path, const sim::Scene& scene,
                                               const FuzzySystem& system, SourceFiles& sources,
                                               DiagnosticList& diagnostics) {
  const std::size_t errors_before = diagnostics.error_count();
  std::string header = kLabelColumn;
  for (const sim::InputBinding& binding : scene.material.bindings)
    if (binding.kind == sim::InputBinding::Kind::Constant && system.find_input(binding.input) >= 0)
      header += "," + binding.input;
  const std::optional<CsvTable> read =
      read_csv_file(path, path, sim::kMaxCsvFileBytes, "patients file",
                    SourceRange{"argument --patients", 0, 0, 0, 0}, sources, diagnostics, header);
  if (!read) return std::nullopt;
  const CsvTable& table = *read;
  PatientsFile file;
  std::size_t label_column = 0;
  std::vector<int> column_input;
  if (!read_header(table, scene, system, label_column, column_input, file, diagnostics)) return std::nullopt;
  if (table.rows.empty()) {
    diagnostics.error(SourceRange{path, 1, 1, 1, 1}, "the patients file has a header but no patients",
                      {"add one row per patient under the header"});
    return std::nullopt;
  }
  if (table.rows.size() > sim::kMaxCohortPatients) {
    diagnostics.error(SourceRange{path, 0, 0, 0, 0},
                      "the patients file has " + std::to_string(table.rows.size()) + " patients; at most " +
                          std::to_string(sim::kMaxCohortPatients) + " (docs/limits.md): split it into several files");
    return std::nullopt;
  }
  std::map<std::string, int> first_line;  // folded label -> the line that gave it first
  file.patients.reserve(table.rows.size());
  for (const auto& row : table.rows) {
    if (row.size() != table.header.size()) {
      diagnostics.error(row.front().range, "this row has " + std::to_string(row.size()) + " fields, the header " +
                                               std::to_string(table.header.size()));
      continue;
    }
    PatientRow patient;
    patient.line = row.front().range.line;
    const CsvCell& label = row[label_column];
    patient.label = label.text;
    if (const auto why = sim::unsafe_patient_label(label.text)) {
      diagnostics.error(label.range, "label '" + label.text + "': " + *why);
    } else {
      const auto [it, inserted] = first_line.emplace(sim::folded_label(label.text), patient.line);
      if (!inserted)
        diagnostics.error(label.range, "label '" + label.text + "' is given twice (labels name folders, compared "
                                                                "ignoring case)",
                          {"first given on line " + std::to_string(it->second)});
    }
    for (std::size_t c = 0; c < row.size(); ++c) {
      if (column_input[c] < 0) continue;
      const Variable& input = system.inputs[static_cast<std::size_t>(column_input[c])];
      const std::optional<double> value = parse_input_value(row[c].text, input, row[c].range, diagnostics);
      if (!value) continue;
      if (!std::isfinite(*value)) {
        diagnostics.error(row[c].range, "input '" + input.name + "' is " + format_number(*value),
                          {"give a finite number within [" + format_number(input.min) + ", " +
                           format_number(input.max) + "]"});
        continue;
      }
      if (*value < input.min || *value > input.max)
        diagnostics.warning(row[c].range, "input-out-of-range",
                            "input '" + input.name + "' = " + format_number(*value) + " is outside its range [" +
                                format_number(input.min) + ", " + format_number(input.max) + "]; evaluated as given");
      patient.values.push_back(*value);
    }
    file.patients.push_back(std::move(patient));
  }
  if (diagnostics.error_count() > errors_before) return std::nullopt;
  return file;
}

}  // namespace fmpc::cli

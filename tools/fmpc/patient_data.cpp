#include "tools/fmpc/patient_data.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "compiler/ir/units.h"
#include "diagnostics/number_format.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/evaluation_points.h"

namespace fmpc::cli {

namespace {

std::string lower_case(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// One column the request reads: which header cell, and the factor that brings its values into the variable's unit.
struct ColumnUse {
  std::size_t column = 0;
  std::string from_unit;  // the header's unit, converted from; empty: values taken as given
  std::string to_unit;
};

class PatientDataReader {
 public:
  PatientDataReader(const CsvTable& table, const PatientDataRequest& request, DiagnosticList& diagnostics)
      : table_(table), request_(request), diagnostics_(diagnostics) {}

  std::optional<PatientData> read() {
    // Errors the caller found before (in its options, say) do not stop the reading: every mistake at once.
    const std::size_t errors_before = diagnostics_.error_count();
    const auto failed = [&] { return diagnostics_.error_count() > errors_before; };
    for (const auto& [input, column] : request_.input_columns) {
      bool known = false;
      for (const FuzzySystem* system : request_.systems) known = known || system->find_input(input) >= 0;
      if (!known)
        diagnostics_.error(SourceRange{"argument --column " + input + "=" + column, 0, 0, 0, 0},
                           "'" + input + "' is not an input of the rules",
                           {"the inputs are: " + input_list()});
    }
    for (const CsvCell& cell : table_.header) header_.push_back(split_header_unit(cell));
    used_.assign(header_.size(), false);
    find_duplicates();
    find_label();
    input_uses_.resize(request_.systems.size());
    for (std::size_t s = 0; s < request_.systems.size(); ++s)
      for (const Variable& input : request_.systems[s]->inputs) input_uses_[s].push_back(find_input(input));
    if (request_.measured_output) find_measured();
    if (failed()) return std::nullopt;
    note_unused_columns();
    data_.points.resize(request_.systems.size());
    data_.origins.resize(request_.systems.size());
    for (const std::vector<CsvCell>& row : table_.rows) read_row(row);
    if (failed()) return std::nullopt;
    if (data_.labels.empty()) {
      diagnostics_.error(SourceRange{table_.path, 1, 1, 1, 1},
                         table_.rows.empty() ? "the table has no patients: add a row under the header"
                                             : "no patient has a measured value");
      return std::nullopt;
    }
    if (data_.skipped_rows > 0)
      data_.notes.push_back(std::to_string(data_.skipped_rows) + " row" + (data_.skipped_rows == 1 ? "" : "s") +
                            " without a measured value skipped");
    return std::move(data_);
  }

 private:
  std::string input_list() const {
    std::string list;
    for (const FuzzySystem* system : request_.systems)
      for (const Variable& input : system->inputs)
        if (list.find("'" + input.name + "'") == std::string::npos)
          list += (list.empty() ? "'" : ", '") + input.name + "'";
    return list;
  }

  std::optional<std::size_t> column_named(const std::string& name) const {
    for (std::size_t c = 0; c < header_.size(); ++c)
      if (header_[c].name == name) return c;
    return std::nullopt;
  }

  void find_duplicates() {
    for (std::size_t c = 0; c < header_.size(); ++c)
      for (std::size_t d = 0; d < c; ++d)
        if (header_[c].name == header_[d].name) {
          diagnostics_.error(header_[c].range, "column '" + header_[c].name + "' appears twice",
                             {"first at column " + std::to_string(d + 1) + "; rename or remove one"});
          break;
        }
  }

  void find_label() {
    for (const char* name : {"label", "patient", "id"})
      for (std::size_t c = 0; c < header_.size(); ++c)
        if (lower_case(header_[c].name) == name && !label_) {
          label_ = c;
          used_[c] = true;
        }
  }

  // The unit conversion from the header's stated unit into `variable`'s; an error when they do not convert.
  ColumnUse use_of(std::size_t column, const Variable& variable) {
    ColumnUse use{column, "", variable.unit};
    const HeaderColumn& header = header_[column];
    used_[column] = true;
    if (header.unit.empty() || header.unit == variable.unit) return use;
    if (variable.unit.empty()) {
      note("'" + table_.header[column].text + "': the rule file gives '" + variable.name +
           "' no unit, so the stated " + header.unit + " is taken as given");
      return use;
    }
    if (!convert_unit(1.0, header.unit, variable.unit)) {
      diagnostics_.error(header.range, "column '" + header.name + "' is in " + header.unit + ", which does not convert to " +
                                           variable.unit + ", the unit of '" + variable.name + "'",
                         {"give the values in " + variable.unit + " (or a unit fmpc converts: docs/language.md, \"Units\")"});
      return use;
    }
    use.from_unit = header.unit;
    note("'" + table_.header[column].text + "' converted from " + header.unit + " to " + variable.unit);
    return use;
  }

  ColumnUse find_input(const Variable& input) {
    const auto mapped = request_.input_columns.find(input.name);
    const std::string wanted = mapped != request_.input_columns.end() ? mapped->second : input.name;
    if (const std::optional<std::size_t> column = column_named(wanted)) return use_of(*column, input);
    std::vector<std::string> names;
    for (const HeaderColumn& header : header_) names.push_back(header.name);
    std::vector<std::string> notes;
    if (auto suggestion = closest_name(wanted, names)) notes.push_back("did you mean '" + *suggestion + "'?");
    notes.push_back("name a column after each input, or map one: --column " + input.name + "=COLUMN");
    diagnostics_.error(SourceRange{table_.path, 1, 1, 1, 1},
                       "the header has no column '" + wanted + "' for input '" + input.name + "'", notes);
    return ColumnUse{};
  }

  void find_measured() {
    const Variable& output = request_.systems.front()->outputs[*request_.measured_output];
    std::vector<std::string> candidates;
    if (!request_.measured_column.empty()) {
      candidates.push_back(request_.measured_column);
    } else {
      candidates = {output.name, "measured", "measured_" + output.name, output.name + "_measured"};
    }
    for (const std::string& name : candidates)
      if (const std::optional<std::size_t> column = column_named(name)) {
        if (used_[*column]) {
          diagnostics_.error(header_[*column].range, "column '" + name + "' is already read as an input or the label",
                             {"name the measured column with --measured COLUMN"});
          return;
        }
        measured_use_ = use_of(*column, output);
        data_.measured_column = table_.header[*column].text;
        return;
      }
    std::string tried;
    for (const std::string& name : candidates) tried += (tried.empty() ? "'" : ", '") + name + "'";
    std::vector<std::string> names, notes;
    for (const HeaderColumn& header : header_) names.push_back(header.name);
    for (const std::string& name : candidates)
      if (auto suggestion = closest_name(name, names); suggestion && notes.empty())
        notes.push_back("did you mean '" + *suggestion + "'?");
    notes.push_back("name the column with --measured COLUMN");
    diagnostics_.error(SourceRange{table_.path, 1, 1, 1, 1},
                       "the header has no column of measured '" + output.name + "' (looked for " + tried + ")", notes);
  }

  void note_unused_columns() {
    std::string unused;
    for (std::size_t c = 0; c < header_.size(); ++c)
      if (!used_[c]) unused += (unused.empty() ? "'" : ", '") + table_.header[c].text + "'";
    if (!unused.empty()) note("columns not used: " + unused);
  }

  void note(const std::string& text) {
    if (std::find(data_.notes.begin(), data_.notes.end(), text) == data_.notes.end()) data_.notes.push_back(text);
  }

  // The cell's value in the variable's unit; nullopt after an error.
  std::optional<double> value_of(const CsvCell& cell, const ColumnUse& use, const std::string& what) {
    if (cell.text.empty()) {
      diagnostics_.error(cell.range, "no value for " + what);
      return std::nullopt;
    }
    const std::optional<double> value = parse_number(cell.text);
    if (!value || !std::isfinite(*value)) {
      diagnostics_.error(cell.range, "'" + cell.text + "' is not a finite number (" + what + ")");
      return std::nullopt;
    }
    if (use.from_unit.empty()) return value;
    return convert_unit(*value, use.from_unit, use.to_unit);
  }

  void read_row(const std::vector<CsvCell>& row) {
    if (row.size() != table_.header.size()) {
      diagnostics_.error(row.front().range, "this row has " + std::to_string(row.size()) + " fields, the header " +
                                                std::to_string(table_.header.size()));
      return;
    }
    const int line = row.front().range.line;
    double measured = 0.0;
    if (measured_use_) {
      const CsvCell& cell = row[measured_use_->column];
      if (cell.text.empty()) {
        diagnostics_.warning(cell.range, "missing-measurement", "no measured value: this row is skipped");
        ++data_.skipped_rows;
        return;
      }
      const std::optional<double> value = value_of(cell, *measured_use_, "the measured value");
      if (!value) return;
      measured = *value;
    }
    const std::size_t errors_before = diagnostics_.error_count();
    std::vector<std::vector<double>> points(request_.systems.size());
    std::vector<std::vector<SourceRange>> origins(request_.systems.size());
    for (std::size_t s = 0; s < request_.systems.size(); ++s)
      for (std::size_t i = 0; i < input_uses_[s].size(); ++i) {
        const CsvCell& cell = row[input_uses_[s][i].column];
        const std::optional<double> value =
            value_of(cell, input_uses_[s][i], "input '" + request_.systems[s]->inputs[i].name + "'");
        points[s].push_back(value.value_or(0.0));
        origins[s].push_back(cell.range);
      }
    if (diagnostics_.error_count() > errors_before) return;
    data_.labels.push_back(label_ && !row[*label_].text.empty() ? row[*label_].text : "row " + std::to_string(line));
    data_.lines.push_back(line);
    SourceRange whole = row.front().range;
    whole.end_line = whole.line;
    whole.end_column = row.back().range.end_column;
    data_.rows.push_back(whole);
    if (measured_use_) data_.measured.push_back(measured);
    for (std::size_t s = 0; s < request_.systems.size(); ++s) {
      data_.points[s].push_back(std::move(points[s]));
      data_.origins[s].push_back(std::move(origins[s]));
    }
  }

  const CsvTable& table_;
  const PatientDataRequest& request_;
  DiagnosticList& diagnostics_;
  std::vector<HeaderColumn> header_;
  std::vector<bool> used_;
  std::optional<std::size_t> label_;
  std::vector<std::vector<ColumnUse>> input_uses_;
  std::optional<ColumnUse> measured_use_;
  PatientData data_;
};

}  // namespace

std::optional<PatientData> read_patient_data(const CsvTable& table, const PatientDataRequest& request,
                                             DiagnosticList& diagnostics) {
  return PatientDataReader(table, request, diagnostics).read();
}

std::optional<std::size_t> output_named(const FuzzySystem& system, const std::string& name,
                                        DiagnosticList& diagnostics) {
  if (name.empty()) return std::size_t{0};
  const int index = system.find_output(name);
  if (index >= 0) return static_cast<std::size_t>(index);
  std::vector<std::string> notes;
  if (auto suggestion = closest_name(name, variable_names(system.outputs)))
    notes.push_back("did you mean '" + *suggestion + "'?");
  std::string outputs;
  for (const Variable& v : system.outputs) outputs += (outputs.empty() ? "" : ", ") + v.name;
  notes.push_back("the outputs of '" + system.name + "' are: " + outputs);
  diagnostics.error(SourceRange{"argument --output-variable", 0, 0, 0, 0},
                    "'" + name + "' is not an output of system '" + system.name + "'", notes);
  return std::nullopt;
}

std::string output_file_argument(const std::vector<std::string>& values, const FuzzySystem& system,
                                 DiagnosticList& diagnostics) {
  std::vector<std::string> files;
  for (const std::string& value : values) {
    if (system.find_output(value) < 0) {
      files.push_back(value);
      continue;
    }
    diagnostics.error(SourceRange{"argument --output " + value, 0, 0, 0, 0},
                      "'" + value + "' is an output of system '" + system.name +
                          "', not a file: -o/--output names the file the command writes",
                      {"choose the output with --output-variable " + value + " (-o ./" + value +
                       " writes a file of that name)"});
  }
  if (files.size() > 1)
    diagnostics.error(SourceRange{"argument --output " + files[1], 0, 0, 0, 0},
                      "-o/--output is given twice ('" + files[0] + "' and '" + files[1] + "'); give one file");
  return files.empty() ? "" : files.front();
}

bool parse_column_mappings(const std::vector<std::string>& arguments, std::map<std::string, std::string>& mappings,
                           DiagnosticList& diagnostics) {
  bool ok = true;
  for (const std::string& argument : arguments) {
    const std::size_t eq = argument.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == argument.size()) {
      diagnostics.error(SourceRange{"argument --column " + argument, 0, 0, 0, 0},
                        "expected INPUT=COLUMN (the input's name, then the CSV column that holds it)");
      ok = false;
      continue;
    }
    mappings[argument.substr(0, eq)] = argument.substr(eq + 1);
  }
  return ok;
}

}  // namespace fmpc::cli

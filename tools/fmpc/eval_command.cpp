#include <CLI/CLI.hpp>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <sstream>

#include "compiler/backend/table/lookup_table.h"
#include "compiler/eval/evaluation_report.h"
#include "compiler/eval/interpreter.h"
#include "compiler/frontend/fmpc_language.h"
#include "diagnostics/number_format.h"
#include "kernels/type2_math.h"
#include "runtime/io/input_file.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/csv_table.h"
#include "tools/fmpc/evaluation_points.h"
#include "tools/fmpc/progress_line.h"
#include "tools/fmpc/report_text.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"

namespace fmpc::cli {

namespace {

// The most samples --explain prints (docs/limits.md): about 30 bytes of text each.
constexpr std::size_t kMaxExplainSamplesPerPoint = 100000;
constexpr std::size_t kMaxExplainSamplesTotal = 10000000;

struct EvalOptions {
  std::string file;
  std::vector<std::string> assignments;  // NAME=VALUE
  std::string csv;                       // points file, "-" for stdin
  std::string output = "-";
  std::string system;
  bool explain = false;
  bool summary = false;
  double explain_threshold = 1e-3;
  std::size_t max_warnings = 20;
  std::string semantics = "matlab";
};

std::string with_unit(double value, const Variable& variable) { return value_with_unit(value, variable.unit); }

// Each antecedent clause's grade at `inputs` (hedge, then negation: MATLAB's order, as the interpreter), so that
// --explain shows why a rule fired as strongly as it did. Interval type-2 clauses show [lower, upper].
std::string clause_grades(const FuzzySystem& system, std::size_t rule_index, const std::vector<double>& inputs) {
  const Rule& rule = system.rules[rule_index];
  std::string text;
  for (const Clause& clause : rule.antecedent) {
    const Variable& input = system.inputs[static_cast<std::size_t>(clause.variable)];
    const Term& term = input.terms[static_cast<std::size_t>(clause.term)];
    GradeInterval<double> grade = interval_hedge(term_membership(term, inputs[static_cast<std::size_t>(clause.variable)]),
                                                 hedge_exponent(clause.hedge));
    if (clause.negated) grade = interval_not(grade);
    const std::string hedge = to_string(clause.hedge);
    text += (text.empty() ? "" : ", ") + input.name + " is " + (clause.negated ? "not " : "") +
            (hedge.empty() ? "" : hedge + " ") + term.name + " = " +
            (grade.lower == grade.upper ? four_digits(grade.upper)
                                        : "[" + four_digits(grade.lower) + ", " + four_digits(grade.upper) + "]");
  }
  if (rule.antecedent.empty()) text = "none (the rule always fires)";
  return text;
}

void write_explanation(const FuzzySystem& system, const EvaluationPoint& point, const Explanation& explanation,
                       double threshold, std::ostream& out) {
  out << point.label << ":";
  for (std::size_t i = 0; i < system.inputs.size(); ++i)
    out << (i ? ", " : " ") << system.inputs[i].name << " = " << with_unit(point.inputs[i], system.inputs[i]);
  out << '\n';
  const Evaluation& evaluation = explanation.evaluation;
  for (std::size_t o = 0; o < system.outputs.size(); ++o) {
    out << "  " << system.outputs[o].name << " = " << with_unit(evaluation.outputs[o], system.outputs[o]);
    if (o < evaluation.intervals.size()) {
      const TypeReducedOutput& interval = evaluation.intervals[o];
      out << "  [yl, yr] = [" << format_number(interval.lower) << ", " << format_number(interval.upper) << "]";
    }
    out << '\n';
  }
  const auto& strengths = evaluation.firing_strengths;
  const bool type2 = !evaluation.firing_lower.empty();
  std::size_t shown = 0;
  std::ostringstream rules;
  for (std::size_t r = 0; r < strengths.size(); ++r) {
    if (!(strengths[r] >= threshold)) continue;
    ++shown;
    std::string name = system.rule_display_name(r);
    name.resize(std::max<std::size_t>(name.size(), 8), ' ');
    char strength[64];
    if (type2)
      std::snprintf(strength, sizeof strength, "[%.6f, %.6f]", evaluation.firing_lower[r], strengths[r]);
    else
      std::snprintf(strength, sizeof strength, "%.6f", strengths[r]);
    rules << "    " << name << ' ' << strength << "  " << format_rule_body(system, r) << '\n';
    rules << "    " << std::string(name.size(), ' ') << " clause grades: " << clause_grades(system, r, point.inputs)
          << '\n';
  }
  out << "  rules fired (firing strength " << (type2 ? "[lower, upper], upper " : "") << ">= "
      << format_number(threshold) << "): " << shown << " of " << strengths.size() << '\n'
      << rules.str();
  for (std::size_t o = 0; o < evaluation.intervals.size(); ++o) {
    const TypeReducedOutput& interval = evaluation.intervals[o];
    out << "  type reduction of '" << system.outputs[o].name << "' (" << to_string(interval.method) << "): ";
    if (interval.left_switch < 0) {
      out << "none (" << (evaluation.flags.outputs_no_rule_fired.empty() ? "every weight exact" : "no rule fired")
          << ")\n";
      continue;
    }
    const auto side = [&](const char* end, int k, double x, int iterations) {
      out << end << " switch k = " << k;
      if (k > 0) out << " (after x = " << format_number(x) << ")";
      out << ", " << iterations << (iterations == 1 ? " iteration" : " iterations");
    };
    side("yl", interval.left_switch, interval.left_switch_x, interval.left_iterations);
    out << "; ";
    side("yr", interval.right_switch, interval.right_switch_x, interval.right_iterations);
    out << '\n';
  }
  for (std::size_t o = 0; o < explanation.outputs.size(); ++o) {
    const OutputExplanation& set = explanation.outputs[o];
    const bool intervals = set.membership_lower.size() == set.x.size() && !set.x.empty();
    if (system.type == SystemType::Mamdani)
      out << "  aggregated output set '" << system.outputs[o].name << "' (" << set.x.size()
          << (intervals ? " points, x: [lower, upper]):\n" : " points, x: membership):\n");
    else
      out << "  rule outputs of '" << system.outputs[o].name << "' (" << set.x.size()
          << (intervals ? " rules, value: [lower, upper] weight):\n" : " rules, value: weight):\n");
    const std::size_t per_line = intervals ? 4 : 6;
    for (std::size_t k = 0; k < set.x.size(); ++k) {
      // Sample positions are min + k (max - min) / (n - 1) and carry rounding noise; 6 digits show where they are.
      char cell[96];
      if (intervals)
        std::snprintf(cell, sizeof cell, "%.6g: [%.4f, %.4f]", set.x[k], set.membership_lower[k], set.membership[k]);
      else
        std::snprintf(cell, sizeof cell, "%.6g: %.4f", set.x[k], set.membership[k]);
      out << (k % per_line == 0 ? "    " : "  ") << cell
          << (k % per_line == per_line - 1 || k + 1 == set.x.size() ? "\n" : "");
    }
  }
}

// The points' CSV (`--csv FILE`, or standard input without it), parsed; nullopt with an error when it cannot be
// read or parsed. Its text joins `sources` so that diagnostics can quote it.
std::optional<CsvTable> read_points_csv(const std::string& csv_option, const FuzzySystem& system,
                                        SourceFiles& sources, DiagnosticList& diagnostics) {
  const std::string csv_path = csv_option.empty() ? "-" : csv_option;
  const std::string shown_path = csv_path == "-" ? "<stdin>" : csv_path;
  return read_csv_file(csv_path, shown_path, sim::kMaxCsvFileBytes, "CSV file", SourceRange{shown_path, 0, 0, 0, 0},
                       sources, diagnostics, csv_header_of(system));
}

// ---- lookup tables (.fzt) ----

// Values given for inputs the table fixed at compile time (--fix): accepted where they equal the fixed value, so
// that the points a rule file takes are taken too; an error otherwise. `named` is the input's name as given.
bool check_fixed_value(const LookupTable& table, const std::string& named, const std::string& text,
                       const SourceRange& where, DiagnosticList& diagnostics) {
  for (const TableFixedInput& fixed : table.fixed_inputs) {
    if (fixed.name != named) continue;
    const std::optional<double> value = parse_number(text);
    if (!value || *value != fixed.value)
      diagnostics.error(where, "input '" + named + "' is fixed at " + format_number(fixed.value) +
                                   (fixed.unit.empty() ? "" : " " + fixed.unit) + " in table '" + table.system_name +
                                   "' (compiled with --fix); it cannot be " + text,
                        {"evaluate the rule file instead, or compile a table that varies '" + named + "'"});
    return true;
  }
  return false;
}

int run_eval_table(const EvalOptions& options, const std::string& bytes) {
  DiagnosticList diagnostics;
  SourceFiles sources;
  const std::optional<LookupTable> table = parse_fzt(options.file, bytes, diagnostics);
  if (table) {
    if (options.explain)
      diagnostics.error(kCommandLine,
                        "--explain needs a rule file; '" + options.file + "' is a lookup table (.fzt)",
                        {"fmpc eval the rule file the table was compiled from (" + table->source_path + ")"});
    if (!options.system.empty() && options.system != table->system_name)
      diagnostics.error(kCommandLine,
                        "the table holds system '" + table->system_name + "', not '" + options.system + "'");
  }
  if (!table || diagnostics.has_errors()) {
    print_diagnostics(diagnostics, sources, std::cerr);
    return kExitErrors;
  }
  const FuzzySystem interface = table_interface(*table);
  std::vector<EvaluationPoint> points;
  std::string label_column;  // the points' label column (docs/cli.md), empty without one
  if (!options.assignments.empty() && !options.csv.empty()) {
    diagnostics.error(kCommandLine, "give NAME=VALUE inputs or --csv, not both");
  } else if (!options.assignments.empty()) {
    std::vector<std::string> varying;
    for (const std::string& assignment : options.assignments) {
      const std::size_t eq = assignment.find('=');
      if (eq != std::string::npos &&
          check_fixed_value(*table, assignment.substr(0, eq), assignment.substr(eq + 1),
                            SourceRange{"argument '" + assignment + "'", 0, 0, 0, 0}, diagnostics))
        continue;
      varying.push_back(assignment);
    }
    if (auto point = point_from_assignments(varying, interface, diagnostics)) points.push_back(std::move(*point));
  } else if (std::optional<CsvTable> read = read_points_csv(options.csv, interface, sources, diagnostics)) {
    CsvTable& csv = *read;
    // Columns of fixed inputs: checked against the fixed value, then left out.
    for (std::size_t c = csv.header.size(); c-- > 0;) {
      bool fixed = false;
      for (const TableFixedInput& input : table->fixed_inputs) fixed = fixed || input.name == csv.header[c].text;
      if (!fixed) continue;
      for (auto& row : csv.rows) {
        if (c < row.size()) {
          check_fixed_value(*table, csv.header[c].text, row[c].text, row[c].range, diagnostics);
          row.erase(row.begin() + static_cast<std::ptrdiff_t>(c));
        }
      }
      csv.header.erase(csv.header.begin() + static_cast<std::ptrdiff_t>(c));
    }
    if (!diagnostics.has_errors()) points = points_from_csv(csv, interface, diagnostics, &label_column);
  }
  std::ostringstream csv;
  if (!diagnostics.has_errors()) {
    std::vector<std::string> header = variable_names(interface.inputs);
    if (!label_column.empty()) header.insert(header.begin(), label_column);
    for (const Variable& v : interface.outputs) header.push_back(v.name);
    csv << format_csv_row(header);
    std::vector<const double*> breakpoints;
    std::vector<int> counts;
    const TableView<double> view = view_of(*table, breakpoints, counts);
    std::vector<double> out(interface.outputs.size());
    DiagnosticList point_diagnostics;
    for (const EvaluationPoint& point : points) {
      interpolate_table(view, point.inputs.data(), out.data());
      report_table_inputs(interface, point.inputs, point.origins, point_diagnostics);
      std::vector<std::string> row;
      if (!label_column.empty()) row.push_back(point.name);
      for (double v : point.inputs) row.push_back(format_number(v));
      for (double v : out) row.push_back(format_number(v));
      csv << format_csv_row(row);
    }
    append_capped(point_diagnostics, options.max_warnings, options.file, diagnostics);
  }
  print_diagnostics(diagnostics, sources, std::cerr);
  if (diagnostics.has_errors()) return kExitErrors;
  std::string error;
  if (!write_text_file_atomically(options.output, csv.str(), error)) {
    std::cerr << options.output << ": error: " << error << '\n';
    return kExitErrors;
  }
  return kExitOk;
}
// One row per point: its inputs and outputs to four significant digits and the rule that fired most strongly,
// in aligned columns (units in the header). The exact numbers are in the CSV (-o) and --explain.
class SummaryTable {
 public:
  // `label_column`: the header of the points' label column, which then names the rows; empty without one.
  SummaryTable(const FuzzySystem& system, const std::string& label_column) {
    std::vector<std::string> header{label_column.empty() ? "point" : label_column};
    labelled_ = !label_column.empty();
    for (const auto* variables : {&system.inputs, &system.outputs})
      for (const Variable& v : *variables)
        header.push_back(v.unit.empty() || v.unit == "dimensionless" ? v.name : v.name + " (" + v.unit + ")");
    header.push_back("strongest rule");
    rows_.push_back(std::move(header));
  }
  void add(const FuzzySystem& system, const EvaluationPoint& point, const Evaluation& evaluation) {
    std::vector<std::string> row{point.name.empty() ? std::to_string(rows_.size()) : point.name};
    for (double v : point.inputs) row.push_back(four_digits(v));
    for (double v : evaluation.outputs) row.push_back(four_digits(v));
    std::size_t best = evaluation.firing_strengths.size();
    for (std::size_t r = 0; r < evaluation.firing_strengths.size(); ++r)
      if (evaluation.firing_strengths[r] > 0 &&
          (best == evaluation.firing_strengths.size() || evaluation.firing_strengths[r] > evaluation.firing_strengths[best]))
        best = r;
    row.push_back(best == evaluation.firing_strengths.size()
                      ? "none fired"
                      : system.rule_display_name(best) + " (" + four_digits(evaluation.firing_strengths[best]) + ")");
    rows_.push_back(std::move(row));
  }
  void write(std::ostream& out) const {
    std::vector<std::size_t> widths(rows_.front().size(), 0);
    for (const auto& row : rows_)
      for (std::size_t c = 0; c < row.size(); ++c) widths[c] = std::max(widths[c], row[c].size());
    for (const auto& row : rows_) {
      std::string line;
      for (std::size_t c = 0; c < row.size(); ++c) {
        // Numbers right-aligned, labels and the rule name (last) left-aligned; no trailing spaces.
        const std::string pad(widths[c] - row[c].size(), ' ');
        const bool text = c + 1 == row.size() || (c == 0 && labelled_);
        line += (c ? "  " : "") + (c + 1 == row.size() ? row[c] : text ? row[c] + pad : pad + row[c]);
      }
      out << line << '\n';
    }
  }

 private:
  std::vector<std::vector<std::string>> rows_;
  bool labelled_ = false;
};

Explanation explain_or_evaluate(Interpreter& interpreter, const std::vector<double>& inputs, bool with_sets) {
  if (with_sets) return interpreter.explain(inputs);
  return Explanation{interpreter.evaluate(inputs), {}};
}

int run_eval(const EvalOptions& options) {
  // A table or a rule file, told apart by the first bytes, each read under its own limit.
  std::string error;
  const std::optional<sim::KindOfInput> input = sim::read_input_file(
      options.file,
      {sim::InputKind{"lookup table", sim::kMaxTableFileBytes, fzt_signature()},
       sim::InputKind{"rule file", sim::kMaxRuleFileBytes, ""}},
      error);
  if (!input) {
    DiagnosticList diagnostics;
    diagnostics.error(SourceRange{options.file, 0, 0, 0, 0}, error);
    print_diagnostics(diagnostics, SourceFiles{}, std::cerr);
    return kExitErrors;
  }
  if (input->kind == 0) return run_eval_table(options, input->contents);
  LoadedRuleFile file = sim::load_rule_text(options.file, input->contents);
  if (file.diagnostics.has_errors()) {
    print_diagnostics(file.diagnostics, file.sources, std::cerr);
    return kExitErrors;
  }
  // Lint warnings belong to `fmpc check`; eval reports only what concerns the points it evaluates.
  DiagnosticList diagnostics;
  SourceFiles& sources = file.sources;
  const FuzzySystem* system = select_system(file, options.system, diagnostics);
  std::vector<EvaluationPoint> points;
  std::string label_column;  // the points' label column (docs/cli.md), empty without one
  if (system) {
    if (!options.assignments.empty() && !options.csv.empty()) {
      diagnostics.error(kCommandLine, "give NAME=VALUE inputs or --csv, not both");
    } else if (!options.assignments.empty()) {
      if (auto point = point_from_assignments(options.assignments, *system, diagnostics))
        points.push_back(std::move(*point));
    } else if (options.csv.empty() && ::isatty(STDIN_FILENO) == 1) {
      // Reading CSV from a terminal would wait with no sign of what it waits for: say what it needs instead.
      const std::vector<std::string> names = variable_names(system->inputs);
      std::string header, example;
      for (std::size_t i = 0; i < names.size(); ++i) {
        header += (i ? "," : "") + names[i];
        example += (i ? " " : "") + names[i] + "=" +
                   format_number((system->inputs[i].min + system->inputs[i].max) / 2.0);
      }
      diagnostics.error(kCommandLine,
                        "no points to evaluate: give every input of '" + system->name + "' as NAME=VALUE, or a CSV file",
                        {"for example: fmpc eval " + options.file + " " + example,
                         "or: fmpc eval " + options.file + " --csv points.csv (header row: " + header + ")",
                         "or pipe the CSV on standard input (--csv - reads a terminal too, ending with Ctrl-D)"});
    } else {
      if (const std::optional<CsvTable> csv = read_points_csv(options.csv, *system, sources, diagnostics))
        points = points_from_csv(*csv, *system, diagnostics, &label_column);
    }
  }
  // --explain prints every sample of each output's aggregated set for every point, and builds the sets in memory
  // first: refused above a stated size (docs/limits.md) instead of growing to gigabytes.
  if (system && options.explain && !diagnostics.has_errors() && system->samples > 0) {
    const double per_point = static_cast<double>(system->samples) * static_cast<double>(system->outputs.size());
    const double total = per_point * static_cast<double>(std::max<std::size_t>(points.size(), 1));
    if (per_point > static_cast<double>(kMaxExplainSamplesPerPoint) ||
        total > static_cast<double>(kMaxExplainSamplesTotal)) {
      diagnostics.error(system->range,
                        "--explain would print " + format_number(total) + " samples (" +
                            std::to_string(system->samples) + " per output, " +
                            std::to_string(system->outputs.size()) + " output(s), " + std::to_string(points.size()) +
                            " point(s)); the limits are " + format_number(double(kMaxExplainSamplesPerPoint)) +
                            " per point and " + format_number(double(kMaxExplainSamplesTotal)) +
                            " in all: lower 'samples', explain fewer points, or evaluate without --explain");
    }
  }
  std::ostringstream csv;
  std::ostringstream explanation_text;
  if (system && !diagnostics.has_errors()) {
    std::vector<std::string> header = variable_names(system->inputs);
    if (!label_column.empty()) header.insert(header.begin(), label_column);
    for (const Variable& v : system->outputs) {
      header.push_back(v.name);
      if (system->interval_type2) {
        header.push_back(v.name + ".lower");
        header.push_back(v.name + ".upper");
      }
    }
    csv << format_csv_row(header);
    DiagnosticList point_diagnostics;
    EvaluationOptions evaluation_options;
    evaluation_options.reference = options.semantics == "octave" ? Reference::Octave : Reference::Matlab;
    Interpreter interpreter(*system, evaluation_options);
    SummaryTable summary(*system, label_column);
    ProgressLine progress("eval");  // a million points of a large system take minutes
    for (std::size_t p = 0; p < points.size(); ++p) {
      const EvaluationPoint& point = points[p];
      progress.show_fraction(p, points.size(), "point");
      const Explanation explanation = explain_or_evaluate(interpreter, point.inputs, options.explain);
      report_evaluation_flags(*system, point.inputs, point.origins, point.where, explanation.evaluation,
                              point_diagnostics);
      std::vector<std::string> row;
      if (!label_column.empty()) row.push_back(point.name);
      for (double v : point.inputs) row.push_back(format_number(v));
      const Evaluation& evaluation = explanation.evaluation;
      for (std::size_t o = 0; o < evaluation.outputs.size(); ++o) {
        row.push_back(format_number(evaluation.outputs[o]));
        if (o < evaluation.intervals.size()) {
          row.push_back(format_number(evaluation.intervals[o].lower));
          row.push_back(format_number(evaluation.intervals[o].upper));
        }
      }
      csv << format_csv_row(row);
      if (options.explain) write_explanation(*system, point, explanation, options.explain_threshold, explanation_text);
      if (options.summary) summary.add(*system, point, evaluation);
    }
    progress.finish();
    if (options.summary) summary.write(explanation_text);
    // A large CSV out of range everywhere would bury the terminal: keep the first warnings and count the rest.
    append_capped(point_diagnostics, options.max_warnings, options.file, diagnostics);
  }
  print_diagnostics(diagnostics, sources, std::cerr);
  if (diagnostics.has_errors()) return kExitErrors;
  error.clear();
  if (options.explain || options.summary) {
    std::cout << explanation_text.str();
    if (options.output != "-" && !write_text_file_atomically(options.output, csv.str(), error)) {
      std::cerr << options.output << ": error: " << error << '\n';
      return kExitErrors;
    }
  } else if (!write_text_file_atomically(options.output, csv.str(), error)) {
    std::cerr << options.output << ": error: " << error << '\n';
    return kExitErrors;
  }
  return kExitOk;
}

}  // namespace

void register_eval_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<EvalOptions>();
  CLI::App* command = app.add_subcommand(
      "eval",
      "Evaluate a rule file, or a compiled lookup table (.fzt), at points given as NAME=VALUE, or as CSV with a\n"
      "header row (--csv FILE, or on stdin). Writes CSV (inputs then outputs; interval type-2 outputs add\n"
      "OUTPUT.lower and OUTPUT.upper, the type-reduced interval). A table takes its axes as inputs (values for\n"
      "inputs it fixed must equal them) and clamps values beyond its axes.");
  command->add_option("file", options->file, "Rule file (fmpc, MATLAB .fis, FLL or FCL) or lookup table (.fzt)")
      ->required();
  command->add_option("inputs", options->assignments, "Input values, NAME=VALUE (all inputs)");
  command->add_option("--csv", options->csv, "CSV file of points with a header row naming the inputs; - for stdin");
  command->add_option("-o,--output", options->output, "Where to write the CSV results (default stdout)");
  command->add_option("--system", options->system, "Which system of the file to evaluate");
  command->add_flag("--explain", options->explain,
                    "Print every point's outputs, the rules that fired with their strengths, and the aggregated "
                    "output set (the CSV then goes only to -o)");
  command
      ->add_flag("--summary", options->summary,
                 "Print one aligned row per point instead of CSV: inputs and outputs to 4 significant digits and the "
                 "strongest rule (the CSV then goes only to -o; --explain gives the full account)")
      ->excludes("--explain");
  command
      ->add_option("--explain-threshold", options->explain_threshold,
                   "Smallest firing strength --explain lists (0 lists every rule)")
      ->check(CLI::Range(0.0, 1.0));
  command->add_option("--max-warnings", options->max_warnings, "Most per-point warnings to print");
  command
      ->add_option("--semantics", options->semantics,
                   "Whose numbers to reproduce where MATLAB and Octave's fuzzy-logic-toolkit differ "
                   "(docs/numerics.md)")
      ->check(CLI::IsMember({"matlab", "octave"}));
  command->callback([options, &exit_code] { exit_code = run_eval(*options); });
}

}  // namespace fmpc::cli

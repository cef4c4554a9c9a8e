// fmpc plot: pictures of a rule file (PNG or SVG, tools/plot): a control surface (one output over two inputs, the
// others fixed) as a heat map with contours, the membership functions of one variable (--terms, MATLAB's plotmf),
// or the rule viewer at one input point (--rules, MATLAB's ruleview).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>

#include "compiler/eval/control_surface.h"
#include "compiler/eval/evaluation_report.h"
#include "compiler/eval/interpreter.h"
#include "diagnostics/number_format.h"
#include "kernels/fuzzy_math.h"
#include "kernels/type2_math.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/evaluation_points.h"
#include "tools/fmpc/patient_data.h"
#include "tools/fmpc/progress_line.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"
#include "tools/plot/heat_map.h"
#include "tools/plot/line_chart.h"
#include "tools/plot/rule_view.h"

namespace fmpc::cli {

namespace {

struct PlotOptions {
  std::string file;
  std::string x;
  std::string y;
  std::vector<std::string> fixes;  // NAME=VALUE
  std::string output_variable;     // empty: the first output
  std::string system;
  int resolution = 101;
  std::optional<double> z_min;
  std::optional<double> z_max;
  std::string terms;   // --terms VAR
  bool rules = false;  // --rules
  std::vector<std::string> images;  // -o/--output, as given
  std::string image;                // the one file among them (output_file_argument)
};

// The most rule rows the rule viewer draws before it keeps only the rules that fire.
constexpr std::size_t kMaxRuleRows = 40;

// Index of the variable called `name` among `variables`, or -1 with a located error naming the choices.
int find_variable(const std::vector<Variable>& variables, const std::string& name, const std::string& role,
                  const SourceRange& where, DiagnosticList& diagnostics) {
  for (std::size_t i = 0; i < variables.size(); ++i)
    if (variables[i].name == name) return static_cast<int>(i);
  std::vector<std::string> notes;
  const std::vector<std::string> names = variable_names(variables);
  if (auto suggestion = closest_name(name, names)) notes.push_back("did you mean '" + *suggestion + "'?");
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  notes.push_back("the " + role + "s are: " + list);
  diagnostics.error(where, "'" + name + "' is not an " + role + " of the system", notes);
  return -1;
}

std::string axis_label(const Variable& variable) {
  return variable.unit.empty() || variable.unit == "dimensionless" ? variable.name
                                                                   : variable.name + " (" + variable.unit + ")";
}

// A clause's grade interval at x: the term's [lower, upper] grade, hedged, then negated (MATLAB's order).
GradeInterval<double> clause_interval(const Term& term, const Clause& clause, double x) {
  GradeInterval<double> grade = interval_hedge(term_membership(term, x), hedge_exponent(clause.hedge));
  return clause.negated ? interval_not(grade) : grade;
}

std::vector<double> samples_over(const Variable& variable, std::size_t count) {
  std::vector<double> x(count);
  for (std::size_t k = 0; k < count; ++k)
    x[k] = variable.min + (variable.max - variable.min) * static_cast<double>(k) / static_cast<double>(count - 1);
  return x;
}

// A Sugeno rule's output at `inputs`: the constant, or sum p_i x_i + c (MATLAB's linear output; the interpreter's
// sugeno_rule_value, compiler/eval/interpreter.cpp, is internal to it).
double sugeno_value(const MembershipFunction& mf, const std::vector<double>& inputs) {
  if (mf.kind == MfKind::Constant && !mf.params.empty()) return mf.params[0];
  if (mf.kind != MfKind::Linear || mf.params.size() != inputs.size() + 1) return std::nan("");
  double z = mf.params.back();
  for (std::size_t i = 0; i < inputs.size(); ++i) z += mf.params[i] * inputs[i];
  return z;
}

int write_image(const std::string& path, const std::string& bytes) {
  std::string error;
  if (!write_text_file_atomically(path, bytes, error)) {
    std::cerr << path << ": error: " << error << '\n';
    return kExitErrors;
  }
  return kExitOk;
}

// The membership functions of one variable (MATLAB plotmf): one curve per term, interval type-2 footprints shaded.
int plot_terms(const FuzzySystem& system, const PlotOptions& options, DiagnosticList& diagnostics,
               const SourceFiles& sources) {
  const SourceRange where{"argument --terms", 0, 0, 0, 0};
  const Variable* variable = nullptr;
  bool is_output = false;
  if (system.find_input(options.terms) >= 0) {
    variable = &system.inputs[static_cast<std::size_t>(system.find_input(options.terms))];
  } else if (system.find_output(options.terms) >= 0) {
    variable = &system.outputs[static_cast<std::size_t>(system.find_output(options.terms))];
    is_output = true;
  } else {
    std::vector<std::string> names = variable_names(system.inputs);
    for (const Variable& v : system.outputs) names.push_back(v.name);
    std::vector<std::string> notes;
    if (auto suggestion = closest_name(options.terms, names)) notes.push_back("did you mean '" + *suggestion + "'?");
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    notes.push_back("the variables of '" + system.name + "' are: " + list);
    diagnostics.error(where, "'" + options.terms + "' is not a variable of system '" + system.name + "'", notes);
  }
  if (variable && is_output && system.type == SystemType::Sugeno)
    diagnostics.error(where,
                      "'" + variable->name +
                          "' is a Sugeno output: its terms are constants or linear "
                          "functions of the inputs, not membership functions over a range",
                      {"plot an input's terms, or the rule viewer (--rules) to see each rule's output value"});
  if (diagnostics.has_errors()) {
    print_diagnostics(diagnostics, sources, std::cerr);
    return kExitErrors;
  }
  plot::LineChart chart;
  chart.title.push_back(system.name + ": membership functions of " + (is_output ? "output '" : "input '") +
                        variable->name + "'");
  if (!variable->description.empty()) chart.title.push_back(variable->description);
  chart.x = plot::Axis{variable->min, variable->max, false, axis_label(*variable)};
  chart.y = plot::Axis{0, 1, false, "degree of membership"};
  chart.round_axes = false;
  const std::vector<double> x = samples_over(*variable, static_cast<std::size_t>(std::max(options.resolution, 401)));
  for (std::size_t t = 0; t < variable->terms.size(); ++t) {
    const Term& term = variable->terms[t];
    plot::Series series;
    series.name = term.name + "  " + matlab_name(term.mf.kind);
    series.colour = plot::categorical_colour(t);
    series.x = x;
    for (double v : x) {
      const GradeInterval<double> grade = term_membership(term, v);
      series.y.push_back(grade.upper);
      if (system.interval_type2) series.y_lower.push_back(grade.lower);
    }
    chart.series.push_back(std::move(series));
  }
  if (system.interval_type2) chart.notes.push_back("shaded: footprint of uncertainty (lower to upper)");
  chart.notes.push_back(std::to_string(variable->terms.size()) + " terms on [" + format_number(variable->min) + ", " +
                        format_number(variable->max) + "]");
  print_diagnostics(diagnostics, sources, std::cerr);
  const int status = write_image(options.image, plot::render_line_chart(chart, plot::image_format_for(options.image)));
  if (status == kExitOk)
    std::cout << options.image << ": " << variable->terms.size() << " terms of '" << variable->name << "'\n";
  return status;
}

// MATLAB's ruleview at one point: each rule's clause grades and clipped consequent, each output's aggregate.
int plot_rules(const FuzzySystem& system, const std::vector<double>& point, const PlotOptions& options,
               DiagnosticList& diagnostics, const SourceFiles& sources) {
  if (system.interval_type2) {
    diagnostics.error(SourceRange{"argument --rules", 0, 0, 0, 0},
                      "the rule viewer draws type-1 systems; '" + system.name + "' is interval type-2",
                      {"use `fmpc eval --explain` for its firing intervals and type reduction"});
    print_diagnostics(diagnostics, sources, std::cerr);
    return kExitErrors;
  }
  Interpreter interpreter(system);
  const Explanation explanation = interpreter.explain(point);
  const Evaluation& evaluation = explanation.evaluation;
  const std::size_t count = 201;
  plot::RuleView view;
  view.title.push_back(system.name + ": rules at one point (" + std::string(to_string(system.type)) + ", " +
                       to_string(system.implication) + " implication, " + to_string(system.aggregation) +
                       " aggregation, " + to_string(system.defuzzifier) + ")");
  std::string at;
  for (std::size_t i = 0; i < system.inputs.size(); ++i)
    at += (i ? ", " : "") + system.inputs[i].name + " = " + value_with_unit(point[i], system.inputs[i].unit);
  view.title.push_back(at);
  for (std::size_t i = 0; i < system.inputs.size(); ++i) {
    view.input_titles.push_back(system.inputs[i].name + " = " + format_number(point[i]));
    view.input_ranges.push_back({system.inputs[i].min, system.inputs[i].max});
  }
  for (std::size_t o = 0; o < system.outputs.size(); ++o) {
    char value[32];
    std::snprintf(value, sizeof value, "%.4g", evaluation.outputs[o]);
    const Variable& output = system.outputs[o];
    view.output_titles.push_back(output.name + " = " + value +
                                 (output.unit.empty() || output.unit == "dimensionless" ? "" : " " + output.unit));
    view.output_ranges.push_back({system.outputs[o].min, system.outputs[o].max});
  }
  // MATLAB shows every rule; past kMaxRuleRows rows a figure stops being readable, so then only the strongest
  // kMaxRuleRows rules at this point are drawn (in file order), and the title says how strong the others are.
  std::vector<bool> drawn(system.rules.size(), true);
  // Sugeno stems are drawn as tall as each rule's weight relative to the strongest rule's.
  const double strongest = evaluation.firing_strengths.empty() ? 0.0
                                                               : *std::max_element(evaluation.firing_strengths.begin(),
                                                                                   evaluation.firing_strengths.end());
  std::vector<std::vector<std::pair<double, double>>> sugeno_stems(system.outputs.size());
  if (system.type == SystemType::Sugeno) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "stems: each rule's output, as tall as its weight relative to the strongest rule's (%.3g)",
                  strongest);
    view.title.push_back(text);
  }
  if (system.rules.size() > kMaxRuleRows) {
    std::vector<std::size_t> order(system.rules.size());
    for (std::size_t r = 0; r < order.size(); ++r) order[r] = r;
    const auto& s = evaluation.firing_strengths;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return s[a] > s[b]; });
    double rest = 0;
    for (std::size_t k = kMaxRuleRows; k < order.size(); ++k) {
      drawn[order[k]] = false;
      rest = std::max(rest, s[order[k]]);
    }
    char text[160];
    std::snprintf(text, sizeof text, "the %zu strongest of %zu rules here; the other %zu fire at most %.3g",
                  kMaxRuleRows, system.rules.size(), system.rules.size() - kMaxRuleRows, rest);
    view.title.push_back(text);
  }
  for (std::size_t r = 0; r < system.rules.size(); ++r) {
    const Rule& rule = system.rules[r];
    const double strength = evaluation.firing_strengths[r];
    if (!drawn[r]) continue;
    char title[64];
    std::snprintf(title, sizeof title, ": %.3g", strength);
    view.rule_titles.push_back(system.rule_display_name(r) + title);
    std::vector<plot::RulePanel> inputs(system.inputs.size()), outputs(system.outputs.size());
    for (const Clause& clause : rule.antecedent) {
      const Variable& input = system.inputs[static_cast<std::size_t>(clause.variable)];
      const Term& term = input.terms[static_cast<std::size_t>(clause.term)];
      plot::RulePanel& panel = inputs[static_cast<std::size_t>(clause.variable)];
      panel.present = true;
      panel.x = samples_over(input, count);
      panel.grade = clause_interval(term, clause, point[static_cast<std::size_t>(clause.variable)]).upper;
      for (double x : panel.x) {
        const double mu = clause_interval(term, clause, x).upper;
        panel.membership.push_back(mu);
        panel.filled.push_back(std::min(mu, panel.grade));
      }
      panel.marker = point[static_cast<std::size_t>(clause.variable)];
    }
    for (const Clause& clause : rule.consequent) {
      const auto o = static_cast<std::size_t>(clause.variable);
      const Variable& output = system.outputs[o];
      plot::RulePanel& panel = outputs[o];
      panel.present = true;
      if (system.type == SystemType::Mamdani) {
        const Term& term = output.terms[static_cast<std::size_t>(clause.term)];
        panel.x = samples_over(output, count);
        for (double x : panel.x) {
          const double mu = clause_interval(term, clause, x).upper;
          panel.membership.push_back(mu);
          panel.filled.push_back(tnorm(system.implication, strength, mu));
        }
      } else {
        panel.marker = sugeno_value(output.terms[static_cast<std::size_t>(clause.term)].mf, point);
        panel.grade = strongest > 0 ? strength / strongest : 0.0;
        sugeno_stems[o].push_back({panel.marker, panel.grade});
      }
    }
    view.inputs.push_back(std::move(inputs));
    view.outputs.push_back(std::move(outputs));
  }
  for (std::size_t o = 0; o < system.outputs.size(); ++o) {
    plot::RulePanel panel;
    panel.present = true;
    panel.marker = evaluation.outputs[o];
    if (system.type == SystemType::Mamdani && o < explanation.outputs.size()) {
      panel.x = explanation.outputs[o].x;
      panel.membership = explanation.outputs[o].membership;
      panel.filled = explanation.outputs[o].membership;
    }
    panel.stems = sugeno_stems[o];
    view.aggregate.push_back(std::move(panel));
  }
  view.aggregate_title = system.type == SystemType::Mamdani ? "aggregate" : "weighted average";
  for (int o : evaluation.flags.outputs_no_rule_fired)
    diagnostics.warning(kCommandLine, "no-rule-fired",
                        "no rule fired for output '" + system.outputs[static_cast<std::size_t>(o)].name +
                            "' at this point; the no-fire policy set it to " +
                            format_number(evaluation.outputs[static_cast<std::size_t>(o)]));
  print_diagnostics(diagnostics, sources, std::cerr);
  const int status = write_image(options.image, plot::render_rule_view(view, plot::image_format_for(options.image)));
  if (status == kExitOk) {
    std::cout << options.image << ": " << system.rules.size() << " rules at " << at << ";";
    for (std::size_t o = 0; o < system.outputs.size(); ++o)
      std::cout << ' ' << system.outputs[o].name << " = "
                << value_with_unit(evaluation.outputs[o], system.outputs[o].unit);
    std::cout << '\n';
  }
  return status;
}

int run_plot(PlotOptions options) {
  LoadedRuleFile file = load_rule_file_from_disk(options.file);
  if (file.diagnostics.has_errors()) {
    print_diagnostics(file.diagnostics, file.sources, std::cerr);
    return kExitErrors;
  }
  DiagnosticList diagnostics;
  const FuzzySystem* found = select_system(file, options.system, diagnostics);
  if (!found) {
    print_diagnostics(diagnostics, file.sources, std::cerr);
    return kExitErrors;
  }
  const FuzzySystem& system = *found;
  options.image = output_file_argument(options.images, system, diagnostics);
  const int modes = !options.terms.empty() + options.rules + (!options.x.empty() || !options.y.empty());
  if (modes != 1 || diagnostics.has_errors()) {
    if (modes != 1)
      diagnostics.error(kCommandLine,
                        modes == 0 ? "nothing to plot: give --x IN --y IN (a surface), --terms VAR or --rules"
                                   : "give one of --x/--y (a surface), --terms VAR or --rules",
                        {"fmpc plot --help lists the options of each"});
    print_diagnostics(diagnostics, file.sources, std::cerr);
    return kExitErrors;
  }
  if (!options.terms.empty()) return plot_terms(system, options, diagnostics, file.sources);
  const bool surface = !options.rules;
  int ix = -1, iy = -1;
  if (surface) {
    if (options.x.empty() || options.y.empty())
      diagnostics.error(SourceRange{options.x.empty() ? "argument --x" : "argument --y", 0, 0, 0, 0},
                        "a surface needs both --x and --y");
    if (!options.x.empty())
      ix = find_variable(system.inputs, options.x, "input", SourceRange{"argument --x", 0, 0, 0, 0}, diagnostics);
    if (!options.y.empty())
      iy = find_variable(system.inputs, options.y, "input", SourceRange{"argument --y", 0, 0, 0, 0}, diagnostics);
  }
  if (ix >= 0 && ix == iy)
    diagnostics.error(SourceRange{"argument --y", 0, 0, 0, 0}, "--x and --y both name '" + options.x + "'",
                      {"a surface needs two different inputs"});
  int io = 0;
  if (!options.output_variable.empty())
    io = find_variable(system.outputs, options.output_variable, "output", SourceRange{"argument --output-variable", 0, 0, 0, 0},
                       diagnostics);
  else if (system.outputs.empty())
    diagnostics.error(system.range, "system '" + system.name + "' has no output to plot");

  // Inputs not on an axis sit at the middle of their range unless fixed (MATLAB gensurf's reference inputs).
  std::vector<double> point(system.inputs.size());
  for (std::size_t i = 0; i < system.inputs.size(); ++i) point[i] = (system.inputs[i].min + system.inputs[i].max) / 2.0;
  std::vector<bool> fixed(system.inputs.size(), false);
  for (const std::string& assignment : options.fixes) {
    const SourceRange where{"argument --fix " + assignment, 0, 0, 0, 0};
    const std::size_t eq = assignment.find('=');
    if (eq == std::string::npos) {
      diagnostics.error(where, "expected NAME=VALUE", {"for example: --fix " + system.inputs.front().name + "=7.5"});
      continue;
    }
    const int index = find_variable(system.inputs, assignment.substr(0, eq), "input", where, diagnostics);
    if (index < 0) continue;
    const auto i = static_cast<std::size_t>(index);
    if (index == ix || index == iy) {
      diagnostics.error(where, "'" + system.inputs[i].name + "' is on an axis and cannot also be fixed");
      continue;
    }
    if (fixed[i]) diagnostics.error(where, "input '" + system.inputs[i].name + "' is fixed twice");
    const std::string text = assignment.substr(eq + 1);
    char* end = nullptr;
    errno = 0;
    const double value = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(value)) {
      diagnostics.error(where, "'" + text + "' is not a finite number (input '" + system.inputs[i].name + "')");
      continue;
    }
    if (value < system.inputs[i].min || value > system.inputs[i].max)
      diagnostics.warning(where, "input-out-of-range",
                          "input '" + system.inputs[i].name + "' = " + format_number(value) + " is outside [" +
                              format_number(system.inputs[i].min) + ", " + format_number(system.inputs[i].max) +
                              "]; evaluated as given");
    fixed[i] = true;
    point[i] = value;
  }
  if (options.z_min && options.z_max && !(*options.z_max > *options.z_min))
    diagnostics.error(SourceRange{"argument --zmax", 0, 0, 0, 0}, "--zmax must be greater than --zmin");
  if (diagnostics.has_errors()) {
    print_diagnostics(diagnostics, file.sources, std::cerr);
    return kExitErrors;
  }
  if (!surface) return plot_rules(system, point, options, diagnostics, file.sources);

  const auto n = static_cast<std::size_t>(options.resolution);
  const Variable& x_input = system.inputs[static_cast<std::size_t>(ix)];
  const Variable& y_input = system.inputs[static_cast<std::size_t>(iy)];
  const Variable& output = system.outputs[static_cast<std::size_t>(io)];
  ProgressLine progress("plot");  // 1001 x 1001 points of a 100,000-rule system take minutes
  const ControlSurface grid = control_surface(
      system, static_cast<std::size_t>(ix), static_cast<std::size_t>(iy), static_cast<std::size_t>(io), point, n, {},
      [&](std::size_t row, std::size_t rows) { progress.show_fraction(row, rows, "row"); });
  progress.finish();
  plot::HeatMap map;
  map.x = grid.x;
  map.y = grid.y;
  map.z = grid.z;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (double z : map.z)
    if (!std::isnan(z)) {
      lo = std::min(lo, z);
      hi = std::max(hi, z);
    }
  const std::size_t nan_count = grid.nan_points;
  if (nan_count > 0)
    diagnostics.warning(kCommandLine, "nan-output",
                        std::to_string(nan_count) + " of " + std::to_string(n * n) +
                            " points evaluate to NaN (drawn grey): no rule fired under `when no rule fires: error`");
  map.z_min = options.z_min.value_or(std::isfinite(lo) ? lo : 0.0);
  map.z_max = options.z_max.value_or(std::isfinite(hi) ? hi : 1.0);
  if (!(map.z_max > map.z_min)) map.z_max = map.z_min + 1.0;  // a flat surface still gets a colour bar
  map.x_label = axis_label(x_input);
  map.y_label = axis_label(y_input);
  map.z_label = axis_label(output);
  map.title.push_back(system.name + ": " + output.name + " over " + x_input.name + ", " + y_input.name);
  // The inputs held fixed, with their units and whether the user fixed them or they sit mid-range.
  std::string rest;
  for (std::size_t i = 0; i < system.inputs.size(); ++i) {
    if (static_cast<int>(i) == ix || static_cast<int>(i) == iy) continue;
    rest += (rest.empty() ? "fixed: " : ", ") + system.inputs[i].name + " = " +
            value_with_unit(point[i], system.inputs[i].unit) + (fixed[i] ? "" : " (mid-range)");
  }
  if (!rest.empty()) map.title.push_back(rest);

  print_diagnostics(diagnostics, file.sources, std::cerr);
  if (write_image(options.image, plot::render_heat_map(map, plot::image_format_for(options.image))) != kExitOk)
    return kExitErrors;
  std::cout << options.image << ": " << output.name << " from " << format_number(lo) << " to " << format_number(hi)
            << (output.unit.empty() ? "" : " " + output.unit) << " over " << n << " x " << n
            << " points; colour scale [" << format_number(map.z_min) << ", " << format_number(map.z_max) << "]\n";
  return kExitOk;
}

}  // namespace

void register_plot_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<PlotOptions>();
  CLI::App* command = app.add_subcommand(
      "plot",
      "Draw a rule file (PNG, or SVG for -o NAME.svg): a control surface (--x IN --y IN: one output over two\n"
      "inputs as a heat map with contours, the other inputs fixed with --fix NAME=VALUE or mid-range, as MATLAB's\n"
      "gensurf), the membership functions of a variable (--terms VAR, as plotmf), or the rule viewer at one point\n"
      "(--rules, inputs from --fix or mid-range, as ruleview).");
  command->add_option("file", options->file, "Rule file (fmpc or MATLAB .fis)")->required();
  command->add_option("--x", options->x, "Surface: input on the horizontal axis");
  command->add_option("--y", options->y, "Surface: input on the vertical axis");
  command->add_option("--terms", options->terms, "Draw the membership functions of this input or output");
  command->add_flag("--rules", options->rules,
                    "Draw the rule viewer: each rule's clause grades and clipped consequent, the aggregate and the "
                    "crisp output, at the point --fix gives (other inputs mid-range)");
  command->add_option("--fix", options->fixes,
                      "NAME=VALUE for an input not on an axis, or of the rule viewer's point (repeatable)");
  command->add_option("--output-variable", options->output_variable, "Surface: output to plot (default: the first)");
  command->add_option("--system", options->system, "Which system of the file (when it holds several)");
  command->add_option("--resolution", options->resolution, "Surface: grid points per axis")->check(CLI::Range(2, 1001));
  command->add_option("--zmin", options->z_min, "Surface: output value at the bottom of the colour scale");
  command->add_option("--zmax", options->z_max, "Surface: output value at the top of the colour scale");
  command->add_option("-o,--output,--image,--png", options->images, "Picture to write: .svg for SVG, else PNG")
      ->required()
      ->allow_extra_args(false);
  command->callback([options, &exit_code] { exit_code = run_plot(*options); });
}

}  // namespace fmpc::cli

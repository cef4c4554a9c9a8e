// fmpc plot: a control surface (one output over two inputs, the others fixed) as a PNG heat map.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>

#include "compiler/eval/interpreter.h"
#include "diagnostics/number_format.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"
#include "tools/plot/heat_map.h"

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
  std::string png;
};

const SourceRange kCommandLine{"command line", 0, 0, 0, 0};

std::vector<std::string> names_of(const std::vector<Variable>& variables) {
  std::vector<std::string> names;
  for (const Variable& v : variables) names.push_back(v.name);
  return names;
}

// Index of the variable called `name` among `variables`, or -1 with a located error naming the choices.
int find_variable(const std::vector<Variable>& variables, const std::string& name, const std::string& role,
                  const SourceRange& where, DiagnosticList& diagnostics) {
  for (std::size_t i = 0; i < variables.size(); ++i)
    if (variables[i].name == name) return static_cast<int>(i);
  std::vector<std::string> notes;
  const std::vector<std::string> names = names_of(variables);
  if (auto suggestion = closest_name(name, names)) notes.push_back("did you mean '" + *suggestion + "'?");
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  notes.push_back("the " + role + "s are: " + list);
  diagnostics.error(where, "'" + name + "' is not an " + role + " of the system", notes);
  return -1;
}

std::string axis_label(const Variable& variable) {
  return variable.unit.empty() ? variable.name : variable.name + " (" + variable.unit + ")";
}

int run_plot(const PlotOptions& options) {
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
  const int ix = find_variable(system.inputs, options.x, "input", SourceRange{"argument --x", 0, 0, 0, 0}, diagnostics);
  const int iy = find_variable(system.inputs, options.y, "input", SourceRange{"argument --y", 0, 0, 0, 0}, diagnostics);
  if (ix >= 0 && ix == iy)
    diagnostics.error(SourceRange{"argument --y", 0, 0, 0, 0}, "--x and --y both name '" + options.x + "'",
                      {"a surface needs two different inputs"});
  int io = 0;
  if (!options.output_variable.empty())
    io = find_variable(system.outputs, options.output_variable, "output", SourceRange{"argument --output", 0, 0, 0, 0},
                       diagnostics);
  else if (system.outputs.empty())
    diagnostics.error(system.range, "system '" + system.name + "' has no output to plot");

  // Inputs not on an axis sit at the middle of their range unless fixed (MATLAB gensurf's reference inputs).
  std::vector<double> point(system.inputs.size());
  for (std::size_t i = 0; i < system.inputs.size(); ++i)
    point[i] = (system.inputs[i].min + system.inputs[i].max) / 2.0;
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

  const auto n = static_cast<std::size_t>(options.resolution);
  const Variable& x_input = system.inputs[static_cast<std::size_t>(ix)];
  const Variable& y_input = system.inputs[static_cast<std::size_t>(iy)];
  const Variable& output = system.outputs[static_cast<std::size_t>(io)];
  plot::HeatMap map;
  map.x.resize(n);
  map.y.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / static_cast<double>(n - 1);
    map.x[k] = x_input.min + t * (x_input.max - x_input.min);
    map.y[k] = y_input.min + t * (y_input.max - y_input.min);
  }
  map.z.resize(n * n);
  Interpreter interpreter(system);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  std::size_t nan_count = 0;
  for (std::size_t r = 0; r < n; ++r)
    for (std::size_t c = 0; c < n; ++c) {
      point[static_cast<std::size_t>(ix)] = map.x[c];
      point[static_cast<std::size_t>(iy)] = map.y[r];
      const double z = interpreter.evaluate(point).outputs[static_cast<std::size_t>(io)];
      map.z[r * n + c] = z;
      if (std::isnan(z)) {
        ++nan_count;
        continue;
      }
      lo = std::min(lo, z);
      hi = std::max(hi, z);
    }
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
  std::string rest;
  for (std::size_t i = 0; i < system.inputs.size(); ++i) {
    if (static_cast<int>(i) == ix || static_cast<int>(i) == iy) continue;
    const std::string item = system.inputs[i].name + "=" + format_number(point[i]);
    if (!rest.empty() && (rest.size() + item.size() + 1) * 12 > 600) {
      map.title.push_back(rest);
      rest.clear();
    }
    rest += (rest.empty() ? "" : " ") + item;
  }
  if (!rest.empty()) map.title.push_back(rest);
  if (map.title.size() > 3) map.title.resize(3);  // the space above the plot holds three lines

  print_diagnostics(diagnostics, file.sources, std::cerr);
  std::string error;
  if (!write_text_file_atomically(options.png, plot::encode_png(plot::render_heat_map(map)), error)) {
    std::cerr << options.png << ": error: " << error << '\n';
    return kExitErrors;
  }
  std::cout << options.png << ": " << output.name << " from " << format_number(lo) << " to " << format_number(hi)
            << (output.unit.empty() ? "" : " " + output.unit) << " over " << n << " x " << n
            << " points; colour scale [" << format_number(map.z_min) << ", " << format_number(map.z_max) << "]\n";
  return diagnostics.warning_count() > 0 ? kExitWarnings : kExitOk;
}

}  // namespace

void register_plot_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<PlotOptions>();
  CLI::App* command = app.add_subcommand(
      "plot",
      "Draw a control surface as a PNG heat map: one output over two inputs on an N x N grid, the other inputs\n"
      "fixed (--fix NAME=VALUE; unfixed ones sit mid-range, as MATLAB's gensurf). Give several files the same\n"
      "--zmin/--zmax to compare them on one colour scale. Exit status: 0 done, 1 warnings, 2 errors.");
  command->add_option("file", options->file, "Rule file (fmpc or MATLAB .fis)")->required();
  command->add_option("--x", options->x, "Input on the horizontal axis")->required();
  command->add_option("--y", options->y, "Input on the vertical axis")->required();
  command->add_option("--fix", options->fixes, "NAME=VALUE for an input not on an axis (repeatable)");
  command->add_option("--output", options->output_variable, "Output to plot (default: the first)");
  command->add_option("--system", options->system, "Which system of the file (when it holds several)");
  command->add_option("--resolution", options->resolution, "Grid points per axis")
      ->check(CLI::Range(2, 1001))
      ->default_val(101);
  command->add_option("--zmin", options->z_min, "Output value at the bottom of the colour scale");
  command->add_option("--zmax", options->z_max, "Output value at the top of the colour scale");
  command->add_option("-o,--png", options->png, "PNG file to write")->required();
  command->callback([options, &exit_code] { exit_code = run_plot(*options); });
}

}  // namespace fmpc::cli

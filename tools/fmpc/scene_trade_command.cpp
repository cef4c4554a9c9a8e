// fmpc trade SCENE.yaml: the scene run as variants (force model, precision, integrator and step, mesh refinement)
// against a co-rotational FEM reference, measured on this machine (runtime/scene/simulation_trade.h).
// docs/trade.md, "Scenes", explains how to read the table and the plot.
#include "tools/fmpc/scene_trade_command.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <utility>

#include "diagnostics/number_format.h"
#include "runtime/scene/scene_file.h"
#include "runtime/io/memory_limit.h"
#include "runtime/scene/simulation_trade.h"
#include "tools/fmpc/progress_line.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"
#include "tools/plot/pareto_plot.h"

namespace fmpc::cli {

namespace {

const char* const kRuleOptions[] = {"--system",          "--fix",         "--vary", "--points", "--seed",
                                    "--resolutions",     "--max-grid-points", "--min-seconds", "--cxx",
                                    "--cxx-flags"};
const char* const kSceneOptions[] = {"--models",   "--precisions", "--integrators", "--refinements",
                                     "--reference-refinements", "--reference-dt-factor", "--duration"};

std::string join(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) text += (i ? ", " : "") + names[i];
  return text;
}

std::vector<std::string> given(CLI::App& command, const char* const* begin, const char* const* end) {
  std::vector<std::string> names;
  for (const char* const* name = begin; name != end; ++name)
    if (const CLI::Option* option = command.get_option_no_throw(*name); option && option->count() > 0)
      names.emplace_back(*name);
  return names;
}

// The arguments as library options; errors name the argument.
// Every --models name (sim::trade_models' order) joined by ", ", the last by `last`.
std::string trade_model_names(const std::string& last) {
  const std::vector<sim::TradeModel> models = sim::trade_models();
  std::string text;
  for (std::size_t i = 0; i < models.size(); ++i)
    text += (i == 0 ? "" : i + 1 == models.size() ? last : ", ") + sim::trade_model_name(models[i]);
  return text;
}

std::optional<sim::SimulationTradeOptions> trade_options(const SceneTradeArguments& arguments,
                                                         DiagnosticList& diagnostics) {
  sim::SimulationTradeOptions options;
  const SourceRange nowhere{};
  if (!arguments.models.empty()) {
    options.models.clear();
    for (const std::string& name : arguments.models) {
      if (const auto model = sim::parse_trade_model(name)) options.models.push_back(*model);
      else
        diagnostics.error(nowhere, "--models: '" + name + "' is not a model; use " + trade_model_names(" or "));
    }
  }
  if (!arguments.precisions.empty()) {
    options.precisions.clear();
    for (const std::string& name : arguments.precisions) {
      if (name == "float") options.precisions.push_back(sim::Precision::Float);
      else if (name == "double") options.precisions.push_back(sim::Precision::Double);
      else diagnostics.error(nowhere, "--precisions: '" + name + "' is not a precision; use float or double");
    }
  }
  if (!arguments.integrators.empty()) {
    options.integrators.clear();
    for (const std::string& text : arguments.integrators) {
      const std::size_t colon = text.find(':');
      const std::string name = text.substr(0, colon);
      std::optional<sim::Integrator> integrator;
      for (const sim::Integrator candidate :
           {sim::Integrator::ForwardEuler, sim::Integrator::SemiImplicitEuler, sim::Integrator::VelocityVerlet,
            sim::Integrator::RungeKutta4, sim::Integrator::ImplicitEuler})
        if (name == sim::scene_name(candidate)) integrator = candidate;
      if (!integrator) {
        diagnostics.error(nowhere, "--integrators: '" + name + "' is not an integrator; use forward_euler, "
                                   "semi_implicit_euler, velocity_verlet, rk4 or implicit_euler, each optionally "
                                   "with :FACTOR (its step in automatic steps, e.g. implicit_euler:4)");
        continue;
      }
      // Implicit Euler is stable at any step: by default it takes 4 automatic steps at once.
      double factor = *integrator == sim::Integrator::ImplicitEuler ? 4.0 : 1.0;
      if (colon != std::string::npos) {
        const std::string number = text.substr(colon + 1);
        char* end = nullptr;
        factor = std::strtod(number.c_str(), &end);
        if (number.empty() || end != number.c_str() + number.size() || !(factor > 0.0) || !std::isfinite(factor) ||
            factor > 1e6) {
          diagnostics.error(nowhere, "--integrators: '" + text + "': the factor after ':' must be a positive number "
                                     "of automatic steps (at most 1e6)");
          continue;
        }
      }
      options.integrators.push_back({*integrator, factor});
    }
  }
  if (!arguments.refinements.empty()) options.refinements = arguments.refinements;
  options.reference_refinements = arguments.reference_refinements;
  if (arguments.reference_dt_factor) options.reference_dt_factor = *arguments.reference_dt_factor;
  options.duration = arguments.duration;
  if (diagnostics.has_errors()) return std::nullopt;
  return options;
}

}  // namespace

std::shared_ptr<SceneTradeArguments> add_scene_trade_options(CLI::App& command) {
  auto arguments = std::make_shared<SceneTradeArguments>();
  command.add_option("--models", arguments->models,
                     "Scenes: force models (" + trade_model_names(", ") + "; default all)")
      ->delimiter(',');
  command.add_option("--precisions", arguments->precisions, "Scenes: float, double (default both)")->delimiter(',');
  command.add_option("--integrators", arguments->integrators,
                     "Scenes: NAME[:FACTOR], the step FACTOR x semi-implicit Euler's automatic step (default "
                     "semi_implicit_euler,implicit_euler:4)")
      ->delimiter(',');
  command.add_option("--refinements", arguments->refinements,
                     "Scenes: 1:8 mesh refinements of the variants (default 0,1)")
      ->delimiter(',')
      ->check(CLI::Range(0u, sim::kMaxTradeRefinements));
  command.add_option("--reference-refinements", arguments->reference_refinements,
                     "Scenes: refinements of the reference (default: the finest of --refinements)")
      ->check(CLI::Range(0u, sim::kMaxTradeRefinements));
  command.add_option("--reference-dt-factor", arguments->reference_dt_factor,
                     "Scenes: the reference's step in automatic steps (default 0.5)");
  command.add_option("--duration", arguments->duration, "Scenes: simulated seconds (default: the scene's)");
  return arguments;
}

bool is_scene_path(const std::string& path) {
  const auto ends_with = [&](const std::string& suffix) {
    return path.size() >= suffix.size() && path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  return ends_with(".yaml") || ends_with(".yml");
}

int refuse_scene_options(CLI::App& command, const std::string& file) {
  const std::vector<std::string> names = given(command, std::begin(kSceneOptions), std::end(kSceneOptions));
  if (names.empty()) return kExitOk;
  std::cerr << "fmpc trade: error: " << join(names) << (names.size() == 1 ? " applies" : " apply")
            << " to scene files (.yaml); '" << file << "' is a rule file\n";
  return kExitErrors;
}

int run_scene_trade(CLI::App& command, const std::string& scene_path, const std::string& csv,
                    const std::string& markdown, const std::string& plot, const SceneTradeArguments& arguments) {
  DiagnosticList diagnostics;
  SourceFiles sources;
  // Errors about the command line (no file) are the command's, as the rule side words them.
  const auto report = [&] {
    DiagnosticList located;
    for (Diagnostic d : diagnostics.items()) {
      if (d.range.file.empty()) d.range.file = "fmpc trade";
      located.add(std::move(d));
    }
    located.sort_by_position();
    print_diagnostics(located, sources, std::cerr);
  };
  const std::vector<std::string> rule_options = given(command, std::begin(kRuleOptions), std::end(kRuleOptions));
  if (!rule_options.empty()) {
    std::cerr << "fmpc trade: error: " << join(rule_options) << (rule_options.size() == 1 ? " applies" : " apply")
              << " to rule files; '" << scene_path << "' is a scene (docs/trade.md lists the scene options)\n";
    return kExitErrors;
  }
  std::optional<sim::SimulationTradeOptions> options = trade_options(arguments, diagnostics);
  if (!options) {
    report();
    return kExitErrors;
  }
  std::string read_error;
  const std::optional<std::string> text = read_text_file(scene_path, sim::kMaxSceneFileBytes, "scene file", read_error);
  if (!text) {
    diagnostics.error(SourceRange{scene_path, 0, 0, 0, 0}, read_error);
    report();
    return kExitErrors;
  }
  sources.add(scene_path, *text);
  const std::optional<sim::Scene> scene = sim::parse_scene(scene_path, *text, diagnostics);
  if (!scene) {
    report();
    return kExitErrors;
  }
  // What the runs will cost, said before they start; then progress by work done (tetrahedra x steps), which the
  // runs' times follow, with the time left.
  ProgressLine progress("trade");
  std::string running;
  options->plan = [](const sim::TradePlan& plan) {
    const auto three_digits = [](double value) {
      char digits[32];
      std::snprintf(digits, sizeof digits, "%.3g", value);
      return std::string(digits);
    };
    std::cerr << "fmpc trade: " << plan.runs << " runs, about " << three_digits(plan.element_steps)
              << " element-steps in all (the largest run " << three_digits(plan.largest_tetrahedra)
              << " tetrahedra, the longest " << three_digits(plan.largest_steps) << " steps, at most "
              << sim::gibibytes_text(plan.largest_memory_bytes) << " of memory)" << std::endl;
  };
  options->progress = [&](std::size_t done, std::size_t total, const std::string& what) {
    running = "run " + std::to_string(std::min(done + 1, total)) + " of " + std::to_string(total) + " (" + what + ")";
  };
  options->work_progress = [&](double done, double total) { progress.show_fraction(done, total, running + ", work"); };
  const std::optional<sim::SimulationTradeResult> result = sim::run_simulation_trade(*scene, *options, diagnostics);
  progress.finish();
  report();
  if (!result) return kExitErrors;

  const std::string table = sim::simulation_trade_markdown(*result);
  std::cout << table;
  std::vector<std::pair<std::string, std::string>> writes;  // all or none
  if (!markdown.empty()) writes.emplace_back(markdown, table);
  if (!csv.empty()) writes.emplace_back(csv, sim::simulation_trade_csv(*result));
  if (!plot.empty()) {
    plot::TradePlot figure;
    figure.error_unit = "displacement, relative";
    figure.speed_label = "steps per CPU second (one thread)";
    figure.title = {"fmpc trade: scene " + result->scene_name,
                    format_number(result->duration) + " s, CPU, one thread, against the FEM reference"};
    for (const sim::SimulationTradeRow& row : result->rows)
      if (row.completed && row.steps_per_second > 0.0)
        figure.points.push_back(
            {row.variant, row.steps_per_second, row.errors.displacement_max, sim::trade_model_name(row.model)});
    // Only the front is labelled: the dominated variants crowd together (the CSV names every point).
    const std::vector<std::size_t> front = plot::pareto_front(figure.points);
    for (std::size_t i = 0; i < figure.points.size(); ++i)
      if (std::find(front.begin(), front.end(), i) == front.end()) figure.points[i].label.clear();
    writes.emplace_back(plot, plot::render_trade_plot(figure, plot::image_format_for(plot)));
  }
  std::string error;
  if (!write_text_files_atomically(writes, error)) {
    std::cerr << "fmpc trade: error: " << error << '\n';
    return kExitErrors;
  }
  return kExitOk;
}

}  // namespace fmpc::cli

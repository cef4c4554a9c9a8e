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
#include "runtime/fem/element_law_registry.h"
#include "runtime/scene/simulation_trade.h"
#if defined(FMPC_RUNTIME_HAVE_CUDA)
#include "runtime/gpu/gpu_simulation.h"
#endif
#include "tools/fmpc/progress_line.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"
#include "tools/plot/pareto_plot.h"

namespace fmpc::cli {

namespace {

const char* const kRuleOptions[] = {"--system",          "--fix",         "--vary", "--points", "--seed",
                                    "--resolutions",     "--max-grid-points", "--min-seconds", "--cxx",
                                    "--cxx-flags"};
const char* const kSceneOptions[] = {"--models",     "--precisions",  "--integrators",  "--refinements",
                                     "--reference-refinements", "--reference-dt-factor", "--duration",
                                     "--variants",   "--elements",    "--meshes",        "--max-error",
                                     "--error",      "--plot-error",  "--write-scene",   "--max-reference-seconds",
                                     "--threads"};

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
  if (!arguments.variants.empty()) {
    options.axes.clear();
    std::string names;
    for (const sim::TradeAxisRow& row : sim::trade_axes()) names += std::string(names.empty() ? "" : ", ") + row.name;
    for (const std::string& name : arguments.variants) {
      if (const auto axis = sim::parse_trade_axis(name)) options.axes.push_back(*axis);
      else diagnostics.error(nowhere, "--variants: '" + name + "' is not an axis; use " + names);
    }
    // An axis's values given while the axis is held at the scene's value would be ignored: a mistake.
    for (const sim::TradeAxisRow& row : sim::trade_axes()) {
      const bool held = std::find(options.axes.begin(), options.axes.end(), row.axis) == options.axes.end();
      const bool given = [&] {
        switch (row.axis) {
          case sim::TradeAxis::Laws: return !arguments.models.empty();
          case sim::TradeAxis::Elements: return !arguments.elements.empty();
          case sim::TradeAxis::Meshes: return !arguments.meshes.empty();
          case sim::TradeAxis::Precisions: return !arguments.precisions.empty();
          case sim::TradeAxis::Integrators: return !arguments.integrators.empty();
          case sim::TradeAxis::Refinements: return !arguments.refinements.empty();
        }
        return false;
      }();
      if (held && given)
        diagnostics.error(nowhere, std::string(row.option) + " gives values of the axis '" + row.name +
                                       "', which --variants leaves out (it holds " + row.held + "); add " + row.name +
                                       " to --variants or leave out " + row.option);
    }
  }
  for (const std::string& name : arguments.elements) {
    if (const sim::ElementKindRow* row = sim::element_kind_by_keyword(name)) options.element_kinds.push_back(row->kind);
    else diagnostics.error(nowhere, "--elements: '" + name + "' is not an element kind; use " + join(sim::element_kind_keywords()));
  }
  if (!arguments.meshes.empty()) {
    options.meshes.clear();
    options.meshes_given = true;
    for (const std::string& name : arguments.meshes) {
      if (name == "graded") options.meshes.push_back(sim::TradeMesh::Scene);
      else if (name == "uniform") options.meshes.push_back(sim::TradeMesh::Uniform);
      else diagnostics.error(nowhere, "--meshes: '" + name + "' is not a mesh; use graded (the scene's) or uniform");
    }
  }
  options.max_error = arguments.max_error;
  if (!arguments.error.empty()) {
    sim::TradeMeasures measures{false, false};
    for (const std::string& name : arguments.error) {
      if (name == "displacement") measures.displacement = true;
      else if (name == "probe_force") measures.probe_force = true;
      else diagnostics.error(nowhere, "--error: '" + name + "' is not an error; use displacement or probe_force");
    }
    options.measures = measures;
  }
  if ((!arguments.error.empty() || !arguments.write_scene.empty()) && !arguments.max_error)
    diagnostics.error(nowhere, std::string(arguments.write_scene.empty() ? "--error" : "--write-scene") +
                                   " needs --max-error (the decision it is about)");
  if (!arguments.plot_error.empty() && arguments.plot_error != "displacement" && arguments.plot_error != "probe_force")
    diagnostics.error(nowhere, "--plot-error: '" + arguments.plot_error + "' is not an error; use displacement or "
                               "probe_force");
  if (arguments.max_reference_seconds) {
    options.max_reference_seconds = *arguments.max_reference_seconds;
    if (!(*arguments.max_reference_seconds > 0.0) || !std::isfinite(*arguments.max_reference_seconds))
      diagnostics.error(nowhere, "--max-reference-seconds: give a positive number of seconds, got " +
                                     format_number(*arguments.max_reference_seconds));
  }
  if (arguments.threads) options.threads = *arguments.threads;
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
  std::string axes;
  for (const sim::TradeAxisRow& row : sim::trade_axes()) axes += std::string(axes.empty() ? "" : ", ") + row.name;
  command.add_option("--variants", arguments->variants,
                     "Scenes: the axes that vary (" + axes + "; default all); the others hold the scene's value")
      ->delimiter(',');
  command.add_option("--elements", arguments->elements,
                     "Scenes: element kinds of the FEM models (" + join(sim::element_kind_keywords()) + "; default all)")
      ->delimiter(',');
  command.add_option("--meshes", arguments->meshes,
                     "Scenes: graded (the scene's mesh from a surface), uniform (size_near everywhere); default both")
      ->delimiter(',');
  command.add_option("--max-error", arguments->max_error,
                     "Scenes: decide: the cheapest variant whose relative errors are at most this (0.05 is 5%)");
  command.add_option("--error", arguments->error,
                     "Scenes: the errors --max-error bounds: displacement, probe_force (a displacement probe's "
                     "force, or the first tool's against its path; default: both, or displacement without either)")
      ->delimiter(',');
  command.add_option("--write-scene", arguments->write_scene,
                     "Scenes: write the chosen variant as a scene (with --max-error)");
  command.add_option("--max-reference-seconds", arguments->max_reference_seconds,
                     "Scenes: the most CPU seconds a refinement round of the reference may take (default 300)");
  command.add_option("--plot-error", arguments->plot_error,
                     "Scenes: the error the plot shows: displacement (default) or probe_force");
  command.add_option("--threads", arguments->threads, "Scenes: CPU runs side by side (default: every hardware thread)")
      ->check(CLI::Range(1u, 1024u));
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
    std::cerr << "fmpc trade: " << (plan.cheapest_first ? "at most " : "") << plan.runs << " runs"
              << (plan.cheapest_first ? " (cheapest first: those that cannot win are skipped)" : "") << ", about "
              << three_digits(plan.element_steps) << " element-steps in all (the largest run " << three_digits(plan.largest_tetrahedra)
              << " tetrahedra, the longest " << three_digits(plan.largest_steps) << " steps, at most "
              << sim::gibibytes_text(plan.largest_memory_bytes) << " of memory)" << std::endl;
  };
  options->progress = [&](std::size_t done, std::size_t total, const std::string& what) {
    // Runs go side by side (or in batches), a round at a time: the count of runs done, and the round's first run.
    running = std::to_string(done) + " of " + std::to_string(total) + " runs done (" + what + ")";
  };
  options->work_progress = [&](double done, double total) { progress.show_fraction(done, total, running + ", work"); };
  // Checked before anything runs: a probe force to plot needs a displacement probe or a tool's press.
  if (arguments.plot_error == "probe_force" &&
      sim::trade_probe_force_source(*scene) == sim::TradeForceSource::None) {
    diagnostics.error(scene->range_of(scene->probe ? "loads.probe" : "loads"),
                      "--plot-error probe_force: the scene has no displacement probe and no tool whose path moves "
                      "it, so there is no probe force to plot; use --plot-error displacement");
    report();
    return kExitErrors;
  }
  // On a GPU the runs go as batches (runtime/scene/trade_runs.h); otherwise side by side on every core.
  std::string device;
#if defined(FMPC_RUNTIME_HAVE_CUDA)
  options->gpu = scene->backend != sim::SceneBackend::Cpu && gpu::cuda_device_available(device);
#endif
  const std::optional<sim::SimulationTradeResult> result = sim::run_simulation_trade(*scene, *options, diagnostics);
  progress.finish();
  if (!result) {
    report();
    return kExitErrors;
  }
  sim::SimulationTradeResult shown = *result;
  if (options->gpu) shown.backend = "CUDA (" + device + "), the runs in batches";
  const std::string table = sim::simulation_trade_markdown(shown);
  std::cout << table;
  if (shown.max_error && !shown.chosen) {
    // Unreachable: the table says how close each variant came; nothing is written.
    diagnostics.error(SourceRange{}, "--max-error " + format_number(*shown.max_error) + ": " +
                                         sim::simulation_trade_decision(shown).substr(std::string("Decision: ").size()),
                      {"raise --max-error, or add finer variants (--refinements, --elements quadratic)"});
    report();
    return kExitErrors;
  }
  std::vector<std::pair<std::string, std::string>> writes;  // all or none
  if (!markdown.empty()) writes.emplace_back(markdown, table);
  if (!csv.empty()) writes.emplace_back(csv, sim::simulation_trade_csv(shown));
  if (!arguments.write_scene.empty()) {
    const auto written = sim::chosen_scene_text(*scene, *text, shown, arguments.write_scene, diagnostics);
    if (!written) {
      report();
      return kExitErrors;
    }
    writes.emplace_back(arguments.write_scene, *written);
  }
  if (!plot.empty()) {
    const bool force = arguments.plot_error == "probe_force";
    plot::TradePlot figure;
    figure.error_unit = force ? "probe force, relative" : "displacement (max), relative";
    figure.speed_label = "real-time factor (simulated s per wall s)";
    if (shown.max_error) {
      figure.error_bound = *shown.max_error;
      figure.error_bound_label = "--max-error " + format_number(*shown.max_error);
    }
    figure.title = {"fmpc trade: scene " + shown.scene_name,
                    format_number(shown.duration) + " s on " + shown.backend + ", against the FEM reference"};
    for (const sim::SimulationTradeRow& row : shown.rows)
      if (row.completed && row.real_time_factor > 0.0 && (!force || row.errors.probe_force))
        figure.points.push_back({row.variant, row.real_time_factor,
                                 force ? *row.errors.probe_force : row.errors.displacement_max,
                                 sim::trade_model_name(row.model)});
    // Only the front is labelled: the dominated variants crowd together (the CSV names every point).
    const std::vector<std::size_t> front = plot::pareto_front(figure.points);
    for (std::size_t i = 0; i < figure.points.size(); ++i)
      if (std::find(front.begin(), front.end(), i) == front.end()) figure.points[i].label.clear();
    writes.emplace_back(plot, plot::render_trade_plot(figure, plot::image_format_for(plot)));
  }
  report();
  std::string error;
  if (!write_text_files_atomically(writes, error)) {
    std::cerr << "fmpc trade: error: " << error << '\n';
    return kExitErrors;
  }
  return kExitOk;
}

}  // namespace fmpc::cli

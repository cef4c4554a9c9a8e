// fmpc simulate SCENE: loads a scene file, builds the spring model (fuzzy stiffness included), runs it and writes
// frames, a CSV time series, a JSON summary and, with a probe, a force-displacement PNG (docs/scenes.md).
#include <chrono>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>
#include <regex>
#include <sstream>

#include "runtime/io/atomic_file.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "runtime/scene/scene_run.h"
#include "diagnostics/number_format.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/progress_line.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/simulate_command.h"
#include "tools/fmpc/text_files.h"
#include "tools/plot/line_chart.h"
#if defined(FMPC_RUNTIME_HAVE_CUDA)
#include "runtime/gpu/gpu_simulation.h"
#endif

namespace fmpc::cli {

std::string six_digits(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", std::abs(value) < 1e-12 ? 0.0 : value);
  return text;
}

// While the probe holds still the tissue settles and the force relaxes (a vertical drop at the final displacement), which the notes explain.
std::string render_force_displacement(const std::vector<sim::ProbeCurvePoint>& curve, const sim::Scene& scene,
                                      const sim::BuiltScene& built, plot::ImageFormat format) {
  plot::LineChart chart;
  chart.title.push_back(scene.name + ": probe force against displacement");
  // The description carries E in full precision; four significant digits read better in a picture.
  std::string subtitle;
  {
    static const std::regex long_number(R"([0-9]+\.[0-9]{5,})");
    const std::string& text = built.stiffness_description;
    std::size_t last = 0;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), long_number); it != std::sregex_iterator(); ++it) {
      char short_form[32];
      std::snprintf(short_form, sizeof short_form, "%.4g", std::stod(it->str()));
      subtitle += text.substr(last, static_cast<std::size_t>(it->position()) - last) + short_form;
      last = static_cast<std::size_t>(it->position() + it->length());
    }
    subtitle += text.substr(last);
  }
  if (!scene.material.patient.empty()) subtitle = scene.material.patient + "; " + subtitle;
  chart.title.push_back(subtitle);
  // A cyclic probe (loads.probe.cycles) has no hold: its loops are one curve (a viscoelastic material's hysteresis).
  const int cycles = scene.probe ? scene.probe->cycles : 0;
  const double ramp = scene.probe && cycles == 0 ? scene.probe->ramp : 0.0;
  plot::Series ramp_series, hold_series;
  ramp_series.name = ramp > 0 ? "ramp (0 to " + six_digits(ramp) + " s)" : "loading";
  if (cycles > 0)
    ramp_series.name = std::to_string(cycles) + (cycles == 1 ? " cycle" : " cycles") + " of " +
                       six_digits(2.0 * scene.probe->ramp) + " s";
  ramp_series.colour = plot::categorical_colour(0);
  hold_series.name = "hold (probe still)";
  hold_series.colour = plot::categorical_colour(1);
  double x_lo = 0, x_hi = 0, y_lo = 0, y_hi = 0;
  for (const sim::ProbeCurvePoint& p : curve) {
    const double x = p.displacement * 1000.0;
    x_lo = std::min(x_lo, x);
    x_hi = std::max(x_hi, x);
    y_lo = std::min(y_lo, p.force);
    y_hi = std::max(y_hi, p.force);
    const bool in_hold = ramp > 0 && p.time > ramp;
    plot::Series& series = in_hold ? hold_series : ramp_series;
    if (in_hold && series.x.empty() && !ramp_series.x.empty()) {  // join the phases
      series.x.push_back(ramp_series.x.back());
      series.y.push_back(ramp_series.y.back());
    }
    series.x.push_back(x);
    series.y.push_back(p.force);
  }
  chart.x = plot::Axis{x_lo, x_hi > x_lo ? x_hi : x_lo + 1, false, "probe displacement (mm)"};
  chart.y = plot::Axis{y_lo, y_hi > y_lo ? y_hi : y_lo + 1, false, "probe force (N)"};
  chart.series.push_back(ramp_series);
  if (hold_series.x.size() > 1) {
    chart.series.push_back(hold_series);
    const double force_at_stop = ramp_series.y.back(), force_at_end = hold_series.y.back();
    char change[64];
    std::snprintf(change, sizeof change, "%+.3g%%", 100.0 * (force_at_end - force_at_stop) / std::fabs(force_at_stop));
    chart.notes.push_back("the probe stops at " + six_digits(ramp_series.x.back()) + " mm, t = " + six_digits(ramp) +
                          " s");
    chart.notes.push_back("force then: " + six_digits(force_at_stop) + " N");
    chart.notes.push_back("after the hold: " + six_digits(force_at_end) + " N (" + change + ")");
    chart.notes.push_back("while the probe holds still the");
    chart.notes.push_back("tissue settles: the force moves");
    chart.notes.push_back("along the vertical line");
    chart.markers.push_back(plot::VerticalMarker{ramp_series.x.back(), "probe stops", plot::categorical_colour(1)});
  }
  chart.notes.push_back("duration " + six_digits(curve.back().time) + " s");
  return plot::render_line_chart(chart, format);
}

// Implicit Euler's solves in one line: the method, the iterations per step, the largest residual and the capped steps.
std::string solver_summary(const sim::ImplicitSolverReport& report) {
  const bool direct = report.method == sim::ImplicitMethod::Direct;
  const double mean =
      report.steps == 0 ? 0.0 : static_cast<double>(report.iterations_total) / static_cast<double>(report.steps);
  std::string line = std::string("implicit solver: ") + (direct ? "direct (sparse LDL^T), " : "conjugate gradient, ") +
                     std::to_string(report.iterations_min) + " to " + std::to_string(report.iterations_max) +
                     (direct ? " solves" : " iterations") + " per step (mean " + six_digits(mean) +
                     "), relative residual at most " + six_digits(report.residual_max) + " (tolerance " +
                     six_digits(report.tolerance) + ")";
  if (report.capped_steps > 0)
    line += "; " + std::to_string(report.capped_steps) + " of " + std::to_string(report.steps) +
            " steps stopped at the cap of " + std::to_string(report.max_iterations);
  if (report.contact_unsettled_steps > 0)
    line += "; " + std::to_string(report.contact_unsettled_steps) + " of " + std::to_string(report.steps) +
            " steps' tool contact sets still changed after their last solve (the first at step " +
            std::to_string(report.first_contact_unsettled_step) + "; solver.contact_rounds)";
  return line;
}

// `mesh: {surface}`: the meshing in one line (summary.json has the distributions).
std::string meshing_line(const sim::MeshingRun& run) {
  const sim::TetrahedronQuality& q = run.result.quality;
  return "  meshed from " + std::to_string(run.result.surface_vertices) + " surface vertices in " +
         six_digits(run.seconds) + " s: radius-edge ratio median " + six_digits(q.radius_edge_ratio.p50) + ", 99% " +
         six_digits(q.radius_edge_ratio.p99) + " (" + std::to_string(q.above_ratio_bound) + " above " +
         six_digits(run.options.max_radius_edge_ratio) + "), smallest dihedral angle min " +
         six_digits(q.min_dihedral_degrees.min) + ", 1% " + six_digits(q.min_dihedral_degrees.p1) + " degrees\n";
}

// Applies the command-line overrides; errors name the option and what is allowed.
bool apply_overrides(const SimulateOptions& options, sim::Scene& scene, DiagnosticList& diagnostics) {
  if (!options.backend.empty()) {
    if (options.backend == "auto") scene.backend = sim::SceneBackend::Auto;
    else if (options.backend == "cpu") scene.backend = sim::SceneBackend::Cpu;
    else if (options.backend == "cuda") scene.backend = sim::SceneBackend::Cuda;
    else diagnostics.error(kCommandLine, "--backend: '" + options.backend + "' is not a backend; use auto, cpu or cuda");
  }
  if (!options.precision.empty()) {
    if (options.precision == "float") scene.precision = sim::Precision::Float;
    else if (options.precision == "double") scene.precision = sim::Precision::Double;
    else diagnostics.error(kCommandLine, "--precision: '" + options.precision + "' is not a precision; use float or double");
  }
  if (options.steps) {
    if (*options.steps == 0 || static_cast<double>(*options.steps) > sim::kMaxSimulationSteps)
      diagnostics.error(kCommandLine, "--steps: " + std::to_string(*options.steps) + " is not from 1 to " +
                                          format_number(sim::kMaxSimulationSteps) + " (docs/limits.md)");
    scene.steps = *options.steps;
  }
  if (options.duration) {
    if (!(*options.duration > 0.0) || !std::isfinite(*options.duration))
      diagnostics.error(kCommandLine, "--duration: expected a positive number of seconds");
    scene.duration = *options.duration;
  }
  // With a given dt the step count is known now; with dt auto the runner checks it once dt is (planned_step_count).
  if (!diagnostics.has_errors() && scene.dt) {
    DiagnosticList steps;
    if (!sim::planned_step_count(scene, *scene.dt, steps))
      diagnostics.error(options.duration ? kCommandLine : scene.range_of("dt"),
                        std::string(options.duration ? "--duration: " : "") + steps.items().front().message);
  }
  return !diagnostics.has_errors();
}

std::optional<sim::Scene> read_scene(const SimulateOptions& options, SourceFiles& sources, DiagnosticList& diagnostics) {
  std::string read_error;
  const std::optional<std::string> text = read_text_file(options.scene, sim::kMaxSceneFileBytes, "scene file", read_error);
  if (!text) {
    diagnostics.error(SourceRange{options.scene, 0, 0, 0, 0}, read_error);
    return std::nullopt;
  }
  sources.add(options.scene, *text);
  std::optional<sim::Scene> scene = sim::parse_scene(options.scene, *text, diagnostics);
  if (!scene || !apply_overrides(options, *scene, diagnostics)) return std::nullopt;
  return scene;
}

// Diagnostics in file order, as a reader of the scene meets them.
void report(DiagnosticList& diagnostics, const SourceFiles& sources) {
  diagnostics.sort_by_position();
  print_diagnostics(diagnostics, sources, std::cerr);
}

namespace {

int run_simulate(const SimulateOptions& options) {
  if (!options.patients.empty()) return run_cohort_command(options);
  DiagnosticList diagnostics;
  if (!options.shard.empty() || !options.devices.empty()) {
    diagnostics.error(kCommandLine, !options.shard.empty()
                                        ? "--shard: a shard is a share of a cohort; give the patients with --patients FILE"
                                        : "--devices: a scene alone runs on one device; --devices spreads a cohort's "
                                          "patients (--patients FILE) over GPUs");
    report(diagnostics, SourceFiles{});
    return kExitErrors;
  }
  SourceFiles sources;
  std::optional<sim::Scene> scene = read_scene(options, sources, diagnostics);
  if (!scene) {
    report(diagnostics, sources);
    return kExitErrors;
  }
  const std::optional<sim::BackendChoice> backend = sim::choose_backend(*scene, diagnostics);
  if (backend && !backend->note.empty()) std::cerr << "fmpc simulate: " << backend->note << '\n';
  if (!backend) {
    report(diagnostics, sources);
    return kExitErrors;
  }
  const auto build_start = std::chrono::steady_clock::now();
  std::optional<sim::BuiltScene> built = sim::build_scene(*scene, diagnostics);
  const double build_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count();
  if (built)
    for (const auto& [path, source] : built->sources) sources.add(path, source);
  if (!built) {
    report(diagnostics, sources);
    return kExitErrors;
  }
  sim::SceneRunOptions run_options;
  run_options.backend = backend->backend;
  run_options.output_directory =
      !options.output_directory.empty() ? options.output_directory : sim::default_output_directory(*scene);
  const std::vector<std::filesystem::path> earlier = sim::earlier_run_files(run_options.output_directory);
  ProgressLine progress("simulate");
  run_options.progress = [&](std::size_t done, std::size_t total) { progress.show_fraction(done, total, "step"); };
  const std::optional<sim::SceneRunResult> result = sim::run_scene(*scene, *built, run_options, diagnostics);
  progress.finish();
  std::string plot_path;
  if (result && built->setup.probe && scene->outputs.plot && result->probe_curve.size() >= 2) {
    plot_path = (std::filesystem::path(run_options.output_directory) / "force_displacement.png").string();
    if (!sim::write_file_atomically(
            plot_path, render_force_displacement(result->probe_curve, *scene, *built, plot::ImageFormat::Png),
            diagnostics))
      plot_path.clear();
  }
  std::size_t stale = 0;
  if (result) {
    std::vector<std::string> written = result->files;
    if (!plot_path.empty()) written.push_back(plot_path);
    stale = sim::remove_stale_files(earlier, written, diagnostics);
  }
  report(diagnostics, sources);
  if (!result) return kExitErrors;
  const sim::SimulationSetup& setup = built->setup;
  std::cout << scene->name << ": " << result->steps_taken << " steps of " << six_digits(result->stability.time_step)
            << " s" << (result->stability.automatic ? " (auto)" : "") << ", " << sim::scene_name(setup.integrator)
            << ", " << (setup.precision == sim::Precision::Float ? "float" : "double") << ", " << backend->backend << "\n"
            << "  model: " << sim::model_name(setup) << "; mesh: " << built->mesh.points.size() << " vertices, "
            << built->mesh.tetrahedra.size() << " tetrahedra, " << setup.springs.size() << " springs, "
            << setup.fixed_vertices.size() << " fixed\n"
            << (built->meshing ? meshing_line(*built->meshing) : std::string())
            << "  stiffness: " << built->stiffness_description << "\n"
            << "  wall time " << six_digits(result->wall_seconds) << " s (" << six_digits(result->steps_per_second)
            << " steps/s), max displacement " << six_digits(result->max_displacement * 1000.0) << " mm\n"
            << "  time: scene setup " << six_digits(build_seconds) << " s, simulator " << six_digits(result->timing.simulator)
            << " s, stepping " << six_digits(result->timing.stepping) << " s (first call "
            << six_digits(result->timing.first_advance) << " s), recording " << six_digits(result->timing.recording)
            << " s\n";
  if (result->solver) std::cout << "  " << solver_summary(*result->solver) << "\n";
  if (!result->probe_curve.empty()) {
    const sim::ProbeCurvePoint& last = result->probe_curve.back();
    std::cout << "  probe: " << setup.probe->vertices.size() << " vertices, displacement "
              << six_digits(last.displacement * 1000.0) << " mm, force " << six_digits(last.force) << " N\n";
  }
  if (result->inversions.largest_count > 0) {
    std::cout << "  inverted elements: " << result->inversions.largest_count << " at most (first: tetrahedron "
              << result->inversions.first_element << " at step " << result->inversions.first_step << "), "
              << result->inversions.current_count << " at the end\n";
  } else if (!setup.tetrahedra.empty()) {
    std::cout << "  inverted elements: none\n";
  }
  const sim::PrecisionCheckResult& precision = result->precision_check;
  std::cout << "  precision check: " << precision.reason;
  if (precision.ran)
    std::cout << " (probe force " << six_digits(precision.probe_force_difference) << ", largest displacement "
              << six_digits(precision.displacement_difference) << " relative)";
  std::cout << "\n  wrote " << result->files.size() + (plot_path.empty() ? 0 : 1) << " files to "
            << run_options.output_directory << (plot_path.empty() ? "" : " (plot: force_displacement.png)");
  if (stale > 0) std::cout << "; removed " << stale << " stale file" << (stale == 1 ? "" : "s") << " of an earlier run";
  std::cout << "\n";
  return result->completed ? kExitOk : kExitErrors;
}

}  // namespace

void register_simulate_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<SimulateOptions>();
  CLI::App* command = app.add_subcommand("simulate", "Run a scene file: frames (.vtu/.pvd), CSV, JSON summary, plot");
  command->add_option("SCENE", options->scene, "Scene file (YAML; docs/scenes.md)")->required();
  command->add_option("--backend", options->backend, "auto, cpu or cuda (overrides the scene's backend)");
  command->add_option("--precision", options->precision, "float or double (overrides the scene's precision)");
  auto* steps = command->add_option("--steps", options->steps, "Number of steps (instead of the scene's duration)");
  auto* duration = command->add_option("--duration", options->duration, "Simulated time in seconds");
  steps->excludes(duration);
  command->add_option("-o,--output", options->output_directory,
                      "Output directory (default: the scene's outputs.directory, else NAME_output); with "
                      "--patients, one folder per patient in it");
  command->add_option("--patients", options->patients,
                      "Cohort: a CSV with a label column and one column per rule input the scene binds; every "
                      "patient runs in one batch (docs/cohorts.md)");
  command->add_option("--shard", options->shard,
                      "With --patients: I/N runs every N-th patient from the I-th (0-based)");
  command->add_option("--devices", options->devices,
                      "With --patients on CUDA: 'all' or device numbers (0,1): the patients split over those GPUs, "
                      "one batch and host thread each, cohort.csv as on one GPU");
  command->callback([options, &exit_code] { exit_code = run_simulate(*options); });
}

}  // namespace fmpc::cli

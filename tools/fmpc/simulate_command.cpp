// fmpc simulate SCENE: loads a scene file, builds the spring model (fuzzy stiffness included), runs it and writes
// frames, a CSV time series, a JSON summary and, with a probe, a force-displacement PNG (docs/scenes.md).
#include <CLI/CLI.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>

#include "runtime/io/atomic_file.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "runtime/scene/scene_run.h"
#include "diagnostics/number_format.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"
#include "tools/plot/bitmap_font.h"
#include "tools/plot/heat_map.h"
#include "tools/plot/png_image.h"
#if defined(FMPC_RUNTIME_HAVE_CUDA)
#include "runtime/gpu/gpu_simulation.h"
#endif

namespace fmpc::cli {

namespace {

struct SimulateOptions {
  std::string scene;
  std::string backend;
  std::string precision;
  std::optional<std::size_t> steps;
  std::optional<double> duration;
  std::string output_directory;
};

const SourceRange kCommandLine{"command line", 0, 0, 0, 0};

// Tick labels and the run's report: six significant digits (hiding residues such as 0.6000000000000001).
std::string six_digits(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", std::abs(value) < 1e-12 ? 0.0 : value);
  return text;
}

// Force (N) against probe displacement (mm): 640 x 480, plot area 480 x 340, ticks from nice_ticks.
plot::RgbImage render_force_displacement(const std::vector<sim::ProbeCurvePoint>& curve, const std::string& title) {
  const int width = 640, height = 480, left = 100, top = 60, plot_width = 500, plot_height = 340;
  const plot::Rgb white{255, 255, 255}, black{0, 0, 0}, grey{200, 200, 200}, blue{31, 119, 180};
  plot::RgbImage image(width, height, white);
  double x_min = 0.0, x_max = 0.0, y_min = 0.0, y_max = 0.0;
  for (const auto& p : curve) {
    x_min = std::min(x_min, p.displacement * 1000.0);
    x_max = std::max(x_max, p.displacement * 1000.0);
    y_min = std::min(y_min, p.force);
    y_max = std::max(y_max, p.force);
  }
  if (!(x_max > x_min)) x_max = x_min + 1.0;
  if (!(y_max > y_min)) y_max = y_min + 1.0;
  const std::vector<double> x_ticks = plot::nice_ticks(x_min, x_max, 6);
  const std::vector<double> y_ticks = plot::nice_ticks(y_min, y_max, 6);
  x_min = std::min(x_min, x_ticks.front());
  x_max = std::max(x_max, x_ticks.back());
  y_min = std::min(y_min, y_ticks.front());
  y_max = std::max(y_max, y_ticks.back());
  const auto px = [&](double x) { return left + static_cast<int>(std::lround((x - x_min) / (x_max - x_min) * plot_width)); };
  const auto py = [&](double y) {
    return top + plot_height - static_cast<int>(std::lround((y - y_min) / (y_max - y_min) * plot_height));
  };
  for (const double x : x_ticks) {
    image.fill_rect(px(x), top, 1, plot_height, grey);
    const std::string label = six_digits(x);
    plot::draw_text(image, px(x) - plot::text_width(label, 2) / 2, top + plot_height + 8, label, black, 2);
  }
  for (const double y : y_ticks) {
    image.fill_rect(left, py(y), plot_width, 1, grey);
    const std::string label = six_digits(y);
    plot::draw_text(image, left - 8 - plot::text_width(label, 2), py(y) - plot::text_height(2) / 2, label, black, 2);
  }
  image.fill_rect(left, top, 1, plot_height + 1, black);
  image.fill_rect(left, top + plot_height, plot_width + 1, 1, black);
  // Segments drawn densely enough to leave no gaps (one dot per pixel of the longer side), 3 pixels thick.
  for (std::size_t i = 1; i < curve.size(); ++i) {
    const double x0 = px(curve[i - 1].displacement * 1000.0), y0 = py(curve[i - 1].force);
    const double x1 = px(curve[i].displacement * 1000.0), y1 = py(curve[i].force);
    const int n = std::max(1, static_cast<int>(std::max(std::abs(x1 - x0), std::abs(y1 - y0))));
    for (int k = 0; k <= n; ++k) {
      const double t = static_cast<double>(k) / n;
      image.fill_rect(static_cast<int>(std::lround(x0 + t * (x1 - x0))) - 1,
                      static_cast<int>(std::lround(y0 + t * (y1 - y0))) - 1, 3, 3, blue);
    }
  }
  const std::string x_label = "probe displacement (mm)", y_label = "probe force (N)";
  plot::draw_text(image, left + plot_width / 2 - plot::text_width(x_label, 2) / 2, height - 40, x_label, black, 2);
  plot::draw_text(image, 8, top + plot_height / 2 + plot::text_width(y_label, 2) / 2, y_label, black, 2, true);
  const int title_scale = plot::text_width(title, 2) <= width - 20 ? 2 : 1;
  plot::draw_text(image, (width - plot::text_width(title, title_scale)) / 2, 20, title, black, title_scale);
  return image;
}

// A progress bar on stderr, drawn only on a terminal and only once the run has taken a second.
class ProgressBar {
 public:
  ProgressBar() : enabled_(::isatty(STDERR_FILENO) == 1), start_(std::chrono::steady_clock::now()) {}
  void update(std::size_t done, std::size_t total) {
    if (!enabled_ || total == 0) return;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (elapsed < 1.0) return;
    const int width = 40;
    const int filled = static_cast<int>(static_cast<double>(width) * static_cast<double>(done) / static_cast<double>(total));
    std::cerr << "\r[" << std::string(static_cast<std::size_t>(filled), '#')
              << std::string(static_cast<std::size_t>(width - filled), '.') << "] " << 100 * done / total << "% step "
              << done << "/" << total << std::flush;
    drawn_ = true;
  }
  void finish() {
    if (drawn_) std::cerr << "\r" << std::string(72, ' ') << "\r" << std::flush;
  }

 private:
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_;
};

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

// The backend that runs: `auto` takes CUDA when a device can be used and says which it took; `cuda` without a
// usable device is an error that says why.
std::optional<std::string> choose_backend(const sim::Scene& scene, DiagnosticList& diagnostics) {
  std::string device;
#if defined(FMPC_RUNTIME_HAVE_CUDA)
  const bool have_device = gpu::cuda_device_available(device);
#else
  const bool have_device = false;
  device = "this fmpc was built without CUDA";
#endif
  switch (scene.backend) {
    case sim::SceneBackend::Cpu:
      return std::string("cpu");
    case sim::SceneBackend::Auto:
      if (have_device) {
        std::cerr << "fmpc simulate: backend auto: running on CUDA (" << device << ")\n";
        return std::string("cuda");
      }
      std::cerr << "fmpc simulate: backend auto: no GPU (" << device << "); running on the CPU\n";
      return std::string("cpu");
    case sim::SceneBackend::Cuda:
      if (have_device) return std::string("cuda");
      diagnostics.error(scene.range_of("backend"),
                        "backend: 'cuda' cannot run here: " + device + "; use backend cpu or auto");
      return std::nullopt;
  }
  return std::nullopt;
}

// Diagnostics in file order, as a reader of the scene meets them.
void report(DiagnosticList& diagnostics, const SourceFiles& sources) {
  diagnostics.sort_by_position();
  print_diagnostics(diagnostics, sources, std::cerr);
}

int run_simulate(const SimulateOptions& options) {
  DiagnosticList diagnostics;
  SourceFiles sources;
  std::string read_error;
  const std::optional<std::string> text = read_text_file(options.scene, sim::kMaxSceneFileBytes, "scene file", read_error);
  if (!text) {
    diagnostics.error(SourceRange{options.scene, 0, 0, 0, 0}, read_error);
    report(diagnostics, sources);
    return kExitErrors;
  }
  sources.add(options.scene, *text);
  std::optional<sim::Scene> scene = sim::parse_scene(options.scene, *text, diagnostics);
  if (!scene || !apply_overrides(options, *scene, diagnostics)) {
    report(diagnostics, sources);
    return kExitErrors;
  }
  const std::optional<std::string> backend = choose_backend(*scene, diagnostics);
  if (!backend) {
    report(diagnostics, sources);
    return kExitErrors;
  }
  std::optional<sim::BuiltScene> built = sim::build_scene(*scene, diagnostics);
  if (built)
    for (const auto& [path, source] : built->sources) sources.add(path, source);
  if (!built) {
    report(diagnostics, sources);
    return kExitErrors;
  }
  sim::SceneRunOptions run_options;
  run_options.backend = *backend;
  run_options.output_directory = !options.output_directory.empty()      ? options.output_directory
                                 : !scene->outputs.directory.empty() ? scene->outputs.directory
                                                                     : scene->name + "_output";
  ProgressBar progress;
  run_options.progress = [&](std::size_t done, std::size_t total) { progress.update(done, total); };
  const std::optional<sim::SceneRunResult> result = sim::run_scene(*scene, *built, run_options, diagnostics);
  progress.finish();
  std::string plot_path;
  if (result && built->setup.probe && scene->outputs.plot && result->probe_curve.size() >= 2) {
    std::string title = scene->name;
    if (!scene->material.patient.empty()) title += ": " + scene->material.patient;
    plot_path = (std::filesystem::path(run_options.output_directory) / "force_displacement.png").string();
    if (!sim::write_file_atomically(plot_path,
                                    plot::encode_png(render_force_displacement(result->probe_curve, title)),
                                    diagnostics))
      plot_path.clear();
  }
  report(diagnostics, sources);
  if (!result) return kExitErrors;
  const sim::SimulationSetup& setup = built->setup;
  std::cout << scene->name << ": " << result->steps_taken << " steps of " << six_digits(result->stability.time_step)
            << " s" << (result->stability.automatic ? " (auto)" : "") << ", " << sim::scene_name(setup.integrator)
            << ", " << (setup.precision == sim::Precision::Float ? "float" : "double") << ", " << *backend << "\n"
            << "  model: " << sim::scene_name(setup.model) << "; mesh: " << built->mesh.points.size() << " vertices, "
            << built->mesh.tetrahedra.size() << " tetrahedra, " << setup.springs.size() << " springs, "
            << setup.fixed_vertices.size() << " fixed\n"
            << "  stiffness: " << built->stiffness_description << "\n"
            << "  wall time " << six_digits(result->wall_seconds) << " s (" << six_digits(result->steps_per_second)
            << " steps/s), max displacement " << six_digits(result->max_displacement * 1000.0) << " mm\n";
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
            << run_options.output_directory << (plot_path.empty() ? "" : " (plot: force_displacement.png)") << "\n";
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
                      "Output directory (default: the scene's outputs.directory, else NAME_output)");
  command->callback([options, &exit_code] { exit_code = run_simulate(*options); });
}

}  // namespace fmpc::cli

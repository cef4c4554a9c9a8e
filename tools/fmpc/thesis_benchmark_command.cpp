// fmpc thesis-benchmark: the thesis's experiment (runtime/analysis/liver_benchmark.h) for rule files and patients,
// printed as CSV: per controller and patient, the similarity (runtime/analysis/curve_similarity.h) of the
// displacement and velocity curves with the Basafa-Farahmand benchmark's, and their correlations.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include "diagnostics/number_format.h"
#include "runtime/analysis/liver_benchmark.h"
#include "runtime/analysis/organ_step_response.h"
#include "runtime/io/input_file.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/csv_table.h"
#include "tools/fmpc/evaluation_points.h"
#include "tools/fmpc/progress_line.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"
#include "tools/plot/line_chart.h"

namespace fmpc::cli {

namespace {

struct ThesisBenchmarkOptions {
  std::vector<std::string> rules;
  std::string patients;
  std::string curves;
  std::string plot_directory;
  std::vector<double> moduli;  // kPa, given directly (--modulus)
  std::string scene;           // --scene: an organ under the same step force (organ_step_response.h)
  std::optional<double> organ_time_step;  // s, --organ-time-step: instead of the scene's dt
  sim::LiverBenchmarkOptions run;
};

constexpr std::size_t kPatientFileLimit = std::size_t{1} << 20;

// Patients from a CSV with a column per input of `system`, read as `fmpc eval` reads its points; named by its
// `label` or `patient` column, or "patient 1", "patient 2", ... in row order without one.
std::optional<std::vector<sim::LiverPatient>> read_patients(const std::string& path, const FuzzySystem& system,
                                                            SourceFiles& sources, DiagnosticList& diagnostics) {
  const std::optional<CsvTable> table =
      read_csv_file(path, path, kPatientFileLimit, "patient table",
                    SourceRange{"argument --patients", 0, 0, 0, 0}, sources, diagnostics, csv_header_of(system));
  if (!table) return std::nullopt;
  const std::size_t errors_before = diagnostics.error_count();
  const std::vector<EvaluationPoint> points = points_from_csv(*table, system, diagnostics);
  if (diagnostics.error_count() > errors_before) return std::nullopt;
  if (points.empty()) {
    diagnostics.error(SourceRange{path, 1, 1, 1, 1}, "the patient table has no rows");
    return std::nullopt;
  }
  std::vector<sim::LiverPatient> patients;
  for (const EvaluationPoint& point : points)
    patients.push_back({point.name.empty() ? "patient " + std::to_string(patients.size() + 1) : point.name,
                        point.inputs});
  return patients;
}

std::string similarity_row(const sim::ControllerRun& run) {
  const auto correlation = [](const sim::CurveComparison& c) {
    return c.correlation ? format_number(*c.correlation) : std::string("undefined");
  };
  std::vector<std::string> row = {run.controller, run.patient, format_number(run.modulus / 1000.0),
                                  format_number(run.stiffness), format_number(run.benchmark_displacement.similarity),
                                  format_number(run.benchmark_velocity.similarity),
                                  format_number(run.thesis_displacement.similarity),
                                  format_number(run.thesis_velocity.similarity),
                                  correlation(run.benchmark_displacement), correlation(run.benchmark_velocity),
                                  correlation(run.thesis_displacement), correlation(run.thesis_velocity)};
  if (run.organ_response)
    for (const std::string& cell :
         {format_number(run.organ_displacement.similarity), format_number(run.organ_velocity.similarity),
          correlation(run.organ_displacement), correlation(run.organ_velocity)})
      row.push_back(cell);
  return format_csv_row(row);
}

// The pairings a run has, with their responses: the benchmark law, the thesis's linear law, the organ (--scene).
std::vector<std::pair<const char*, const sim::MassPointResponse*>> run_responses(const sim::ControllerRun& run) {
  std::vector<std::pair<const char*, const sim::MassPointResponse*>> responses = {
      {"benchmark_law", &run.benchmark_response}, {"thesis_msm", &run.thesis_response}};
  if (run.organ_response) responses.emplace_back("organ", &*run.organ_response);
  return responses;
}

// One row per sample time: the reference's curves, then each run's (benchmark law, then thesis's linear law).
std::string curves_csv(const sim::LiverBenchmarkReport& report) {
  std::vector<std::string> header = {"time_s", "benchmark_displacement_m", "benchmark_velocity_m_per_s"};
  for (const auto& run : report.runs)
    for (const auto& pairing : run_responses(run))
      for (const char* quantity : {"displacement_m", "velocity_m_per_s"})
        header.push_back(run.controller + "_" + run.patient + "_" + pairing.first + "_" + quantity);
  std::string csv = format_csv_row(header);
  const auto& time = report.reference.displacement.time;
  for (std::size_t i = 0; i < time.size(); ++i) {
    std::vector<std::string> row = {format_number(time[i]), format_number(report.reference.displacement.value[i]),
                                    format_number(report.reference.velocity.value[i])};
    for (const auto& run : report.runs)
      for (const auto& pairing : run_responses(run)) {
        row.push_back(format_number(pairing.second->displacement.value[i]));
        row.push_back(format_number(pairing.second->velocity.value[i]));
      }
    csv += format_csv_row(row);
  }
  return csv;
}

// File-name stem for a group of runs: letters and digits kept, anything else becomes '_'.
std::string file_stem(const std::string& label) {
  std::string stem;
  for (const char c : label) stem += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return stem;
}

// For every patient (and the --modulus runs as one group): displacement and velocity against time, the benchmark
// and each run in both pairings, as PNG files named after the group.
std::vector<std::pair<std::string, std::string>> plot_files(const sim::LiverBenchmarkReport& report,
                                                            const std::string& directory) {
  std::vector<std::string> groups;
  for (const auto& run : report.runs) {
    const std::string group = run.controller == "constant" ? "constant" : run.patient;
    if (std::find(groups.begin(), groups.end(), group) == groups.end()) groups.push_back(group);
  }
  std::vector<std::pair<std::string, std::string>> files;
  for (const std::string& group : groups) {
    for (const bool velocity : {false, true}) {
      plot::LineChart figure;
      figure.title = {(velocity ? "velocity, " : "displacement, ") + group, "a step of 1 N at t = 0"};
      figure.x.title = "time (s)";
      figure.y.title = velocity ? "velocity (mm/s)" : "displacement (mm)";
      double x_hi = 0.0, y_lo = 0.0, y_hi = 0.0;  // the axes always include 0
      const auto add = [&](const std::string& label, const sim::MassPointResponse& response) {
        const sim::Curve& curve = velocity ? response.velocity : response.displacement;
        plot::Series series;
        series.name = label;
        series.x = curve.time;
        series.y = curve.value;
        series.colour = plot::categorical_colour(figure.series.size());
        for (double& y : series.y) {
          y *= 1000.0;
          y_lo = std::min(y_lo, y);
          y_hi = std::max(y_hi, y);
        }
        for (const double t : series.x) x_hi = std::max(x_hi, t);
        figure.series.push_back(std::move(series));
      };
      add("benchmark (Basafa-Farahmand, K1 0.05 N)", report.reference);
      for (const auto& run : report.runs) {
        if ((run.controller == "constant" ? "constant" : run.patient) != group) continue;
        const std::string name = run.controller == "constant" ? run.patient : run.controller;
        add(name + ", benchmark law", run.benchmark_response);
        add(name + ", thesis MSM", run.thesis_response);
        if (run.organ_response) add(name + ", organ", *run.organ_response);
      }
      figure.x.lo = 0.0;
      figure.x.hi = x_hi > 0.0 ? x_hi : 1.0;
      figure.y.lo = y_lo;
      figure.y.hi = y_hi > y_lo ? y_hi : y_lo + 1.0;
      const std::string path = (std::filesystem::path(directory) /
                                (file_stem(group) + (velocity ? "_velocity.png" : "_displacement.png")))
                                   .string();
      files.emplace_back(path, plot::render_line_chart(figure, plot::ImageFormat::Png));
    }
  }
  return files;
}

int run_thesis_benchmark(const ThesisBenchmarkOptions& options) {
  std::vector<std::unique_ptr<LoadedRuleFile>> rule_files;
  std::vector<sim::LiverController> controllers;
  DiagnosticList diagnostics;
  for (const std::string& path : options.rules) {
    rule_files.push_back(std::make_unique<LoadedRuleFile>(load_rule_file_from_disk(path)));
    LoadedRuleFile& file = *rule_files.back();
    if (file.diagnostics.has_errors()) {
      print_diagnostics(file.diagnostics, file.sources, std::cerr);
      return kExitErrors;
    }
    const FuzzySystem* system = select_system(file, "", diagnostics);
    if (!system) {
      print_diagnostics(diagnostics, file.sources, std::cerr);
      return kExitErrors;
    }
    controllers.push_back({std::filesystem::path(path).stem().string(), system});
  }
  const SourceRange command_line{"command line", 0, 0, 0, 0};
  if (controllers.empty() && options.moduli.empty()) {
    diagnostics.error(command_line, "nothing to compare with the benchmark",
                      {"give controller rule files with --patients, or --modulus KPA"});
  } else if (!controllers.empty() && options.patients.empty()) {
    diagnostics.error(command_line, "controllers need patients: give --patients CSV (a column per input)");
  } else if (controllers.empty() && !options.patients.empty()) {
    diagnostics.error(SourceRange{"argument --patients", 0, 0, 0, 0},
                      "patients need controllers: give the rule files to evaluate for them");
  }
  for (const double modulus : options.moduli)
    if (!(modulus > 0.0) || !std::isfinite(modulus))
      diagnostics.error(SourceRange{"argument --modulus", 0, 0, 0, 0},
                        "--modulus " + format_number(modulus) + ": give a positive, finite Young's modulus in kPa");
  SourceFiles sources;
  std::vector<sim::LiverPatient> patients;
  if (!controllers.empty() && !options.patients.empty()) {
    DiagnosticList reading;  // points_from_csv stops at any earlier error: read apart, then merge
    auto read = read_patients(options.patients, *controllers.front().system, sources, reading);
    diagnostics.append(reading);
    if (read) patients = std::move(*read);
  }
  if (options.organ_time_step && (!(*options.organ_time_step > 0.0) || !std::isfinite(*options.organ_time_step)))
    diagnostics.error(SourceRange{"argument --organ-time-step", 0, 0, 0, 0},
                      "--organ-time-step " + format_number(*options.organ_time_step) +
                          ": give a positive, finite time step in seconds");
  if (options.organ_time_step && options.scene.empty())
    diagnostics.error(SourceRange{"argument --organ-time-step", 0, 0, 0, 0},
                      "--organ-time-step steps an organ: give its scene with --scene");
  std::optional<sim::Scene> scene;
  if (!options.scene.empty()) {
    std::string read_error;
    const std::optional<std::string> text =
        read_text_file(options.scene, sim::kMaxSceneFileBytes, "scene file", read_error);
    if (!text) {
      diagnostics.error(SourceRange{"argument --scene", 0, 0, 0, 0}, read_error);
    } else {
      sources.add(options.scene, *text);
      scene = sim::parse_scene(options.scene, *text, diagnostics);
      if (scene && options.organ_time_step) {
        scene->dt = *options.organ_time_step;
        scene->ranges["dt"] = SourceRange{"argument --organ-time-step", 0, 0, 0, 0};
      }
      if (scene && !sim::check_organ_scene(*scene, diagnostics)) scene.reset();
    }
  }
  if (diagnostics.has_errors()) {
    print_diagnostics(diagnostics, sources, std::cerr);
    return kExitErrors;
  }
  std::vector<double> moduli;
  for (const double kpa : options.moduli) moduli.push_back(kpa * 1000.0);
  ProgressLine progress("thesis-benchmark");
  sim::LiverBenchmarkOptions run_options = options.run;
  run_options.progress = [&](std::size_t done, std::size_t total) { progress.show_fraction(done, total, "run"); };
  bool first_organ = true;
  if (scene)
    run_options.organ = [&](double modulus, DiagnosticList& into) {
      // Every run builds the same mesh: its warnings are said once, a later run's only with its errors.
      DiagnosticList run_diagnostics;
      auto response = sim::simulate_organ_step(*scene, modulus, run_options, first_organ ? into : run_diagnostics);
      if (!first_organ && run_diagnostics.has_errors()) into.append(run_diagnostics);
      first_organ = false;
      return response;
    };
  const auto report = sim::run_liver_benchmark(controllers, patients, moduli, run_options, diagnostics);
  progress.finish();
  if (!report) {
    print_diagnostics(diagnostics, sources, std::cerr);
    return kExitErrors;
  }
  std::vector<std::pair<std::string, std::string>> outputs;
  if (!options.curves.empty()) outputs.emplace_back(options.curves, curves_csv(*report));
  if (!options.plot_directory.empty()) {
    std::error_code error;
    std::filesystem::create_directories(options.plot_directory, error);
    if (error) {
      std::cerr << "argument --plot: error: cannot create folder '" << options.plot_directory
                << "': " << error.message() << "\n";
      return kExitErrors;
    }
    for (auto& file : plot_files(*report, options.plot_directory)) outputs.push_back(std::move(file));
  }
  std::string error;
  if (!outputs.empty() && !write_text_files_atomically(outputs, error)) {
    std::cerr << "error: " << error << "\n";
    return kExitErrors;
  }
  std::vector<std::string> header = {"controller", "patient", "modulus_kPa", "stiffness_N_per_m",
                                     "benchmark_law_displacement_similarity", "benchmark_law_velocity_similarity",
                                     "thesis_msm_displacement_similarity", "thesis_msm_velocity_similarity",
                                     "benchmark_law_displacement_correlation", "benchmark_law_velocity_correlation",
                                     "thesis_msm_displacement_correlation", "thesis_msm_velocity_correlation"};
  if (scene)
    for (const char* column : {"organ_displacement_similarity", "organ_velocity_similarity",
                               "organ_displacement_correlation", "organ_velocity_correlation"})
      header.push_back(column);
  std::string out = format_csv_row(header);
  for (const auto& run : report->runs) out += similarity_row(run);
  std::cout << out;
  print_diagnostics(diagnostics, sources, std::cerr);
  return kExitOk;
}

}  // namespace

void register_thesis_benchmark_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<ThesisBenchmarkOptions>();
  CLI::App* command = app.add_subcommand(
      "thesis-benchmark",
      "The thesis's experiment (docs/liver_fibrosis.md): each controller's stiffness for each patient drives one\n"
      "mass point under a step force, both as the Basafa-Farahmand benchmark law and as the thesis's linear mass\n"
      "point; prints the similarity of their displacement and velocity curves with the benchmark's (CSV).\n"
      "Exit status: 0 done, 2 errors.");
  command->add_option("rules", options->rules, "Controller rule files (fmpc or MATLAB .fis); named by file stem");
  command->add_option("--patients", options->patients, "CSV of FibroScan readings, a column per input");
  command->add_option("--modulus", options->moduli, "A Young's modulus (kPa) to compare as given (repeatable)");
  command->add_option("--curves", options->curves, "CSV file to write every curve to");
  command->add_option("--plot", options->plot_directory,
                      "Folder for PNG plots of displacement and velocity against time, one pair per patient");
  command->add_option("--scene", options->scene,
                      "Also drive this scene's organ (its probe shares the step force; its mesh, model, integrator\n"
                      "and step as it gives them) with each modulus, and compare its probe's curves");
  command->add_option("--organ-time-step", options->organ_time_step,
                      "The organ's time step (s) instead of the scene's dt (its integrator as the scene gives it)");
  command->add_option("--mass", options->run.mass, "Mass point (kg)")->default_val(1.5);
  command->add_option("--force", options->run.force, "Step force (N)")->default_val(1.0);
  command->add_option("--duration", options->run.duration, "Simulated time (s)")->default_val(10.0);
  command->add_option("--time-step", options->run.time_step, "RK4 time step (s)")->default_val(1e-3);
  command->add_option("--samples", options->run.samples, "Samples per curve")->default_val(1001);
  options->run.time_step_range = SourceRange{"argument --time-step", 0, 0, 0, 0};
  command->callback([options, &exit_code] { exit_code = run_thesis_benchmark(*options); });
}

}  // namespace fmpc::cli

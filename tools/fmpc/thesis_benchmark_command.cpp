// fmpc thesis-benchmark: the thesis's experiment (runtime/analysis/liver_benchmark.h) for rule files and patients,
// printed as CSV: per controller and patient, the similarity (runtime/analysis/curve_similarity.h) of the
// displacement and velocity curves with the Basafa-Farahmand benchmark's, and their correlations.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iostream>
#include <memory>

#include "diagnostics/number_format.h"
#include "runtime/analysis/liver_benchmark.h"
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
  return format_csv_row({run.controller, run.patient, format_number(run.modulus / 1000.0),
                         format_number(run.stiffness), format_number(run.benchmark_displacement.similarity),
                         format_number(run.benchmark_velocity.similarity),
                         format_number(run.thesis_displacement.similarity),
                         format_number(run.thesis_velocity.similarity), correlation(run.benchmark_displacement),
                         correlation(run.benchmark_velocity), correlation(run.thesis_displacement),
                         correlation(run.thesis_velocity)});
}

// One row per sample time: the reference's curves, then each run's (benchmark law, then thesis's linear law).
std::string curves_csv(const sim::LiverBenchmarkReport& report) {
  std::vector<std::string> header = {"time_s", "benchmark_displacement_m", "benchmark_velocity_m_per_s"};
  for (const auto& run : report.runs)
    for (const char* pairing : {"benchmark_law", "thesis_msm"})
      for (const char* quantity : {"displacement_m", "velocity_m_per_s"})
        header.push_back(run.controller + "_" + run.patient + "_" + pairing + "_" + quantity);
  std::string csv = format_csv_row(header);
  const auto& time = report.reference.displacement.time;
  for (std::size_t i = 0; i < time.size(); ++i) {
    std::vector<std::string> row = {format_number(time[i]), format_number(report.reference.displacement.value[i]),
                                    format_number(report.reference.velocity.value[i])};
    for (const auto& run : report.runs)
      for (const auto* response : {&run.benchmark_response, &run.thesis_response}) {
        row.push_back(format_number(response->displacement.value[i]));
        row.push_back(format_number(response->velocity.value[i]));
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
  if (diagnostics.has_errors()) {
    print_diagnostics(diagnostics, sources, std::cerr);
    return kExitErrors;
  }
  std::vector<double> moduli;
  for (const double kpa : options.moduli) moduli.push_back(kpa * 1000.0);
  ProgressLine progress("thesis-benchmark");
  sim::LiverBenchmarkOptions run_options = options.run;
  run_options.progress = [&](std::size_t done, std::size_t total) { progress.show_fraction(done, total, "run"); };
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
  std::string out = format_csv_row({"controller", "patient", "modulus_kPa", "stiffness_N_per_m",
                                    "benchmark_law_displacement_similarity", "benchmark_law_velocity_similarity",
                                    "thesis_msm_displacement_similarity", "thesis_msm_velocity_similarity",
                                    "benchmark_law_displacement_correlation", "benchmark_law_velocity_correlation",
                                    "thesis_msm_displacement_correlation", "thesis_msm_velocity_correlation"});
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
  command->add_option("--mass", options->run.mass, "Mass point (kg)")->default_val(1.5);
  command->add_option("--force", options->run.force, "Step force (N)")->default_val(1.0);
  command->add_option("--duration", options->run.duration, "Simulated time (s)")->default_val(10.0);
  command->add_option("--time-step", options->run.time_step, "RK4 time step (s)")->default_val(1e-3);
  command->add_option("--samples", options->run.samples, "Samples per curve")->default_val(1001);
  options->run.time_step_range = SourceRange{"argument --time-step", 0, 0, 0, 0};
  command->callback([options, &exit_code] { exit_code = run_thesis_benchmark(*options); });
}

}  // namespace fmpc::cli

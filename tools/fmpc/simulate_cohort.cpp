// fmpc simulate SCENE --patients FILE [--shard I/N] [--devices LIST|all]: one scene for a cohort of patients
// (docs/cohorts.md). Every row of the patients file is checked first; then the patients of this shard are built,
// given one time step and run together (one GPU batch, one per GPU with --devices, or worker threads on the CPU),
// each writing the usual outputs into its own folder, and cohort.csv and an overlay of the force-displacement curves
// are written beside the folders, both or neither.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <thread>

#include "diagnostics/number_format.h"
#include "runtime/io/atomic_file.h"
#include "runtime/integrate/worker_pool.h"
#include "runtime/io/input_file.h"
#include "runtime/scene/cohort.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "runtime/scene/scene_run.h"
#include "tools/fmpc/csv_table.h"
#include "tools/fmpc/patients_file.h"
#include "tools/fmpc/progress_line.h"
#include "tools/fmpc/report_text.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/simulate_command.h"
#include "tools/plot/heat_map.h"
#include "tools/plot/line_chart.h"
#if defined(FMPC_RUNTIME_HAVE_CUDA)
#include "runtime/gpu/gpu_simulation.h"
#endif

namespace fmpc::cli {

namespace {

// Past this many curves the overlay colours them by Young's modulus with a colour bar instead of naming each one in
// a legend (a legend of more entries would run off the figure or shrink past reading).
constexpr std::size_t kMaxLegendCurves = 10;

// One patient's build diagnostics as the cohort reports them: the first patient's in full (mesh repairs, assumed
// units: the scene's own, said once), every patient's errors and rules that fired for no patient, and never the
// input-out-of-range warnings (already given at the patients file's cells).
void append_build_diagnostics(const DiagnosticList& from, const std::string& label, bool first,
                              DiagnosticList& to) {
  for (Diagnostic diagnostic : from.items()) {
    if (diagnostic.code == "input-out-of-range") continue;
    const bool own = diagnostic.severity == Severity::Error || diagnostic.code == "no-rule-fired";
    if (!own && !first) continue;
    if (own) diagnostic.message = "patient '" + label + "': " + diagnostic.message;
    to.add(std::move(diagnostic));
  }
}

// The size that the cohort's limit counts: springs, or tetrahedra with the FEM.
double model_size(const sim::SimulationSetup& setup) {
  return static_cast<double>(setup.springs.size()) +
         (setup.springs.size() == 0 ? static_cast<double>(setup.tetrahedra.size()) : 0.0);
}

struct CohortMember {
  std::size_t row = 0;  // in the patients file
  sim::Scene scene;
  std::unique_ptr<sim::BuiltScene> built;
};

// cohort.csv: one row per patient of the run (docs/cohorts.md lists the columns).
std::string cohort_table(const PatientsFile& file, const std::vector<CohortMember>& members,
                         const sim::CohortRunResult& run) {
  std::vector<std::string> header = {"label"};
  header.insert(header.end(), file.inputs.begin(), file.inputs.end());
  for (const char* column : {"E_kPa", "E_max_kPa", "completed", "final_probe_displacement_m", "final_probe_force_N",
                             "max_displacement_m", "inverted_elements", "steps", "dt_s", "steps_per_second"})
    header.push_back(column);
  std::string csv = format_csv_row(header);
  for (std::size_t m = 0; m < members.size(); ++m) {
    const PatientRow& patient = file.patients[members[m].row];
    const sim::SceneRunResult& result = *run.patients[m];
    const sim::BuiltScene& built = *members[m].built;
    std::vector<std::string> row = {patient.label};
    for (const double value : patient.values) row.push_back(format_number(value));
    row.push_back(built.material ? format_number(built.material->modulus_min / 1000.0) : "");
    row.push_back(built.material ? format_number(built.material->modulus_max / 1000.0) : "");
    row.push_back(result.completed ? "true" : "false");
    const bool probe = !result.probe_curve.empty();
    row.push_back(probe ? format_number(result.probe_curve.back().displacement) : "");
    row.push_back(probe ? format_number(result.probe_curve.back().force) : "");
    row.push_back(format_number(result.max_displacement));
    row.push_back(std::to_string(result.inversions.largest_count));
    row.push_back(std::to_string(result.steps_taken));
    row.push_back(format_number(result.stability.time_step));
    row.push_back(format_number(result.steps_per_second));
    csv += format_csv_row(row);
  }
  return csv;
}

// Every patient's force against displacement in one figure: named in a legend up to kMaxLegendCurves curves, else
// coloured by Young's modulus (viridis) with a colour bar.
std::string cohort_plot(const sim::Scene& scene, const PatientsFile& file, const std::vector<CohortMember>& members,
                        const sim::CohortRunResult& run, const std::string& shard_text) {
  plot::LineChart chart;
  chart.title.push_back(scene.name + ": probe force against displacement, " + std::to_string(members.size()) +
                        " patients" + shard_text);
  double e_lo = INFINITY, e_hi = -INFINITY;
  for (const CohortMember& member : members) {
    if (!member.built->material) continue;
    e_lo = std::min(e_lo, member.built->material->modulus_min / 1000.0);
    e_hi = std::max(e_hi, member.built->material->modulus_min / 1000.0);
  }
  const bool by_modulus = members.size() > kMaxLegendCurves && e_hi >= e_lo;
  chart.title.push_back(by_modulus ? "colour: Young's modulus E at rest (the rules' output for each patient)"
                                   : "one curve per patient; E at rest in the legend");
  double x_lo = 0, x_hi = 0, y_lo = 0, y_hi = 0;
  for (std::size_t m = 0; m < members.size(); ++m) {
    const sim::SceneRunResult& result = *run.patients[m];
    plot::Series series;
    const double modulus = members[m].built->material ? members[m].built->material->modulus_min / 1000.0 : 0.0;
    if (by_modulus) {
      series.colour = plot::viridis(e_hi > e_lo ? (modulus - e_lo) / (e_hi - e_lo) : 0.5);
      series.width = 1.2;
    } else {
      series.colour = plot::categorical_colour(m);
      series.name = file.patients[members[m].row].label +
                    (members[m].built->material ? " (E " + four_digits(modulus) + " kPa)" : "");
    }
    for (const sim::ProbeCurvePoint& point : result.probe_curve) {
      series.x.push_back(point.displacement * 1000.0);
      series.y.push_back(point.force);
      x_lo = std::min(x_lo, series.x.back());
      x_hi = std::max(x_hi, series.x.back());
      y_lo = std::min(y_lo, point.force);
      y_hi = std::max(y_hi, point.force);
    }
    chart.series.push_back(std::move(series));
  }
  chart.x = plot::Axis{x_lo, x_hi > x_lo ? x_hi : x_lo + 1, false, "probe displacement (mm)"};
  chart.y = plot::Axis{y_lo, y_hi > y_lo ? y_hi : y_lo + 1, false, "probe force (N)"};
  if (by_modulus) chart.colour_bar = plot::ColourBar{e_lo, e_hi > e_lo ? e_hi : e_lo + 1, "Young's modulus E (kPa)"};
  return plot::render_line_chart(chart, plot::ImageFormat::Png);
}

// --devices: nullopt after an error; empty when not given. Checked against the devices this process sees before
// anything is read or built.
std::optional<std::vector<int>> cohort_devices(const std::string& text, DiagnosticList& diagnostics) {
  if (text.empty()) return std::vector<int>{};
  const SourceRange where{"argument --devices", 0, 0, 0, 0};
  std::string error;
#if defined(FMPC_RUNTIME_HAVE_CUDA)
  const std::optional<int> count = gpu::cuda_device_count(error);
#else
  const std::optional<int> count;
  error = "this fmpc was built without CUDA; a cohort spreads over GPUs only in a CUDA build";
#endif
  if (!count) {
    diagnostics.error(where, "--devices: " + error);
    return std::nullopt;
  }
  auto devices = sim::parse_device_list(text, *count, error);
  if (!devices)
    diagnostics.error(where, "--devices: " + error, {"list the GPUs with nvidia-smi -L; 'all' takes every one"});
  return devices;
}

}  // namespace

int run_cohort_command(const SimulateOptions& options) {
  const auto command_start = std::chrono::steady_clock::now();
  const auto seconds_since_start = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - command_start).count();
  };
  DiagnosticList diagnostics;
  SourceFiles sources;
  sim::CohortShard shard;
  if (!options.shard.empty()) {
    std::string error;
    const auto parsed = sim::parse_cohort_shard(options.shard, error);
    if (parsed) shard = *parsed;
    else diagnostics.error(SourceRange{"argument --shard", 0, 0, 0, 0}, "--shard: " + error);
  }
  const std::optional<std::vector<int>> devices = cohort_devices(options.devices, diagnostics);
  std::optional<sim::Scene> scene = read_scene(options, sources, diagnostics);
  if (!scene) {
    report(diagnostics, sources);
    return kExitErrors;
  }
  if (scene->material.source != sim::SceneMaterial::Source::Rules) {
    diagnostics.error(scene->range_of("material"),
                      "--patients: the scene's material does not come from rules; a cohort gives each patient the "
                      "inputs the scene binds through material.rules",
                      {"use material: {rules: FILE, inputs: {...}} (docs/cohorts.md)"});
    report(diagnostics, sources);
    return kExitErrors;
  }
  // The rules are read and loaded once for every patient (build_scene then parses nothing).
  sim::LoadedRules rules;
  {
    std::string read_error;
    const auto text = sim::read_input_file(scene->material.file, sim::kMaxRuleFileBytes, "rule file", read_error);
    if (text) {
      rules.path = scene->material.file;
      rules.text = *text;
      sources.add(rules.path, rules.text);
      DiagnosticList rule_diagnostics;
      rules.rules = load_rule_file(rules.path, rules.text, rule_diagnostics);
      for (const Diagnostic& diagnostic : rule_diagnostics.items())
        if (diagnostic.severity == Severity::Error) diagnostics.add(diagnostic);
    }
    if (!text || diagnostics.has_errors()) {
      // The scene's own build says what is wrong with the file, located at material.rules.
      sim::build_scene(*scene, diagnostics);
      report(diagnostics, sources);
      return kExitErrors;
    }
  }
  const FuzzySystem* system = nullptr;
  for (const FuzzySystem& candidate : rules.rules.systems)
    if (candidate.name == scene->material.system || (scene->material.system.empty() && rules.rules.systems.size() == 1))
      system = &candidate;
  if (system == nullptr) {
    sim::build_scene(*scene, diagnostics, 0, &rules);  // names the systems the file holds, located at the scene
    if (!diagnostics.has_errors())
      diagnostics.error(scene->range_of("material.rules"), "material.rules: no system of the rule file is selected");
    report(diagnostics, sources);
    return kExitErrors;
  }
  const std::optional<PatientsFile> file = read_patients_file(options.patients, *scene, *system, sources, diagnostics);
  if (!file || diagnostics.has_errors()) {
    report(diagnostics, sources);
    return kExitErrors;
  }
  const std::vector<std::size_t> rows = sim::shard_patients(file->patients.size(), shard);
  const std::string shard_text = options.shard.empty() ? std::string()
                                                       : " (shard " + std::to_string(shard.index) + "/" +
                                                             std::to_string(shard.count) + ")";
  if (rows.empty()) {
    report(diagnostics, sources);
    std::cout << scene->name << ": shard " << shard.index << "/" << shard.count << " of " << file->patients.size()
              << " patients holds none; nothing to run\n";
    return kExitOk;
  }
  const std::optional<sim::BackendChoice> backend = sim::choose_backend(*scene, diagnostics);
  if (backend && !backend->note.empty()) std::cerr << "fmpc simulate: " << backend->note << '\n';
  if (backend && backend->backend != "cuda" && devices && !devices->empty())
    diagnostics.error(SourceRange{"argument --devices", 0, 0, 0, 0},
                      "--devices spreads a cohort over GPUs, and this one runs on the CPU (" +
                          (backend->note.empty() ? "backend cpu" : backend->note) +
                          "); drop --devices (the CPU's workers are the scene's `threads`) or use --backend cuda");
  if (!backend || diagnostics.has_errors()) {
    report(diagnostics, sources);
    return kExitErrors;
  }

  // The first patient of the run is built first: its size times the run's patients is checked against the limit
  // before the others are built.
  const bool automatic_dt = !scene->dt.has_value();
  std::vector<CohortMember> members;
  std::optional<double> smallest_elsewhere;
  std::vector<bool> in_run(file->patients.size(), false);
  for (const std::size_t row : rows) in_run[row] = true;
  std::vector<std::size_t> order = {rows.front()};
  for (std::size_t row = 0; row < file->patients.size(); ++row)
    if (row != rows.front() && (in_run[row] || automatic_dt)) order.push_back(row);
  // The first patient alone, for the size limit; then the others side by side (the rules are shared and read-only).
  const auto build = [&](std::size_t row, DiagnosticList& build_diagnostics) {
    const PatientRow& patient = file->patients[row];
    CohortMember member{row, sim::patient_scene(*scene, patient.label, file->inputs, patient.values), nullptr};
    auto built = sim::build_scene(member.scene, build_diagnostics, 0, &rules);
    if (built) member.built = std::make_unique<sim::BuiltScene>(std::move(*built));
    return member;
  };
  {
    DiagnosticList build_diagnostics;
    CohortMember first = build(order.front(), build_diagnostics);
    append_build_diagnostics(build_diagnostics, file->patients[order.front()].label, true, diagnostics);
    if (first.built)
      for (const auto& [path, source] : first.built->sources) sources.add(path, source);
    if (!first.built) {
      report(diagnostics, sources);
      return kExitErrors;
    }
    const double size = model_size(first.built->setup) * static_cast<double>(rows.size());
    if (size > sim::kMaxCohortSprings) {
      diagnostics.error(SourceRange{"argument --patients", 0, 0, 0, 0},
                        "the run's " + std::to_string(rows.size()) + " patients have " + format_number(size) +
                            " springs (or tetrahedra) together; at most " + format_number(sim::kMaxCohortSprings) +
                            " in one run (docs/limits.md)",
                        {"spread the cohort over runs with --shard I/N"});
      report(diagnostics, sources);
      return kExitErrors;
    }
    members.push_back(std::move(first));
  }
  std::vector<CohortMember> others(order.size() - 1);
  std::vector<DiagnosticList> others_diagnostics(others.size());
  std::vector<double> others_step(others.size(), INFINITY);  // the automatic step of a patient another shard runs
  {
    const unsigned threads = scene->threads != 0 ? scene->threads : std::max(1u, std::thread::hardware_concurrency());
    sim::WorkerPool pool(static_cast<unsigned>(std::min<std::size_t>(threads, std::max<std::size_t>(others.size(), 1))));
    pool.run(
        others.size(),
        [&](std::size_t begin, std::size_t end) {
          for (std::size_t i = begin; i < end; ++i) {
            others[i] = build(order[i + 1], others_diagnostics[i]);
            if (!others[i].built || in_run[order[i + 1]]) continue;
            DiagnosticList ignored;  // this patient runs in another shard, which reports its problems
            if (const auto report = sim::check_stability(others[i].built->setup, ignored))
              others_step[i] = report->time_step;
            others[i].built.reset();
          }
        },
        1);
  }
  for (std::size_t i = 0; i < others.size(); ++i) {
    append_build_diagnostics(others_diagnostics[i], file->patients[order[i + 1]].label, false, diagnostics);
    if (std::isfinite(others_step[i]))
      smallest_elsewhere = smallest_elsewhere ? std::min(*smallest_elsewhere, others_step[i]) : others_step[i];
    if (others[i].built) members.push_back(std::move(others[i]));
  }
  if (diagnostics.has_errors()) {
    report(diagnostics, sources);
    return kExitErrors;
  }
  std::sort(members.begin(), members.end(), [](const CohortMember& a, const CohortMember& b) { return a.row < b.row; });
  std::vector<sim::BuiltScene*> built;
  std::vector<std::string> labels;
  for (CohortMember& member : members) {
    built.push_back(member.built.get());
    labels.push_back(file->patients[member.row].label);
  }
  const std::optional<double> dt = sim::prepare_cohort(built, labels, smallest_elsewhere, diagnostics);
  if (!dt) {
    report(diagnostics, sources);
    return kExitErrors;
  }

  const std::filesystem::path root =
      !options.output_directory.empty() ? options.output_directory : sim::default_output_directory(*scene);
  std::vector<sim::CohortPatient> patients;
  std::vector<std::vector<std::filesystem::path>> earlier;
  for (const CohortMember& member : members) {
    const std::string& label = file->patients[member.row].label;
    patients.push_back(sim::CohortPatient{label, &member.scene, member.built.get(), (root / label).string()});
    earlier.push_back(sim::earlier_run_files(root / label));
  }
  const double build_seconds = seconds_since_start();
  sim::CohortRunOptions run_options;
  run_options.backend = backend->backend;
  run_options.threads = scene->threads;
  if (devices) run_options.devices = *devices;
  ProgressLine progress("simulate");
  run_options.progress = [&](std::size_t done, std::size_t total) {
    progress.show_fraction(done, total, "step");
  };
  const std::optional<sim::CohortRunResult> run = sim::run_cohort(patients, run_options, diagnostics);
  progress.finish();
  if (!run) {
    report(diagnostics, sources);
    return kExitErrors;
  }

  // Each patient's picture, and its folder cleaned of an earlier run's leftovers.
  bool every_patient = true, every_completed = true;
  std::size_t files = 0, stale = 0;
  for (std::size_t m = 0; m < members.size(); ++m) {
    const std::optional<sim::SceneRunResult>& result = run->patients[m];
    if (!result) {
      every_patient = false;
      continue;
    }
    every_completed = every_completed && result->completed;
    std::vector<std::string> written = result->files;
    if (members[m].built->setup.probe && members[m].scene.outputs.plot && result->probe_curve.size() >= 2) {
      const std::string plot_path = (std::filesystem::path(patients[m].output_directory) / "force_displacement.png").string();
      if (sim::write_file_atomically(plot_path,
                                     render_force_displacement(result->probe_curve, members[m].scene,
                                                               *members[m].built, plot::ImageFormat::Png),
                                     diagnostics))
        written.push_back(plot_path);
      else
        every_patient = false;
    }
    files += written.size();
    stale += sim::remove_stale_files(earlier[m], written, diagnostics);
  }
  // cohort.csv and the overlay together, only when every patient's outputs were written.
  std::vector<std::pair<std::string, std::string>> cohort_files;
  if (every_patient) {
    cohort_files.emplace_back((root / sim::kCohortTableFile).string(), cohort_table(*file, members, *run));
    bool curves = true;
    for (const auto& result : run->patients) curves = curves && result->probe_curve.size() >= 2;
    if (curves && scene->outputs.plot)
      cohort_files.emplace_back((root / sim::kCohortPlotFile).string(), cohort_plot(*scene, *file, members, *run, shard_text));
    if (!sim::write_files_atomically(cohort_files, diagnostics)) cohort_files.clear();
  }
  report(diagnostics, sources);

  const sim::SimulationSetup& setup = members.front().built->setup;
  std::size_t completed = 0, inverted = 0;
  double force_lo = INFINITY, force_hi = -INFINITY, e_lo = INFINITY, e_hi = -INFINITY;
  for (std::size_t m = 0; m < members.size(); ++m) {
    if (members[m].built->material) {
      e_lo = std::min(e_lo, members[m].built->material->modulus_min / 1000.0);
      e_hi = std::max(e_hi, members[m].built->material->modulus_max / 1000.0);
    }
    const auto& result = run->patients[m];
    if (!result) continue;
    completed += result->completed ? 1 : 0;
    inverted += result->inversions.largest_count > 0 ? 1 : 0;
    if (!result->probe_curve.empty()) {
      force_lo = std::min(force_lo, result->probe_curve.back().force);
      force_hi = std::max(force_hi, result->probe_curve.back().force);
    }
  }
  const std::size_t steps = run->patients.front() ? run->patients.front()->steps_taken : 0;
  const double command_seconds = seconds_since_start();
  std::cout << scene->name << ": cohort of " << members.size() << " patient" << (members.size() == 1 ? "" : "s")
            << shard_text << " from " << options.patients << ", " << steps << " steps of " << six_digits(*dt) << " s"
            << (automatic_dt ? " (auto: the smallest automatic step of the cohort's " +
                                   std::to_string(file->patients.size()) + " patients)"
                             : "")
            << ", " << sim::scene_name(setup.integrator) << ", "
            << (setup.precision == sim::Precision::Float ? "float" : "double") << ", " << backend->backend << "\n"
            << "  model: " << sim::model_name(setup) << "; per patient " << members.front().built->mesh.points.size()
            << " vertices, " << setup.springs.size() << " springs\n";
  if (e_hi >= e_lo) std::cout << "  E from the rules: " << six_digits(e_lo) << " to " << six_digits(e_hi) << " kPa\n";
  std::cout << "  completed: " << completed << " of " << members.size() << "; with inverted elements: " << inverted
            << "\n";
  if (force_hi >= force_lo)
    std::cout << "  final probe force: " << six_digits(force_lo) << " to " << six_digits(force_hi) << " N\n";
  // The rates over the stepping alone and over the whole command, each labelled: a batch step advances every
  // patient; patient-steps count each patient's, and spring-steps (tetrahedron-steps without springs) its model.
  const double patients_run = static_cast<double>(members.size());
  const double model_steps = model_size(setup) * patients_run * static_cast<double>(steps);
  const char* model_unit = setup.springs.size() > 0 ? "spring-steps/s" : "tetrahedron-steps/s";
  const auto rates = [&](double seconds) {
    const double per_second = seconds > 0.0 ? 1.0 / seconds : 0.0;
    return six_digits(static_cast<double>(steps) * per_second) + " batch steps/s, " +
           six_digits(static_cast<double>(steps) * patients_run * per_second) + " patient-steps/s, " +
           six_digits(model_steps * per_second) + " " + model_unit;
  };
  std::cout << "  stepping (the simulator's advance calls, checks included): " << six_digits(run->stepping_seconds)
            << " s, " << rates(run->stepping_seconds) << "\n"
            << "  whole command: " << six_digits(command_seconds) << " s (reading and building "
            << six_digits(build_seconds) << " s, stepping and recording " << six_digits(run->wall_seconds)
            << " s, writing and the precision check " << six_digits(command_seconds - build_seconds - run->wall_seconds)
            << " s), " << rates(command_seconds) << "\n"
            << "  wrote " << files << " files in " << members.size() << " patient folders under " << root.string();
  if (!cohort_files.empty())
    std::cout << ", and " << sim::kCohortTableFile << (cohort_files.size() > 1 ? std::string(" and ") + sim::kCohortPlotFile : "");
  if (stale > 0) std::cout << "; removed " << stale << " stale file" << (stale == 1 ? "" : "s") << " of an earlier run";
  std::cout << "\n";
  return every_patient && every_completed && !cohort_files.empty() ? kExitOk : kExitErrors;
}

}  // namespace fmpc::cli

#include <algorithm>
#include <exception>
#include <functional>
#include <mutex>
#include <regex>
#include <thread>

#include "runtime/integrate/worker_pool.h"
#include "runtime/io/atomic_file.h"
#include "runtime/scene/cohort.h"
#include "runtime/scene/scene_batch_run.h"
#include "runtime/scene/scene_run.h"

namespace fmpc::sim {

namespace {

// A patient's messages as its own: "patient 'P7': " before each (given `patient`), or a GPU batch's "scene N: ..."
// and "... in scene N" named by the patient they are about (a batch of one names no scene).
void append_for_patients(const DiagnosticList& from, const std::vector<CohortPatient>& patients,
                         std::optional<std::size_t> patient, DiagnosticList& to) {
  static const std::regex batch_scene(R"(^scene ([0-9]+): |in scene ([0-9]+))");
  const auto named = [&](std::size_t p) { return "patient '" + patients[p].label + "'"; };
  for (Diagnostic diagnostic : from.items()) {
    std::smatch match;
    if (patient) {
      diagnostic.message = named(*patient) + ": " + diagnostic.message;
    } else if (std::regex_search(diagnostic.message, match, batch_scene)) {
      const std::size_t who = std::stoull(match[1].matched ? match[1].str() : match[2].str());
      if (who < patients.size()) {
        diagnostic.message = match[1].matched ? named(who) + ": " + match.suffix().str()
                                              : match.prefix().str() + "in " + named(who) + match.suffix().str();
      }
    } else if (patients.size() == 1) {
      diagnostic.message = named(0) + ": " + diagnostic.message;
    }
    to.add(std::move(diagnostic));
  }
}

}  // namespace

std::optional<double> prepare_cohort(const std::vector<BuiltScene*>& patients, const std::vector<std::string>& labels,
                                     std::optional<double> smallest_elsewhere, DiagnosticList& diagnostics) {
  if (patients.empty()) {
    diagnostics.error(SourceRange{}, "a cohort needs at least one patient");
    return std::nullopt;
  }
  std::vector<CohortPatient> named(patients.size());
  for (std::size_t p = 0; p < patients.size() && p < labels.size(); ++p) named[p].label = labels[p];
  std::optional<double> smallest = smallest_elsewhere;
  const bool automatic = !patients.front()->setup.time_step.has_value();
  for (std::size_t p = 0; p < patients.size(); ++p) {
    DiagnosticList patient_diagnostics;
    const auto report = check_stability(patients[p]->setup, patient_diagnostics);
    // Only the errors: the run's own check repeats the warnings.
    DiagnosticList errors;
    for (const Diagnostic& diagnostic : patient_diagnostics.items())
      if (diagnostic.severity == Severity::Error) errors.add(diagnostic);
    append_for_patients(errors, named, p, diagnostics);
    if (!report) continue;
    smallest = smallest ? std::min(*smallest, report->time_step) : report->time_step;
  }
  if (diagnostics.has_errors() || !smallest) return std::nullopt;
  for (BuiltScene* patient : patients) {
    if (automatic) patient->setup.time_step = *smallest;
    patient->setup.threads = 1;
  }
  return smallest;
}

std::optional<CohortRunResult> run_cohort(const std::vector<CohortPatient>& patients, const CohortRunOptions& options,
                                          DiagnosticList& diagnostics) {
  if (patients.empty()) {
    diagnostics.error(SourceRange{}, "a cohort needs at least one patient");
    return std::nullopt;
  }
  for (std::size_t d = 0; d < options.devices.size(); ++d) {
    const int device = options.devices[d];
    const bool repeated = std::find(options.devices.begin(), options.devices.begin() + static_cast<long>(d), device) !=
                          options.devices.begin() + static_cast<long>(d);
    if (device < 0 || repeated) {
      diagnostics.error(SourceRange{}, "a cohort's devices are distinct device numbers from 0; device " +
                                           std::to_string(device) + (repeated ? " is named twice" : " is negative"));
      return std::nullopt;
    }
  }
  for (const CohortPatient& patient : patients)
    if (!ensure_directory(patient.output_directory, diagnostics)) return std::nullopt;
#if !defined(FMPC_RUNTIME_HAVE_CUDA)
  if (options.backend == "cuda") {
    diagnostics.error(SourceRange{}, "this fmpc was built without CUDA; run the cohort with backend cpu or auto");
    return std::nullopt;
  }
#endif
  const Backend backend = run_backend(options.backend);
  // One batch per device (or CPU slot), each a consecutive range of the patients in its own host thread; one batch
  // alone runs in the caller's thread as a scene does.
  const std::vector<PatientRange> ranges = split_patients(patients.size(), std::max<std::size_t>(1, options.devices.size()));
  const unsigned threads =
      ranges.size() == 1 ? options.threads
                         : std::max(1u, resolve_thread_count(options.threads, patients.size(), 2) /
                                            static_cast<unsigned>(ranges.size()));
  // Each patient's messages kept apart, then named by its label; each batch's ("scene N: ...") named by the patient
  // they are about.
  std::vector<DiagnosticList> patient_diagnostics(patients.size());
  struct Batch {
    std::vector<CohortPatient> patients;
    std::vector<SceneBatchMember> members;
    SimulationOptions options;
    DiagnosticList diagnostics;
    std::optional<SceneBatchResult> run;
    std::exception_ptr failure;
  };
  std::vector<Batch> batches(ranges.size());
  for (std::size_t b = 0; b < ranges.size(); ++b) {
    Batch& batch = batches[b];
    for (std::size_t p = ranges[b].begin; p < ranges[b].end; ++p) {
      batch.patients.push_back(patients[p]);
      SceneBatchMember member;
      member.scene = patients[p].scene;
      member.built = patients[p].built;
      member.options.output_directory = patients[p].output_directory;
      member.options.backend = options.backend;
      member.diagnostics = &patient_diagnostics[p];
      batch.members.push_back(member);
    }
    batch.options.backend = backend;
    batch.options.batch_threads = threads;
    if (backend == Backend::Cuda && !options.devices.empty()) batch.options.gpu.device = options.devices[b];
  }
  // Progress over batches: the steps every batch has done, said when that grows.
  std::mutex progress_mutex;
  std::vector<std::size_t> steps_done(batches.size(), 0);
  std::size_t steps_said = 0;
  const auto batch_progress = [&](std::size_t b) -> std::function<void(std::size_t, std::size_t)> {
    if (!options.progress) return {};
    if (batches.size() == 1) return options.progress;
    return [&, b](std::size_t done, std::size_t total) {
      const std::lock_guard<std::mutex> lock(progress_mutex);
      steps_done[b] = done;
      const std::size_t everywhere = *std::min_element(steps_done.begin(), steps_done.end());
      if (everywhere <= steps_said) return;
      steps_said = everywhere;
      options.progress(everywhere, total);
    };
  };
  const auto run_batch = [&](std::size_t b) {
    Batch& batch = batches[b];
    try {
      batch.run = run_scene_batch(batch.members, batch.options, batch_progress(b), batch.diagnostics);
    } catch (...) {
      batch.failure = std::current_exception();  // rethrown in the caller's thread, as a batch alone would throw
    }
  };
  if (batches.size() == 1) {
    run_batch(0);
  } else {
    std::vector<std::thread> workers;
    for (std::size_t b = 0; b < batches.size(); ++b) workers.emplace_back(run_batch, b);
    for (std::thread& worker : workers) worker.join();
  }
  for (const Batch& batch : batches)
    if (batch.failure) std::rethrow_exception(batch.failure);
  bool every_batch = true;
  CohortRunResult result;
  for (const Batch& batch : batches) {
    append_for_patients(batch.diagnostics, batch.patients, std::nullopt, diagnostics);
    every_batch = every_batch && batch.run.has_value();
    if (!batch.run) continue;
    result.patients.insert(result.patients.end(), batch.run->results.begin(), batch.run->results.end());
    result.wall_seconds = std::max(result.wall_seconds, batch.run->wall_seconds);
    result.stepping_seconds = std::max(result.stepping_seconds, batch.run->stepping_seconds);
    result.spring_steps += batch.run->spring_steps;
  }
  for (std::size_t p = 0; p < patients.size(); ++p)
    append_for_patients(patient_diagnostics[p], patients, p, diagnostics);
  if (!every_batch) return std::nullopt;
  return result;
}

}  // namespace fmpc::sim

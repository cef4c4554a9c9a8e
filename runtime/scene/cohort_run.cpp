#include <algorithm>
#include <regex>

#include "runtime/io/atomic_file.h"
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
  for (const CohortPatient& patient : patients)
    if (!ensure_directory(patient.output_directory, diagnostics)) return std::nullopt;
#if !defined(FMPC_RUNTIME_HAVE_CUDA)
  if (options.backend == "cuda") {
    diagnostics.error(SourceRange{}, "this fmpc was built without CUDA; run the cohort with backend cpu or auto");
    return std::nullopt;
  }
#endif
  // Each patient's messages kept apart, then named by its label; the batch's ("scene N: ...") named by the patient
  // they are about.
  std::vector<DiagnosticList> patient_diagnostics(patients.size());
  std::vector<SceneBatchMember> members(patients.size());
  for (std::size_t p = 0; p < patients.size(); ++p) {
    members[p].scene = patients[p].scene;
    members[p].built = patients[p].built;
    members[p].options.output_directory = patients[p].output_directory;
    members[p].options.backend = options.backend;
    members[p].diagnostics = &patient_diagnostics[p];
  }
  DiagnosticList batch_diagnostics;
  const auto run =
      run_scene_batch(members, run_backend(options.backend), options.threads, options.progress, batch_diagnostics);
  append_for_patients(batch_diagnostics, patients, std::nullopt, diagnostics);
  for (std::size_t p = 0; p < patients.size(); ++p)
    append_for_patients(patient_diagnostics[p], patients, p, diagnostics);
  if (!run) return std::nullopt;
  CohortRunResult result;
  result.patients = run->results;
  result.wall_seconds = run->wall_seconds;
  result.stepping_seconds = run->stepping_seconds;
  result.spring_steps = run->spring_steps;
  return result;
}

}  // namespace fmpc::sim

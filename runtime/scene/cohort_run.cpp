#include <algorithm>
#include <chrono>
#include <mutex>
#include <regex>
#include <thread>

#include "runtime/integrate/worker_pool.h"
#include "runtime/io/atomic_file.h"
#include "runtime/scene/precision_check.h"
#include "runtime/scene/scene_recorder.h"
#include "runtime/scene/scene_run.h"
#if defined(FMPC_RUNTIME_HAVE_CUDA)
#include "runtime/gpu/gpu_simulation.h"
#endif

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

#if defined(FMPC_RUNTIME_HAVE_CUDA)
// One patient of a GPU batch as the recorder reads it: the state downloaded at the event for every patient at once
// (GpuBatchSimulation::scene_states), the probe read on the host from it exactly as GpuBatchSimulation::probe_reading
// reads it (sim::read_probe on the same positions, velocities and stiffness), so each patient's outputs are those of
// its run alone.
class BatchMemberState final : public SceneState {
 public:
  BatchMemberState(const gpu::GpuBatchSimulation& batch, std::size_t index, const SimulationSetup& setup)
      : batch_(batch), index_(index), setup_(setup) {}
  // The springs' stiffness is constant without a strain table: read once.
  bool read_stiffness(DiagnosticList& diagnostics) {
    if (setup_.strain_stiffness) return true;
    stiffness_ = batch_.current_stiffness(index_, diagnostics);
    return stiffness_.size() == setup_.springs.size();
  }
  void set_state(std::vector<Point3>* positions, std::vector<Point3>* velocities) {
    positions_ = positions;
    velocities_ = velocities;
  }
  std::size_t steps_taken() const override { return batch_.steps_taken(); }
  double time() const override { return static_cast<double>(steps_taken()) * stability().time_step; }
  const StabilityReport& stability() const override { return batch_.stability(index_); }
  std::vector<Point3> positions(DiagnosticList&) const override { return positions_ ? *positions_ : std::vector<Point3>{}; }
  std::vector<Point3> velocities(DiagnosticList&) const override {
    return velocities_ ? *velocities_ : std::vector<Point3>{};
  }
  ProbeReading probe_reading(DiagnosticList& diagnostics) const override {
    if (!setup_.probe || !positions_ || !velocities_) return {};
    return read_probe(setup_, time(), *positions_, *velocities_, current_stiffness(diagnostics));
  }
  std::vector<double> current_stiffness(DiagnosticList& diagnostics) const override {
    if (setup_.strain_stiffness) return batch_.current_stiffness(index_, diagnostics);
    return stiffness_;
  }
  const InversionReport& inversions() const override { return batch_.inversions(index_); }

 private:
  const gpu::GpuBatchSimulation& batch_;
  std::size_t index_;
  const SimulationSetup& setup_;
  std::vector<double> stiffness_;
  std::vector<Point3>* positions_ = nullptr;
  std::vector<Point3>* velocities_ = nullptr;
};

// Every patient's state now, one download per array for the whole batch.
bool read_members(const gpu::GpuBatchSimulation& batch, bool with_velocities, std::vector<std::vector<Point3>>& positions,
                  std::vector<std::vector<Point3>>& velocities, std::vector<BatchMemberState>& members,
                  DiagnosticList& diagnostics) {
  if (!batch.scene_states(positions, with_velocities ? &velocities : nullptr, diagnostics)) return false;
  for (std::size_t p = 0; p < members.size(); ++p)
    members[p].set_state(&positions[p], with_velocities ? &velocities[p] : nullptr);
  return true;
}

std::optional<CohortRunResult> run_cohort_on_gpu(const std::vector<CohortPatient>& patients,
                                                 const CohortRunOptions& options, DiagnosticList& diagnostics) {
  std::vector<SimulationSetup> setups;
  for (const CohortPatient& patient : patients) setups.push_back(patient.built->setup);
  DiagnosticList batch_diagnostics;
  const auto batch = gpu::GpuBatchSimulation::create(setups, gpu::GpuOptions{}, batch_diagnostics);
  append_for_patients(batch_diagnostics, patients, std::nullopt, diagnostics);
  if (!batch) return std::nullopt;
  std::vector<BatchMemberState> members;
  for (std::size_t p = 0; p < patients.size(); ++p) members.emplace_back(*batch, p, patients[p].built->setup);
  for (BatchMemberState& member : members)
    if (!member.read_stiffness(diagnostics)) return std::nullopt;
  const Scene& scene = *patients.front().scene;
  const auto planned = planned_step_count(scene, batch->stability(0).time_step, diagnostics);
  if (!planned) return std::nullopt;
  const std::size_t total = *planned;
  std::vector<SceneRunOptions> run_options(patients.size());
  std::vector<std::unique_ptr<SceneRecorder>> recorders;
  for (std::size_t p = 0; p < patients.size(); ++p) {
    run_options[p].output_directory = patients[p].output_directory;
    run_options[p].backend = "cuda";
    recorders.push_back(std::make_unique<SceneRecorder>(*patients[p].scene, *patients[p].built, run_options[p], total));
  }
  // Every patient has the same events (same scene outputs, same step count): the first recorder's.
  const SceneRecorder& plan = *recorders.front();
  std::vector<std::vector<Point3>> positions, velocities;
  std::vector<DiagnosticList> patient_diagnostics(patients.size());
  const auto record_all = [&](bool frame, bool sample) {
    if (!read_members(*batch, frame || sample, positions, velocities, members, diagnostics)) return false;
    for (std::size_t p = 0; p < patients.size(); ++p) recorders[p]->record(members[p], frame, sample, patient_diagnostics[p]);
    return true;
  };
  const auto start = std::chrono::steady_clock::now();
  bool running = true;
  if (plan.is_frame(0) || plan.is_sample(0)) running = record_all(plan.is_frame(0), plan.is_sample(0));
  DiagnosticList run_diagnostics;
  for (const std::size_t event : plan.events()) {
    if (!running || event == 0) continue;
    running = batch->advance(event - batch->steps_taken(), run_diagnostics);
    if (!running) break;
    if (!record_all(plan.is_frame(event), plan.is_sample(event))) {
      append_for_patients(run_diagnostics, patients, std::nullopt, diagnostics);
      return std::nullopt;
    }
    if (options.progress) options.progress(event, total);
  }
  append_for_patients(run_diagnostics, patients, std::nullopt, diagnostics);
  if (!running) record_all(plan.records_at_end(), plan.samples_at_end());
  CohortRunResult result;
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // The precision check: every patient again in the other precision, in a second batch at the same step.
  SceneRunResult provisional;
  provisional.completed = running;
  provisional.steps_taken = batch->steps_taken();
  std::vector<SimulationSetup> other_setups;  // outlives other_members, which refer to it
  std::unique_ptr<gpu::GpuBatchSimulation> other;
  std::vector<BatchMemberState> other_members;
  std::vector<std::vector<Point3>> other_positions, other_velocities;
  if (!precision_check_skipped(scene, setups.front(), provisional)) {
    provisional.stability = batch->stability(0);
    for (const SimulationSetup& setup : setups) other_setups.push_back(precision_check_setup(setup, provisional));
    DiagnosticList ignored;  // the main run reported everything the scene says
    other = gpu::GpuBatchSimulation::create(other_setups, gpu::GpuOptions{}, ignored);
    if (other && other->advance(provisional.steps_taken, ignored)) {
      for (std::size_t p = 0; p < patients.size(); ++p) other_members.emplace_back(*other, p, other_setups[p]);
      bool read = read_members(*other, true, other_positions, other_velocities, other_members, ignored);
      for (BatchMemberState& member : other_members) read = read && member.read_stiffness(ignored);
      if (!read) other_members.clear();
    }
  }
  for (std::size_t p = 0; p < patients.size(); ++p) {
    const SceneState* other_state = other_members.empty() ? nullptr : &other_members[p];
    const SimulationSetup& setup = patients[p].built->setup;
    result.patients.push_back(recorders[p]->finish(
        members[p], running, result.wall_seconds,
        [&](const SceneRunResult& run) {
          if (const auto skipped = precision_check_skipped(*patients[p].scene, setup, run)) {
            PrecisionCheckResult check;
            check.other = setup.precision == Precision::Float ? Precision::Double : Precision::Float;
            check.reason = *skipped;
            return check;
          }
          return compare_precision(*patients[p].scene, setup, run, other_state, patient_diagnostics[p]);
        },
        patient_diagnostics[p]));
    append_for_patients(patient_diagnostics[p], patients, p, diagnostics);
    result.spring_steps += static_cast<double>(setup.springs.size()) * static_cast<double>(batch->steps_taken());
  }
  return result;
}
#endif

std::optional<CohortRunResult> run_cohort_on_cpu(const std::vector<CohortPatient>& patients,
                                                 const CohortRunOptions& options, DiagnosticList& diagnostics) {
  CohortRunResult result;
  result.patients.resize(patients.size());
  std::vector<DiagnosticList> patient_diagnostics(patients.size());
  std::mutex progress_lock;
  std::size_t done = 0;
  const unsigned threads = options.threads != 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  WorkerPool pool(static_cast<unsigned>(std::min<std::size_t>(threads, patients.size())));
  const auto start = std::chrono::steady_clock::now();
  // One patient per index: chunks of whole patients, each run exactly as run_scene runs it alone.
  pool.run(
      patients.size(),
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t p = begin; p < end; ++p) {
          SceneRunOptions run_options;
          run_options.output_directory = patients[p].output_directory;
          run_options.backend = "cpu";
          result.patients[p] = run_scene(*patients[p].scene, *patients[p].built, run_options, patient_diagnostics[p]);
          const std::lock_guard<std::mutex> lock(progress_lock);
          ++done;
          if (options.progress) options.progress(done, patients.size());
        }
      },
      1);
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t p = 0; p < patients.size(); ++p) {
    append_for_patients(patient_diagnostics[p], patients, p, diagnostics);
    if (result.patients[p])
      result.spring_steps += static_cast<double>(patients[p].built->setup.springs.size()) *
                             static_cast<double>(result.patients[p]->steps_taken);
  }
  return result;
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
  if (options.backend == "cuda") {
#if defined(FMPC_RUNTIME_HAVE_CUDA)
    return run_cohort_on_gpu(patients, options, diagnostics);
#else
    diagnostics.error(SourceRange{}, "this fmpc was built without CUDA; run the cohort with backend cpu or auto");
    return std::nullopt;
#endif
  }
  return run_cohort_on_cpu(patients, options, diagnostics);
}

}  // namespace fmpc::sim

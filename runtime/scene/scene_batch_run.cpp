#include "runtime/scene/scene_batch_run.h"

#include <chrono>
#include <memory>

#include "runtime/integrate/worker_pool.h"
#include "runtime/io/atomic_file.h"
#include "runtime/scene/precision_check.h"
#include "runtime/scene/scene_recorder.h"
#include "runtime/scene/scene_state.h"

namespace fmpc::sim {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point from) { return std::chrono::duration<double>(Clock::now() - from).count(); }

// The members' states at an event: a scene alone reads its simulation; a batch's scenes are read at once (one
// download per array on CUDA) into host copies (SceneState).
class BatchReader {
 public:
  explicit BatchReader(const Simulation& simulation) : simulation_(simulation) {
    for (std::size_t s = 0; s < simulation.scene_count(); ++s) states_.emplace_back(simulation, s);
  }
  bool read_stiffness(DiagnosticList& diagnostics) {
    if (states_.size() == 1) return true;
    for (SceneState& state : states_)
      if (!state.read_stiffness(diagnostics)) return false;
    return true;
  }
  bool read(bool with_velocities, DiagnosticList& diagnostics) {
    if (states_.size() == 1) return true;
    if (!simulation_.scene_states(positions_, with_velocities ? &velocities_ : nullptr, diagnostics)) return false;
    for (std::size_t s = 0; s < states_.size(); ++s)
      states_[s].set_state(&positions_[s], with_velocities ? &velocities_[s] : nullptr);
    return true;
  }
  const SceneState& state(std::size_t s) const { return states_[s]; }

 private:
  const Simulation& simulation_;
  std::vector<SceneState> states_;
  std::vector<std::vector<Point3>> positions_, velocities_;
};

// f(m) for every member: side by side on a pool for a batch (each member writes only its own outputs and messages),
// in the caller's thread for a scene alone.
template <typename Task>
void for_each_member(std::size_t count, WorkerPool* pool, Task task) {
  if (pool == nullptr) {
    for (std::size_t m = 0; m < count; ++m) task(m);
    return;
  }
  pool->run(
      count,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t m = begin; m < end; ++m) task(m);
      },
      1);
}

}  // namespace

std::optional<SceneBatchResult> run_scene_batch(const std::vector<SceneBatchMember>& members,
                                                const SimulationOptions& options,
                                                const std::function<void(std::size_t, std::size_t)>& progress,
                                                DiagnosticList& diagnostics) {
  SceneRunTiming timing;
  std::vector<SimulationSetup> setups;
  for (const SceneBatchMember& member : members) setups.push_back(member.built->setup);
  const auto created = Clock::now();
  const auto simulation = Simulation::create(std::move(setups), options, diagnostics);
  if (!simulation) return std::nullopt;
  timing.simulator = seconds_since(created);
  for (const SceneBatchMember& member : members)
    if (!ensure_directory(member.options.output_directory, *member.diagnostics)) return std::nullopt;
  BatchReader reader(*simulation);
  if (!reader.read_stiffness(diagnostics)) return std::nullopt;
  const Scene& scene = *members.front().scene;
  const auto planned = planned_step_count(scene, simulation->stability(0).time_step, diagnostics);
  if (!planned) return std::nullopt;
  const std::size_t total = *planned;
  std::vector<std::unique_ptr<SceneRecorder>> recorders;
  for (const SceneBatchMember& member : members)
    recorders.push_back(std::make_unique<SceneRecorder>(*member.scene, *member.built, member.options, total));
  std::unique_ptr<WorkerPool> pool;
  if (members.size() > 1) pool = std::make_unique<WorkerPool>(resolve_thread_count(options.batch_threads, members.size(), 2));
  // Every member has the same events (the same scene outputs, the same step count): the first recorder's.
  const SceneRecorder& plan = *recorders.front();
  const bool implicit = simulation->setup(0).integrator == Integrator::ImplicitEuler;
  const auto record_all = [&](bool frame, bool sample) {
    const auto from = Clock::now();
    if (implicit)
      for (std::size_t m = 0; m < members.size(); ++m) recorders[m]->add_solver_steps(simulation->take_implicit_steps(m));
    const bool read = reader.read(frame || sample, diagnostics);
    if (read)
      for_each_member(members.size(), pool.get(), [&](std::size_t m) {
        recorders[m]->record(reader.state(m), frame, sample, *members[m].diagnostics);
      });
    timing.recording += seconds_since(from);
    return read;
  };
  const auto start = Clock::now();
  bool running = true;
  if (plan.is_frame(0) || plan.is_sample(0)) running = record_all(plan.is_frame(0), plan.is_sample(0));
  bool first = true;
  for (const std::size_t event : plan.events()) {
    if (!running || event == 0) continue;
    const auto from = Clock::now();
    // A step stopped at the solver's cap is said once, at the end, with how many did (capped_steps_message).
    DiagnosticList advance_diagnostics;
    running = simulation->advance(event - simulation->steps_taken(), advance_diagnostics);
    const double advanced = seconds_since(from);
    for (const Diagnostic& diagnostic : advance_diagnostics.items())
      if (diagnostic.code != "cg-not-converged") diagnostics.add(diagnostic);
    timing.stepping += advanced;
    if (first) timing.first_advance = advanced;
    first = false;
    if (!running) break;
    // The largest displacement is followed at every event (about 100 per run).
    if (!record_all(plan.is_frame(event), plan.is_sample(event))) return std::nullopt;
    if (progress) progress(event, total);
  }
  if (!running) record_all(plan.records_at_end(), plan.samples_at_end());
  SceneBatchResult result;
  result.wall_seconds = seconds_since(start);
  result.stepping_seconds = timing.stepping;
  if (implicit)
    for (std::size_t m = 0; m < members.size(); ++m)
      if (const auto message = capped_steps_message(simulation->implicit_solver(m))) {
        const Scene& member_scene = *members[m].scene;
        const SourceRange at = member_scene.ranges.count("solver") ? member_scene.range_of("solver")
                                                                     : simulation->setup(m).source_range;
        members[m].diagnostics->warning(at, "cg-not-converged", *message);
      }

  // The precision check: every member again in the other precision, as a second batch at the same step.
  SceneRunResult provisional;
  provisional.completed = running;
  provisional.steps_taken = simulation->steps_taken();
  std::unique_ptr<Simulation> other;
  std::unique_ptr<BatchReader> other_reader;
  if (!precision_check_skipped(scene, provisional, result.wall_seconds)) {
    provisional.stability = simulation->stability(0);
    std::vector<SimulationSetup> other_setups;
    for (std::size_t m = 0; m < members.size(); ++m)
      other_setups.push_back(precision_check_setup(simulation->setup(m), provisional));
    DiagnosticList ignored;  // the run reported everything the scene says
    other = Simulation::create(std::move(other_setups), options, ignored);
    if (other && other->advance(provisional.steps_taken, ignored)) {
      other_reader = std::make_unique<BatchReader>(*other);
      if (!other_reader->read_stiffness(ignored) || !other_reader->read(true, ignored)) other_reader.reset();
    }
  }
  result.results.resize(members.size());
  for (auto& recorder : recorders) recorder->set_timing(timing);
  for_each_member(members.size(), pool.get(), [&](std::size_t m) {
    const SceneBatchMember& member = members[m];
    const SimulationSetup& setup = simulation->setup(m);
    result.results[m] = recorders[m]->finish(
        reader.state(m), running, result.wall_seconds,
        [&](const SceneRunResult& run) {
          if (const auto skipped = precision_check_skipped(*member.scene, run, result.wall_seconds)) {
            PrecisionCheckResult check;
            check.other = setup.precision == Precision::Float ? Precision::Double : Precision::Float;
            check.reason = *skipped;
            return check;
          }
          return compare_precision(*member.scene, setup, run, other_reader ? &other_reader->state(m) : nullptr,
                                   *member.diagnostics);
        },
        *member.diagnostics);
  });
  for (std::size_t m = 0; m < members.size(); ++m)
    result.spring_steps +=
        static_cast<double>(simulation->setup(m).springs.size()) * static_cast<double>(simulation->steps_taken());
  return result;
}

}  // namespace fmpc::sim

#include "runtime/scene/trade_runs.h"

#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numeric>
#include <thread>
#include <utility>

#include "diagnostics/number_format.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/io/memory_limit.h"
#include "runtime/mesh/mesh_refinement.h"
#include "runtime/scene/trade_schedule.h"

namespace fmpc::sim {

namespace {

// CPU time of the calling thread: each CPU run steps on one thread, and runs go side by side, so the process's time
// would count the others.
double thread_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string short_model(const TradeModel& model) {
  if (model.element_law >= 0) return element_law_row(model.element_law).trade_label;
  return model.mapping == StiffnessMapping::LloydSzekelyHarders2007 ? "springs LSH" : "springs VG";
}

const char* short_integrator(Integrator integrator) {
  switch (integrator) {
    case Integrator::ForwardEuler:
      return "FE";
    case Integrator::SemiImplicitEuler:
      return "SIE";
    case Integrator::VelocityVerlet:
      return "VV";
    case Integrator::RungeKutta4:
      return "RK4";
    case Integrator::ImplicitEuler:
      return "IE";
  }
  return "?";
}

double dot3(const Point3& a, const Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// The row's description of the run, before it steps; the step: a whole number of steps ending at the duration,
// each at most dt_factor x the automatic step.
SimulationTradeRow prepared_row(const RunKey& key, const BuiltRun& built, const Scene& scene, double duration,
                                SimulationSetup& setup) {
  SimulationTradeRow row;
  row.variant = run_label(key);
  row.model = key.build.model;
  row.element_kind = key.build.element_kind;
  row.mesh = key.build.mesh;
  row.mapping = key.build.model.element_law < 0 ? key.build.model.mapping : scene.material.mapping;
  row.precision = key.precision;
  row.integrator = {key.integrator, key.dt_factor};
  row.refinements = key.build.refinements;
  row.vertices = built.scene.mesh.points.size();
  row.tetrahedra = built.scene.mesh.tetrahedra.size();
  setup = built.scene.setup;
  setup.precision = key.precision;
  setup.integrator = key.integrator;
  setup.threads = 1;
  const double step = key.dt_factor * built.automatic_step;
  row.steps = static_cast<std::size_t>(std::max(1.0, steps_covering(duration, step)));
  row.dt = duration / static_cast<double>(row.steps);
  setup.time_step = row.dt;
  setup.step_count = row.steps;
  row.memory_bytes = trade_memory_estimate(setup, built.edges);
  return row;
}

double extent_of(const SimulationSetup& setup) {
  Point3 low = setup.rest_positions.front(), high = low;
  for (const Point3& p : setup.rest_positions)
    for (std::size_t a = 0; a < 3; ++a) low[a] = std::min(low[a], p[a]), high[a] = std::max(high[a], p[a]);
  return distance(low, high);
}

// The state of scene `s` of a finished simulation into the outcome: the compared vertices' displacement, the
// probe's force along its target, the inversions.
void read_outcome(const Simulation& simulation, std::size_t s, const SimulationSetup& setup,
                  std::size_t compared_vertices, RunOutcome& outcome, DiagnosticList& diagnostics) {
  SimulationTradeRow& row = outcome.row;
  row.inverted_elements = simulation.inversions(s).largest_count;
  const std::vector<Point3> positions = simulation.positions(s, diagnostics);
  outcome.displacement.assign(compared_vertices, Point3{0.0, 0.0, 0.0});
  for (std::size_t v = 0; v < compared_vertices && v < positions.size(); ++v) {
    const Point3& start_point = start_position(setup, v);
    for (std::size_t a = 0; a < 3; ++a) outcome.displacement[v][a] = positions[v][a] - start_point[a];
    row.final_max_displacement =
        std::max(row.final_max_displacement, std::sqrt(dot3(outcome.displacement[v], outcome.displacement[v])));
  }
  if (setup.probe && setup.probe->mode == ProbeLoad::Mode::Displacement) {
    const double length = std::sqrt(dot3(setup.probe->target, setup.probe->target));
    if (length > 0.0) row.final_probe_force = dot3(simulation.probe_reading(s, diagnostics).force, setup.probe->target) / length;
  } else if (!setup.tools.empty() && !setup.tools.front().path.empty()) {
    // The first tool's force against its travel (trade_probe_force_source): the tissue pushing back on a press.
    const std::vector<ToolKeyframe>& path = setup.tools.front().path;
    Point3 travel{};
    for (std::size_t a = 0; a < 3; ++a) travel[a] = path.back().pose.position[a] - path.front().pose.position[a];
    const double length = std::sqrt(dot3(travel, travel));
    const std::vector<ToolReading> readings = simulation.tool_readings(s, diagnostics);
    if (length > 0.0 && !readings.empty()) row.final_probe_force = -dot3(readings.front().force, travel) / length;
  }
}

void record_failure(SimulationTradeRow& row, const DiagnosticList& run_diagnostics) {
  if (row.completed) return;
  for (const Diagnostic& d : run_diagnostics.items())
    if (d.severity == Severity::Error) {
      row.failure = d.message;
      return;
    }
  row.failure = "did not complete";
}

// Steps a created simulation from `from` to `steps` in hundredths of the run (progress during a long run; advance
// resumes where it stopped; the checks advance makes at its end do not change the state), adding the stepping's
// time to `cpu` and `wall`; `stop` (optional), asked after each chunk with the steps done and the CPU time so far,
// ends it early. Returns whether every step completed.
bool step_to_end(Simulation& simulation, std::size_t from, std::size_t steps, DiagnosticList& diagnostics,
                 double& cpu, double& wall, const std::function<void(std::size_t)>& stepped,
                 const std::function<bool(std::size_t, double)>& stop = {}) {
  const double cpu_start = thread_cpu_seconds() - cpu, wall_start = wall_seconds() - wall;
  const std::size_t hundredth = std::max<std::size_t>(1, steps / 100);
  // Asked to stop early, it starts with one step and doubles up to a hundredth: a prefix of an expensive run (an
  // implicit step on the quadratic block took 0.1 s) is cut at the first step past its time, not a hundredth later.
  std::size_t chunk = stop ? 1 : hundredth;
  bool completed = true;
  for (std::size_t done = from; done < steps && completed;) {
    const std::size_t now = std::min(chunk, steps - done);
    completed = simulation.advance(now, diagnostics);
    done += now;
    chunk = std::min(2 * chunk, hundredth);
    if (stepped) stepped(now);
    if (stop && done < steps && stop(done, thread_cpu_seconds() - cpu_start)) break;
  }
  cpu = thread_cpu_seconds() - cpu_start;
  wall = wall_seconds() - wall_start;
  return completed;
}

void finish_timing(SimulationTradeRow& row, std::size_t steps_taken, double cpu, double wall, double duration) {
  row.cpu_seconds = cpu;
  row.wall_seconds = wall;
  row.steps_per_second = static_cast<double>(steps_taken) / std::max(cpu, 1e-9);
  row.real_time_factor = row.completed ? duration / std::max(wall, 1e-9) : 0.0;
}

// The progress of all runs, told one call at a time.
class WorkCounter {
 public:
  explicit WorkCounter(const std::function<void(double)>& done) : done_(done) {}
  void add(double work) {
    if (!done_) return;
    const std::lock_guard<std::mutex> lock(mutex_);
    total_ += work;
    done_(total_);
  }

 private:
  const std::function<void(double)>& done_;
  std::mutex mutex_;
  double total_ = 0.0;
};

// A run on one thread (or the GPU), started and stepped in parts: what run_alone does at once, and what the
// cheapest-first runs pause after their prefix.
struct StartedRun {
  RunOutcome outcome;
  SimulationSetup setup;
  DiagnosticList diagnostics;
  std::unique_ptr<Simulation> simulation;  // null: not created (an error in diagnostics), or dropped while paused
  std::size_t steps_done = 0;
  double cpu = 0.0, wall = 0.0;  // s, of the stepping so far
  bool failed = false;           // an advance returned false
};

void start_run(const RunKey& key, const BuiltRun& built, const Scene& scene, const TradeExecution& execution,
               StartedRun& run) {
  run.outcome = RunOutcome{};
  run.outcome.row = prepared_row(key, built, scene, execution.duration, run.setup);
  run.outcome.extent = extent_of(run.setup);
  run.diagnostics = DiagnosticList{};
  run.steps_done = 0;
  run.cpu = run.wall = 0.0;
  run.failed = false;
  SimulationOptions options;
  options.backend = execution.gpu ? Backend::Cuda : Backend::Cpu;
  options.batch_threads = 1;
  run.simulation = Simulation::create(run.setup, run.diagnostics, options);
}

// Steps a started run on towards its end (until `stop` says so, when given); true when it has ended (every step
// taken, or failed).
bool step_run(StartedRun& run, double work, WorkCounter& counter,
              const std::function<bool(std::size_t, double)>& stop = {}) {
  if (!run.simulation) return true;
  const std::size_t steps = run.outcome.row.steps;
  const bool completed = step_to_end(*run.simulation, run.steps_done, steps, run.diagnostics, run.cpu, run.wall,
                                     [&](std::size_t now) {
                                       counter.add(work * static_cast<double>(now) / static_cast<double>(steps));
                                     },
                                     stop);
  run.steps_done = run.simulation->steps_taken();
  run.failed = !completed;
  return run.failed || run.steps_done >= steps;
}

// The ended run's row: its timing, final state and failure.
RunOutcome finish_run(StartedRun& run, const TradeExecution& execution) {
  if (run.simulation) {
    run.outcome.row.completed = !run.failed && run.steps_done >= run.outcome.row.steps;
    finish_timing(run.outcome.row, run.simulation->steps_taken(), run.cpu, run.wall, execution.duration);
    read_outcome(*run.simulation, 0, run.setup, execution.compared_vertices, run.outcome, run.diagnostics);
  }
  record_failure(run.outcome.row, run.diagnostics);
  run.simulation.reset();
  return std::move(run.outcome);
}

// One run alone on the calling thread (or the GPU).
std::optional<RunOutcome> run_alone(const RunKey& key, const BuiltRun& built, const Scene& scene,
                                    const TradeExecution& execution, double work, WorkCounter& counter) {
  StartedRun run;
  start_run(key, built, scene, execution, run);
  step_run(run, work, counter);
  return finish_run(run, execution);
}

// Runs that can share one launch: the same model, element kind, precision and explicit integrator, and the same
// number of steps (a batch advances every scene together; each keeps its own mesh and step).
auto batch_group(const RunKey& key, std::size_t steps) {
  return std::make_tuple(key.build.model, key.build.element_kind, key.precision, key.integrator, steps);
}

// A group of runs as one Simulation batch; when the batch cannot be created (what a GPU batch cannot share), each
// runs alone. Every member's wall time is the batch's: it ran for all of them.
void run_batch(const std::vector<std::size_t>& members, const std::vector<RunKey>& keys,
               const std::vector<std::shared_ptr<const BuiltRun>>& built, const std::vector<double>& work,
               const Scene& scene, const TradeExecution& execution, WorkCounter& counter,
               std::vector<std::optional<RunOutcome>>& outcomes) {
  std::vector<SimulationSetup> setups(members.size());
  std::vector<RunOutcome> prepared(members.size());
  for (std::size_t m = 0; m < members.size(); ++m) {
    const std::size_t i = members[m];
    prepared[m].row = prepared_row(keys[i], *built[i], scene, execution.duration, setups[m]);
    prepared[m].extent = extent_of(setups[m]);
  }
  DiagnosticList batch_diagnostics;
  SimulationOptions options;
  options.backend = execution.gpu ? Backend::Cuda : Backend::Cpu;
  options.batch_threads = execution.threads;
  std::unique_ptr<Simulation> simulation;
  if (members.size() > 1) simulation = Simulation::create(setups, options, batch_diagnostics);
  if (!simulation) {
    for (const std::size_t i : members)
      outcomes[i] = run_alone(keys[i], *built[i], scene, execution, work[i], counter);
    return;
  }
  double batch_work = 0.0;
  for (const std::size_t i : members) batch_work += work[i];
  const std::size_t steps = prepared.front().row.steps;
  double cpu = 0.0, wall = 0.0;
  const bool completed = step_to_end(*simulation, 0, steps, batch_diagnostics, cpu, wall, [&](std::size_t now) {
    counter.add(batch_work * static_cast<double>(now) / static_cast<double>(steps));
  });
  for (std::size_t m = 0; m < members.size(); ++m) {
    RunOutcome& outcome = prepared[m];
    outcome.row.completed = completed;
    finish_timing(outcome.row, simulation->steps_taken(), wall, wall, execution.duration);
    DiagnosticList read_diagnostics;
    read_outcome(*simulation, m, setups[m], execution.compared_vertices, outcome, read_diagnostics);
    record_failure(outcome.row, batch_diagnostics);
    outcomes[members[m]] = std::move(outcome);
  }
}

// Runs `worker` on min(threads, tasks) threads (at least one: the calling thread is one of them) and waits for all.
void on_workers(unsigned threads, std::size_t tasks, const std::function<void()>& worker) {
  const unsigned count = std::max(1u, std::min<unsigned>(threads, static_cast<unsigned>(tasks)));
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < count; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& thread : pool) thread.join();
}

}  // namespace

bool trade_has_springs(const TradeModel& model) {
  return model.element_law < 0 || element_law_row(model.element_law).beside_springs;
}

std::string trade_percent(double fraction) { return significant_digits(100.0 * fraction, 3) + "%"; }

std::string run_label(const RunKey& key) {
  std::string text = short_model(key.build.model);
  if (key.build.element_kind > 0) text += std::string(" ") + element_kind_row(key.build.element_kind).keyword;
  text += (key.precision == Precision::Float ? " f32 " : " f64 ") + std::string(short_integrator(key.integrator));
  if (key.dt_factor != 1.0) text += " x" + significant_digits(key.dt_factor, 3);
  text += " r" + std::to_string(key.build.refinements);
  if (key.build.mesh == TradeMesh::Uniform) text += " uniform";
  return text;
}

Scene trade_variant_scene(const Scene& scene, const BuildKey& key, double duration) {
  Scene variant = scene;
  variant.duration = duration;
  variant.steps.reset();
  const TradeModel& model = key.model;
  variant.volume_term = model.element_law >= 0 && element_law_row(model.element_law).beside_springs;
  variant.model = trade_has_springs(model) ? ForceModel::Springs : ForceModel::Elements;
  if (!trade_has_springs(model)) {
    variant.element_law = model.element_law;
    variant.element_kind = std::max(key.element_kind, 0);
  }
  if (model.element_law < 0) variant.material.mapping = model.mapping;
  if (key.mesh == TradeMesh::Uniform) {
    // Uniform at the size the scene asks for near the tool.
    SceneSurfaceMeshing& surface = variant.mesh.surface;
    surface.options.size.size_far = surface.options.size.size_near;
    surface.size_far_given = true;
  }
  return variant;
}

std::shared_ptr<const BuiltRun> TradeScenes::get(const BuildKey& key, DiagnosticList& diagnostics) {
  std::shared_ptr<Slot> slot;
  {
    const std::lock_guard<std::mutex> lock(slots_mutex_);
    std::shared_ptr<Slot>& entry = slots_[key];
    if (!entry) entry = std::make_shared<Slot>();
    slot = entry;
  }
  const std::lock_guard<std::mutex> building(slot->building);
  if (slot->built) return slot->built;
  const std::string variant = run_label(RunKey{key, Precision::Double, Integrator::SemiImplicitEuler, 1.0});
  if (!slot->failed) {
    DiagnosticList build_diagnostics;
    auto scene = build_scene(trade_variant_scene(scene_, key, duration_), build_diagnostics, key.refinements);
    auto built = std::make_shared<BuiltRun>();
    if (scene) {
      built->scene = std::move(*scene);
      built->edges = distinct_edge_count(built->scene.mesh);
      // Semi-implicit Euler's automatic step on this model and mesh: what every variant's step is a factor of.
      SimulationSetup setup = built->scene.setup;
      setup.integrator = Integrator::SemiImplicitEuler;
      setup.precision = Precision::Double;
      setup.time_step.reset();
      const auto report = check_stability(setup, build_diagnostics);
      built->automatic_step = report ? report->time_step : 0.0;
      if (report && built->automatic_step > 0.0 && std::isfinite(built->automatic_step)) {
        slot->built = std::move(built);
        return slot->built;
      }
      slot->errors.error(scene_.range_of("model"), "the " + variant + " variant has no automatic step to scale (above)");
    } else {
      slot->errors.error(scene_.range_of("model"), "the " + variant + " variant cannot be built from this scene "
                                                                       "(above); leave it out with --variants or "
                                                                       "the axis's option");
    }
    slot->failed = true;
    DiagnosticList errors;
    for (const Diagnostic& d : build_diagnostics.items())
      if (d.severity == Severity::Error) errors.error(d.range, d.message, d.notes);
    errors.append(slot->errors);
    slot->errors = std::move(errors);
  }
  diagnostics.append(slot->errors);
  return nullptr;
}

void TradeScenes::drop(const BuildKey& key) {
  const std::lock_guard<std::mutex> lock(slots_mutex_);
  const auto it = slots_.find(key);
  if (it == slots_.end()) return;
  const std::lock_guard<std::mutex> building(it->second->building);
  if (!it->second->failed) slots_.erase(it);
}

std::vector<std::optional<RunOutcome>> execute_trade_runs(const std::vector<RunKey>& keys,
                                                          const std::vector<double>& work, TradeScenes& scenes,
                                                          const TradeExecution& execution,
                                                          const std::function<void(double)>& done,
                                                          DiagnosticList& diagnostics) {
  std::vector<std::optional<RunOutcome>> outcomes(keys.size());
  // The most work first (the longest runs do not start last); the runs on one built scene stay together.
  std::vector<std::size_t> order(keys.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return work[a] > work[b]; });
  std::map<BuildKey, std::size_t> users;
  for (const RunKey& key : keys) ++users[key.build];
  WorkCounter counter(done);
  std::mutex shared;  // diagnostics, users
  const auto finished = [&](const BuildKey& build) {
    const std::lock_guard<std::mutex> lock(shared);
    if (--users[build] == 0) scenes.drop(build);
  };

  if (execution.gpu || execution.batch) {
    // Every scene built first (one after another: the device runs one batch at a time anyway), then the groups.
    std::vector<std::shared_ptr<const BuiltRun>> built(keys.size());
    std::map<decltype(batch_group(RunKey{}, 0)), std::vector<std::size_t>> groups;
    std::vector<decltype(batch_group(RunKey{}, 0))> group_order;
    for (const std::size_t i : order) {
      built[i] = scenes.get(keys[i].build, diagnostics);
      if (!built[i]) continue;
      SimulationSetup setup;
      const std::size_t steps = prepared_row(keys[i], *built[i], scenes.scene(), execution.duration, setup).steps;
      const bool alone = keys[i].integrator == Integrator::ImplicitEuler;
      const auto group = alone ? std::make_tuple(keys[i].build.model, -2 - static_cast<int>(i), keys[i].precision,
                                                 keys[i].integrator, steps)
                               : batch_group(keys[i], steps);
      if (groups[group].empty()) group_order.push_back(group);
      groups[group].push_back(i);
    }
    for (const auto& group : group_order)
      run_batch(groups[group], keys, built, work, scenes.scene(), execution, counter, outcomes);
    return outcomes;
  }

  std::atomic<std::size_t> next{0};
  on_workers(execution.threads, keys.size(), [&] {
    for (std::size_t n = next++; n < order.size(); n = next++) {
      const std::size_t i = order[n];
      DiagnosticList run_diagnostics;
      const std::shared_ptr<const BuiltRun> built = scenes.get(keys[i].build, run_diagnostics);
      if (built) outcomes[i] = run_alone(keys[i], *built, scenes.scene(), execution, work[i], counter);
      finished(keys[i].build);
      const std::lock_guard<std::mutex> lock(shared);
      diagnostics.append(run_diagnostics);
    }
  });
  return outcomes;
}

CheapestFirstRuns execute_cheapest_first(const std::vector<RunKey>& keys, const std::vector<double>& work,
                                         TradeScenes& scenes, const TradeExecution& execution,
                                         const std::function<bool(const RunOutcome&)>& meets, double bound,
                                         const std::function<void(double)>& done, DiagnosticList& diagnostics) {
  CheapestFirstRuns result;
  result.outcomes.resize(keys.size());
  result.estimates.assign(keys.size(), std::nan(""));
  result.prefix_steps.assign(keys.size(), 0);
  result.skips.resize(keys.size());
  std::vector<StartedRun> runs(keys.size());
  CheapestFirstSchedule schedule(bound);
  WorkCounter counter(done);
  std::mutex shared;  // schedule, diagnostics, result, the paused runs' memory
  // Paused runs keep their state while it fits in a quarter of the memory this process may use (the runs that go
  // on then resume); beyond it a paused run is dropped and starts again from its first step if it goes on.
  const MemoryLimit limit = memory_limit();
  const double paused_budget = limit.bytes > 0 ? 0.25 * static_cast<double>(limit.bytes) : HUGE_VAL;
  double paused_bytes = 0.0;
  // Starts run i on its built scene; false after appending why it cannot be built.
  const auto start = [&](std::size_t i) {
    DiagnosticList build_diagnostics;
    const std::shared_ptr<const BuiltRun> built = scenes.get(keys[i].build, build_diagnostics);
    if (!built) {
      const std::lock_guard<std::mutex> lock(shared);
      diagnostics.append(build_diagnostics);
      return false;
    }
    start_run(keys[i], *built, scenes.scene(), execution, runs[i]);
    return true;
  };
  const auto ended_run = [&](std::size_t i) {
    RunOutcome outcome = finish_run(runs[i], execution);
    const bool met = outcome.row.completed && meets(outcome);
    const std::lock_guard<std::mutex> lock(shared);
    schedule.finished(outcome.row.cpu_seconds, met);
    result.outcomes[i] = std::move(outcome);
  };

  // The prefixes, the least planned work first (short runs end within theirs and bound the others early).
  std::vector<std::size_t> order(keys.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return work[a] < work[b]; });
  std::atomic<std::size_t> next{0};
  on_workers(execution.threads, keys.size(), [&] {
    for (std::size_t n = next++; n < order.size(); n = next++) {
      const std::size_t i = order[n];
      StartedRun& run = runs[i];
      if (!start(i)) continue;
      bool cut = false;
      const bool ended = step_run(run, work[i], counter, [&](std::size_t, double cpu) {
        const std::lock_guard<std::mutex> lock(shared);
        cut = schedule.beyond_bound(cpu);
        return cut || cpu >= execution.prefix_seconds;
      });
      const std::size_t steps = run.outcome.row.steps;
      if (ended) {
        ended_run(i);
        continue;
      }
      result.prefix_steps[i] = run.steps_done;
      const std::lock_guard<std::mutex> lock(shared);
      if (cut) {
        result.skips[i] = TradeSkip{run.cpu, true};
        run.simulation.reset();
        continue;
      }
      // Its CPU time per step so far, for the steps left.
      result.estimates[i] =
          run.cpu * static_cast<double>(steps) / static_cast<double>(std::max<std::size_t>(run.steps_done, 1));
      schedule.add(i, result.estimates[i]);
      const double bytes = 2.0 * run.outcome.row.memory_bytes;  // its arrays and the setup kept beside them
      if (paused_bytes + bytes <= paused_budget) paused_bytes += bytes;
      else run.simulation.reset();
    }
  });

  // The rest, cheapest estimate first; one estimated above the cheapest run known to meet E is skipped.
  on_workers(execution.threads, keys.size(), [&] {
    for (;;) {
      std::optional<std::size_t> picked;
      {
        const std::lock_guard<std::mutex> lock(shared);
        picked = schedule.next();
      }
      if (!picked) return;
      const std::size_t i = *picked;
      StartedRun& run = runs[i];
      // Dropped while paused (memory): it starts again, and its cost is that of the whole run from its start.
      if (!run.simulation && !start(i)) continue;
      step_run(run, work[i], counter);
      ended_run(i);
    }
  });
  for (const CheapestFirstSchedule::Skip& skip : schedule.skipped()) {
    result.skips[skip.id] = TradeSkip{skip.estimate, false};
    runs[skip.id].simulation.reset();
  }
  for (const RunKey& key : keys) scenes.drop(key.build);
  return result;
}

// Bytes of the arrays the CPU stepping reads and writes, in the run's precision (indices 4 bytes): the vertex state
// and its loads, the model's per-spring and per-element arrays with their CSR, and the integrator's extra vectors;
// implicit Euler adds its assembled sparse matrix (9 entries per vertex and per edge twice, double value + int
// index) and its conjugate-gradient vectors. Not counted: the setup kept in double, the worker pool, the allocator.
double trade_memory_estimate(const SimulationSetup& setup, std::size_t edges) {
  const double real = setup.precision == Precision::Float ? 4.0 : 8.0;
  const auto vertices = static_cast<double>(setup.rest_positions.size());
  const auto springs = static_cast<double>(setup.springs.size());
  const auto elements = static_cast<double>(setup.tetrahedra.size());
  // position, velocity, rest, acceleration (3 each), mass, held axes; the inversion replay's checkpoint (3 x 3).
  double bytes = vertices * (12.0 * real + real + 1.0);
  if (!setup.tetrahedra.empty()) bytes += vertices * 9.0 * real + elements * 16.0;
  if (!setup.external_forces.empty()) bytes += vertices * 3.0 * real;
  // Springs: rest length, stiffness, damping; CSR offset, spring and neighbour per endpoint.
  if (springs > 0.0)
    bytes += springs * (real * (setup.springs.damping.empty() ? 2.0 : 3.0)) + (vertices + 1.0) * 4.0 + springs * 16.0;
  if (!setup.elements.empty()) {
    // Dm^-1 and V0, each term's parameters and damping, the corner forces.
    double per_element = 9.0 + 1.0 + 12.0;
    for (const ElementTerm& term : setup.elements.terms) {
      for (const std::vector<double>& parameter : term.parameter) per_element += parameter.empty() ? 0.0 : 1.0;
      per_element += term.stiffness_damping.empty() ? 0.0 : 1.0;
    }
    bytes += elements * per_element * real + (vertices + 1.0) * 4.0 + elements * 16.0;
  }
  switch (setup.integrator) {
    case Integrator::VelocityVerlet:
      bytes += vertices * 9.0 * real;
      break;
    case Integrator::RungeKutta4:
      bytes += vertices * (9.0 + 24.0) * real;
      break;
    case Integrator::ImplicitEuler: {
      const double entries = 9.0 * (vertices + 2.0 * static_cast<double>(edges));
      bytes += entries * (8.0 + 4.0) + entries * 16.0;  // the matrix and its triplets
      bytes += vertices * 3.0 * 8.0 * 7.0;              // right-hand side, solution, r, p, q, z, Jacobi diagonal
      break;
    }
    case Integrator::ForwardEuler:
    case Integrator::SemiImplicitEuler:
      break;
  }
  return bytes;
}

}  // namespace fmpc::sim

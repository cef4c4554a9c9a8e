// The run supervisor, written once for every backend (runtime/integrate/stepping_engine.h): Simulation::create and
// advance's checks, checkpoints and exact replays, the inversion policy and the messages; the readers forward to the
// engine.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "runtime/integrate/stepping_engine.h"
#if defined(FMPC_RUNTIME_HAVE_CUDA)
#include "runtime/gpu/gpu_simulation.h"
#endif

namespace fmpc::sim {

std::unique_ptr<Simulation> Simulation::create(const SimulationSetup& setup, DiagnosticList& diagnostics,
                                               const SimulationOptions& options) {
  std::vector<SimulationSetup> one;
  one.push_back(setup);
  return create(std::move(one), options, diagnostics);
}

// The simulation keeps its scenes (probes, messages, the displacement bound, the engine's views): moved in, not
// copied again.
std::unique_ptr<Simulation> Simulation::create(std::vector<SimulationSetup> scenes, const SimulationOptions& options,
                                               DiagnosticList& diagnostics) {
#if !defined(FMPC_RUNTIME_HAVE_CUDA)
  if (options.backend == Backend::Cuda) {
    diagnostics.error(SourceRange{}, "this fmpc was built without CUDA; run the scene with backend cpu or auto");
    return nullptr;
  }
#endif
  if (scenes.empty()) {
    diagnostics.error(SourceRange{}, options.backend == Backend::Cuda ? "a GPU batch needs at least one scene"
                                                                      : "a simulation needs at least one scene");
    return nullptr;
  }
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    if (options.backend == Backend::Cuda && scenes[s].integrator == Integrator::ImplicitEuler &&
        scenes[s].implicit.method == ImplicitMethod::Direct) {
      diagnostics.error(scenes[s].source_range,
                        "implicit Euler's direct solver runs on the CPU only; use the CPU backend, or the conjugate "
                        "gradient (method cg or auto) on CUDA");
      return nullptr;
    }
  }
  std::vector<StabilityReport> stability;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
#if defined(FMPC_RUNTIME_HAVE_CUDA)
    if (options.backend == Backend::Cuda && !gpu::batch_accepts(scenes, s, diagnostics)) return nullptr;
#endif
    DiagnosticList scene_diagnostics;
    const auto report = check_stability(scenes[s], scene_diagnostics);  // validates the setup first
    if (scenes.size() > 1) {
      for (Diagnostic diagnostic : scene_diagnostics.items()) {
        diagnostic.message = "scene " + std::to_string(s) + ": " + diagnostic.message;
        diagnostics.add(std::move(diagnostic));
      }
    } else {
      diagnostics.append(scene_diagnostics);
    }
    if (!report) return nullptr;
    DiagnosticList tool_diagnostics;
    if (!check_tools_outside(scenes[s], tool_diagnostics)) {
      for (Diagnostic diagnostic : tool_diagnostics.items()) {
        if (scenes.size() > 1) diagnostic.message = "scene " + std::to_string(s) + ": " + diagnostic.message;
        diagnostics.add(std::move(diagnostic));
      }
      return nullptr;
    }
    stability.push_back(*report);
  }
  std::unique_ptr<Simulation> simulation(new Simulation(std::move(scenes), std::move(stability), options.backend));
#if defined(FMPC_RUNTIME_HAVE_CUDA)
  if (options.backend == Backend::Cuda) {
    simulation->engine_ = gpu::create_engine(simulation->scenes_, simulation->stability_, options.gpu, diagnostics);
  } else {
    simulation->engine_ = create_cpu_engine(simulation->scenes_, simulation->stability_, options.batch_threads);
  }
#else
  simulation->engine_ = create_cpu_engine(simulation->scenes_, simulation->stability_, options.batch_threads);
#endif
  if (!simulation->engine_) return nullptr;
  if (!simulation->start_tools(diagnostics)) return nullptr;
  if (simulation->needs_checkpoints() && !simulation->engine_->save_checkpoint(diagnostics)) return nullptr;
  return simulation;
}

Simulation::Simulation(std::vector<SimulationSetup> scenes, std::vector<StabilityReport> stability, Backend backend)
    : scenes_(std::move(scenes)), stability_(std::move(stability)), backend_(backend) {
  vertex_begin_.push_back(0);
  for (const SimulationSetup& setup : scenes_)
    vertex_begin_.push_back(vertex_begin_.back() + static_cast<int>(setup.rest_positions.size()));
  inversions_.assign(scenes_.size(), InversionReport{});
}

Simulation::~Simulation() = default;

bool Simulation::fail() {
  failed_ = true;
  return false;
}

// A checkpoint is kept where a replay may need it: to locate a non-finite step the engine does not find at once, or
// a first inversion a scene with tetrahedra may still have.
bool Simulation::needs_checkpoints() const {
  if (!engine_->non_finite_is_exact()) return true;
  for (std::size_t scene = 0; scene < scenes_.size(); ++scene)
    if (!scenes_[scene].tetrahedra.empty() && inversions_[scene].largest_count == 0) return true;
  return false;
}

bool Simulation::advance(std::size_t steps, DiagnosticList& diagnostics, std::size_t check_every) {
  if (failed_) return false;
  // Where the nodal damping's displacement bound is checked (from the positions held), one check per run.
  std::size_t checks_per_run = engine_->checks_per_run();
  for (std::size_t scene = 0; scene < scenes_.size(); ++scene)
    if (displacement_bound_checked(scene)) checks_per_run = 1;
  if (tools_move()) checks_per_run = 1;  // steps one at a time while a tool's path moves
  const std::size_t last = engine_->steps_taken() + steps;
  while (engine_->steps_taken() < last) {
    // Checks fall on multiples of check_every counted from the run's start, and at the end.
    const std::size_t start = engine_->steps_taken();
    std::vector<std::size_t> ends;
    for (std::size_t at = start; at < last && ends.size() < checks_per_run;) {
      at = check_every == 0 ? last : std::min(last, (at / check_every + 1) * check_every);
      if (!ends.empty() && at - start > engine_->most_steps_per_run()) break;
      ends.push_back(at);
    }
    if (!run_engine(ends, diagnostics)) return fail();
    // Each check acted on in order as if its chunk had been run alone: acting on a check before the run's last
    // means restoring the checkpoint (a replay), after which the run's later steps are dropped.
    for (std::size_t check = 0; check < ends.size(); ++check) {
      engine_->select_check(check);
      const std::optional<int> bad = engine_->first_non_finite_vertex(diagnostics);
      if (!bad) return fail();
      if (*bad < vertex_begin_.back()) return locate_non_finite(*bad, diagnostics);
      const std::size_t restores = restores_;
      if (!check_displacement_bound(diagnostics) || !check_inversions(diagnostics)) return fail();
      if (needs_checkpoints() && !engine_->save_checkpoint(diagnostics)) return fail();
      if (restores_ != restores) break;
    }
  }
  return true;
}

std::size_t Simulation::scene_of(int vertex) const {
  return static_cast<std::size_t>(std::upper_bound(vertex_begin_.begin(), vertex_begin_.end(), vertex) -
                                  vertex_begin_.begin() - 1);
}

// A check found a non-finite vertex: where the engine does not stop at the step that made it, replay from the
// checkpoint one step at a time to that step (the steps are deterministic), then report it.
bool Simulation::locate_non_finite(int vertex, DiagnosticList& diagnostics) {
  if (!engine_->non_finite_is_exact()) {
    const std::size_t failed_by = engine_->steps_taken();
    if (!engine_->restore_checkpoint(diagnostics)) return fail();
    ++restores_;
    std::optional<int> bad = vertex_begin_.back();
    while (engine_->steps_taken() < failed_by && *bad >= vertex_begin_.back()) {
      if (!run_engine({engine_->steps_taken() + 1}, diagnostics)) return fail();
      bad = engine_->first_non_finite_vertex(diagnostics);
      if (!bad) return fail();
    }
    vertex = *bad < vertex_begin_.back() ? *bad : 0;
  }
  const std::size_t scene = scene_of(vertex);
  const int local = vertex - vertex_begin_[scene];
  NonFiniteReport report;
  report.scene = scene;
  report.step = engine_->steps_taken();
  report.time = static_cast<double>(report.step) * stability_[scene].time_step;
  report.vertex = local;
  report.spring = culprit_spring(scene, static_cast<std::size_t>(local), diagnostics);
  non_finite_ = report;
  const SpringNetwork& net = scenes_[scene].springs;
  std::ostringstream message;
  message << "the " << engine_->label() << "simulation became non-finite at step " << report.step
          << " (t = " << report.time << " s)";
  if (scenes_.size() > 1) message << " in scene " << scene;
  message << ": vertex " << local << " has a NaN or infinite position or velocity";
  if (report.spring >= 0) {
    const auto s = static_cast<std::size_t>(report.spring);
    message << "; its most strained spring is " << report.spring << " (vertices " << net.first[s] << " and "
            << net.second[s] << ")";
  }
  message << "; lower dt, raise damping, or check the loads";
  diagnostics.error(scenes_[scene].source_range, message.str());
  return fail();
}

// The spring at v whose length is non-finite, or else the one with the largest |strain|.
std::int32_t Simulation::culprit_spring(std::size_t scene, std::size_t v, DiagnosticList& diagnostics) const {
  const std::vector<Point3> points = engine_->positions(scene, diagnostics);
  const SpringNetwork& net = scenes_[scene].springs;
  if (points.size() != net.vertex_count) return -1;
  std::int32_t best = -1;
  double worst = -1.0;
  for (auto e = net.adjacency_offset[v]; e < net.adjacency_offset[v + 1]; ++e) {
    const auto s = static_cast<std::size_t>(net.adjacency_spring[static_cast<std::size_t>(e)]);
    const double length =
        distance(points[static_cast<std::size_t>(net.first[s])], points[static_cast<std::size_t>(net.second[s])]);
    const double strain = std::isfinite(length) ? std::abs(length - net.rest_length[s]) / net.rest_length[s]
                                                : std::numeric_limits<double>::infinity();
    if (strain > worst) {
      worst = strain;
      best = static_cast<std::int32_t>(s);
    }
    if (!std::isfinite(strain)) break;
  }
  return best;
}

// Whether the scene's nodal damping gamma1 |x - x0| was bounded with a displacement (StabilityReport), which
// check_displacement_bound checks.
bool Simulation::displacement_bound_checked(std::size_t scene) const {
  return scenes_[scene].nodal_damping_gamma1 > 0.0 && std::isfinite(stability_[scene].assumed_displacement_max);
}

// A vertex that moved further than the nodal damping's bound assumed stops the run with an error.
bool Simulation::check_displacement_bound(DiagnosticList& diagnostics) {
  for (std::size_t scene = 0; scene < scenes_.size(); ++scene) {
    if (!displacement_bound_checked(scene)) continue;
    const SimulationSetup& setup = scenes_[scene];
    const double bound = stability_[scene].assumed_displacement_max;
    const std::vector<Point3> points = engine_->positions(scene, diagnostics);
    for (std::size_t v = 0; v < points.size(); ++v) {
      const double moved = distance(points[v], setup.rest_positions[v]);
      if (moved <= bound) continue;
      std::ostringstream message;
      if (scenes_.size() > 1) message << "scene " << scene << ": ";
      message << "vertex " << v << " moved " << moved << " m from rest by step " << engine_->steps_taken()
              << ", beyond the " << bound << " m the stable time step assumed for the nodal damping gamma1 |x - x0| "
              << "(gamma1 = " << setup.nodal_damping_gamma1 << " N s/m^2); give a smaller dt explicitly or lower gamma1";
      diagnostics.error(setup.source_range, message.str());
      return false;
    }
  }
  return true;
}

// Inversions counted at every check; a scene's first one is located exactly by replaying from the checkpoint one
// step at a time, then warned about (the run goes on) or, with on_inversion: stop, an error.
bool Simulation::check_inversions(DiagnosticList& diagnostics) {
  bool any = false;
  for (const SimulationSetup& setup : scenes_) any = any || !setup.tetrahedra.empty();
  if (!any) return true;
  std::vector<unsigned> counts;
  std::vector<int> firsts;
  if (!engine_->count_inverted(counts, firsts, diagnostics)) return false;
  bool newly = false;
  for (std::size_t scene = 0; scene < counts.size(); ++scene)
    newly = newly || (counts[scene] > 0 && inversions_[scene].largest_count == 0);
  if (newly) {
    const std::size_t failed_by = engine_->steps_taken();
    if (!engine_->restore_checkpoint(diagnostics)) return false;
    ++restores_;
    bool stop = false;
    for (;;) {
      if (!engine_->count_inverted(counts, firsts, diagnostics)) return false;
      for (std::size_t scene = 0; scene < counts.size(); ++scene) {
        InversionReport& report = inversions_[scene];
        if (counts[scene] == 0 || report.largest_count > 0) continue;
        report.first_step = engine_->steps_taken();
        report.first_time = static_cast<double>(report.first_step) * stability_[scene].time_step;
        report.first_element = firsts[scene];
        report.largest_count = report.current_count = counts[scene];
        std::string message = inversion_message(scenes_[scene], report);
        if (scenes_.size() > 1) message = "scene " + std::to_string(scene) + ": " + message;
        if (scenes_[scene].on_inversion == InversionPolicy::Stop) {
          diagnostics.error(scenes_[scene].source_range, message + "; the scene's on_inversion is stop");
          stop = true;
        } else {
          diagnostics.warning(scenes_[scene].source_range, "inverted-elements", message);
        }
      }
      if (stop) return false;
      if (engine_->steps_taken() >= failed_by) break;
      if (!run_engine({engine_->steps_taken() + 1}, diagnostics)) return false;
    }
  }
  for (std::size_t scene = 0; scene < counts.size(); ++scene) {
    inversions_[scene].current_count = counts[scene];
    inversions_[scene].largest_count = std::max<std::size_t>(inversions_[scene].largest_count, counts[scene]);
  }
  return true;
}

std::size_t Simulation::scene_count() const { return scenes_.size(); }
std::size_t Simulation::steps_taken() const { return engine_->steps_taken(); }
double Simulation::time(std::size_t scene) const {
  return static_cast<double>(engine_->steps_taken()) * stability_.at(scene).time_step;
}
const SimulationSetup& Simulation::setup(std::size_t scene) const { return scenes_.at(scene); }
const StabilityReport& Simulation::stability(std::size_t scene) const { return stability_.at(scene); }
Backend Simulation::backend() const { return backend_; }
SimulationLaunches Simulation::launches() const { return engine_->launches(); }
const std::optional<NonFiniteReport>& Simulation::non_finite() const { return non_finite_; }
const InversionReport& Simulation::inversions(std::size_t scene) const { return inversions_.at(scene); }
int Simulation::implicit_max_iterations_used() const { return engine_->implicit_max_iterations_used(); }
ImplicitSolverReport Simulation::implicit_solver(std::size_t scene) const { return engine_->implicit_solver(scene); }
std::vector<ImplicitStepRecord> Simulation::take_implicit_steps(std::size_t scene) {
  return engine_->take_implicit_steps(scene);
}
bool Simulation::reduces_in_place() const { return engine_->reduces_in_place(); }

bool scene_exists(std::size_t scene, std::size_t count, DiagnosticList& diagnostics) {
  if (scene < count) return true;
  diagnostics.error(SourceRange{},
                    "scene " + std::to_string(scene) + " does not exist; the batch has " + std::to_string(count));
  return false;
}

std::vector<Point3> Simulation::positions(std::size_t scene, DiagnosticList& diagnostics) const {
  if (!scene_exists(scene, scenes_.size(), diagnostics)) return {};
  return engine_->positions(scene, diagnostics);
}
std::vector<Point3> Simulation::velocities(std::size_t scene, DiagnosticList& diagnostics) const {
  if (!scene_exists(scene, scenes_.size(), diagnostics)) return {};
  return engine_->velocities(scene, diagnostics);
}
bool Simulation::scene_states(std::vector<std::vector<Point3>>& positions,
                              std::vector<std::vector<Point3>>* velocities, DiagnosticList& diagnostics) const {
  return engine_->scene_states(positions, velocities, diagnostics);
}
std::optional<double> Simulation::kinetic_energy(std::size_t scene, DiagnosticList& diagnostics) const {
  if (!scene_exists(scene, scenes_.size(), diagnostics)) return std::nullopt;
  return engine_->kinetic_energy(scene, diagnostics);
}
std::optional<double> Simulation::potential_energy(std::size_t scene, DiagnosticList& diagnostics) const {
  if (!scene_exists(scene, scenes_.size(), diagnostics)) return std::nullopt;
  return engine_->potential_energy(scene, diagnostics);
}
std::optional<double> Simulation::elastic_energy(std::size_t scene, DiagnosticList& diagnostics) const {
  if (!scene_exists(scene, scenes_.size(), diagnostics)) return std::nullopt;
  return engine_->elastic_energy(scene, diagnostics);
}
std::optional<double> Simulation::largest_displacement(std::size_t scene, DiagnosticList& diagnostics) const {
  if (!scene_exists(scene, scenes_.size(), diagnostics)) return std::nullopt;
  return engine_->largest_displacement(scene, diagnostics);
}
ProbeReading Simulation::probe_reading(std::size_t scene, DiagnosticList& diagnostics) const {
  if (!scene_exists(scene, scenes_.size(), diagnostics)) return {};
  return engine_->probe_reading(scene, diagnostics);
}
std::vector<double> Simulation::current_stiffness(std::size_t scene, DiagnosticList& diagnostics) const {
  if (!scene_exists(scene, scenes_.size(), diagnostics)) return {};
  return engine_->current_stiffness(scene, diagnostics);
}

}  // namespace fmpc::sim

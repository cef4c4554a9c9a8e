#pragma once
// What a backend gives the run supervisor (Simulation::advance, runtime/integrate/run_supervisor.cpp) and the
// Simulation's readers: a batch of scenes stepped without checks, what the checks read, one checkpoint, and the
// state read back. One engine per backend (runtime/integrate/cpu_engine.cpp; the CUDA backend's in runtime/gpu/);
// the supervisor, written once, decides when to check, replays from the checkpoint to exact steps, applies the
// inversion policy and writes the messages. Internal to runtime/: users hold a Simulation.
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

class SteppingEngine {
 public:
  virtual ~SteppingEngine() = default;

  // ---- stepping, for the supervisor ---------------------------------------------------------------------------------
  // "the " + label + "simulation became non-finite ...": "" on the CPU, "GPU " on CUDA.
  virtual const char* label() const = 0;
  virtual std::size_t steps_taken() const = 0;
  // The checks one run() may take (the CUDA backend's persistent launches store each check's state into a checkpoint
  // slot: many; otherwise 1), and the most steps a run with several checks may span.
  virtual std::size_t checks_per_run() const = 0;
  virtual std::size_t most_steps_per_run() const = 0;
  // Steps the batch to each of `ends` (increasing step counts, at most checks_per_run of them), holding the state
  // after the last; where non_finite_is_exact, a step that makes the state non-finite ends the run there. Appends
  // the conjugate gradient's warning where an implicit step stopped at its cap. False after a device error.
  virtual bool run(const std::vector<std::size_t>& ends, DiagnosticList& diagnostics) = 0;
  // Makes check `check` of the last run() the state the checks below read (steps_taken() becomes its end); the last
  // check is the state held.
  virtual void select_check(std::size_t check) = 0;
  // The smallest batch vertex with a non-finite position or velocity at the checked state, or the batch's vertex
  // count when there is none; nullopt after a device error.
  virtual std::optional<int> first_non_finite_vertex(DiagnosticList& diagnostics) = 0;
  // Whether a non-finite state found after run() is the first step that produced it (no replay needed), and whether
  // the engine relies on the checkpoint to find that step.
  virtual bool non_finite_is_exact() const = 0;
  // Per scene, at the checked state: inverted tetrahedra and the smallest (its index in the scene, -1: none).
  virtual bool count_inverted(std::vector<unsigned>& counts, std::vector<int>& firsts, DiagnosticList& diagnostics) = 0;
  // The checkpoint: the checked state (and what the integrator carries between steps) saved, or restored together
  // with its step count.
  virtual bool save_checkpoint(DiagnosticList& diagnostics) = 0;
  virtual bool restore_checkpoint(DiagnosticList& diagnostics) = 0;
  virtual int implicit_max_iterations_used() const = 0;
  // Implicit Euler's solves per scene (ImplicitSolverLog below); a checkpoint saves and restores them with the state.
  virtual ImplicitSolverReport implicit_solver(std::size_t scene) const = 0;
  virtual std::vector<ImplicitStepRecord> take_implicit_steps(std::size_t scene) = 0;

  // ---- reading, for the Simulation's readers ----------------------------------------------------------------------
  virtual std::vector<Point3> positions(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual std::vector<Point3> velocities(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual bool scene_states(std::vector<std::vector<Point3>>& positions, std::vector<std::vector<Point3>>* velocities,
                            DiagnosticList& diagnostics) const = 0;
  virtual std::optional<double> kinetic_energy(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual std::optional<double> potential_energy(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual std::optional<double> elastic_energy(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual std::optional<double> largest_displacement(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual bool reduces_in_place() const = 0;
  virtual ProbeReading probe_reading(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  virtual std::vector<double> current_stiffness(std::size_t scene, DiagnosticList& diagnostics) const = 0;
  // The scene's positions where they live on a device (the state held, the stream finished); nullopt on the host.
  virtual std::optional<DevicePositions> device_positions(std::size_t, DiagnosticList&) const { return std::nullopt; }
  virtual SimulationLaunches launches() const { return {}; }

  // ---- rigid tools and the material, for the Simulation's setters ------------------------------------------------
  // A scene with tools: its per-vertex contact stiffness and damping (rigid_tools.h's contact_stiffness and
  // contact_damping, the latter empty without contact damping; given at creation and after a material change) and its
  // tools' world shapes (given before the steps they act in). Scenes without tools are never given either.
  virtual bool set_contact(std::size_t scene, const std::vector<double>& stiffness, const std::vector<double>& damping,
                           DiagnosticList& diagnostics) = 0;
  virtual bool set_tool_shapes(std::size_t scene, const std::vector<kernels::ToolShape<double>>& shapes,
                               DiagnosticList& diagnostics) = 0;
  // The scene's material arrays in its setup (the springs' stiffness and damping, the element terms' parameters and
  // damping, the strain table) were replaced by arrays of the same sizes between two steps: the engine takes them.
  virtual bool refresh_material(std::size_t scene, DiagnosticList& diagnostics) = 0;
};

// The CPU engine of a batch whose every scene passed check_stability (`stability`, one each), its scenes stepped side
// by side on `batch_threads` workers (0: every hardware thread). It reads `scenes` (the Simulation's) for its life.
std::unique_ptr<SteppingEngine> create_cpu_engine(const std::vector<SimulationSetup>& scenes,
                                                  const std::vector<StabilityReport>& stability,
                                                  unsigned batch_threads);

// The warning text of a step that stopped at the cap (code `cg-not-converged`), the same for both backends.
std::string cg_stopped_message(ImplicitMethod method, std::size_t step, int iterations, double relative_residual,
                               double tolerance);

// The warning (code `contact-not-settled`) of an implicit step whose tools' contact set still changed after `rounds`
// solves (the setup's implicit.contact_rounds), the same for both backends.
std::string contact_unsettled_message(std::size_t step, int rounds);

// One scene's implicit solves as an engine keeps them: the report's sums, the records not yet taken, and their
// state at the checkpoint (a replay from it then counts each step once).
class ImplicitSolverLog {
 public:
  ImplicitSolverLog() = default;
  ImplicitSolverLog(ImplicitMethod method, double tolerance, int max_iterations);
  // Adds a step's record; true when it is the first step of the run that stopped at the cap (the engine warns once).
  bool record(const ImplicitStepRecord& step);
  void fallback() { ++report_.direct_fallbacks; }
  // Counts a step whose tools' contact set still changed after its last solve of at most `rounds` (the setup's
  // implicit.contact_rounds), and warns about the run's first (contact-not-settled, at `where`) unless one round
  // was the scene's choice.
  void contact_unsettled(std::size_t step, int rounds, const SourceRange& where, DiagnosticList& diagnostics);
  const ImplicitSolverReport& report() const { return report_; }
  std::vector<ImplicitStepRecord> take();
  // The checkpoint at `step` steps taken, and back to it.
  void save(std::size_t step);
  void restore();

 private:
  ImplicitSolverReport report_, saved_;
  std::size_t saved_step_ = 0;
  std::vector<ImplicitStepRecord> pending_;
  bool warned_ = false, contact_warned_ = false;  // a replay from the checkpoint does not warn again
};

// True where `scene` indexes a batch of `count` scenes; otherwise an error saying so (Simulation's per-scene calls).
bool scene_exists(std::size_t scene, std::size_t count, DiagnosticList& diagnostics);

}  // namespace fmpc::sim

#pragma once
// fmpc::runtime (docs/runtime.md): what a program that links fmpc drives every tick, e.g. a surgical simulator's
// haptic loop: a scene loaded from a file, YAML text or a setup built in code, stepped n steps or to a time on the
// CPU or the GPU, its rigid tools posed every tick and their reaction forces and torques read back, its state read
// (positions on the host, or where they live on the GPU), and its material swapped for a recompiled rule file or
// table between two steps. A thin layer over sim::Simulation (runtime/integrate/simulation.h), the one simulation
// interface: a session adds the scene it came from and its files, nothing of the stepping.
//
// Errors are data, as everywhere in fmpc: a call that can fail returns false (or nullopt, or null) after appending
// to the DiagnosticList it is given, and render() turns the list into the compiler-style text with the scene's lines
// quoted. Nothing prints or exits. A failed call changes nothing, except a step that stops at a non-finite state or an
// inversion under on_inversion: stop, after which every step fails (the error says where).
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {
struct Scene;
}  // namespace fmpc::sim

namespace fmpc::runtime {

using sim::DevicePositions;
using sim::Point3;
using sim::ToolPose;
using sim::ToolReading;

struct SessionOptions {
  // Where the session steps: the scene's `backend` (Auto: a scene's own choice, the GPU when it can be used; the CPU
  // for a setup), or the CPU or the GPU whatever the scene says.
  enum class Backend { Auto, Cpu, Cuda } backend = Backend::Auto;
};

// The energies of the state now (J): kinetic 1/2 m |v|^2, elastic (springs and element terms), potential (elastic
// and the loads' -(m g + f) . x). On CUDA reduced on the device in double.
struct Energies {
  double kinetic = 0.0;
  double elastic = 0.0;
  double potential = 0.0;
};

class Session {
 public:
  // A scene file (docs/scenes.md): read (at most runtime/io/input_file.h's kMaxSceneFileBytes), parsed, built.
  static std::unique_ptr<Session> open(const std::string& path, DiagnosticList& diagnostics,
                                       const SessionOptions& options = {});
  // Scene YAML given as text; `path` names it in messages and its folder resolves the scene's relative files.
  static std::unique_ptr<Session> from_yaml(const std::string& text, const std::string& path,
                                            DiagnosticList& diagnostics, const SessionOptions& options = {});
  // A setup built in code (docs/simulator.md, "Driving it"); its material can then be swapped only for another setup.
  static std::unique_ptr<Session> from_setup(sim::SimulationSetup setup, DiagnosticList& diagnostics,
                                             const SessionOptions& options = {});
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // ---- stepping ----------------------------------------------------------------------------------------------------
  // `steps` steps with the checks of Simulation::advance (NaN/Inf, inversions) at its end and every 64 steps.
  bool step(std::size_t steps, DiagnosticList& diagnostics);
  // The steps that bring the time to at least `time` (s): none when it is already there; a time that is not finite
  // or lies more than kMaxSimulationSteps steps ahead is an error.
  bool step_to(double time, DiagnosticList& diagnostics);
  double time() const;           // s
  double time_step() const;      // s
  std::size_t steps_taken() const;
  sim::Backend backend() const;
  // The run's stability report (the time step, the critical step, the limit applied).
  const sim::StabilityReport& stability() const;

  // ---- rigid tools -------------------------------------------------------------------------------------------------
  std::size_t tool_count() const;
  // The index of the tool named `name`, or nullopt.
  std::optional<std::size_t> find_tool(const std::string& name) const;
  // The tool's pose for the steps from now on (metres, a quaternion w, x, y, z; normalised): a NaN, an infinite or a
  // zero quaternion is an error naming the tool, and the tool stays where it was.
  bool set_tool_pose(std::size_t tool, const ToolPose& pose, DiagnosticList& diagnostics);
  const std::vector<ToolPose>& tool_poses() const;
  // What every tool feels now: the tissue's force on it (N) and its torque about the tool's origin (N m).
  std::vector<ToolReading> tool_readings(DiagnosticList& diagnostics) const;
  // step_to(time), one step at a time, and what every tool felt over those steps: its impulse (the force each step
  // applies, times dt) over their duration, the force a haptic device should render for the tick; likewise the
  // torque. `contacts` and `deepest` are the largest at a step. The force a step applies is the reading at its start
  // for forward and semi-implicit Euler, at its end for implicit Euler (so one implicit step per tick averages to
  // the end-of-tick reading) and the mean of both for velocity Verlet (exact) and RK4 (an estimate). `end`, when
  // given, receives the readings at the last step's end (tool_readings() then). Each step is one advance with its
  // checks and one reading (on CUDA a download of the positions), so this costs more than step_to. With no step
  // to take, `mean` is the reading now.
  bool step_to_averaging(double time, std::vector<ToolReading>& mean, DiagnosticList& diagnostics,
                         std::vector<ToolReading>* end = nullptr);

  // ---- the state ---------------------------------------------------------------------------------------------------
  std::size_t vertex_count() const;
  // Every vertex's position now (m): a host copy (downloaded on CUDA).
  std::vector<Point3> positions(DiagnosticList& diagnostics) const;
  std::vector<Point3> velocities(DiagnosticList& diagnostics) const;
  // CUDA only: the positions where they live (sim::DevicePositions), no copy.
  std::optional<DevicePositions> device_positions(DiagnosticList& diagnostics) const;
  std::optional<Energies> energies(DiagnosticList& diagnostics) const;
  // Inverted tetrahedra: counted at every check, the first located exactly (sim::InversionReport).
  const sim::InversionReport& inversions() const;

  // ---- the material ------------------------------------------------------------------------------------------------
  // Swaps the material for a rule file (any dialect fmpc reads) or a compiled table (.fzt) between two steps: the
  // scene is built again with it (its bindings, regions and mapping as they were) and the simulation takes the new
  // stiffness, keeping its state and time (Simulation::replace_material). A file whose selected system has other
  // inputs than the scene binds, a file with errors, a material that makes the time step unstable, or a session
  // made from a setup are errors, and the old material stays.
  bool swap_material(const std::string& file, DiagnosticList& diagnostics);
  // The same for a setup built in code from the same mesh and model with another material.
  bool swap_material(const sim::SimulationSetup& material, DiagnosticList& diagnostics);

  // The simulation under the session (its setup, stability report, probe readings, ...).
  const sim::Simulation& simulation() const { return *simulation_; }
  // The diagnostics as fmpc prints them, with the scene's (and its rule file's) lines quoted.
  std::string render(const DiagnosticList& diagnostics) const;
  // The texts render() quotes from: the scene and the rule files read.
  const SourceFiles& sources() const { return sources_; }

 private:
  Session();
  static std::unique_ptr<Session> from_scene(const std::string& path, const std::string& text,
                                             DiagnosticList& diagnostics, const SessionOptions& options);
  bool create_simulation(sim::SimulationSetup setup, sim::Backend backend, DiagnosticList& diagnostics);

  std::unique_ptr<sim::Scene> scene_;  // null for a setup
  std::unique_ptr<sim::Simulation> simulation_;
  SourceFiles sources_;
};

}  // namespace fmpc::runtime

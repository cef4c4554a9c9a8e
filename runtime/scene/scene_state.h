#pragma once
// Internal to runtime/scene: one scene of a running Simulation as the outputs read it at an event. A scene alone reads
// the simulation (on CUDA its energies and largest displacement are reduced on the device); the scenes of a batch are
// read at once (Simulation::scene_states: one download per array on CUDA) and each from its host copy, its probe with
// read_probe on that copy exactly as the simulation's probe_reading reads it, so each scene's outputs are those of its
// run alone. Not installed.
#include <cstddef>
#include <optional>
#include <utility>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

inline double dot(const Point3& a, const Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// The largest distance of any vertex from its start.
double largest_displacement(const std::vector<Point3>& positions, const std::vector<Point3>& start);

class SceneState {
 public:
  SceneState(const Simulation& simulation, std::size_t scene) : simulation_(simulation), scene_(scene) {}

  // A batch's scene: its state from the host copies given (kept by the caller until the next event), its stiffness
  // read once where it stays fixed (no strain table). False after a device error.
  bool read_stiffness(DiagnosticList& diagnostics);
  void set_state(const std::vector<Point3>* positions, const std::vector<Point3>* velocities) {
    positions_ = positions;
    velocities_ = velocities;
  }

  std::size_t steps_taken() const { return simulation_.steps_taken(); }
  double time() const { return simulation_.time(scene_); }
  const StabilityReport& stability() const { return simulation_.stability(scene_); }
  const InversionReport& inversions() const { return simulation_.inversions(scene_); }
  ImplicitSolverReport implicit_solver() const { return simulation_.implicit_solver(scene_); }
  std::vector<Point3> positions(DiagnosticList& diagnostics) const;
  std::vector<Point3> velocities(DiagnosticList& diagnostics) const;
  ProbeReading probe_reading(DiagnosticList& diagnostics) const;
  std::vector<double> current_stiffness(DiagnosticList& diagnostics) const;
  // What each tool feels now: the simulation's reading, or a batch's from its host copy (the same read_tools).
  std::vector<ToolReading> tool_readings(DiagnosticList& diagnostics) const;
  // The largest distance of a vertex from `start` (its start positions): reduced where the state lives when it
  // does (reduces_in_place), else from positions().
  std::optional<double> largest_displacement(const std::vector<Point3>& start, DiagnosticList& diagnostics) const;
  // The kinetic and the elastic energy of the state whose positions and velocities are given (a sample's CSV row):
  // summed here from them, or, where the state reduces in place, there (on CUDA in another order, so the last bits
  // may differ from the host's sums).
  std::optional<std::pair<double, double>> energies(const SimulationSetup& setup, const std::vector<Point3>& positions,
                                                    const std::vector<Point3>& velocities,
                                                    DiagnosticList& diagnostics) const;
  // Whether largest_displacement and energies reduce where the state lives and ignore the positions and velocities
  // passed: then a sample without a frame downloads nothing (on a 14M-vertex box, two samples' downloads and host
  // loops cost 1.6 s of a 4.1 s run).
  bool reduces_in_place() const { return positions_ == nullptr && simulation_.reduces_in_place(); }

 private:
  const Simulation& simulation_;
  std::size_t scene_;
  std::vector<double> stiffness_;
  bool stiffness_read_ = false;
  const std::vector<Point3>* positions_ = nullptr;
  const std::vector<Point3>* velocities_ = nullptr;
};

}  // namespace fmpc::sim

#pragma once
// Internal to runtime/scene: a run's state as the outputs read it, whichever backend holds it, and the stepper that
// advances one scene alone (run_scene, the precision check). Not installed.
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

inline double dot(const Point3& a, const Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// The largest distance of any vertex from its start.
double largest_displacement(const std::vector<Point3>& positions, const std::vector<Point3>& start);

// A run's state as the outputs read it, whichever backend holds it (called per output event, never per element).
class SceneState {
 public:
  virtual ~SceneState() = default;
  virtual std::size_t steps_taken() const = 0;
  virtual double time() const = 0;
  virtual const StabilityReport& stability() const = 0;
  virtual std::vector<Point3> positions(DiagnosticList& diagnostics) const = 0;
  virtual std::vector<Point3> velocities(DiagnosticList& diagnostics) const = 0;
  virtual ProbeReading probe_reading(DiagnosticList& diagnostics) const = 0;
  virtual std::vector<double> current_stiffness(DiagnosticList& diagnostics) const = 0;
  virtual const InversionReport& inversions() const = 0;
  // The largest distance of a vertex from `start` (its start positions): from positions() here; a backend whose
  // state lives elsewhere reduces it there (what every progress event asks, so it must not move the state).
  virtual std::optional<double> largest_displacement(const std::vector<Point3>& start,
                                                     DiagnosticList& diagnostics) const;
  // The kinetic and the elastic energy of the state whose positions and velocities are given (a sample's CSV row):
  // summed here from them; a backend whose state lives elsewhere sums there (on CUDA: in another order, so the
  // last bits may differ from the CPU's sums).
  virtual std::optional<std::pair<double, double>> energies(const SimulationSetup& setup,
                                                            const std::vector<Point3>& positions,
                                                            const std::vector<Point3>& velocities,
                                                            DiagnosticList& diagnostics) const;
  // Whether largest_displacement and energies reduce where the state lives and ignore the positions and velocities
  // passed: then a sample without a frame downloads nothing (on a 14M-vertex box, two samples' downloads and
  // host loops cost 1.6 s of a 4.1 s run).
  virtual bool reduces_in_place() const { return false; }
};

// A run that steps itself (one scene alone).
class SceneStepper : public SceneState {
 public:
  virtual bool advance(std::size_t steps, DiagnosticList& diagnostics) = 0;
};

// A stepper on `backend` ("cpu" or "cuda"); null after appending errors.
std::unique_ptr<SceneStepper> create_stepper(const SimulationSetup& setup, const std::string& backend,
                                             DiagnosticList& diagnostics);

}  // namespace fmpc::sim

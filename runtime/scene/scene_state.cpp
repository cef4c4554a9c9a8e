#include "runtime/scene/scene_state.h"

#include <algorithm>

#if defined(FMPC_RUNTIME_HAVE_CUDA)
#include "runtime/gpu/gpu_simulation.h"
#endif

namespace fmpc::sim {

namespace {

class CpuStepper final : public SceneStepper {
 public:
  explicit CpuStepper(std::unique_ptr<CpuSimulation> simulation) : simulation_(std::move(simulation)) {}
  bool advance(std::size_t steps, DiagnosticList& diagnostics) override { return simulation_->advance(steps, diagnostics); }
  std::size_t steps_taken() const override { return simulation_->steps_taken(); }
  double time() const override { return simulation_->time(); }
  const StabilityReport& stability() const override { return simulation_->stability(); }
  std::vector<Point3> positions(DiagnosticList&) const override { return simulation_->positions(); }
  std::vector<Point3> velocities(DiagnosticList&) const override { return simulation_->velocities(); }
  ProbeReading probe_reading(DiagnosticList&) const override { return simulation_->probe_reading(); }
  std::vector<double> current_stiffness(DiagnosticList&) const override { return simulation_->current_stiffness(); }
  const InversionReport& inversions() const override { return simulation_->inversions(); }

 private:
  std::unique_ptr<CpuSimulation> simulation_;
};

#if defined(FMPC_RUNTIME_HAVE_CUDA)
class CudaStepper final : public SceneStepper {
 public:
  explicit CudaStepper(std::unique_ptr<gpu::GpuSimulation> simulation) : simulation_(std::move(simulation)) {}
  bool advance(std::size_t steps, DiagnosticList& diagnostics) override { return simulation_->advance(steps, diagnostics); }
  std::size_t steps_taken() const override { return simulation_->steps_taken(); }
  double time() const override { return simulation_->time(); }
  const StabilityReport& stability() const override { return simulation_->stability(); }
  std::vector<Point3> positions(DiagnosticList& diagnostics) const override {
    return simulation_->positions(diagnostics);
  }
  std::vector<Point3> velocities(DiagnosticList& diagnostics) const override {
    return simulation_->velocities(diagnostics);
  }
  ProbeReading probe_reading(DiagnosticList& diagnostics) const override {
    return simulation_->probe_reading(diagnostics);
  }
  std::vector<double> current_stiffness(DiagnosticList& diagnostics) const override {
    return simulation_->current_stiffness(diagnostics);
  }
  const InversionReport& inversions() const override { return simulation_->inversions(); }
  std::optional<double> largest_displacement(const std::vector<Point3>&, DiagnosticList& diagnostics) const override {
    return simulation_->largest_displacement(diagnostics);
  }
  bool reduces_in_place() const override { return true; }
  std::optional<std::pair<double, double>> energies(const SimulationSetup&, const std::vector<Point3>&,
                                                    const std::vector<Point3>&,
                                                    DiagnosticList& diagnostics) const override {
    const auto kinetic = simulation_->kinetic_energy(diagnostics);
    const auto elastic = simulation_->elastic_energy(diagnostics);
    if (!kinetic || !elastic) return std::nullopt;
    return std::make_pair(*kinetic, *elastic);
  }

 private:
  std::unique_ptr<gpu::GpuSimulation> simulation_;
};
#endif

}  // namespace

std::unique_ptr<SceneStepper> create_stepper(const SimulationSetup& setup, const std::string& backend,
                                             DiagnosticList& diagnostics) {
  if (backend == "cuda") {
#if defined(FMPC_RUNTIME_HAVE_CUDA)
    auto simulation = gpu::GpuSimulation::create(setup, diagnostics);
    if (!simulation) return nullptr;
    return std::make_unique<CudaStepper>(std::move(simulation));
#else
    diagnostics.error(SourceRange{}, "this fmpc was built without CUDA; run the scene with backend cpu or auto");
    return nullptr;
#endif
  }
  auto simulation = CpuSimulation::create(setup, diagnostics);
  if (!simulation) return nullptr;
  return std::make_unique<CpuStepper>(std::move(simulation));
}

double largest_displacement(const std::vector<Point3>& positions, const std::vector<Point3>& start) {
  double largest = 0.0;
  for (std::size_t v = 0; v < positions.size() && v < start.size(); ++v)
    largest = std::max(largest, distance(positions[v], start[v]));
  return largest;
}

std::optional<std::pair<double, double>> SceneState::energies(const SimulationSetup& setup,
                                                              const std::vector<Point3>& positions,
                                                              const std::vector<Point3>& velocities,
                                                              DiagnosticList&) const {
  return std::make_pair(kinetic_energy(setup, velocities), elastic_energy(setup, positions));
}

std::optional<double> SceneState::largest_displacement(const std::vector<Point3>& start,
                                                       DiagnosticList& diagnostics) const {
  const std::vector<Point3> now = positions(diagnostics);
  if (now.size() != start.size()) return std::nullopt;  // a device error, already reported
  return sim::largest_displacement(now, start);
}

}  // namespace fmpc::sim

#pragma once
// CPU and GPU runs side by side: the differences the GPU tests measure and the tolerances they state
// (docs/simulator.md: after 10,000 steps every position within 1e-5 m in float and 1e-12 m in double). Both sides
// evaluate the same FMPC_HD functions in the same order and the device code is compiled with --fmad=false, so the
// expected difference of an explicit integrator is 0; the tests print the measured one.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/gpu/gpu_simulation.h"
#include "runtime/integrate/simulation.h"
#include "tests/gpu/gpu_test_harness.h"

namespace fmpc::gpu_test {

// A simulation on the CUDA backend (one scene, or a batch) and on the CPU: the one interface, sim::Simulation.
inline std::unique_ptr<sim::Simulation> gpu_simulation(const sim::SimulationSetup& setup, DiagnosticList& diagnostics,
                                                       const sim::GpuOptions& options = {}) {
  sim::SimulationOptions cuda;
  cuda.backend = sim::Backend::Cuda;
  cuda.gpu = options;
  return sim::Simulation::create(setup, diagnostics, cuda);
}
inline std::unique_ptr<sim::Simulation> gpu_batch(std::vector<sim::SimulationSetup> scenes,
                                                  const sim::GpuOptions& options, DiagnosticList& diagnostics) {
  sim::SimulationOptions cuda;
  cuda.backend = sim::Backend::Cuda;
  cuda.gpu = options;
  return sim::Simulation::create(std::move(scenes), cuda, diagnostics);
}

// Every step's record the same, its residual to the bit.
inline bool same_records(const std::vector<sim::ImplicitStepRecord>& a, const std::vector<sim::ImplicitStepRecord>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k) {
    if (a[k].step != b[k].step || a[k].iterations != b[k].iterations || a[k].capped != b[k].capped ||
        std::memcmp(&a[k].relative_residual, &b[k].relative_residual, sizeof(double)) != 0)
      return false;
  }
  return true;
}

// The four ways an implicit solve launches on a small mesh: one block (the plan's choice), the cooperative grid
// where the one-block solve would be planned, the per-iteration launches with fused stages, and a launch per kernel
// (the plan's choice above kFusedStageDofs degrees of freedom). All give the same bits.
struct CgLaunch {
  const char* name;
  sim::GpuOptions options;
};
inline std::array<CgLaunch, 4> cg_launches() {
  sim::GpuOptions cooperative, fused, separate;
  cooperative.cg_single_block = false;
  fused.persistent = false;
  separate.persistent = false;
  separate.cg_fused_stages = false;
  return {CgLaunch{"one block", {}}, CgLaunch{"cooperative", cooperative}, CgLaunch{"fused per-iteration", fused},
          CgLaunch{"separate per-iteration", separate}};
}

inline const char* name_of(sim::Precision precision) { return precision == sim::Precision::Float ? "float" : "double"; }

// The conjugate-gradient cap of the sanitizer smokes' implicit runs: every CG kernel (and every phase of the
// cooperative one) runs in each iteration, so a few iterations check them all, while racecheck, which instruments
// each shared-memory access, takes minutes per converged solve of the cooperative launch's one to three blocks (each
// walks all the dot products' virtual blocks). Reaching the cap is a warning, not an error.
inline constexpr int kSanitizedCgIterations = 6;

// Forward Euler amplifies every undamped vibration, and neither the dashpots along springs nor the elements'
// stiffness-proportional damping reach the sideways vibrations of stretched springs or the rotations of loaded
// elements, so dt auto refuses it without mass damping (docs/simulator.md, stability): its scenes get alpha = 20 /s.
inline double forward_euler_mass_damping(sim::Integrator integrator) {
  return integrator == sim::Integrator::ForwardEuler ? 20.0 : 0.0;
}

inline double max_difference(const std::vector<sim::Point3>& a, const std::vector<sim::Point3>& b) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (std::size_t v = 0; v < a.size(); ++v) {
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const double d = std::abs(a[v][axis] - b[v][axis]);
      if (!(d <= worst)) worst = d;  // NaN propagates as a failure
    }
  }
  return worst;
}

inline bool bitwise_equal(const std::vector<sim::Point3>& a, const std::vector<sim::Point3>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(sim::Point3)) == 0);
}

inline std::string first_error(const DiagnosticList& diagnostics) {
  for (const auto& d : diagnostics.items()) {
    if (d.severity == Severity::Error) return d.message;
  }
  return {};
}

inline std::string describe(const DiagnosticList& diagnostics) {
  std::string text;
  for (const auto& d : diagnostics.items()) text += d.message + "; ";
  return text;
}

// The largest difference of the positions (m) and, separately, of the velocities (m/s); infinity when a run failed.
struct Difference {
  double positions = std::numeric_limits<double>::infinity();
  double velocities = std::numeric_limits<double>::infinity();
};

inline Difference cpu_gpu_difference(const sim::SimulationSetup& setup, std::size_t steps,
                                     const gpu::GpuOptions& options) {
  DiagnosticList diagnostics;
  const auto cpu = sim::Simulation::create(setup, diagnostics);
  const auto device = gpu_simulation(setup, diagnostics, options);
  if (!cpu || !device || !cpu->advance(steps, diagnostics) || !device->advance(steps, diagnostics)) {
    note("setup or run failed: " + describe(diagnostics));
    return {};
  }
  Difference difference;
  difference.positions = max_difference(cpu->positions(diagnostics), device->positions(diagnostics));
  difference.velocities = max_difference(cpu->velocities(diagnostics), device->velocities(diagnostics));
  if (diagnostics.has_errors()) {
    note("errors: " + describe(diagnostics));
    return {};
  }
  return difference;
}

// Velocities are compared at 100 x the position tolerance per second (the scenes move at most ~0.1 m/s).
inline double position_tolerance(sim::Precision precision) { return precision == sim::Precision::Float ? 1e-5 : 1e-12; }
inline double velocity_tolerance(sim::Precision precision) { return 100.0 * position_tolerance(precision); }

inline constexpr sim::Integrator kGpuIntegrators[] = {sim::Integrator::ForwardEuler, sim::Integrator::SemiImplicitEuler,
                                                      sim::Integrator::VelocityVerlet, sim::Integrator::RungeKutta4};

// CPU and GPU side by side for `steps` steps: positions, velocities, the probe's reading and the springs' current
// stiffness; the largest differences.
struct SceneDifference {
  Difference state;
  double probe_force = std::numeric_limits<double>::infinity();
  double stiffness = std::numeric_limits<double>::infinity();
};

inline SceneDifference scene_difference(const sim::SimulationSetup& setup, std::size_t steps) {
  SceneDifference out;
  DiagnosticList diagnostics;
  const auto cpu = sim::Simulation::create(setup, diagnostics);
  const auto device = gpu_simulation(setup, diagnostics);
  if (!cpu || !device || !cpu->advance(steps, diagnostics) || !device->advance(steps, diagnostics)) {
    note("setup or run failed: " + describe(diagnostics));
    return out;
  }
  out.state.positions = max_difference(cpu->positions(diagnostics), device->positions(diagnostics));
  out.state.velocities = max_difference(cpu->velocities(diagnostics), device->velocities(diagnostics));
  const sim::ProbeReading a = cpu->probe_reading(diagnostics), b = device->probe_reading(diagnostics);
  out.probe_force = 0.0;
  for (std::size_t axis = 0; axis < 3; ++axis)
    out.probe_force = std::max(out.probe_force, std::abs(a.force[axis] - b.force[axis]));
  const std::vector<double> k_cpu = cpu->current_stiffness(diagnostics), k_gpu = device->current_stiffness(diagnostics);
  out.stiffness = k_cpu.size() == k_gpu.size() ? 0.0 : std::numeric_limits<double>::infinity();
  for (std::size_t s = 0; s < k_cpu.size() && s < k_gpu.size(); ++s)
    out.stiffness = std::max(out.stiffness, std::abs(k_cpu[s] - k_gpu[s]));
  if (diagnostics.has_errors()) {
    note("errors: " + describe(diagnostics));
    out.state = {};
  }
  return out;
}

// Implicit Euler: the same preconditioned CG as Eigen's, summed in another order, so GPU and CPU agree to the
// solver's tolerance (1e-5 m in float, 1e-9 m in double after 200 steps) rather than bitwise; two GPU runs with
// different check intervals repeat bitwise. `what` names the case in the notes.
inline void check_implicit_against_cpu(const sim::SimulationSetup& setup, const std::string& what) {
  const SceneDifference d = scene_difference(setup, 200);
  const double tolerance = setup.precision == sim::Precision::Float ? 1e-5 : 1e-9;
  std::ostringstream line;  // std::to_string would print 1e-9 as 0.000000
  line << "implicit Euler, " << what << ": max |GPU - CPU| after 200 steps " << d.state.positions << " m (tolerance "
       << tolerance << "), " << d.state.velocities << " m/s";
  note(line.str());
  FMPC_EXPECT(d.state.positions <= tolerance);
  FMPC_EXPECT(d.state.velocities <= 100.0 * tolerance);
  DiagnosticList diagnostics;
  const auto first = gpu_simulation(setup, diagnostics);
  const auto second = gpu_simulation(setup, diagnostics);
  FMPC_REQUIRE(first && second && first->advance(50, diagnostics) && second->advance(50, diagnostics, 7));
  FMPC_EXPECT(bitwise_equal(first->positions(diagnostics), second->positions(diagnostics)));
  FMPC_EXPECT(first->implicit_max_iterations_used() > 0);
  note("implicit Euler, " + what + ": at most " + std::to_string(first->implicit_max_iterations_used()) +
       " CG iterations per step");
}

}  // namespace fmpc::gpu_test

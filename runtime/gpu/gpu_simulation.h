#pragma once
// The CUDA backend's host side (runtime/integrate/stepping_engine.h's engine for Backend::Cuda): built only when nvcc
// is found (FMPC_RUNTIME_HAVE_CUDA); this header itself needs no CUDA headers. Users hold a sim::Simulation (runtime/
// integrate/simulation.h) created with SimulationOptions::backend = Backend::Cuda. Every force model (springs,
// element terms, both) runs with every integrator: forward and semi-implicit Euler (one fused kernel per step, or
// many steps per persistent launch), velocity Verlet (two kernels per step), RK4 (four stage kernels per step) and
// implicit Euler (a matrix-free, Jacobi-preconditioned conjugate gradient in double, kernels/implicit_math.h), all
// over the same FMPC_HD functions as the CPU loop, in float or double. Probes and strain tables run beside every step
// as on the CPU. Repeated explicit steps are replayed from CUDA graphs. A batch's scenes are concatenated into one
// network and advanced by one launch per kernel: they share the integrator, the precision, the spring law and its
// parameters, the element laws, gravity and the nodal damping (batch_accepts); sizes, materials, fixed vertices,
// forces, probes and initial states may differ, and each scene's probe is applied by its own threads from its own
// values (no atomics), so a scene's results are bitwise those it has alone. The engine runs on GpuOptions::device,
// made current in the creating thread before any allocation (a cohort spread over GPUs: one thread per device). Implicit Euler and strain tables need a
// batch of one scene. Every CUDA call and launch is checked and turned into a Diagnostic; nothing exits.
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "runtime/integrate/simulation.h"

namespace fmpc::sim {
class SteppingEngine;
}

namespace fmpc::gpu {

using sim::GpuOptions;

// Whether a CUDA device can be used, with its name or the reason it cannot.
bool cuda_device_available(std::string& description);

// The CUDA devices this process sees (cudaGetDeviceCount: CUDA_VISIBLE_DEVICES applies), or nullopt with CUDA's
// reason in `error`. No device at all is a count of 0, not an error.
std::optional<int> cuda_device_count(std::string& error);

// Whether scene s can join the batch (what a batch cannot share is refused before the device is touched, with an
// error naming the scene); false after appending the error.
bool batch_accepts(const std::vector<sim::SimulationSetup>& scenes, std::size_t s, DiagnosticList& diagnostics);

// The engine of a batch whose scenes passed batch_accepts and check_stability (`stability`, one each), uploaded;
// null after appending errors. It reads `scenes` and `stability` (the Simulation's) for its whole life.
std::unique_ptr<sim::SteppingEngine> create_engine(const std::vector<sim::SimulationSetup>& scenes,
                                                   const std::vector<sim::StabilityReport>& stability,
                                                   const GpuOptions& options, DiagnosticList& diagnostics);

}  // namespace fmpc::gpu

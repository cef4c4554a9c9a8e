#pragma once
// The CUDA backend's host side. Built only when nvcc is found (FMPC_RUNTIME_HAVE_CUDA); this header itself needs
// no CUDA headers. Integrators on the GPU: forward Euler and semi-implicit Euler, one fused kernel per step over
// the same FMPC_HD functions as the CPU loop, in float or double. Every CUDA call and launch is checked and turned
// into a Diagnostic; nothing exits.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "runtime/integrate/simulation.h"

namespace fmpc::gpu {

// Whether a CUDA device can be used, with its name or the reason it cannot.
bool cuda_device_available(std::string& description);

class GpuSimulation {
 public:
  // Validates the setup like the CPU backend (same stability check), then uploads it.
  static std::unique_ptr<GpuSimulation> create(const sim::SimulationSetup& setup, DiagnosticList& diagnostics);
  virtual ~GpuSimulation() = default;

  // Advances `steps` steps, checking for NaN/Inf every `check_every` steps and at the end; on a non-finite value
  // the error names the check's step, the vertex and its most strained spring (read back to the host).
  virtual bool advance(std::size_t steps, DiagnosticList& diagnostics, std::size_t check_every = 64) = 0;
  virtual std::size_t steps_taken() const = 0;
  virtual std::vector<sim::Point3> positions(DiagnosticList& diagnostics) const = 0;
  virtual std::vector<sim::Point3> velocities(DiagnosticList& diagnostics) const = 0;
  virtual const sim::StabilityReport& stability() const = 0;
};

}  // namespace fmpc::gpu

#include "runtime/gpu/gpu_simulation.h"

#include <cuda_runtime_api.h>

#include <limits>
#include <string>

#include "runtime/gpu/cuda_check.h"
#include "runtime/gpu/gpu_engine.h"

namespace fmpc::gpu {

bool cuda_device_available(std::string& description) {
  int count = 0;
  const cudaError_t status = cudaGetDeviceCount(&count);
  if (status != cudaSuccess) {
    description = std::string("no usable CUDA device: ") + cudaGetErrorString(status);
    return false;
  }
  if (count == 0) {
    description = "no CUDA device";
    return false;
  }
  cudaDeviceProp properties{};
  if (cudaGetDeviceProperties(&properties, 0) != cudaSuccess) {
    description = "CUDA device 0 cannot be queried";
    return false;
  }
  description = properties.name;
  return true;
}

std::optional<int> cuda_device_count(std::string& error) {
  int count = 0;
  const cudaError_t status = cudaGetDeviceCount(&count);
  // No driver or no device: CUDA says so through this call's status; both mean no device to run on.
  if (status == cudaErrorNoDevice || status == cudaErrorInsufficientDriver) return 0;
  if (status != cudaSuccess) {
    error = std::string("cudaGetDeviceCount failed: ") + cudaGetErrorName(status) + " (" + cudaGetErrorString(status) +
            ")";
    return std::nullopt;
  }
  return count;
}

std::unique_ptr<sim::SteppingEngine> create_engine(const std::vector<sim::SimulationSetup>& scenes,
                                                   const std::vector<sim::StabilityReport>& stability,
                                                   const GpuOptions& options, DiagnosticList& diagnostics) {
  std::size_t vertices = 0, entries = 0;
  for (const sim::SimulationSetup& setup : scenes) {
    vertices += setup.rest_positions.size();
    entries += setup.springs.adjacency_spring.size();
  }
  const auto limit = static_cast<std::size_t>(std::numeric_limits<int>::max() - 1);
  if (vertices > limit || entries > limit) {
    diagnostics.error(SourceRange{}, "the GPU backend indexes vertices and springs with int; " +
                                         std::to_string(vertices) + " vertices and " + std::to_string(entries) +
                                         " spring ends are too many: split the batch");
    return nullptr;
  }
  // Before the engine allocates anything: its device, in this thread (GpuOptions::device).
  if (options.device >= 0) FMPC_CUDA_CHECK(cudaSetDevice(options.device), diagnostics, nullptr);
  if (scenes.front().precision == sim::Precision::Float) {
    auto engine = std::make_unique<GpuEngine<float>>(scenes, stability, options);
    if (!engine->upload(diagnostics)) return nullptr;
    return engine;
  }
  auto engine = std::make_unique<GpuEngine<double>>(scenes, stability, options);
  if (!engine->upload(diagnostics)) return nullptr;
  return engine;
}

}  // namespace fmpc::gpu

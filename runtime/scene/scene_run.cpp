#include "runtime/scene/scene_run.h"

#include "runtime/scene/scene_batch_run.h"
#if defined(FMPC_RUNTIME_HAVE_CUDA)
#include "runtime/gpu/gpu_simulation.h"
#include "runtime/fem/element_law_registry.h"
#endif

namespace fmpc::sim {

std::optional<BackendChoice> choose_backend(const Scene& scene, DiagnosticList& diagnostics) {
  std::string device;
#if defined(FMPC_RUNTIME_HAVE_CUDA)
  const bool have_device = gpu::cuda_device_available(device);
#else
  const bool have_device = false;
  device = "this fmpc was built without CUDA";
#endif
  const bool direct = scene.integrator == Integrator::ImplicitEuler && scene.solver.method == ImplicitMethod::Direct;
  // An element kind CUDA does not run yet with the scene's integrator (element_kind_limits).
  const char* cuda_backend_refusal =
      scene.model == ForceModel::Elements
          ? cuda_refusal(element_kind_limits(scene.element_kind), scene.integrator == Integrator::ImplicitEuler)
          : nullptr;
  switch (scene.backend) {
    case SceneBackend::Cpu:
      return BackendChoice{"cpu", ""};
    case SceneBackend::Auto:
      if (have_device && direct)
        return BackendChoice{"cpu", "backend auto: solver.method direct runs on the CPU only; running on the CPU"};
      if (have_device && cuda_backend_refusal)
        return BackendChoice{"cpu", std::string("backend auto: fem.element ") +
                                        element_kind_row(scene.element_kind).keyword + " " + cuda_backend_refusal +
                                        "; running on the CPU"};
      if (have_device) return BackendChoice{"cuda", "backend auto: running on CUDA (" + device + ")"};
      return BackendChoice{"cpu", "backend auto: no GPU (" + device + "); running on the CPU"};
    case SceneBackend::Cuda:
      if (direct) {
        diagnostics.error(scene.range_of("solver.method"),
                          "solver.method: the direct solver runs on the CPU only; this scene asks for backend cuda: "
                          "use method cg (or auto, the CG on CUDA) or backend cpu");
        return std::nullopt;
      }
      if (cuda_backend_refusal) {
        diagnostics.error(scene.range_of("backend"), std::string("backend: fem.element ") +
                                                         element_kind_row(scene.element_kind).keyword + " " +
                                                         cuda_backend_refusal + "; use backend cpu or auto");
        return std::nullopt;
      }
      if (have_device) return BackendChoice{"cuda", ""};
      diagnostics.error(scene.range_of("backend"),
                        "backend: 'cuda' cannot run here: " + device + "; use backend cpu or auto");
      return std::nullopt;
  }
  return std::nullopt;
}

std::string default_output_directory(const Scene& scene) {
  return !scene.outputs.directory.empty() ? scene.outputs.directory : scene.name + "_output";
}

// The backend a run's options name ("cpu" or "cuda").
Backend run_backend(const std::string& name) { return name == "cuda" ? Backend::Cuda : Backend::Cpu; }

std::optional<SceneRunResult> run_scene(const Scene& scene, const BuiltScene& built, const SceneRunOptions& options,
                                        DiagnosticList& diagnostics) {
  SceneBatchMember member{&scene, &built, options, &diagnostics};
  SimulationOptions simulation_options;
  simulation_options.backend = run_backend(options.backend);
  const auto run = run_scene_batch({member}, simulation_options, options.progress, diagnostics);
  if (!run) return std::nullopt;
  return std::move(run->results.front());
}

}  // namespace fmpc::sim

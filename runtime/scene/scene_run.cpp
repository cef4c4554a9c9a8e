#include "runtime/scene/scene_run.h"

#include <chrono>

#include "runtime/io/atomic_file.h"
#include "runtime/scene/precision_check.h"
#include "runtime/scene/scene_recorder.h"
#include "runtime/scene/scene_state.h"
#if defined(FMPC_RUNTIME_HAVE_CUDA)
#include "runtime/gpu/gpu_simulation.h"
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
  switch (scene.backend) {
    case SceneBackend::Cpu:
      return BackendChoice{"cpu", ""};
    case SceneBackend::Auto:
      if (have_device) return BackendChoice{"cuda", "backend auto: running on CUDA (" + device + ")"};
      return BackendChoice{"cpu", "backend auto: no GPU (" + device + "); running on the CPU"};
    case SceneBackend::Cuda:
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

std::optional<SceneRunResult> run_scene(const Scene& scene, const BuiltScene& built, const SceneRunOptions& options,
                                        DiagnosticList& diagnostics) {
  const SimulationSetup& setup = built.setup;
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point from) {
    return std::chrono::duration<double>(Clock::now() - from).count();
  };
  SceneRunTiming timing;
  const auto created = Clock::now();
  const auto simulation = create_stepper(setup, options.backend, diagnostics);
  if (!simulation) return std::nullopt;
  timing.simulator = seconds_since(created);
  if (!ensure_directory(options.output_directory, diagnostics)) return std::nullopt;
  const auto planned = planned_step_count(scene, simulation->stability().time_step, diagnostics);
  if (!planned) return std::nullopt;
  const std::size_t total = *planned;
  SceneRecorder recorder(scene, built, options, total);
  const auto record = [&](bool frame, bool sample) {
    const auto from = Clock::now();
    recorder.record(*simulation, frame, sample, diagnostics);
    timing.recording += seconds_since(from);
  };
  const auto start = Clock::now();
  if (recorder.is_frame(0) || recorder.is_sample(0)) record(recorder.is_frame(0), recorder.is_sample(0));
  bool running = true;
  bool first = true;
  for (const std::size_t event : recorder.events()) {
    if (event == 0) continue;
    const auto from = Clock::now();
    running = simulation->advance(event - simulation->steps_taken(), diagnostics);
    const double advanced = seconds_since(from);
    timing.stepping += advanced;
    if (first) timing.first_advance = advanced;
    first = false;
    if (!running) break;
    // The largest displacement is followed at every event (about 100 per run).
    record(recorder.is_frame(event), recorder.is_sample(event));
    if (options.progress) options.progress(event, total);
  }
  if (!running) record(recorder.records_at_end(), recorder.samples_at_end());
  const double wall = seconds_since(start);
  recorder.set_timing(timing);
  return recorder.finish(
      *simulation, running, wall,
      [&](const SceneRunResult& run) { return check_precision(scene, built, options, run, diagnostics); },
      diagnostics);
}

}  // namespace fmpc::sim

#pragma once
// Internal to runtime/scene: the one runner of scenes, for a scene alone (run_scene) and for a cohort (run_cohort):
// the scenes as one Simulation batch, advanced event by event with each scene's outputs recorded at its events, the
// precision check as a second batch in the other precision, and each scene's outputs written. Not installed.
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/scene/scene_run.h"

namespace fmpc::sim {

struct SceneBatchMember {
  const Scene* scene = nullptr;
  const BuiltScene* built = nullptr;
  SceneRunOptions options;  // its output folder and backend name; progress is the batch's
  // Where its own messages go (recording, outputs, the precision check): may be the batch's list.
  DiagnosticList* diagnostics = nullptr;
};

struct SceneBatchResult {
  std::vector<std::optional<SceneRunResult>> results;  // per member, in order
  double wall_seconds = 0.0;                           // stepping and recording
  double stepping_seconds = 0.0;                       // the advance calls alone
  double spring_steps = 0.0;                           // over members: springs x steps taken
};

// The members share the scene's outputs and step count (a scene alone, or a cohort's patients prepared at one time
// step). Errors of the batch (creating it, stepping) go to `diagnostics`. nullopt when nothing could start.
// `options`: the backend, the CPU's workers over the members (batch_threads; 0: every hardware thread, also the
// workers that record and write the members side by side) and on CUDA the device (gpu.device: the batch and its
// precision check run on it from the calling thread).
std::optional<SceneBatchResult> run_scene_batch(const std::vector<SceneBatchMember>& members,
                                                const SimulationOptions& options,
                                                const std::function<void(std::size_t, std::size_t)>& progress,
                                                DiagnosticList& diagnostics);

}  // namespace fmpc::sim

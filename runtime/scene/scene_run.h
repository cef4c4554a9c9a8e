#pragma once
// Runs a built scene on the CPU or the CUDA backend and writes its outputs (docs/scenes.md, "Outputs"): VTK XML frames (.vtu)
// and their .pvd collection, a CSV time series (probe displacement and force, kinetic and elastic energy) and a JSON
// summary, each written atomically. Nothing is printed: progress goes to a callback the caller may draw.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"

namespace fmpc::sim {

struct SceneRunOptions {
  std::string output_directory;  // created when missing
  std::string backend = "cpu";   // "cpu" or "cuda" (the caller decides; the summary records it)
  // Called about 100 times during the run with (steps done, steps planned).
  std::function<void(std::size_t, std::size_t)> progress;
};

struct ProbeCurvePoint {
  double time = 0.0;          // s
  double displacement = 0.0;  // m, along the probe's direction (its target's direction)
  double force = 0.0;         // N, along the same direction
};

struct SceneRunResult {
  bool completed = false;  // false: stopped by a non-finite state (the error says where)
  std::size_t steps_planned = 0;
  std::size_t steps_taken = 0;
  StabilityReport stability;
  double wall_seconds = 0.0;
  double steps_per_second = 0.0;
  double max_displacement = 0.0;  // m, over every vertex at the recorded times (frames and samples)
  std::vector<ProbeCurvePoint> probe_curve;  // at the samples; empty without a probe
  InversionReport inversions;
  std::vector<std::string> files;            // written, in order
  std::string csv_path;                      // empty when no CSV was written
};

// Steps: scene.steps when set, else ceil(duration / dt) (dt from the stability check when `auto`).
// Returns nullopt when the simulation could not start or an output could not be written (errors appended).
std::optional<SceneRunResult> run_scene(const Scene& scene, const BuiltScene& built, const SceneRunOptions& options,
                                        DiagnosticList& diagnostics);

// The CSV's header for a scene with or without a probe (docs/scenes.md lists the columns).
std::vector<std::string> time_series_columns(bool with_probe);

}  // namespace fmpc::sim

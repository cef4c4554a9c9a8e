#pragma once
// Internal to runtime/scene: the precision check (scene_run.h, PrecisionCheckResult): the same run again in the other
// precision, compared with the run's final answers. Not installed.
#include <optional>
#include <string>

#include "diagnostics/diagnostic.h"
#include "runtime/scene/scene_run.h"
#include "runtime/scene/scene_state.h"

namespace fmpc::sim {

// Why the precision check does not run for this run, or nullopt when it does (outputs.precision_check, and `auto`'s
// limit on the run's stepping time, `stepping_seconds`).
std::optional<std::string> precision_check_skipped(const Scene& scene, const SceneRunResult& run,
                                                   double stepping_seconds);

// The setup of the rerun: the other precision at the run's step.
SimulationSetup precision_check_setup(const SimulationSetup& setup, const SceneRunResult& run);

// The rerun's final state (null: it did not complete) against the run's final answers, warned about when they differ.
PrecisionCheckResult compare_precision(const Scene& scene, const SimulationSetup& setup, const SceneRunResult& run,
                                       const SceneState* other_run, DiagnosticList& diagnostics);

}  // namespace fmpc::sim

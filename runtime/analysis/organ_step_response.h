#pragma once
// The thesis's experiment on an organ (docs/liver_fibrosis.md, "On the meshed liver"): a scene's tissue takes a
// controller's Young's modulus and its probe carries the one-mass experiment's load history, a step force of F held
// for the whole run; the probe's displacement and velocity curves then compare with the Basafa-Farahmand benchmark
// as the one mass point's do (liver_benchmark.h).
//
// The point load on the organ: the scene's probe picks its vertices (by a ray and a radius, or by index) and the
// total force F is shared equally among them (ProbeLoad::Mode::Force), along the direction the scene pushes (its
// probe's displacement or force, else its ray's direction), from t = 0, the organ at rest. The curves are the
// probe vertices' mean displacement and mean velocity along that direction. The mesh, model, element, law,
// material mapping, Poisson ratio, damping, fixed vertices, integrator, step and precision are the scene's; the
// scene's own probe load (its displacement or force, ramp and cycles) is replaced, and a mesh meshed from a surface
// is sized by the scene's own probe path, so the organ is the one `fmpc simulate` runs.
#include <optional>

#include "diagnostics/diagnostic.h"
#include "runtime/analysis/liver_benchmark.h"
#include "runtime/scene/scene_file.h"

namespace fmpc::sim {

// Whether `scene` can carry the experiment: a probe (a scene with rigid tools alone is refused: they follow paths,
// a force cannot drive them) and a material given as a Young's modulus (youngs_modulus, rules or table; spring
// constants cannot take a controller's modulus). Errors are located at the scene's fields.
bool check_organ_scene(const Scene& scene, DiagnosticList& diagnostics);

// The unit vector of the probe's push in `scene` (see above), or nullopt when it has none (a zero target picked by
// index).
std::optional<Point3> organ_probe_direction(const SceneProbe& probe);

// Builds `scene` with Young's modulus `modulus` (Pa) everywhere, applies options.force on its probe as a step and
// samples options.samples times over options.duration (the nearest step to each evenly spaced time; the scene's
// step must give at least samples - 1 steps). Errors (the scene's own, or a run that fails) are appended; nullopt
// then.
std::optional<MassPointResponse> simulate_organ_step(const Scene& scene, double modulus,
                                                     const LiverBenchmarkOptions& options,
                                                     DiagnosticList& diagnostics);

}  // namespace fmpc::sim

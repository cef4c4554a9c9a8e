#include "runtime/scene/spring_model_builder.h"

#include <cmath>

namespace fmpc::sim {

std::optional<SimulationSetup> build_spring_model(const Mesh& mesh, const SpringModelSpec& spec,
                                                  DiagnosticList& diagnostics) {
  SourceRange range;
  range.file = mesh.source;
  if (!(spec.length_unit > 0.0) || !std::isfinite(spec.length_unit)) {
    diagnostics.error(range, "the length unit must be a positive number of metres per mesh unit");
    return std::nullopt;
  }
  if (mesh.tetrahedra.empty() && mesh.triangles.empty()) {
    diagnostics.error(range, "the mesh has no tetrahedra or triangles to build springs from");
    return std::nullopt;
  }
  Mesh scaled = mesh;
  for (Point3& p : scaled.points) {
    for (double& coordinate : p) coordinate *= spec.length_unit;
  }
  SimulationSetup setup;
  setup.rest_positions = scaled.points;
  setup.springs = scaled.tetrahedra.empty() ? springs_from_triangles(scaled, spec.triangle_springs, diagnostics)
                                            : springs_from_tetrahedra(scaled, diagnostics);
  if (diagnostics.has_errors()) return std::nullopt;
  if (!compute_rest_lengths(setup.springs, scaled.points, diagnostics)) return std::nullopt;
  if (!assign_stiffness(setup.springs, spec.stiffness, diagnostics)) return std::nullopt;
  setup.mass = lumped_masses(scaled, spec.mass, diagnostics);
  if (setup.mass.empty() && !scaled.points.empty()) return std::nullopt;
  if (!assign_damping(setup.springs, setup.mass, spec.damping, diagnostics)) return std::nullopt;
  return setup;
}

}  // namespace fmpc::sim

#include "runtime/scene/spring_model_builder.h"

#include <cmath>

#include "runtime/mesh/mesh_check.h"

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
  if (is_modulus_mapping(spec.stiffness.mapping)) {
    // Young's modulus mappings weigh every spring by the volumes (areas) of its elements: a degenerate element has
    // none to give, and a network built over it would be silently soft there.
    const bool volume = !mesh.tetrahedra.empty();
    const std::size_t errors = diagnostics.error_count();
    for (const MeshFinding& finding : check_mesh(mesh)) {
      const bool degenerate = volume ? finding.kind == MeshFindingKind::DegenerateTetrahedron
                                     : finding.kind == MeshFindingKind::DegenerateTriangle;
      if (!degenerate) continue;
      SourceRange at = range;
      at.line = finding.line;
      at.column = finding.line > 0 ? 1 : 0;
      diagnostics.error(at, finding_message(finding) + ": the " + mapping_citation(spec.stiffness.mapping) +
                                " mapping needs every element's " + (volume ? "volume" : "area") +
                                "; repair the mesh first (repair_mesh drops degenerate elements)");
    }
    if (diagnostics.error_count() > errors) return std::nullopt;
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

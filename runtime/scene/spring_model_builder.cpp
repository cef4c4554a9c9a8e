#include "runtime/scene/spring_model_builder.h"

#include <cmath>
#include <utility>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "runtime/integrate/worker_pool.h"
#include "runtime/mesh/mesh_check.h"

namespace fmpc::sim {

namespace {

// glibc serves blocks under its dynamic mmap threshold (up to 32 MiB: the per-vertex arrays of meshes of up to about
// 8M vertices, such as the repair's maps and the CSR's counters) from the heap, and keeps the pages of those freed in
// its middle: 2.4 bytes per spring at 160^3 cells (docs/performance.md, "Host setup"). Handing them back before the
// setup's last arrays are allocated keeps them out of its peak.
void return_free_heap_pages() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

}  // namespace

std::optional<SimulationSetup> build_spring_model(const Mesh& mesh, const SpringModelSpec& spec,
                                                  DiagnosticList& diagnostics, WorkerPool* given_pool) {
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
  PoolLease lease(given_pool, spec.threads, mesh.points.size() + mesh.tetrahedra.size() + mesh.triangles.size());
  WorkerPool& pool = lease.pool();
  if (is_modulus_mapping(spec.stiffness.mapping)) {
    // Young's modulus mappings weigh every spring by the volumes (areas) of its elements: a degenerate element has
    // none to give, and a network built over it would be silently soft there.
    const bool volume = !mesh.tetrahedra.empty();
    const std::size_t errors = diagnostics.error_count();
    for (const MeshFinding& finding : degenerate_elements(mesh, {}, &pool)) {
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
  SimulationSetup setup;
  resize_large(setup.rest_positions, mesh.points.size());
  pool.run(mesh.points.size(), [&](std::size_t first, std::size_t last) {
    for (std::size_t v = first; v < last; ++v) {
      for (std::size_t axis = 0; axis < 3; ++axis) setup.rest_positions[v][axis] = mesh.points[v][axis] * spec.length_unit;
    }
  });
  const std::vector<Point3>& metres = setup.rest_positions;
  // The masses come first, while little memory is in use, from the same grouping of the elements by vertex as the
  // springs; their errors are reported where they always were, after the springs' and the stiffness'.
  DiagnosticList mass_diagnostics;
  std::vector<double> mass;
  {
    VertexElements at = elements_at_vertices(mesh, &pool);
    mass = lumped_masses(mesh, metres, spec.mass, mass_diagnostics, &pool, &at);
    setup.springs = mesh.tetrahedra.empty()
                        ? springs_from_triangles(mesh, metres, spec.triangle_springs, diagnostics, &pool, std::move(at))
                        : springs_from_tetrahedra(mesh, metres, diagnostics, &pool, std::move(at));
  }
  if (diagnostics.has_errors()) return std::nullopt;
  return_free_heap_pages();
  if (!compute_rest_lengths(setup.springs, metres, diagnostics, 1e-9, &pool)) return std::nullopt;
  if (!assign_stiffness(setup.springs, spec.stiffness, diagnostics, &pool, ElementMeasures::Release))
    return std::nullopt;
  diagnostics.append(mass_diagnostics);
  setup.mass = std::move(mass);
  if (setup.mass.empty() && !mesh.points.empty()) return std::nullopt;
  if (!assign_damping(setup.springs, setup.mass, spec.damping, diagnostics, &pool)) return std::nullopt;
  return setup;
}

}  // namespace fmpc::sim

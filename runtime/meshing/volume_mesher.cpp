#include "runtime/meshing/volume_mesher.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "diagnostics/number_format.h"
#include "runtime/meshing/tetgen_mesher.h"

namespace fmpc::sim {

namespace {

// A predicted count, rounded: "320000".
std::string count_text(double value) { return std::to_string(std::llround(value)); }

}  // namespace

bool volume_mesher_available() { return tetgen_available(); }

std::vector<std::string> size_field_problems(const SizeField& field, const SizeOptionNames& names) {
  std::vector<std::string> problems;
  const auto positive = [&](double value, const std::string& name) {
    if (!(std::isfinite(value) && value > 0.0))
      problems.push_back(name + " must be a positive length (mesh units), got " + format_number(value));
  };
  positive(field.size_far, names.size_far);
  positive(field.size_near, names.size_near);
  if (field.size_near > field.size_far)
    problems.push_back(names.size_near + " (" + format_number(field.size_near) + ") must not exceed " + names.size_far +
                       " (" + format_number(field.size_far) + ")");
  if (!(std::isfinite(field.near_distance) && field.near_distance >= 0.0))
    problems.push_back(names.near_distance + " must be a length >= 0 (mesh units), got " +
                       format_number(field.near_distance));
  positive(field.grading, names.grading);
  if (field.sources.size() > kMaxSizeSources)
    problems.push_back("the size field has " + std::to_string(field.sources.size()) + " sources; at most " +
                       std::to_string(kMaxSizeSources) + " are allowed");
  return problems;
}

std::optional<VolumeMesh> mesh_volume(Mesh surface, const VolumeMeshOptions& options, DiagnosticList& diagnostics) {
  const SourceRange file_range{surface.source, 0, 0, 0, 0};
  VolumeMesh result;
  result.surface_vertices = surface.points.size();
  result.surface_triangles = surface.triangles.size();
  if (surface.points.size() > kMaxSurfaceVertices || surface.triangles.size() > kMaxSurfaceTriangles) {
    diagnostics.error(file_range, "the surface has " + std::to_string(surface.points.size()) + " vertices and " +
                                      std::to_string(surface.triangles.size()) +
                                      " triangles; the mesher takes at "
                                      "most " +
                                      std::to_string(kMaxSurfaceVertices) + " and " +
                                      std::to_string(kMaxSurfaceTriangles) + ": decimate the surface first");
    return std::nullopt;
  }
  if (!surface.tetrahedra.empty()) {
    diagnostics.error(file_range,
                      "the file holds tetrahedra already; give it as mesh.file (a volume mesh), not as a "
                      "surface to mesh");
    return std::nullopt;
  }
  const auto problems = size_field_problems(options.size);
  for (const std::string& problem : problems) diagnostics.error(file_range, problem);
  if (!problems.empty()) return std::nullopt;
  result.surface = check_closed_surface(surface, diagnostics);
  if (!result.surface.closed) return std::nullopt;
  if (result.surface.inward) {
    reverse_triangles(surface);
    result.surface.volume = -result.surface.volume;
    diagnostics.warning(file_range, "surface-orientation",
                        "the surface's triangles are oriented inwards (enclosed volume " +
                            significant_digits(result.surface.volume, 3) +
                            " with the normals reversed); meshed as if reversed");
  }
  auto intersecting = tetgen_self_intersections(surface, diagnostics);
  if (!intersecting) return std::nullopt;
  if (!intersecting->empty()) {
    if (!options.smooth_intersections) {
      report_self_intersections(surface, *intersecting, diagnostics);
      return std::nullopt;
    }
    result.untangling = untangle_surface(surface, std::move(*intersecting), diagnostics);
    if (!result.untangling) return std::nullopt;
    DiagnosticList none;  // the moved surface has the same triangles: still closed and outward
    result.surface = check_closed_surface(surface, none);
    diagnostics.warning(file_range, "surface-smoothed",
                        std::to_string(result.untangling->intersecting_triangles) +
                            " triangles intersected other parts of the surface; smoothing moved " +
                            std::to_string(result.untangling->moved_vertices) + " vertices by at most " +
                            significant_digits(result.untangling->largest_move, 3) + " mesh units in " +
                            std::to_string(result.untangling->rounds) +
                            (result.untangling->rounds == 1 ? " round" : " rounds") + " (smooth_intersections)");
  }
  if (options.keep_surface && options.split_surface) {
    result.split = split_surface_to_size(surface, options.size, kMaxSurfaceTriangles, diagnostics);
    if (!result.split) return std::nullopt;
  }
  result.estimate = estimate_tetrahedra(surface, options.size);
  if (result.estimate.tetrahedra > static_cast<double>(options.max_tetrahedra)) {
    diagnostics.error(file_range, "the size field asks for about " + count_text(result.estimate.tetrahedra) +
                                      " tetrahedra (an estimate from the enclosed volume, " +
                                      significant_digits(result.estimate.volume, 3) +
                                      " mesh units^3, and the sizes); the "
                                      "limit is " +
                                      std::to_string(options.max_tetrahedra) +
                                      ": raise size_far or size_near, or shrink near_distance");
    return std::nullopt;
  }
  const std::size_t max_inserted = kMaxMeshedVertices - std::min(kMaxMeshedVertices, surface.points.size());
  auto mesh = tetgen_tetrahedralize(surface, options, max_inserted, diagnostics);
  if (!mesh) return std::nullopt;
  if (mesh->points.size() >= surface.points.size() + max_inserted) {
    diagnostics.error(file_range, "the mesher reached its cap of " + std::to_string(kMaxMeshedVertices) +
                                      " vertices before meeting the size field and quality bounds; raise size_far "
                                      "or size_near");
    return std::nullopt;
  }
  if (mesh->tetrahedra.size() > options.max_tetrahedra) {
    diagnostics.error(file_range, "the mesh has " + std::to_string(mesh->tetrahedra.size()) +
                                      " tetrahedra, past the limit of " + std::to_string(options.max_tetrahedra) +
                                      " (the estimate was " + count_text(result.estimate.tetrahedra) +
                                      "); raise size_far or size_near");
    return std::nullopt;
  }
  // Scenes name surface vertices by their index in the file: TetGen keeps the input points first, in order.
  for (std::size_t v = 0; v < surface.points.size(); ++v) {
    if (v >= mesh->points.size() || mesh->points[v] != surface.points[v]) {
      diagnostics.error(file_range, "internal error: the mesher renumbered surface vertex " + std::to_string(v) +
                                        "; report it with the surface");
      return std::nullopt;
    }
  }
  // Positive orientation (mesh.h) whatever TetGen's convention: a negative element has two vertices swapped.
  for (Tetrahedron& t : mesh->tetrahedra)
    if (signed_volume(*mesh, t) < 0.0) std::swap(t[2], t[3]);
  if (result.split) result.flat_removed = remove_flat_surface_tetrahedra(*mesh, surface.triangles);
  mesh->triangles.clear();
  result.mesh = std::move(*mesh);
  result.quality = measure_quality(result.mesh, options.max_radius_edge_ratio, options.min_dihedral_degrees);
  for (const Tetrahedron& t : result.mesh.tetrahedra) {
    Point3 centroid{0.0, 0.0, 0.0};
    for (const auto v : t)
      for (std::size_t a = 0; a < 3; ++a) centroid[a] += result.mesh.points[static_cast<std::size_t>(v)][a] / 4.0;
    result.above_size += element_shape(result.mesh, t).longest_edge > kSizeFieldSlack * size_at(options.size, centroid);
  }
  if (result.above_size > 0 && options.keep_surface) {
    const std::string counted = std::to_string(result.above_size) + " of the " +
                                std::to_string(result.mesh.tetrahedra.size()) +
                                " tetrahedra have edges longer than 1.5 times the size field at their centroid: the ";
    if (result.split)
      diagnostics.warning(file_range, "mesh-size-field",
                          counted +
                              "surface was split to the field, but TetGen inserts no point that would crowd a "
                              "kept surface triangle, so elements at and near the surface may stay coarser");
    else
      diagnostics.warning(
          file_range, "mesh-size-field", counted + "kept surface's triangles are coarser than the field near them",
          {"set keep_surface: false (fmpc mesh: leave out --keep-surface) to let the mesher split them, or "
           "split_surface: true (--split-surface) to split them to the field first"});
  }
  if (result.quality.non_positive > 0) {
    diagnostics.error(file_range, "internal error: the mesher produced " + std::to_string(result.quality.non_positive) +
                                      " tetrahedra of zero volume; report it with the surface");
    return std::nullopt;
  }
  return result;
}

std::string quality_text(const VolumeMesh& mesh, const VolumeMeshOptions& options) {
  const TetrahedronQuality& q = mesh.quality;
  const auto row = [](const std::string& name, const Distribution& d) {
    return "  " + name + ": min " + significant_digits(d.min, 3) + ", 1% " + significant_digits(d.p1, 3) + ", 5% " +
           significant_digits(d.p5, 3) + ", median " + significant_digits(d.p50, 3) + ", 95% " +
           significant_digits(d.p95, 3) + ", 99% " + significant_digits(d.p99, 3) + ", max " +
           significant_digits(d.max, 3) + "\n";
  };
  std::string text = "meshed " + mesh.mesh.source + ": " + std::to_string(mesh.surface_vertices) +
                     " surface vertices, " + std::to_string(mesh.surface_triangles) + " triangles -> " +
                     std::to_string(mesh.mesh.points.size()) + " vertices, " + std::to_string(q.tetrahedra) +
                     " tetrahedra (estimated " + count_text(mesh.estimate.tetrahedra) + ")\n";
  text += "  volume " + significant_digits(q.volume, 3) + " mesh units^3 (the surface encloses " +
          significant_digits(mesh.surface.volume, 3) + ")\n";
  text += "  size field: size_near " + format_number(options.size.size_near) + " within " +
          format_number(options.size.near_distance) + " of " + std::to_string(options.size.sources.size()) +
          (options.size.sources.size() == 1 ? " source" : " sources") + ", graded at " +
          format_number(options.size.grading) + " to size_far " + format_number(options.size.size_far) +
          " (mesh units); surface " + (options.keep_surface ? "kept" : "refined") +
          (mesh.split ? ", its triangles split to the field first (" + std::to_string(mesh.split->triangles_before) +
                            " -> " + std::to_string(mesh.split->triangles_after) + " triangles, " +
                            std::to_string(mesh.split->parents.size()) + " vertices added)"
                      : std::string()) +
          (mesh.flat_removed > 0
               ? "; " + std::to_string(mesh.flat_removed) + " flat elements on the surface removed (coplanar corners)"
               : std::string()) +
          "\n";
  text += row("longest edge (" + std::to_string(mesh.above_size) + " above 1.5 x the size field)", q.longest_edge);
  text += row("radius-edge ratio (bound " + format_number(options.max_radius_edge_ratio) + ", " +
                  std::to_string(q.above_ratio_bound) + " above, " + std::to_string(q.above_ratio_bound_inside) +
                  " of them off the surface)",
              q.radius_edge_ratio);
  text += row("smallest dihedral angle, degrees (sought " + format_number(options.min_dihedral_degrees) + ", " +
                  std::to_string(q.below_dihedral_bound) + " below)",
              q.min_dihedral_degrees);
  return text;
}

}  // namespace fmpc::sim

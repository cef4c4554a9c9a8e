#include "runtime/mesh/generated_mesh.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace fmpc::sim {

Mesh generate_box(const BoxSpec& spec, DiagnosticList& diagnostics) {
  Mesh mesh;
  mesh.source = "generated box " + std::to_string(spec.cells_x) + "x" + std::to_string(spec.cells_y) + "x" +
                std::to_string(spec.cells_z);
  SourceRange range;
  range.file = mesh.source;
  if (spec.cells_x < 1 || spec.cells_y < 1 || spec.cells_z < 1) {
    diagnostics.error(range, "a box needs at least one cell along each axis; set cells to 1 or more");
    return mesh;
  }
  if (!(spec.size[0] > 0.0 && spec.size[1] > 0.0 && spec.size[2] > 0.0) || !std::isfinite(spec.size[0]) ||
      !std::isfinite(spec.size[1]) || !std::isfinite(spec.size[2])) {
    diagnostics.error(range, "a box needs a positive, finite size along each axis");
    return mesh;
  }
  const std::int64_t nx = spec.cells_x + 1, ny = spec.cells_y + 1, nz = spec.cells_z + 1;
  if (nx * ny * nz > (std::int64_t{1} << 31) - 1) {
    diagnostics.error(range, "the box has more than 2^31 vertices; use fewer cells");
    return mesh;
  }
  const auto vertex = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    return static_cast<std::int32_t>((k * ny + j) * nx + i);
  };
  mesh.points.reserve(static_cast<std::size_t>(nx * ny * nz));
  for (std::int64_t k = 0; k < nz; ++k) {
    for (std::int64_t j = 0; j < ny; ++j) {
      for (std::int64_t i = 0; i < nx; ++i) {
        mesh.points.push_back({spec.minimum[0] + spec.size[0] * static_cast<double>(i) / spec.cells_x,
                               spec.minimum[1] + spec.size[1] * static_cast<double>(j) / spec.cells_y,
                               spec.minimum[2] + spec.size[2] * static_cast<double>(k) / spec.cells_z});
      }
    }
  }
  // Kuhn subdivision: one tetrahedron per permutation of the axes, walking from the cell's local corner (0,0,0) to
  // (1,1,1). The cell is mirrored along every axis whose cell index is odd, so that the cut diagonals alternate
  // and the 2 x 2 x 2 block of cells is symmetric under the three reflections: a box cut the same way round in
  // every cell is anisotropic (its loaded face slides sideways about as far as it moves along the load,
  // docs/simulator.md). Mirroring keeps the mesh conforming: both cells sharing a face cut it along the diagonal
  // through their common local corners (0,0) and (1,1) of that face.
  static const int kPermutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (std::int64_t k = 0; k + 1 < nz; ++k) {
    for (std::int64_t j = 0; j + 1 < ny; ++j) {
      for (std::int64_t i = 0; i + 1 < nx; ++i) {
        const std::int64_t cell[3] = {i, j, k};
        const auto global = [&](const int local[3]) {
          std::int64_t g[3];
          for (int axis = 0; axis < 3; ++axis)
            g[axis] = cell[axis] + (cell[axis] % 2 == 1 ? 1 - local[axis] : local[axis]);
          return vertex(g[0], g[1], g[2]);
        };
        for (const auto& order : kPermutations) {
          int local[3] = {0, 0, 0};
          Tetrahedron t{};
          t[0] = global(local);
          for (int step = 0; step < 3; ++step) {
            ++local[order[step]];
            t[static_cast<std::size_t>(step + 1)] = global(local);
          }
          if (signed_volume(mesh, t) < 0.0) std::swap(t[1], t[2]);
          mesh.tetrahedra.push_back(t);
          mesh.tetrahedron_lines.push_back(0);
        }
      }
    }
  }
  return mesh;
}

Mesh generate_ellipsoid(const EllipsoidSpec& spec, DiagnosticList& diagnostics) {
  SourceRange range;
  range.file = "generated ellipsoid";
  if (spec.resolution < 1) {
    diagnostics.error(range, "an ellipsoid needs a resolution of at least 1");
    return Mesh{};
  }
  if (!(spec.radii[0] > 0.0 && spec.radii[1] > 0.0 && spec.radii[2] > 0.0) || !std::isfinite(spec.radii[0]) ||
      !std::isfinite(spec.radii[1]) || !std::isfinite(spec.radii[2])) {
    diagnostics.error(range, "an ellipsoid needs positive, finite radii");
    return Mesh{};
  }
  BoxSpec cube;
  cube.minimum = {-1.0, -1.0, -1.0};
  cube.size = {2.0, 2.0, 2.0};
  cube.cells_x = cube.cells_y = cube.cells_z = 2 * spec.resolution;
  Mesh mesh = generate_box(cube, diagnostics);
  mesh.source = "generated ellipsoid " + std::to_string(spec.resolution);
  for (Point3& p : mesh.points) {
    const double inf_norm = std::max({std::abs(p[0]), std::abs(p[1]), std::abs(p[2])});
    const double two_norm = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    const double scale = two_norm > 0.0 ? inf_norm / two_norm : 0.0;
    for (std::size_t axis = 0; axis < 3; ++axis) p[axis] = spec.centre[axis] + spec.radii[axis] * p[axis] * scale;
  }
  for (Tetrahedron& t : mesh.tetrahedra) {
    if (signed_volume(mesh, t) < 0.0) std::swap(t[1], t[2]);
  }
  return mesh;
}

}  // namespace fmpc::sim

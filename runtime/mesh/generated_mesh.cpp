#include "runtime/mesh/generated_mesh.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "runtime/integrate/worker_pool.h"

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
  // Points and cells are filled in parallel, each at its own index (vertex (i,j,k) at (k ny + j) nx + i, cell
  // (i,j,k)'s six tetrahedra from 6 ((k (ny-1) + j) (nx-1) + i)): the same mesh as one thread appending in order.
  const std::int64_t cells = std::int64_t{spec.cells_x} * spec.cells_y * spec.cells_z;
  PoolLease lease(nullptr, 0, static_cast<std::size_t>(nx * ny * nz + 6 * cells));
  WorkerPool& pool = lease.pool();
  resize_large(mesh.points, static_cast<std::size_t>(nx * ny * nz));
  pool.run(mesh.points.size(), [&](std::size_t first, std::size_t last) {
    for (std::size_t index = first; index < last; ++index) {
      const auto v = static_cast<std::int64_t>(index);
      const std::int64_t i = v % nx, j = v / nx % ny, k = v / (nx * ny);
      mesh.points[index] = {spec.minimum[0] + spec.size[0] * static_cast<double>(i) / spec.cells_x,
                            spec.minimum[1] + spec.size[1] * static_cast<double>(j) / spec.cells_y,
                            spec.minimum[2] + spec.size[2] * static_cast<double>(k) / spec.cells_z};
    }
  });
  // Kuhn subdivision: one tetrahedron per permutation of the axes, walking from corner (0,0,0) to (1,1,1).
  static const int kPermutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  resize_large(mesh.tetrahedra, static_cast<std::size_t>(6 * cells));
  pool.run(static_cast<std::size_t>(cells), [&](std::size_t first, std::size_t last) {
    for (std::size_t cell = first; cell < last; ++cell) {
      const auto c = static_cast<std::int64_t>(cell);
      const std::int64_t i = c % (nx - 1), j = c / (nx - 1) % (ny - 1), k = c / ((nx - 1) * (ny - 1));
      std::size_t next = 6 * cell;
      for (const auto& order : kPermutations) {
        std::int64_t corner[3] = {i, j, k};
        Tetrahedron t{};
        t[0] = vertex(corner[0], corner[1], corner[2]);
        for (int step = 0; step < 3; ++step) {
          ++corner[order[step]];
          t[static_cast<std::size_t>(step + 1)] = vertex(corner[0], corner[1], corner[2]);
        }
        if (signed_volume(mesh, t) < 0.0) std::swap(t[1], t[2]);
        mesh.tetrahedra[next++] = t;
      }
    }
  });
  // No tetrahedron_lines: a generated element has no source line (line_of reads a missing entry as 0), and the
  // array would cost 4 bytes per tetrahedron.
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
  PoolLease lease(nullptr, 0, mesh.points.size() + mesh.tetrahedra.size());
  WorkerPool& pool = lease.pool();
  pool.run(mesh.points.size(), [&](std::size_t first, std::size_t last) {
    for (std::size_t v = first; v < last; ++v) {
      Point3& p = mesh.points[v];
      const double inf_norm = std::max({std::abs(p[0]), std::abs(p[1]), std::abs(p[2])});
      const double two_norm = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      const double scale = two_norm > 0.0 ? inf_norm / two_norm : 0.0;
      for (std::size_t axis = 0; axis < 3; ++axis) p[axis] = spec.centre[axis] + spec.radii[axis] * p[axis] * scale;
    }
  });
  pool.run(mesh.tetrahedra.size(), [&](std::size_t first, std::size_t last) {
    for (std::size_t e = first; e < last; ++e) {
      Tetrahedron& t = mesh.tetrahedra[e];
      if (signed_volume(mesh, t) < 0.0) std::swap(t[1], t[2]);
    }
  });
  return mesh;
}

}  // namespace fmpc::sim

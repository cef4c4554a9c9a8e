#include "runtime/mesh/generated_mesh.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "runtime/integrate/worker_pool.h"
#include "runtime/io/memory_limit.h"

namespace fmpc::sim {

std::uint64_t tetrahedron_count(const BoxSpec& spec) {
  if (spec.cells_x < 1 || spec.cells_y < 1 || spec.cells_z < 1) return 0;
  // Each factor is below 2^31, so the product of three fits in 93 bits only as a double: compare in double first.
  const double cells = static_cast<double>(spec.cells_x) * spec.cells_y * spec.cells_z;
  if (cells * 6.0 > 1.8e19) return UINT64_MAX;
  return 6 * static_cast<std::uint64_t>(spec.cells_x) * static_cast<std::uint64_t>(spec.cells_y) *
         static_cast<std::uint64_t>(spec.cells_z);
}

std::uint64_t tetrahedron_count(const EllipsoidSpec& spec) {
  if (spec.resolution < 1) return 0;
  BoxSpec cube;
  cube.cells_x = cube.cells_y = cube.cells_z = spec.resolution > (1 << 29) ? (1 << 30) : 2 * spec.resolution;
  return tetrahedron_count(cube);
}

std::optional<std::string> generated_mesh_too_large(std::uint64_t tetrahedra) {
  const double bytes = static_cast<double>(tetrahedra) * static_cast<double>(kEstimatedBytesPerTetrahedron);
  const MemoryLimit memory = memory_limit();
  const bool too_many = tetrahedra > kMaxGeneratedTetrahedra;
  const bool too_big = memory.bytes > 0 && bytes > static_cast<double>(memory.bytes);
  if (!too_many && !too_big) return std::nullopt;
  std::string message = "makes " + std::to_string(tetrahedra) + " tetrahedra (an estimated " + gibibytes_text(bytes) +
                        " for the mesh, springs and state); the limit is ";
  if (too_many) return message + std::to_string(kMaxGeneratedTetrahedra) + " tetrahedra (int32 indices)";
  return message + memory.source + ", " + gibibytes_text(static_cast<double>(memory.bytes));
}

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
  if (const auto too_large = generated_mesh_too_large(tetrahedron_count(spec))) {
    diagnostics.error(range, "the box " + *too_large + ": use fewer cells");
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
  // Kuhn subdivision: one tetrahedron per permutation of the axes, walking from the cell's local corner (0,0,0) to
  // (1,1,1). The cell is mirrored along every axis whose cell index is odd, so that the cut diagonals alternate
  // and the 2 x 2 x 2 block of cells is symmetric under the three reflections: a box cut the same way round in
  // every cell is anisotropic (its loaded face slides sideways about as far as it moves along the load,
  // docs/simulator.md). Mirroring keeps the mesh conforming: both cells sharing a face cut it along the diagonal
  // through their common local corners (0,0) and (1,1) of that face.
  static const int kPermutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  resize_large(mesh.tetrahedra, static_cast<std::size_t>(6 * cells));
  pool.run(static_cast<std::size_t>(cells), [&](std::size_t first, std::size_t last) {
    for (std::size_t cell_index = first; cell_index < last; ++cell_index) {
      const auto c = static_cast<std::int64_t>(cell_index);
      const std::int64_t cell[3] = {c % (nx - 1), c / (nx - 1) % (ny - 1), c / ((nx - 1) * (ny - 1))};
      const auto global = [&](const int local[3]) {
        std::int64_t g[3];
        for (int axis = 0; axis < 3; ++axis)
          g[axis] = cell[axis] + (cell[axis] % 2 == 1 ? 1 - local[axis] : local[axis]);
        return vertex(g[0], g[1], g[2]);
      };
      std::size_t next = 6 * cell_index;
      for (const auto& order : kPermutations) {
        int local[3] = {0, 0, 0};
        Tetrahedron t{};
        t[0] = global(local);
        for (int step = 0; step < 3; ++step) {
          ++local[order[step]];
          t[static_cast<std::size_t>(step + 1)] = global(local);
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
  if (const auto too_large = generated_mesh_too_large(tetrahedron_count(spec))) {
    diagnostics.error(range, "the ellipsoid of resolution " + std::to_string(spec.resolution) + " " + *too_large +
                                 ": use a smaller resolution");
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

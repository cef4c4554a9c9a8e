#include "runtime/mesh/generated_mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

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
  if (tetrahedra <= kMaxGeneratedTetrahedra) return std::nullopt;
  const double gib = static_cast<double>(tetrahedra) * static_cast<double>(kEstimatedBytesPerTetrahedron) /
                     static_cast<double>(std::uint64_t{1} << 30);
  char estimate[64];
  std::snprintf(estimate, sizeof estimate, "%.3g GiB", gib);
  return "makes " + std::to_string(tetrahedra) + " tetrahedra (an estimated " + estimate +
         " for the mesh, springs and state); the limit is " + std::to_string(kMaxGeneratedTetrahedra) +
         " tetrahedra (about " + std::to_string(kMaxGeneratedTetrahedra * kEstimatedBytesPerTetrahedron >> 30) +
         " GiB)";
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
  // Kuhn subdivision: one tetrahedron per permutation of the axes, walking from corner (0,0,0) to (1,1,1).
  static const int kPermutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (std::int64_t k = 0; k + 1 < nz; ++k) {
    for (std::int64_t j = 0; j + 1 < ny; ++j) {
      for (std::int64_t i = 0; i + 1 < nx; ++i) {
        for (const auto& order : kPermutations) {
          std::int64_t corner[3] = {i, j, k};
          Tetrahedron t{};
          t[0] = vertex(corner[0], corner[1], corner[2]);
          for (int step = 0; step < 3; ++step) {
            ++corner[order[step]];
            t[static_cast<std::size_t>(step + 1)] = vertex(corner[0], corner[1], corner[2]);
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
  if (const auto too_large = generated_mesh_too_large(tetrahedron_count(spec))) {
    diagnostics.error(range, "the ellipsoid of resolution " + std::to_string(spec.resolution) + " " + *too_large +
                                 ": use a resolution of at most 70");
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

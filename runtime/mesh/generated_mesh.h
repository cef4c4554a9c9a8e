#pragma once
// Tetrahedral meshes built in code, at any resolution, for tests, benchmarks and scenes without a mesh file.
#include <cstdint>
#include <optional>
#include <string>

#include "diagnostics/diagnostic.h"
#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

struct BoxSpec {
  Point3 minimum{0.0, 0.0, 0.0};
  Point3 size{1.0, 1.0, 1.0};
  int cells_x = 1, cells_y = 1, cells_z = 1;  // each cell is split into 6 tetrahedra
};

struct EllipsoidSpec {
  Point3 centre{0.0, 0.0, 0.0};
  Point3 radii{1.0, 1.0, 1.0};
  int resolution = 4;  // cells along each half-axis of the underlying cube
};

// The largest generated mesh (docs/limits.md). A spec is sized before anything is allocated: its tetrahedra are
// counted exactly and the memory the simulator needs for them is estimated (mesh, springs, CSR adjacency and
// state: kEstimatedBytesPerTetrahedron, measured on a 60^3 box, see docs/limits.md). Two limits: 2^28 tetrahedra
// (their corners, springs and CSR entries stay within the int32 indices of every backend), and the estimate within
// the memory this process may use (runtime/io/memory_limit.h: physical memory, ulimit, cgroup; a 240^3 box, 83
// million tetrahedra and 100 million springs, needs about 20 GiB).
inline constexpr std::uint64_t kMaxGeneratedTetrahedra = std::uint64_t{1} << 28;  // 268,435,456
inline constexpr std::uint64_t kEstimatedBytesPerTetrahedron = 256;

std::uint64_t tetrahedron_count(const BoxSpec& spec);        // 6 per cell
std::uint64_t tetrahedron_count(const EllipsoidSpec& spec);  // a box of 2 * resolution cells per axis
// nullopt when the mesh is within the limit; else what it makes, the estimate and the limit (the caller adds
// what to change: cells, or resolution).
std::optional<std::string> generated_mesh_too_large(std::uint64_t tetrahedra);

// A box of (cells_x+1)(cells_y+1)(cells_z+1) vertices; each cube is cut into 6 tetrahedra around a main diagonal
// (Kuhn/Freudenthal subdivision), mirrored along every axis whose cell index is odd, so that the cut has no preferred
// direction (a 2 x 2 x 2 block of cells is symmetric under reflection in each axis) and neighbouring cubes share
// their face diagonals: a conforming mesh.
// Returns an empty mesh and an error for non-positive cell counts or sizes, or more than 2^31 vertices.
Mesh generate_box(const BoxSpec& spec, DiagnosticList& diagnostics);

// A tetrahedral ellipsoid: the box mesh of [-1,1]^3 mapped onto the unit ball by the radial map
// p -> p * |p|_inf / |p|_2 (cube shells onto spheres), then scaled by the radii. All tetrahedra keep positive volume.
Mesh generate_ellipsoid(const EllipsoidSpec& spec, DiagnosticList& diagnostics);

}  // namespace fmpc::sim

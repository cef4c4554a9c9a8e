#pragma once
// Tetrahedral meshes from closed triangle surfaces: the surface is checked (surface_check.h), its size is held
// against the limits below, the number of tetrahedra the size field asks for is estimated and held against its limit
// before the mesher allocates anything, and TetGen (Si 2015, "TetGen, a Delaunay-based quality tetrahedral mesh
// generator", ACM TOMS 41(2)) meshes the volume by constrained Delaunay refinement: every tetrahedron's longest edge
// at most the size field at its centroid, radius-edge ratio at most `max_radius_edge_ratio`, and TetGen's mesh
// optimisation raising the smallest dihedral angles toward `min_dihedral_degrees`. Nothing is printed (TetGen runs
// quiet); the same surface and options give the same mesh bit for bit (TetGen is single-threaded and seeds its own
// random choices per call; calls are serialised across threads, tetgen_mesher.cpp).
#include <cstddef>
#include <optional>
#include <string>

#include "diagnostics/diagnostic.h"
#include "runtime/mesh/mesh.h"
#include "runtime/meshing/mesh_quality.h"
#include "runtime/meshing/size_field.h"
#include "runtime/meshing/surface_check.h"
#include "runtime/meshing/surface_split.h"
#include "runtime/meshing/surface_untangle.h"

namespace fmpc::sim {

// Limits (docs/limits.md), checked before meshing.
inline constexpr std::size_t kMaxSurfaceVertices = 1'000'000;
inline constexpr std::size_t kMaxSurfaceTriangles = 2'000'000;
inline constexpr std::size_t kMaxMeshedTetrahedra = 5'000'000;  // predicted (estimate_tetrahedra) and produced
// TetGen inserts at most this many vertices (its -S cap), whatever the estimate said: a mesh that would need more
// stops refining there and is refused.
inline constexpr std::size_t kMaxMeshedVertices = 1'000'000;

// Quality bounds. 1.5 is tighter than TetGen's default 2.0 and well inside what Delaunay refinement guarantees to
// terminate with (Shewchuk 1998: any bound above 2 in theory; TetGen meets 1.1 and up in practice, more slowly).
inline constexpr double kDefaultRadiusEdgeRatio = 1.5;
inline constexpr double kDefaultMinDihedralDegrees = 10.0;
inline constexpr double kSizeFieldSlack = 1.5;

struct VolumeMeshOptions {
  SizeField size;
  double max_radius_edge_ratio = kDefaultRadiusEdgeRatio;    // enforced by refinement (except at small input angles)
  double min_dihedral_degrees = kDefaultMinDihedralDegrees;  // sought by TetGen's optimisation; reported
  std::size_t max_tetrahedra = kMaxMeshedTetrahedra;
  // A surface that intersects itself is refused (located) unless this is set: then surface_untangle.h smooths it.
  bool smooth_intersections = false;
  // false: TetGen splits surface triangles where the size field or the quality bound asks, protecting every surface
  // edge (SOFA's liver-smooth.obj then needs 18,700 vertices at least); true: the surface's triangles are the mesh's
  // boundary faces, unchanged (TetGen's -Y), and only the interior is refined, as far as the surface lets it (a
  // point that would crowd a surface triangle is not inserted): for surfaces already as fine as the size field near
  // them (the liver: 5,200 vertices at size_far 0.4). Elements left larger than the field are counted and warned
  // about (docs/meshing.md).
  bool keep_surface = false;
  // With keep_surface: the surface's triangles coarser than the size field are split first (surface_split.h), so
  // the kept boundary is as fine as the field where the tools act, and stays the input's polyhedron elsewhere.
  bool split_surface = false;
};

struct VolumeMesh {
  Mesh mesh;  // the surface's vertices first, in their order, then the inserted ones; every tetrahedron positive
  SurfaceCheck surface;
  std::optional<SurfaceUntangling> untangling;  // when the surface intersected itself and was smoothed
  std::optional<SurfaceSplit> split;            // split_surface: what the split added (its vertices follow the input's)
  std::size_t flat_removed = 0;                 // remove_flat_surface_tetrahedra's count (a split surface's)
  std::size_t surface_vertices = 0;
  std::size_t surface_triangles = 0;
  VolumeEstimate estimate;
  // With the elements past the bounds: TetGen cannot remove every one near sharp input angles (radius-edge) and
  // does not guarantee the dihedral bound; they are reported, not refused.
  TetrahedronQuality quality;
  // Elements whose longest edge exceeds kSizeFieldSlack x the size field at their centroid (TetGen meets the field
  // itself where it may split the surface; a kept surface's own triangles can be coarser).
  std::size_t above_size = 0;
};

// A meshing as a scene build records it for the summary: the result (its mesh moved out), the options as used
// (defaults filled in, the probe's sources added) and the wall time.
struct MeshingRun {
  VolumeMesh result;
  VolumeMeshOptions options;
  double seconds = 0.0;
};

// Whether this build has the mesher (FMPC_MESHER, on by default: CMake's libtet1.5-dev).
bool volume_mesher_available();

// The checks on options a caller makes before anything is read: one sentence per problem, naming the option as
// `names` spells it ("size_near" in a scene, "--size-near" on the command line); empty when they are fine.
struct SizeOptionNames {
  std::string size_near = "size_near", size_far = "size_far", near_distance = "near_distance", grading = "grading";
};
std::vector<std::string> size_field_problems(const SizeField& field, const SizeOptionNames& names = {});

// Meshes the volume inside `surface` (triangles, closed; an inward surface is reversed with a `surface-orientation`
// warning). Errors (nullopt): the surface's defects, located (surface_check.h); a limit exceeded, with the numbers;
// what TetGen refuses (a self-intersecting surface) or the vertex cap reached.
std::optional<VolumeMesh> mesh_volume(Mesh surface, const VolumeMeshOptions& options, DiagnosticList& diagnostics);

// One paragraph for a command or a summary: sizes, counts and the quality distributions.
std::string quality_text(const VolumeMesh& mesh, const VolumeMeshOptions& options);

}  // namespace fmpc::sim

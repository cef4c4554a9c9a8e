#pragma once
// The mesh size wanted at each point of a volume: fine (`size_near`) within `near_distance` of where something acts on
// the tissue (a probe's picked vertices and its path; tools' paths), growing linearly with distance beyond that at
// `grading` (mesh units of size per mesh unit of distance), up to `size_far`. Sizes are the longest edge a
// tetrahedron may have there. All lengths in mesh units.
#include <cstddef>
#include <vector>

#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

// 0.25: a tetrahedron's neighbour one size further out may be about 25% larger, a common bound for graded Delaunay
// meshes (element sizes that jump by more than a factor of about 1.5 between neighbours spoil the quality bound).
inline constexpr double kDefaultSizeGrading = 0.25;
// Where things act: a point is a segment with a == b. More sources than this are refused (each evaluation of the
// field visits every source).
inline constexpr std::size_t kMaxSizeSources = 4096;

struct SizeSegment {
  Point3 a{0.0, 0.0, 0.0};
  Point3 b{0.0, 0.0, 0.0};
};

struct SizeField {
  double size_far = 0.0;
  double size_near = 0.0;      // <= size_far; used only where there are sources
  double near_distance = 0.0;  // >= 0
  double grading = kDefaultSizeGrading;
  std::vector<SizeSegment> sources;
};

// The mean length of a triangle surface's edges (each counted once per triangle): the default far size, so that the
// volume is as fine as the surface it comes from.
double mean_edge_length(const Mesh& surface);

double distance_to_segment(const Point3& p, const SizeSegment& segment);
// h(x) = min(size_far, size_near + grading * max(0, d(x) - near_distance)), d the distance to the nearest source;
// size_far everywhere without sources.
double size_at(const SizeField& field, const Point3& p);

// The predicted number of tetrahedra for a closed, outward surface and a size field (an estimate: sampled on a
// regular grid over the surface's bounding box): kTetrahedraPerSizeCube x the integral over the enclosed volume of
// 1 / h(x)^3. The factor is measured on fmpc's meshes with TetGen at the default quality bounds (docs/meshing.md):
// longest edges at most h give tetrahedra much smaller than the regular tetrahedron of edge h (h^3 / 8.49).
inline constexpr double kTetrahedraPerSizeCube = 40.0;
struct VolumeEstimate {
  double volume = 0.0;      // sampled enclosed volume (mesh units^3)
  double tetrahedra = 0.0;  // predicted count
};
VolumeEstimate estimate_tetrahedra(const Mesh& surface, const SizeField& field);

}  // namespace fmpc::sim

#pragma once
// A kept surface (VolumeMeshOptions::keep_surface) is the mesh's boundary as it comes: where its triangles are
// coarser than the size field -- under a tool, where the contact is resolved by the surface's vertices alone -- no
// interior refinement makes the contact finer. On request the surface is split first: every triangle whose longest
// edge exceeds the field at its centroid is bisected by the longest-edge propagation path (M.-C. Rivara,
// "New longest-edge algorithms for the refinement and/or improvement of unstructured triangulations", IJNME 40,
// 1997): always across a longest edge, its neighbour's first where that edge is not the neighbour's longest, so the
// surface stays conforming and no angle falls below half the input's smallest (I. G. Rosenberg and F. Stenger, Math.
// Comp. 29, 1975). Midpoints of flat triangles: the surface stays the same polyhedron, so meshes of different sizes
// bound the same domain. The same surface and field give the same split (triangles in order, ties by vertex index).
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/mesh/mesh.h"
#include "runtime/meshing/size_field.h"

namespace fmpc::sim {

struct SurfaceSplit {
  std::size_t triangles_before = 0;
  std::size_t triangles_after = 0;
  // Per vertex added (the surface's vertices first, then these, in order): the two ends of the edge it halves, both
  // earlier vertices. A selection of surface vertices by index extends to a midpoint whose ends it holds
  // (split_selection).
  std::vector<std::array<std::int32_t, 2>> parents;
};

// Splits `surface` (closed triangles) until every triangle's longest edge is at most size_at(field, its centroid).
// nullopt, with an error naming the limit, when the split would pass `max_triangles` (the mesher's surface limit):
// it stops there.
std::optional<SurfaceSplit> split_surface_to_size(Mesh& surface, const SizeField& field, std::size_t max_triangles,
                                                  DiagnosticList& diagnostics);

// Removes every tetrahedron of zero volume (in double) with two faces on `surface`: where split triangles lie in one
// plane up to the midpoints' rounding, TetGen (exact in its predicates) may fill the rounding's fold with an element
// whose four corners are coplanar in double; its other two faces, in the same plane, then bound the mesh instead
// (the same surface, triangulated across the other diagonal). Returns how many it removed.
std::size_t remove_flat_surface_tetrahedra(Mesh& mesh, const std::vector<Triangle>& surface);

// `selected` (one flag per vertex of the split surface, the original vertices' set by the caller) extended to every
// added vertex whose edge's ends are both selected: a clamped edge stays clamped along its length.
void split_selection(const SurfaceSplit& split, std::size_t original_vertices, std::vector<unsigned char>& selected);

}  // namespace fmpc::sim

#pragma once
// Uniform refinement of a tetrahedral mesh, for convergence studies (`fmpc trade SCENE.yaml`, docs/trade.md): every
// quantity measured on a mesh and on its refinements can be compared vertex by vertex, because a refinement keeps
// the mesh's vertices first, at their indices.
#include <cstdint>

#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

// The 1:8 "red" subdivision of every tetrahedron (Bey 1995, "Tetrahedral grid refinement", Computing 55): a new
// vertex at the midpoint of every edge (of the tetrahedra and the triangles), four corner tetrahedra (each the
// parent scaled by 1/2 about one corner) and the inner octahedron cut into four along its shortest diagonal (the
// first in the order 01-23, 02-13, 03-12 on ties). Each triangle becomes four. Vertex v of `mesh` is vertex v of
// the result; the midpoints follow, one per distinct edge in the order of the edges' sorted (smaller, larger)
// vertex pairs, so the result has V + E vertices. A face's four sub-triangles depend only on its edges' midpoints,
// so a conforming mesh stays conforming whichever diagonals its neighbours chose; every child keeps the parent's
// orientation (positive volume for a positive parent) and the children's volumes sum to the parent's (up to
// rounding). Element source lines are inherited from the parent.
Mesh subdivide_tetrahedra(const Mesh& mesh);

// The number of distinct edges of the tetrahedra and triangles: subdivide_tetrahedra adds one vertex per edge.
std::uint64_t distinct_edge_count(const Mesh& mesh);

}  // namespace fmpc::sim

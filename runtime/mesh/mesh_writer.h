#pragma once
// Mesh files fmpc writes for reuse: Gmsh's ASCII format 2.2 (read back by read_gmsh, and by Gmsh and meshio).
#include <string>

#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

// $MeshFormat 2.2, $Nodes (1-based numbers, coordinates as the shortest text that reads back exactly), $Elements
// (the tetrahedra as type 4 with physical and elementary tags 1, then the triangles as type 2). Reading the text back
// with read_gmsh gives the same mesh, bit for bit.
std::string gmsh_document(const Mesh& mesh);

}  // namespace fmpc::sim

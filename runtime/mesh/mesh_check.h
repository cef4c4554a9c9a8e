#pragma once
// Mesh defects as data: check_mesh lists them, repair_mesh fixes what is safe to fix and says what it did. Nothing
// is printed; a caller turns findings into diagnostics or a report (finding_message gives the sentence).
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

enum class MeshFindingKind {
  IndexOutOfRange,        // an element refers to a vertex that does not exist (repair: element removed)
  DegenerateTetrahedron,  // repeated vertex or |volume| <= shape_tolerance * longest_edge^3 (repair: removed)
  InvertedTetrahedron,    // negative volume (repair: two vertices swapped)
  DuplicateTetrahedron,   // same vertex set as an earlier one (repair: removed)
  DegenerateTriangle,     // repeated vertex or area <= shape_tolerance * longest_edge^2 (repair: removed)
  DuplicateTriangle,      // same vertex set as an earlier one (repair: removed)
  DuplicateVertex,        // within duplicate_distance of an earlier vertex (repair: merged into it)
  UnreferencedVertex,     // used by no element (repair: removed, indices compacted)
};

const char* to_string(MeshFindingKind kind);

struct MeshFinding {
  MeshFindingKind kind = MeshFindingKind::IndexOutOfRange;
  std::size_t index = 0;  // the element (tetrahedron or triangle) or vertex, 0-based, in the mesh as given
  std::size_t other = std::numeric_limits<std::size_t>::max();  // the earlier duplicate, when there is one
  double value = 0.0;                                           // signed volume, area or distance, as applies
  int line = 0;  // source line of the element, 0 when unknown or for vertices
  bool repaired = false;
};

struct MeshCheckOptions {
  double shape_tolerance = 1e-9;
  // Two vertices closer than this (absolute, file units) are duplicates; a negative value means
  // 1e-9 x the bounding-box diagonal.
  double duplicate_distance = -1.0;
};

// Findings in a fixed order: indices out of range, tetrahedra, triangles, duplicate vertices, unreferenced vertices.
std::vector<MeshFinding> check_mesh(const Mesh& mesh, const MeshCheckOptions& options = {});

struct MeshRepairResult {
  std::vector<MeshFinding> findings;  // every finding, repaired ones flagged
  // For each vertex of the mesh as given: its index after repair, or -1 when it was removed. Scenes use it to
  // move fixed-node and probe indices along.
  std::vector<std::int32_t> new_vertex_index;
};

// Merges duplicate vertices, drops degenerate, duplicate and out-of-range elements, flips inverted tetrahedra and
// removes unreferenced vertices (only when the mesh has elements). Every finding of check_mesh is repaired.
MeshRepairResult repair_mesh(Mesh& mesh, const MeshCheckOptions& options = {});

// One sentence for a finding, e.g. "tetrahedron 12 (line 40) is inverted (volume -0.5); repaired: vertices swapped".
std::string finding_message(const MeshFinding& finding);

}  // namespace fmpc::sim

#pragma once
// Mesh defects as data: check_mesh lists them, repair_mesh fixes what is safe to fix and says what it did. Nothing
// is printed; a caller turns findings into diagnostics or a report (finding_message gives the sentence).
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

class WorkerPool;  // runtime/integrate/worker_pool.h

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
  // Worker threads when no pool is given (0: every hardware thread; small meshes use one). The findings and the
  // repair do not depend on it.
  unsigned threads = 0;
};

// Findings in a fixed order: indices out of range, tetrahedra, triangles, duplicate vertices, unreferenced vertices.
// Within each, by index; an element's duplicate finding follows its inverted one. O(N log N) in the vertices and
// elements (sorting and grouping), multi-threaded.
std::vector<MeshFinding> check_mesh(const Mesh& mesh, const MeshCheckOptions& options = {},
                                    WorkerPool* pool = nullptr);

// The DegenerateTetrahedron and DegenerateTriangle findings of check_mesh, in its order, without the rest of its
// work (duplicates, vertices): for callers that need every element's volume or area.
std::vector<MeshFinding> degenerate_elements(const Mesh& mesh, const MeshCheckOptions& options = {},
                                             WorkerPool* pool = nullptr);

struct MeshRepairResult {
  std::vector<MeshFinding> findings;  // every finding, repaired ones flagged
  // For each vertex of the mesh as given: its index after repair, or -1 when it was removed. Scenes use it to
  // move fixed-node and probe indices along.
  std::vector<std::int32_t> new_vertex_index;
};

// Merges duplicate vertices, drops degenerate, duplicate and out-of-range elements, flips inverted tetrahedra and
// removes unreferenced vertices (only when the mesh has elements). Every finding of check_mesh is repaired.
MeshRepairResult repair_mesh(Mesh& mesh, const MeshCheckOptions& options = {}, WorkerPool* pool = nullptr);

// One sentence for a finding, e.g. "tetrahedron 12 (line 40) is inverted (volume -0.5); repaired: vertices swapped".
std::string finding_message(const MeshFinding& finding);

}  // namespace fmpc::sim

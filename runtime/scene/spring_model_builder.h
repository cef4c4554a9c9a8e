#pragma once
// From a mesh and material choices to a ready SimulationSetup: the one path a scene loader (or a test) takes.
// The caller then sets loads, fixed vertices, the integrator and the step count on the returned setup.
#include <optional>

#include "diagnostics/diagnostic.h"
#include "runtime/integrate/simulation.h"
#include "runtime/mesh/mesh.h"
#include "runtime/springs/spring_network.h"

namespace fmpc::sim {

class WorkerPool;  // runtime/integrate/worker_pool.h

struct SpringModelSpec {
  // Tetrahedra give tetrahedron-edge springs; a mesh without tetrahedra uses its triangles (thesis springs).
  TriangleSpringOptions triangle_springs;
  StiffnessSpec stiffness;
  MassSpec mass;
  DampingSpec damping;
  double length_unit = 1.0;  // metres per mesh unit (e.g. 0.001 for liver.vtk's millimetres)
  // Worker threads when no pool is given (0: every hardware thread; small meshes use one). The setup does not depend
  // on it.
  unsigned threads = 0;
};

// Scales the points to metres, builds the springs, rest lengths, stiffness, lumped masses and damping. Returns
// nullopt after appending errors (mesh defects must be repaired first: see repair_mesh). The mesh is not copied, and
// the build's large temporaries make way for what follows them: the grouping of the elements by vertex (4 bytes per
// tetrahedron corner) is released before the CSR is built, the stiffness is written over the springs' element
// measures (left empty: they are only the mappings' input), and the heap's freed pages go back to the system before
// the last arrays are allocated. The peak is the returned setup beside the mesh (docs/performance.md, "Host setup").
std::optional<SimulationSetup> build_spring_model(const Mesh& mesh, const SpringModelSpec& spec,
                                                  DiagnosticList& diagnostics, WorkerPool* pool = nullptr);

}  // namespace fmpc::sim

#pragma once
// From a mesh and material choices to a ready SimulationSetup: the one path a scene loader (or a test) takes.
// The caller then sets loads, fixed vertices, the integrator and the step count on the returned setup.
#include <optional>

#include "diagnostics/diagnostic.h"
#include "runtime/integrate/simulation.h"
#include "runtime/mesh/mesh.h"
#include "runtime/springs/spring_network.h"

namespace fmpc::sim {

struct SpringModelSpec {
  // Tetrahedra give tetrahedron-edge springs; a mesh without tetrahedra uses its triangles (thesis springs).
  TriangleSpringOptions triangle_springs;
  StiffnessSpec stiffness;
  MassSpec mass;
  DampingSpec damping;
  double length_unit = 1.0;  // metres per mesh unit (e.g. 0.001 for liver.vtk's millimetres)
};

// Scales the points to metres, builds the springs, rest lengths, stiffness, lumped masses and damping. Returns
// nullopt after appending errors (mesh defects must be repaired first: see repair_mesh).
std::optional<SimulationSetup> build_spring_model(const Mesh& mesh, const SpringModelSpec& spec,
                                                  DiagnosticList& diagnostics);

}  // namespace fmpc::sim

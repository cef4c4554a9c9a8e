#pragma once
// The host setup before it was made O(N log N) and multi-threaded: the reference of the equivalence tests
// (tests/unit/setup_equivalence_test.cpp). Same signatures as the library's, without the thread pools.
#include <optional>
#include <vector>

#include "runtime/mesh/mesh_check.h"
#include "runtime/scene/spring_model_builder.h"
#include "runtime/springs/spring_network.h"

namespace fmpc::sim::reference {

std::vector<MeshFinding> check_mesh(const Mesh& mesh, const MeshCheckOptions& options = {});
MeshRepairResult repair_mesh(Mesh& mesh, const MeshCheckOptions& options = {});
std::vector<Triangle> boundary_triangles(const Mesh& mesh);
SpringNetwork springs_from_tetrahedra(const Mesh& mesh, DiagnosticList& diagnostics);
SpringNetwork springs_from_triangles(const Mesh& mesh, const TriangleSpringOptions& options,
                                     DiagnosticList& diagnostics);
bool compute_rest_lengths(SpringNetwork& network, const std::vector<Point3>& points, DiagnosticList& diagnostics,
                          double min_relative_length = 1e-9);
void build_adjacency(SpringNetwork& network);
bool assign_stiffness(SpringNetwork& network, const StiffnessSpec& spec, DiagnosticList& diagnostics);
std::vector<double> lumped_masses(const Mesh& mesh, const MassSpec& spec, DiagnosticList& diagnostics);
bool assign_damping(SpringNetwork& network, const std::vector<double>& mass, const DampingSpec& spec,
                    DiagnosticList& diagnostics);
std::optional<SimulationSetup> build_spring_model(const Mesh& mesh, const SpringModelSpec& spec,
                                                  DiagnosticList& diagnostics);

}  // namespace fmpc::sim::reference

#pragma once
// From a tetrahedral mesh and material choices to a SimulationSetup for the co-rotational FEM (the path a scene
// loader takes, as build_spring_model is for springs), and the volume term added to a spring setup.
#include <optional>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/integrate/simulation.h"
#include "runtime/mesh/mesh.h"
#include "runtime/springs/spring_network.h"

namespace fmpc::sim {

struct FemModelSpec {
  // Pa: one value for every element, or one per tetrahedron of the mesh.
  std::vector<double> youngs_modulus;
  std::vector<double> poisson_ratio;  // one value, or one per tetrahedron; each in [0, 0.499]
  MassSpec mass;
  double damping_ratio = 0.0;       // zeta of each element's own fastest mode (assign_element_damping)
  double rayleigh_stiffness = 0.0;  // beta (s), added to every element's
  double length_unit = 1.0;         // metres per mesh unit
};

// Scales the points to metres, checks every element (positive volume: repair the mesh first), and fills the
// masses (lumped: rho V / 4 per corner), the elements (CorotationalLinear) and their damping. The setup has no
// springs (an empty network with an all-zero adjacency). Returns nullopt after appending errors.
std::optional<SimulationSetup> build_fem_model(const Mesh& mesh, const FemModelSpec& spec, DiagnosticList& diagnostics);

// Adds the volume term (VolumePreservation) with modulus kappa (Pa) to a spring setup built from the same
// tetrahedra (setup.tetrahedra), damped like the springs: beta_e = 2 zeta / omega_e + rayleigh_stiffness.
bool add_volume_term(SimulationSetup& setup, double bulk_modulus, double damping_ratio, double rayleigh_stiffness,
                     DiagnosticList& diagnostics);

// The centroid of every tetrahedron of `mesh`, in mesh units (places elements in a scene's regions).
std::vector<Point3> tetrahedron_centroids(const Mesh& mesh);

}  // namespace fmpc::sim

#pragma once
// From a tetrahedral mesh and material choices to a SimulationSetup for a finite-element model (the path a scene
// loader takes, as build_spring_model is for springs), and an element term added to a setup (the term beside a
// spring network).
#include <optional>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/integrate/simulation.h"
#include "runtime/mesh/mesh.h"
#include "runtime/springs/spring_network.h"

namespace fmpc::sim {

struct FemModelSpec {
  int law = default_fem_law().law;            // the element law (its index in element_law_rows())
  int element = default_element_kind().kind;  // the element kind (its index in element_kind_rows())
  // Pa: one value for every element, or one per tetrahedron of the mesh.
  std::vector<double> youngs_modulus;
  std::vector<double> poisson_ratio;  // one value, or one per tetrahedron; the law's builder checks the range
  MassSpec mass;
  double damping_ratio = 0.0;       // zeta of each element's own fastest mode (assign_element_damping)
  double rayleigh_stiffness = 0.0;  // beta (s), added to every element's
  double length_unit = 1.0;         // metres per mesh unit
  SourceRange poisson_where;        // the Poisson ratio's place in the scene (the element kind's limit and warning)
  std::string poisson_field = "material.poisson_ratio";  // and its name in those messages
  std::vector<PronyTerm> prony;     // viscoelasticity on the law; empty: elastic
};

// Scales the points to metres, checks every element (positive volume: repair the mesh first) and the material (the
// law's builder), and fills the masses (lumped: rho V / 4 per corner on linear tetrahedra; a kind with edge nodes
// adds them as vertices after the mesh's, setup.elements.geometry.added_vertex_ends, and lumps by its
// kMassFraction), the element term and its damping. The setup
// has no springs (an empty network with an all-zero adjacency). Returns nullopt after appending errors.
std::optional<SimulationSetup> build_fem_model(const Mesh& mesh, const FemModelSpec& spec, DiagnosticList& diagnostics);

// Appends `term` (its law and parameters from a registry builder) to the setup's element terms over its tetrahedra
// (setup.tetrahedra; their geometry computed on the first term), damped like the rest of the model: beta_e =
// 2 zeta / omega_e + rayleigh_stiffness (assign_element_damping). False after appending an error.
bool add_element_term(SimulationSetup& setup, ElementTerm term, double damping_ratio, double rayleigh_stiffness,
                      DiagnosticList& diagnostics);

// Carries what a scene chose for the mesh's vertices over to the vertices the element kind added (their edge nodes,
// setup.elements.geometry.added_vertex_ends, numbered from `mesh_vertices` on): an added vertex is fixed, held on an
// axis or moved by a displacement probe where both of its edge's ends are (a clamped face stays clamped between its
// corners), starts at its ends' mean position and velocity, and carries no external force. Arrays sized for the mesh's
// vertices are extended; a probe's vertex list and the fixed list gain the added vertices. Nothing changes for a kind
// that adds none.
void extend_to_added_vertices(SimulationSetup& setup, std::size_t mesh_vertices);

// The centroid of every tetrahedron of `mesh`, in mesh units (places elements in a scene's regions).
std::vector<Point3> tetrahedron_centroids(const Mesh& mesh);

}  // namespace fmpc::sim

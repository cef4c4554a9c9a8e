#pragma once
// A spring network as structure-of-arrays plus a CSR adjacency per vertex. The adjacency lets every backend
// gather the forces on a vertex in one fixed order (no float atomics), so CPU threads and CUDA give the same sums.
#include <cstdint>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/integrate/worker_pool.h"
#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

// Every builder below takes an optional WorkerPool (null: a pool of its own, every hardware thread for large inputs,
// see resolve_thread_count); its results, down to the order of springs and CSR entries and the bits of every sum,
// do not depend on the thread count.

enum class SpringKind : std::uint8_t {
  TetrahedronEdge,  // an edge of one or more tetrahedra
  Structural,       // an edge of one or more triangles (thesis Fig. 3.3)
  Flexion,          // joins the two vertices opposite a shared triangle edge (thesis Fig. 3.4, "LINK [2][5]")
  // Joins the two ends of the straightest pair of structural edges through a vertex, skipping that vertex: Provot
  // (1995)'s flexion spring (grid node [i][j] to [i+2][j]) carried over to triangle meshes (springs_from_triangles).
  Bending,
};

struct SpringNetwork {
  std::size_t vertex_count = 0;
  std::vector<std::int32_t> first;   // endpoint with the smaller index
  std::vector<std::int32_t> second;  // endpoint with the larger index
  std::vector<SpringKind> kind;
  // Sum of the volumes of the tetrahedra that contain the edge (TetrahedronEdge) or of the areas of the triangles
  // that contain it (Structural); 0 for flexion and bending springs. Used by the Young's modulus mappings.
  std::vector<double> element_measure;
  std::vector<double> rest_length;  // m (mesh units)
  std::vector<double> stiffness;    // N/m
  std::vector<double> damping;      // N s/m, along the spring (dashpot); empty: no dashpots

  // CSR: the springs at vertex v are adjacency_spring[adjacency_offset[v] .. adjacency_offset[v+1]), in increasing
  // spring order. The other endpoint of each is not kept (adjacency_neighbour gives it; the simulators build their
  // own per-entry copy): 8 bytes per spring, what kept a 97M-spring setup above 64 bytes per spring at its peak.
  std::vector<std::int32_t> adjacency_offset;
  std::vector<std::int32_t> adjacency_spring;

  std::size_t size() const { return first.size(); }
};

// The other endpoint of CSR entry e of vertex v (a spring at v: validate_setup checks that every entry's is).
inline std::int32_t adjacency_neighbour(const SpringNetwork& network, std::size_t v, std::size_t e) {
  const auto s = static_cast<std::size_t>(network.adjacency_spring[e]);
  return static_cast<std::size_t>(network.first[s]) == v ? network.second[s] : network.first[s];
}
// Every entry's other endpoint, in CSR order: what the simulators' gathers read. Null pool: one of its own.
std::vector<std::int32_t> adjacency_neighbours(const SpringNetwork& network, WorkerPool* pool = nullptr);
// The same written to out[0 .. 2 x springs), each plus `base` (a GPU batch numbers each scene's vertices from its
// first); the adjacency must span its entries (validate_setup).
void write_adjacency_neighbours(const SpringNetwork& network, std::int32_t base, std::int32_t* out, WorkerPool& pool);

// The elements at every vertex (the tetrahedra, or without them the triangles), each vertex's in increasing order:
// what springs_from_* and lumped_masses group the mesh by. Built once and passed to both, it saves a pass over the
// elements and their largest temporary (4 bytes per element corner). Indices out of range are left out.
using VertexElements = KeyGroups;
VertexElements elements_at_vertices(const Mesh& mesh, WorkerPool* pool = nullptr);

// One spring per distinct tetrahedron edge, sorted by (first, second); element_measure = incident volumes, summed
// in tetrahedron order. Tetrahedra with out-of-range indices, or more than 2^30 - 1 springs (the int32 adjacency),
// are reported (error) and the network is empty. O(N log N): the tetrahedra are grouped by vertex and each vertex
// collects the edges it starts.
SpringNetwork springs_from_tetrahedra(const Mesh& mesh, DiagnosticList& diagnostics, WorkerPool* pool = nullptr);
// The same with the tetrahedra placed at `points` (one per mesh vertex, e.g. the mesh's points scaled to metres)
// instead of mesh.points, without copying the mesh; `at`: elements_at_vertices(mesh) handed over (std::move), or
// empty to build it here. It is released before the CSR is built, so the two are never held together.
SpringNetwork springs_from_tetrahedra(const Mesh& mesh, const std::vector<Point3>& points, DiagnosticList& diagnostics,
                                     WorkerPool* pool = nullptr, VertexElements at = {});

struct TriangleSpringOptions {
  bool structural = true;
  bool flexion = true;
  bool bending = false;
  // A bending spring i-k through vertex j needs the angle i-j-k to be at least this (degrees): 180 on a straight
  // grid line; 150 keeps the straightest continuation on a mildly irregular mesh and refuses corners.
  double bending_min_angle_degrees = 150.0;
};
// The thesis's springs on a triangle mesh (Tan Sing Yee 2014, section 3.2.1): structural (every triangle edge once,
// Fig. 3.3) and flexion (for every pair of triangles sharing an edge, the two vertices opposite it, unless a spring
// already joins them, Fig. 3.4). Optional bending springs: for every vertex j and every structural neighbour i, the
// neighbour k of j that makes the angle i-j-k largest, when that angle is at least bending_min_angle_degrees and no
// spring joins i and k yet. Springs are ordered structural, flexion, bending, each sorted by (first, second).
SpringNetwork springs_from_triangles(const Mesh& mesh, const TriangleSpringOptions& options,
                                     DiagnosticList& diagnostics, WorkerPool* pool = nullptr);
SpringNetwork springs_from_triangles(const Mesh& mesh, const std::vector<Point3>& points,
                                     const TriangleSpringOptions& options, DiagnosticList& diagnostics,
                                     WorkerPool* pool = nullptr, VertexElements at = {});

// Rest lengths from the positions. A spring shorter than min_relative_length x the mean length is an error naming
// the spring and its vertices (a force direction cannot be defined for it): merge the duplicate vertices first.
bool compute_rest_lengths(SpringNetwork& network, const std::vector<Point3>& points, DiagnosticList& diagnostics,
                          double min_relative_length = 1e-9, WorkerPool* pool = nullptr);

// Fills adjacency_* from first/second (vertex_count vertices, fewer than 2^31 entries).
void build_adjacency(SpringNetwork& network, WorkerPool* pool = nullptr);

// ---- material mapping ----------------------------------------------------------------------------------------

enum class StiffnessMapping {
  Uniform,              // k = value (N/m) for every spring
  StiffnessOverLength,  // k = value / l0 (value in N): SOFA MeshSpringForceField's convention, as in the SOFA liver
                        // scene
  // Van Gelder (1998), "Approximate simulation of elastic membranes by triangulated spring meshes", J. Graphics
  // Tools 3(2):21-42, in its simplest form (stiffness = Young's modulus x incident element measure / length^2):
  //   tetrahedron edges: k = E * sum(V_e) / l0^2      (the paper's three-dimensional extension)
  //   triangle edges:    k = E * h * sum(A_e) / l0^2  (membrane of thickness h; Poisson correction not applied)
  // Flexion and bending springs have no incident element; they get flexion_fraction x the mean structural k at
  // their vertices (for both Young's modulus mappings).
  VanGelder1998,
  // Lloyd, Szekely & Harders (2007), "Identification of spring parameters for deformable object simulation", IEEE
  // TVCG 13(5):1081-1094. Their closed forms (spring matrix fitted to the linear FEM element stiffness matrix):
  //   regular tetrahedron, edge l:        k = (2 sqrt(2) / 25) E l   (least squares; springs force nu = 1/4)
  //   equilateral triangle, thickness h:  k = (sqrt(3) / 4) E h      (exact, plane stress; springs force nu = 1/3)
  // Applied to any element as "measure over length squared", summed over the elements that share the edge:
  //   tetrahedron edges: k = (24/25) E sum(V_e) / l0^2   ((24/25) V / l^2 = (2 sqrt(2)/25) l for a regular one)
  //   triangle edges:    k = E h sum(A_e) / l0^2          (A / l^2 = sqrt(3)/4 for an equilateral one)
  // The Poisson ratio is not a parameter: a network of central springs can only represent nu = 1/4 (3-D) or
  // nu = 1/3 (2-D, the Cauchy relations). docs/simulator.md gives the derivation and what was confirmed.
  LloydSzekelyHarders2007,
};

// "Van Gelder 1998", "Lloyd, Szekely & Harders 2007", ... (summaries and messages).
const char* mapping_citation(StiffnessMapping mapping);
// Whether the mapping's value is Young's modulus (so it uses the element measures).
bool is_modulus_mapping(StiffnessMapping mapping);

struct StiffnessSpec {
  StiffnessMapping mapping = StiffnessMapping::VanGelder1998;
  double value = 0.0;  // N/m (Uniform), N (StiffnessOverLength), Pa = Young's modulus (VanGelder1998, Lloyd...)
  std::vector<double> per_spring;  // optional per-spring value (e.g. a FIS output per spring); overrides `value`
  double thickness = 1.0;          // m, triangle membranes only
  double flexion_fraction = 0.1;
};

// What assign_stiffness leaves of element_measure (the mappings' only input): Keep, or Release it (left empty
// whatever the result), its storage becoming the stiffness so that the two arrays are never held together (the
// model builder's peak, docs/performance.md "Host setup").
enum class ElementMeasures { Keep, Release };

// On an error (naming the first spring that cannot get a stiffness) the springs before it keep theirs, the rest 0.
bool assign_stiffness(SpringNetwork& network, const StiffnessSpec& spec, DiagnosticList& diagnostics,
                      WorkerPool* pool = nullptr, ElementMeasures measures = ElementMeasures::Keep);

struct MassSpec {
  enum class Source { Density, TotalMass } source = Source::Density;
  double value = 1000.0;   // kg/m^3 (Density) or kg (TotalMass)
  double thickness = 1.0;  // m, for triangle meshes
};

// Lumped masses: each tetrahedron gives rho V / 4 to each vertex, each triangle rho h A / 3 (when the mesh has no
// tetrahedra). TotalMass scales those shares to the total; a mesh without elements shares it equally.
// Vertices that get no mass are an error (they would divide by zero), naming the first of them.
std::vector<double> lumped_masses(const Mesh& mesh, const MassSpec& spec, DiagnosticList& diagnostics,
                                  WorkerPool* pool = nullptr);
// The same with the elements placed at `points` (one per mesh vertex) instead of mesh.points; `at` as for the
// springs. Each vertex's mass is the sum of its elements' shares in element order (the bits of the loop that adds
// each element's share to its vertices).
std::vector<double> lumped_masses(const Mesh& mesh, const std::vector<Point3>& points, const MassSpec& spec,
                                  DiagnosticList& diagnostics, WorkerPool* pool = nullptr,
                                  const VertexElements* at = nullptr);

struct DampingSpec {
  enum class Rule {
    // c = 2 zeta sqrt(k mu) with mu = m_a m_b / (m_a + m_b) the reduced mass of the two endpoints: the critical
    // damping of the spring's own two-body mode, scaled by zeta.
    DampingRatio,
    // The thesis's Eq. (3.6): gamma = 2 zeta k / w with a given natural frequency w (rad/s).
    ThesisNaturalFrequency,
    Fixed,  // c = value (N s/m)
  } rule = Rule::DampingRatio;
  double ratio = 0.9;              // zeta; the thesis uses 0.9
  double natural_frequency = 0.0;  // rad/s, ThesisNaturalFrequency only
  double value = 0.0;              // Fixed only
};

bool assign_damping(SpringNetwork& network, const std::vector<double>& mass, const DampingSpec& spec,
                    DiagnosticList& diagnostics, WorkerPool* pool = nullptr);

}  // namespace fmpc::sim

#pragma once
// A run's element terms as plain data (docs/simulator.md, "Element terms"): the elements' kind, nodes, rest geometry
// and node CSR, shared by the terms, and the list of terms, each one law (kernels/laws/, listed in kernels/
// element_laws.h; runtime/fem/element_law_registry.h builds them) with its per-element parameters, summed in list
// order. The backends read them through kernels::ElementTermView. Nothing here names a law or an element kind.
#include <array>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "kernels/element_laws.h"
#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

// Parallel to SimulationSetup::tetrahedra (positively oriented): element e is built on tetrahedron e.
struct ElementGeometry {
  int kind = 0;                      // the element kind's index in kernels::ElementKinds
  int nodes_per_element = 4;         // the kind's kNodes
  std::vector<std::int32_t> nodes;   // nodes_per_element vertices per element (the linear kind's: the tetrahedra)
  std::vector<double> rest_inverse;  // Dm^-1 per element, 9 values, row-major (1/m)
  std::vector<double> rest_volume;   // m^3, positive
  // The nodes at each vertex as CSR: corner_index[corner_offset[v] .. corner_offset[v+1]) are N e + a (element e's
  // node a, N nodes per element), increasing.
  std::vector<std::int32_t> corner_offset;
  std::vector<std::int32_t> corner_index;
  // The inverse of corner_index: corner_slot[N e + a] = k where corner_index[k] = N e + a. The element pass writes
  // node forces at their slots, so each vertex's gather reads one contiguous run (no 12-byte reads scattered over
  // element-major memory: docs/performance.md).
  std::vector<std::int32_t> corner_slot;
  // The vertices the kind adds to the mesh's (its edge nodes, one per mesh edge, shared by the elements around it),
  // numbered from the mesh's vertex count on: vertex (mesh vertices + i) is the midpoint of added_vertex_ends[i].
  std::vector<std::array<std::int32_t, 2>> added_vertex_ends;

  std::size_t size() const { return rest_volume.size(); }
};

// One term of a Prony series (kernels/prony_viscoelasticity.h): its weight g_i, a fraction of the law's instantaneous
// response, and its time constant tau_i (s). A weight bound to a rule output that varies over the elements
// (material.bind) is one per element instead: element_weight, parallel to the elements (empty: `weight` everywhere;
// otherwise `weight` is their largest, for messages).
struct PronyTerm {
  double weight = 0.0;
  double time = 0.0;
  std::vector<double> element_weight;

  PronyTerm() = default;
  PronyTerm(double g, double tau, std::vector<double> per_element = {})
      : weight(g), time(tau), element_weight(std::move(per_element)) {}
};

// Term `term`'s weight at element e.
inline double prony_weight_at(const PronyTerm& term, std::size_t e) {
  return term.element_weight.empty() ? term.weight : term.element_weight[e];
}

struct ElementTerm {
  int law = 0;  // index in kernels::ElementLaws
  // The law's parameters in its order (kParameterCount of them), one value per element each.
  std::vector<double> parameter[kernels::kMostLawParameters];
  std::vector<double> stiffness_damping;  // beta (s) per element; empty: undamped
  // Viscoelasticity on the law (at most kernels::kMostPronyTerms, weights summing below 1); empty: elastic. A term
  // with a series keeps per-point state (point_state_width values per material point).
  std::vector<PronyTerm> prony;
};

struct ElementTerms {
  ElementGeometry geometry;
  std::vector<ElementTerm> terms;  // summed in this order

  bool empty() const { return terms.empty(); }
};

// Elements of kind `kind` (index in kernels::ElementKinds) on `tetrahedra` over `points` (metres): their nodes (the
// corners, then the kind's edge nodes as added vertices after the mesh's), rest geometry (Dm^-1, volumes of the
// tetrahedra) and node CSR over all vertices. An element whose volume is not positive (|V| <= 1e-9 l_max^3, or
// inverted) is an error naming it: repair the mesh first.
std::optional<ElementGeometry> element_geometry(const std::vector<Point3>& points,
                                                const std::vector<Tetrahedron>& tetrahedra, int kind,
                                                DiagnosticList& diagnostics);

// `points` followed by the geometry's added vertices (each the midpoint of its two ends).
std::vector<Point3> with_added_vertices(const std::vector<Point3>& points, const ElementGeometry& geometry);

// Lumped masses over every vertex of the geometry (the mesh's and the added ones) at density rho (kg/m^3): each
// element gives node a rho V0 times its kind's kMassFraction[a], in element order.
std::vector<double> element_lumped_masses(const ElementGeometry& geometry, std::size_t vertex_count, double density);

// geometry.nodes' CSR by vertex (corner_offset, corner_index, corner_slot) over `vertex_count` vertices.
void build_node_csr(ElementGeometry& geometry, std::size_t vertex_count);

// Term `term` of `terms` as the element kinds and laws read it on the host, in double, over the arrays held here,
// with `table` (a strain table's view; null: none) where the term's law reads one. Valid while `terms` and `table`
// live.
kernels::ElementTermView<double> element_term_view(const ElementTerms& terms, std::size_t term,
                                                   const kernels::StrainTableView* table);

// A kind's nodal pass on the host, in double (kernels::element_nodal_shares and nodal_pressure_at, as the engines
// run them): per vertex of the geometry, the pressure and dilatation of `view`'s term at `positions`. Empty for a
// kind without a nodal pass (kernels::element_kind_has_nodal_pass). `attach` points the view at them (valid while
// the field lives).
struct NodalField {
  std::vector<double> pressure, dilatation;
  void attach(kernels::ElementTermView<double>& view) const;
};
NodalField nodal_field(const ElementGeometry& geometry, const kernels::ElementTermView<double>& view,
                       const std::vector<Point3>& positions);

// The Prony series' constants at time step dt (s), in double (exp evaluated here, on the host, once per run): the
// update's a_i = exp(-dt / tau_i), c_i = g_i (1 - a_i) / (dt / tau_i), and the stress's (kernels/
// prony_viscoelasticity.h): at the step's end t_(n+1) where `step_end_stress` (implicit Euler: a_i, c_i and
// gamma = 1 - sum g_i + sum c_i), else at its start t_n (1, g_i, 1). With dt = 0: the update of an instantaneous jump
// (a_i = 1, c_i = g_i), which the engines apply once at the start so that a scene starting deformed starts with the
// history of a jump to that deformation at t = 0. A term with element_weight gets its constants per unit weight
// (kernels::prony_weighted scales them by each element's).
kernels::PronyConstants<double> prony_constants(const std::vector<PronyTerm>& prony, double dt, bool step_end_stress);

// The constants in Real (each rounded once from the double above, the same on both backends).
template <typename Real>
kernels::PronyConstants<Real> prony_constants_in(const std::vector<PronyTerm>& prony, double dt,
                                                 bool step_end_stress) {
  const kernels::PronyConstants<double> c = prony_constants(prony, dt, step_end_stress);
  kernels::PronyConstants<Real> out{};
  out.count = c.count;
  out.stress_scale = static_cast<Real>(c.stress_scale);
  for (int i = 0; i < kernels::kMostPronyTerms; ++i) {
    out.stress_decay[i] = static_cast<Real>(c.stress_decay[i]);
    out.stress_gain[i] = static_cast<Real>(c.stress_gain[i]);
    out.decay[i] = static_cast<Real>(c.decay[i]);
    out.gain[i] = static_cast<Real>(c.gain[i]);
    out.stress_scale_per_weight[i] = static_cast<Real>(c.stress_scale_per_weight[i]);
  }
  return out;
}

// Values per material point a term keeps (0: none), and material points per element of kind `kind`.
int point_state_width(const ElementTerm& term);
int points_per_element(int kind);

// Whether any of the terms keeps per-point state.
bool has_point_state(const ElementTerms& terms);

// Whether the law of `term` reads a strain table's modulus (its kStrainTableModulus).
bool reads_strain_table(const ElementTerm& term);

// Stiffness-proportional damping for one term: beta_e = 2 zeta / omega_e + rayleigh_stiffness, with omega_e^2 the
// element's stiffness bound (its kind's stiffness_bound at its law's rest moduli) over its node mass rho V0 / N: the
// element's own fastest mode gets the damping ratio zeta, as a spring's dashpot 2 zeta sqrt(k mu) damps the spring's
// own mode. rho is the vertex masses' total over the elements' volume. Leaves the array empty when both are zero.
void assign_element_damping(const ElementGeometry& geometry, ElementTerm& term, const std::vector<double>& vertex_mass,
                            double ratio, double rayleigh_stiffness);

// Elements found inverted or flat at some positions: how many, and the first.
struct InversionCount {
  std::size_t count = 0;
  std::int32_t first = -1;  // the smallest index, -1 when none
};

// The four corners of tetrahedron e as rows [corner][axis] of `points`.
void tetrahedron_corners(const std::vector<Tetrahedron>& tetrahedra, std::size_t e, const std::vector<Point3>& points,
                         double out[4][3]);

// Element e's nodes as rows [node][axis] of `points` (N = geometry.nodes_per_element rows).
template <int N>
void element_node_rows(const ElementGeometry& geometry, std::size_t e, const std::vector<Point3>& points,
                       double out[N][3]) {
  for (std::size_t a = 0; a < static_cast<std::size_t>(N); ++a)
    for (std::size_t i = 0; i < 3; ++i)
      out[a][i] = points[static_cast<std::size_t>(geometry.nodes[static_cast<std::size_t>(N) * e + a])][i];
}

}  // namespace fmpc::sim

#pragma once
// An element term: one constitutive law acting on a mesh's elements of one kind, as plain arrays (structure of
// arrays, element-major) that the CPU loops, the CUDA kernels and the host's sums read alike. A run holds a list of
// terms over the same elements, summed in list order (an elastic law, a viscous one, the volume term beside springs).
// Two independent axes, each a list in kernels/element_laws.h:
// - a law (kernels/laws/) is the material at one point, a function of the deformation gradient F: its parameters
//   (Material, material()), first_piola(F, dF/dt), energy_density(F), linearise(F) and stress_differential(dF) (the
//   tangent implicit Euler uses), rest_lame (the small-strain Lame parameters for the stable step) and stress_output;
// - an element kind (kernels/elements/) integrates a law over an element: its nodes, F at its points, the nodal
//   forces, the tangent's action, energy, stress output and stiffness bound, each generic over the law.
// Everything here is generic over both.
#include <type_traits>

#include "kernels/fmpc_hd.h"
#include "kernels/prony_viscoelasticity.h"
#include "kernels/spring_math.h"
#include "kernels/strain_table_math.h"
#include "kernels/tetrahedron_math.h"

namespace fmpc::kernels {

// The most per-element parameters a law has (its kParameterCount).
constexpr int kMostLawParameters = 4;
// The most element terms a run holds (sim::validate_setup refuses more; the GPU's views hold this many).
constexpr int kMostElementTerms = 4;

// A value per element: an array, or, where every element has the same value, that value alone (values null; the
// GPU's views, per_element_of in runtime/gpu): the element pass then reads it from its kernel parameters, and a
// uniform material moves no bytes per element for it. Either way element e reads the same value, so the arithmetic,
// and the bits, are the array's.
template <typename Real>
struct PerElement {
  const Real* values = nullptr;  // one per element; null: `uniform` for every element
  Real uniform = Real(0);

  PerElement() = default;
  FMPC_HD PerElement(const Real* per_element) : values(per_element) {}
  FMPC_HD PerElement(const Real* per_element, Real same) : values(per_element), uniform(same) {}
  template <typename Index>  // int in the kernels, std::size_t in the host's loops, as a pointer indexes
  FMPC_HD Real operator[](Index e) const {
    return values ? values[e] : uniform;
  }
  // Whether some element's value may be non-zero: false for an absent array (null) and for zero everywhere.
  FMPC_HD explicit operator bool() const { return values != nullptr || uniform != Real(0); }
};

// One term's arrays; the geometry (corners, corner_slot, rest_inverse, rest_volume) is shared by the run's terms.
template <typename Real>
struct ElementTermView {
  int law;                 // the law's index in ElementLaws (kernels/element_laws.h)
  int element;             // the element kind's index in ElementKinds (kernels/element_laws.h)
  int count;               // elements
  const int* corners;      // the element kind's kNodes per element
  const int* corner_slot;  // kNodes per element: where each node's force goes (CornerForceView)
  // Where not null, the same slots in a byte per node instead of four (node_slot): node a of element e writes at
  // corner_offset[v] + corner_rank[kNodes e + a], v = corners[kNodes e + a], its entry's rank among v's; the offset is
  // read beside v's state, which the element pass gathers anyway. The GPU's views, where every rank fits a byte.
  const unsigned char* corner_rank;
  const int* corner_offset;  // the corners' CSR offsets (CornerForceView::offset)
  const Real* rest_inverse;  // Dm^-1, 9 per element (1/m); where rest_shape, 9 per shape (rest_inverse_of)
  // Where not null, element e's shape (a byte): its Dm^-1 is that of rest_inverse's entry rest_shape[e], a table of
  // the mesh's distinct ones (the GPU's views of a mesh with at most 256 shapes, a regular grid's: gpu::rest_shapes).
  const unsigned char* rest_shape;
  PerElement<Real> rest_volume;                    // V0 (m^3)
  PerElement<Real> parameter[kMostLawParameters];  // the law's parameters in its order
  PerElement<Real> stiffness_damping;              // beta (s); absent or zero everywhere: undamped
  StrainTableView strain_table;  // E(strain) for a law whose modulus a strain table replaces; strain null: none
  // Per-point state (kernels/prony_viscoelasticity.h) and the Prony series reading it; count 0: elastic (the state's
  // values null). The engines' Real views carry both; the double views of implicit Euler and the host's sums leave
  // them empty: the tangent and the energy are the law's (docs/simulator.md, "Per-point state").
  PointStateView<Real> state;
  PronyConstants<Real> prony;
  // Per term of the series, its weight per element where it varies (prony_weighted); null: the scene's, in `prony`.
  const Real* prony_weight[kMostPronyTerms];
  // Kinds with kNodalPressure (kernels/elements/linear_nodal_pressure.h): per vertex, the nodal pass's pressure p_a
  // (Pa) and dilatation theta_a at the positions the element pass reads; null for the other kinds.
  const Real* nodal_pressure;
  const Real* nodal_dilatation;
};

// Element e's node positions and, where `velocities`, velocities [node][axis], in Real from a state in StateReal (the
// same type in the engines' passes; double from float where the GPU sums a float run's energy in double, exactly as
// the host does from the downloaded positions).
template <int Nodes, typename StateReal, typename Real>
FMPC_HD void element_nodes(int e, const int* nodes, const StateView<StateReal>& s, bool velocities, Real x[Nodes][3],
                           Real v[Nodes][3]) {
  for (int a = 0; a < Nodes; ++a) {
    const int vertex = nodes[Nodes * e + a];
    x[a][0] = static_cast<Real>(s.x[vertex]);
    x[a][1] = static_cast<Real>(s.y[vertex]);
    x[a][2] = static_cast<Real>(s.z[vertex]);
    if (velocities) {
      v[a][0] = static_cast<Real>(s.vx[vertex]);
      v[a][1] = static_cast<Real>(s.vy[vertex]);
      v[a][2] = static_cast<Real>(s.vz[vertex]);
    }
  }
}

// The corner-force slot of node a of element e (ElementTermView::corner_slot, or its offset and rank).
template <int Nodes, typename Real>
FMPC_HD int node_slot(const ElementTermView<Real>& t, int e, int a) {
  const int k = Nodes * e + a;
  return t.corner_rank ? t.corner_offset[t.corners[k]] + static_cast<int>(t.corner_rank[k]) : t.corner_slot[k];
}

// Element e's Dm^-1 (9 values, row-major): its own, or its shape's (ElementTermView::rest_shape).
template <typename Real>
FMPC_HD const Real* rest_inverse_of(const ElementTermView<Real>& t, int e) {
  return t.rest_inverse + 9 * (t.rest_shape ? static_cast<int>(t.rest_shape[e]) : e);
}

// P at material point `point` (element e's, numbered kPoints e + q) of deformation gradient F: the law's stress at
// `material`, then the term's Prony series on the state held. Element kinds call this, never the law's first_piola
// directly; point_first_piola takes the element's own material.
template <typename Law, typename Real>
FMPC_HD void point_first_piola_of(const typename Law::template Material<Real>& material, const ElementTermView<Real>& t,
                                  int e, int point, const Real* F, const Real* F_rate, Real* P) {
  Law::first_piola(material, F, F_rate, P);
  if (t.prony.count > 0) prony_first_piola(prony_weighted(t.prony, t.prony_weight, e), t.state, point, F, P);
}
template <typename Law, typename Real>
FMPC_HD void point_first_piola(const ElementTermView<Real>& t, int e, int point, const Real* F, const Real* F_rate,
                               Real* P) {
  point_first_piola_of<Law>(Law::material(t, e), t, e, point, F, F_rate, P);
}

// Whether Member<Types...> names something (a law's or a kind's optional function): the detection idiom.
template <typename, template <typename...> class Member, typename... Types>
struct Detected : std::false_type {};
template <template <typename...> class Member, typename... Types>
struct Detected<std::void_t<Member<Types...>>, Member, Types...> : std::true_type {};

// Whether a law gives P from its linearisation at the same F (a static first_piola_linearised(material, lin, F,
// F_rate, P): the co-rotational law's, which reuses the linearisation's polar decomposition).
template <typename Law>
using FirstPiolaLinearisedOf = decltype(&Law::first_piola_linearised);
template <typename Law>
using HasFirstPiolaLinearised = Detected<void, FirstPiolaLinearisedOf, Law>;

// point_first_piola_of at F with the law's linearisation `lin` taken at the same F: the law's first_piola_linearised
// where it has one, else its first_piola; the same bits either way.
template <typename Law>
FMPC_HD void point_first_piola_linearised(const typename Law::template Material<double>& material,
                                          const ElementTermView<double>& t, int e, int point,
                                          const typename Law::Linearisation& lin, const double* F,
                                          const double* F_rate, double* P) {
  if constexpr (HasFirstPiolaLinearised<Law>::value) {
    Law::first_piola_linearised(material, lin, F, F_rate, P);
  } else {
    Law::first_piola(material, F, F_rate, P);
  }
  if (t.prony.count > 0) prony_first_piola(prony_weighted(t.prony, t.prony_weight, e), t.state, point, F, P);
}

// Whether a law gives its tangent modulus in closed form (a static tangent_modulus(material, lin, A)).
template <typename Law>
using TangentModulusOf = decltype(&Law::tangent_modulus);
template <typename Law>
using HasTangentModulus = Detected<void, TangentModulusOf, Law>;

// The law's tangent modulus at its linearisation, A = dP/dF as a 9 x 9 matrix: A[9 (3 i + k) + 3 j + l] =
// dP_ik / dF_jl, so that stress_differential's dP_ik = sum_jl A[9 (3 i + k) + 3 j + l] dF_jl. The law's own
// tangent_modulus where it has one, else its stress_differential applied to the nine unit dF (column 3 j + l of A).
// Element kinds build their stiffness from it (kernels/elements/corner_tetrahedron.h), once per element and step.
template <typename Law>
FMPC_HD void law_tangent_modulus(const typename Law::template Material<double>& m,
                                 const typename Law::Linearisation& lin, double* A) {
  if constexpr (HasTangentModulus<Law>::value) {
    Law::tangent_modulus(m, lin, A);
  } else {
    for (int column = 0; column < 9; ++column) {
      double dF[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}, dP[9];
      dF[column] = 1.0;
      Law::stress_differential(m, lin, dF, dP);
      for (int row = 0; row < 9; ++row) A[9 * row + column] = dP[row];
    }
  }
}

// The state update of element e after an accepted step, at positions s (the step's end): each point's Prony history
// from the law's elastic stress there. Only for a term with state (t.prony.count > 0).
template <typename Element, typename Law, typename Real>
FMPC_HD void element_state_update(int e, const ElementTermView<Real>& t, const StateView<Real>& s) {
  constexpr int N = Element::kNodes;
  constexpr int Q = Element::kPoints;
  Real x[N][3], v[N][3], F[Q][9];
  element_nodes<N>(e, t.corners, s, false, x, v);
  Element::deformation_gradients(t, e, x, F);
  const PronyConstants<Real> prony = prony_weighted(t.prony, t.prony_weight, e);
  for (int q = 0; q < Q; ++q) {
    Real P[9];
    Law::first_piola(Element::template point_material<Law>(t, e), F[q], static_cast<const Real*>(nullptr), P);
    prony_update(prony, t.state, Q * e + q, F[q], P);
  }
}

// Element e's node forces `out` into its corner slots (node_slot): written (the run's first term) or added
// (Accumulate). Every slot is read before the first store: a slot read after a store waits for it (the compiler
// cannot tell the arrays apart), which chained the loads' latencies at each thread's end.
template <int N, bool Accumulate, typename Real>
FMPC_HD void store_corner_forces(int e, const ElementTermView<Real>& t, const Real out[N][3],
                                 CornerForce<Real>* force) {
  int slot[N];
  for (int a = 0; a < N; ++a) slot[a] = node_slot<N>(t, e, a);
  for (int a = 0; a < N; ++a) {
    CornerForce<Real>& to = force[slot[a]];
    if (Accumulate) {
      to = {to.x + out[a][0], to.y + out[a][1], to.z + out[a][2], Real(0)};
    } else {
      to = {out[a][0], out[a][1], out[a][2], Real(0)};
    }
  }
}

// The element pass of one term: element e's node forces into force[corner_slot[kNodes e + a]] (the vertex-major
// layout CornerForceView reads), written by the run's first term and added to by each later one (Accumulate), so
// that a vertex's gather sums the terms in list order. Velocities are read only where the term has stiffness
// damping: the laws read them for nothing else, and they are half the pass's gathered bytes.
template <typename Element, typename Law, bool Accumulate, typename Real>
FMPC_HD void element_node_forces(int e, const ElementTermView<Real>& t, const StateView<Real>& s,
                                 CornerForce<Real>* force) {
  constexpr int N = Element::kNodes;
  Real x[N][3], v[N][3], out[N][3];
  const bool damped = static_cast<bool>(t.stiffness_damping);
  // As in LinearTetrahedron::forces: a constant pointer in each branch lets the GPU keep x and v in registers. The
  // nodes are read in each branch with a constant flag, so that the compiler sees v written where it is read (GCC 12
  // reported v as uninitialised once a law's damped stress was inlined).
  if (damped) {
    element_nodes<N>(e, t.corners, s, true, x, v);
    Element::template forces<Law>(t, e, x, v, out);
  } else {
    element_nodes<N>(e, t.corners, s, false, x, v);
    Element::template forces<Law>(t, e, x, static_cast<const Real(*)[3]>(nullptr), out);
  }
  store_corner_forces<N, Accumulate>(e, t, out, force);
}

// Whether an element kind gives its forces and its linearisation in one (forces_and_linearisation<Law>).
template <typename Element, typename Law>
using ForcesAndLinearisationOf = decltype(&Element::template forces_and_linearisation<Law>);
template <typename Element, typename Law>
using HasForcesAndLinearisation = Detected<void, ForcesAndLinearisationOf, Element, Law>;

// element_node_forces (double) with the element's linearisation at the same positions into `lin`, for a kind with
// HasForcesAndLinearisation: implicit Euler's force pass on the CPU, whose step's tangent then reads lin.
template <typename Element, typename Law, bool Accumulate>
FMPC_HD void element_node_forces_linearised(int e, const ElementTermView<double>& t, const StateView<double>& s,
                                            CornerForce<double>* force,
                                            typename Element::template Linearisation<Law>& lin) {
  constexpr int N = Element::kNodes;
  double x[N][3], v[N][3], out[N][3];
  const bool damped = static_cast<bool>(t.stiffness_damping);
  element_nodes<N>(e, t.corners, s, damped, x, v);
  Element::template forces_and_linearisation<Law>(t, e, x, damped ? v : nullptr, lin, out);
  store_corner_forces<N, Accumulate>(e, t, out, force);
}

// The nodal pass of a kind with kNodalPressure (kernels/elements/linear_nodal_pressure.h): element e's shares of
// its nodes' sums, written at its corner slots in the corner-force layout (x: volume change, y: rest volume, z:
// modulus times rest volume), so that each vertex's gather (nodal_pressure_at) sums them in CSR order as it sums
// forces. The CPU engine's nodal pass, the host's sums and the CUDA kernels (nodal_shares_kernel,
// kernels/explicit_step.cu) all run this and nodal_pressure_at: the GPU's nodal field has the CPU's bits.
template <typename Element, typename Law, typename Real, typename StateReal>
FMPC_HD void element_nodal_shares(int e, const ElementTermView<Real>& t, const StateView<StateReal>& s,
                                  CornerForce<Real>* slot) {
  if constexpr (Element::kNodalPressure) {
    constexpr int N = Element::kNodes;
    Real x[N][3], v[N][3], share[3];
    element_nodes<N>(e, t.corners, s, false, x, v);
    Element::template nodal_shares<Law>(t, e, x, share);
    int at[N];
    for (int a = 0; a < N; ++a) at[a] = node_slot<N>(t, e, a);
    for (int a = 0; a < N; ++a) slot[at[a]] = {share[0], share[1], share[2], Real(0)};
  }
}

// Vertex v's nodal dilatation theta = sum (V - V0) / sum V0 and pressure K theta, K = sum lambda V0 / sum V0, from
// the shares at its slots; zero at a vertex no element touches.
template <typename Real>
FMPC_HD void nodal_pressure_at(int v, const CornerForceView<Real>& shares, Real& pressure, Real& dilatation) {
  Real change, volume, modulus_volume;
  gather_corner_force(v, shares, change, volume, modulus_volume);
  if (!(volume > Real(0))) {
    pressure = dilatation = Real(0);
    return;
  }
  dilatation = change / volume;
  pressure = modulus_volume / volume * dilatation;
}

// An element's rest nodes from its tetrahedron's corners: the corners, then (kinds with kEdgeNodes) the midpoint of
// each edge Element::edge_end(m, 0..1) in the kind's order.
template <typename Element>
FMPC_HD void element_rest_nodes(const double corners[4][3], double out[Element::kNodes][3]) {
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i) out[a][i] = corners[a][i];
  if constexpr (Element::kEdgeNodes > 0) {
    for (int m = 0; m < Element::kEdgeNodes; ++m)
      for (int i = 0; i < 3; ++i)
        out[4 + m][i] = 0.5 * (corners[Element::edge_end(m, 0)][i] + corners[Element::edge_end(m, 1)][i]);
  }
}

// The largest modulus a strain table gives (Pa): a law's stiffness bound over a run whose modulus follows it.
FMPC_HD double strain_table_largest_modulus(const StrainTableView& table) {
  double largest = table.modulus[0];
  for (int i = 1; i < table.count; ++i) largest = table.modulus[i] > largest ? table.modulus[i] : largest;
  return largest;
}

}  // namespace fmpc::kernels

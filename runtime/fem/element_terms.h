#pragma once
// A run's element terms as plain data (docs/simulator.md, "Element terms"): the tetrahedra's rest geometry and
// corner CSR, shared by the terms, and the list of terms, each one law (kernels/laws/, listed in kernels/
// element_laws.h; runtime/fem/element_law_registry.h builds them) with its per-element parameters, summed in list
// order. The backends read them through kernels::ElementTermView. Nothing here names a law.
#include <cstdint>
#include <optional>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "kernels/element_laws.h"
#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

// Parallel to SimulationSetup::tetrahedra (positively oriented).
struct ElementGeometry {
  std::vector<double> rest_inverse;  // Dm^-1 per element, 9 values, row-major (1/m)
  std::vector<double> rest_volume;   // m^3, positive
  // The corners at each vertex as CSR: corner_index[corner_offset[v] .. corner_offset[v+1]) are 4 e + c, increasing.
  std::vector<std::int32_t> corner_offset;
  std::vector<std::int32_t> corner_index;
  // The inverse of corner_index: corner_slot[4 e + c] = k where corner_index[k] = 4 e + c. The element pass writes
  // corner forces at their slots, so each vertex's gather reads one contiguous run (no 12-byte reads scattered over
  // element-major memory: docs/performance.md).
  std::vector<std::int32_t> corner_slot;

  std::size_t size() const { return rest_volume.size(); }
};

struct ElementTerm {
  int law = 0;  // index in kernels::ElementLaws
  // The law's parameters in its order (kParameterCount of them), one value per element each.
  std::vector<double> parameter[kernels::kMostLawParameters];
  std::vector<double> stiffness_damping;  // beta (s) per element; empty: undamped
};

struct ElementTerms {
  ElementGeometry geometry;
  std::vector<ElementTerm> terms;  // summed in this order

  bool empty() const { return terms.empty(); }
};

// The rest geometry (Dm^-1, volumes) and the corner CSR of `tetrahedra` over `points` (metres). An element whose
// volume is not positive (|V| <= 1e-9 l_max^3, or inverted) is an error naming it: repair the mesh first.
std::optional<ElementGeometry> element_geometry(const std::vector<Point3>& points,
                                                const std::vector<Tetrahedron>& tetrahedra,
                                                DiagnosticList& diagnostics);

// Term `term` of `terms` as the laws' material() reads it on the host, in double, over the arrays held here (no
// corners: host loops read positions through SimulationSetup::tetrahedra), with `table` (a strain table's view; null:
// none) where the term's law reads one. Valid while `terms` and `table` live.
kernels::ElementTermView<double> element_term_view(const ElementTerms& terms, std::size_t term,
                                                   const kernels::StrainTableView* table);

// Whether the law of `term` reads a strain table's modulus (its kStrainTableModulus).
bool reads_strain_table(const ElementTerm& term);

// Stiffness-proportional damping for one term: beta_e = 2 zeta / omega_e + rayleigh_stiffness, with omega_e^2 the
// element's stiffness bound (its law's stiffness_bound at its own parameters) over its corner mass rho V0 / 4: the
// element's own fastest mode gets the damping ratio zeta, as a spring's dashpot 2 zeta sqrt(k mu) damps the spring's
// own mode. rho is the vertex masses' total over the elements' volume. Leaves the array empty when both are zero.
void assign_element_damping(const ElementGeometry& geometry, ElementTerm& term, const std::vector<double>& vertex_mass,
                            double ratio, double rayleigh_stiffness);

// Tetrahedra whose signed volume at `positions` is not positive (inverted or flat): how many, and the first.
struct InversionCount {
  std::size_t count = 0;
  std::int32_t first = -1;  // the smallest index, -1 when none
};
InversionCount count_inverted_tetrahedra(const std::vector<Tetrahedron>& tetrahedra,
                                         const std::vector<Point3>& positions);

// The four corners of tetrahedron e as rows [corner][axis] of `points`.
void tetrahedron_corners(const std::vector<Tetrahedron>& tetrahedra, std::size_t e, const std::vector<Point3>& points,
                         double out[4][3]);

}  // namespace fmpc::sim

#pragma once
// Per-tetrahedron force fields as plain data (structure of arrays, parallel to SimulationSetup::tetrahedra): the
// co-rotational linear FEM (a force model of its own) and the volume term that keeps a spring network from turning
// inside out (kernels/tetrahedron_math.h has the formulas and their sources). Building one checks the geometry; the
// simulator's backends read the arrays through kernels::TetrahedronFieldView.
#include <cstdint>
#include <optional>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "kernels/tetrahedron_math.h"
#include "runtime/mesh/mesh.h"
#include "runtime/springs/spring_network.h"

namespace fmpc::sim {

struct TetrahedronField {
  kernels::TetrahedronLaw law = kernels::TetrahedronLaw::CorotationalLinear;
  std::vector<double> rest_inverse;       // Dm^-1 per element, 9 values, row-major (1/m)
  std::vector<double> rest_volume;        // m^3, positive
  std::vector<double> youngs_modulus;     // Pa, CorotationalLinear (a strain table replaces it during the run)
  std::vector<double> poisson_ratio;      // CorotationalLinear, in [0, 0.499]
  std::vector<double> bulk_modulus;       // Pa, VolumePreservation (kappa)
  std::vector<double> stiffness_damping;  // s, beta per element; empty: undamped
  // The corners at each vertex as CSR: corner_index[corner_offset[v] .. corner_offset[v+1]) are 4 e + c, increasing.
  std::vector<std::int32_t> corner_offset;
  std::vector<std::int32_t> corner_index;
  // The inverse of corner_index: corner_slot[4 e + c] = k where corner_index[k] = 4 e + c. The element pass writes
  // corner forces at their slots, so each vertex's gather reads one contiguous run (no 12-byte reads scattered over
  // element-major memory: docs/performance.md).
  std::vector<std::int32_t> corner_slot;

  std::size_t size() const { return rest_volume.size(); }
};

// The rest geometry (Dm^-1, volumes) and the corner CSR of `tetrahedra` over `points` (metres). An element whose
// volume is not positive (|V| <= 1e-9 l_max^3, or inverted) is an error naming it: repair the mesh first.
std::optional<TetrahedronField> tetrahedron_geometry(const std::vector<Point3>& points,
                                                     const std::vector<Tetrahedron>& tetrahedra,
                                                     kernels::TetrahedronLaw law, DiagnosticList& diagnostics);

// The element's material as the kernels read it (double), its modulus from the field (no strain table).
kernels::TetrahedronMaterial<double> tetrahedron_material(const TetrahedronField& field, std::size_t element);

// Stiffness-proportional damping per element: beta_e = 2 zeta / omega_e + rayleigh_stiffness, with omega_e^2 the
// element's stiffness bound (kernels::tetrahedron_stiffness_bound, at `modulus_scale` x its modulus: a strain table's
// largest over its rest value) over its corner mass rho V0 / 4: the element's own fastest mode gets the damping
// ratio zeta, as a spring's dashpot 2 zeta sqrt(k mu) damps the spring's own mode. rho is the vertex masses' total
// over the elements' volume. Leaves the array empty when both are zero.
void assign_element_damping(TetrahedronField& field, const std::vector<double>& vertex_mass, double ratio,
                            double rayleigh_stiffness);

// Springs plus the volume term reaching a Young's modulus E and Poisson ratio nu (docs/simulator.md): a central
// spring network obeys the Cauchy relation lambda = mu, with mu = 2 E_s / 5 for the Van Gelder mapping at E_s (the
// bulk modulus 2 E_s / 3 is exact for every tetrahedron, docs/simulator.md) and 24/25 of it for Lloyd's. The springs
// take E_s so that their mu is the target's, the volume term the rest of lambda: kappa = lambda - mu =
// E (4 nu - 1) / (2 (1 + nu)(1 - 2 nu)). nu below 1/4 would need a negative kappa: an error naming the field.
struct VolumeTermCalibration {
  double spring_modulus = 0.0;  // E_s, Pa, for the spring mapping
  double bulk_modulus = 0.0;    // kappa, Pa
};
std::optional<VolumeTermCalibration> calibrate_volume_term(double youngs_modulus, double poisson_ratio,
                                                           StiffnessMapping mapping, const SourceRange& where,
                                                           DiagnosticList& diagnostics);

// Tetrahedra whose signed volume at `positions` is not positive (inverted or flat): how many, and the first.
struct InversionCount {
  std::size_t count = 0;
  std::int32_t first = -1;  // the smallest index, -1 when none
};
InversionCount count_inverted_tetrahedra(const std::vector<Tetrahedron>& tetrahedra,
                                         const std::vector<Point3>& positions);

}  // namespace fmpc::sim

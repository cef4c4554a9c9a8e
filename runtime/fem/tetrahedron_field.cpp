#include "runtime/fem/tetrahedron_field.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "diagnostics/number_format.h"

namespace fmpc::sim {

std::optional<TetrahedronField> tetrahedron_geometry(const std::vector<Point3>& points,
                                                     const std::vector<Tetrahedron>& tetrahedra,
                                                     kernels::TetrahedronLaw law, DiagnosticList& diagnostics) {
  TetrahedronField field;
  field.law = law;
  const std::size_t count = tetrahedra.size();
  field.rest_inverse.resize(9 * count);
  field.rest_volume.resize(count);
  for (std::size_t e = 0; e < count; ++e) {
    const Tetrahedron& t = tetrahedra[e];
    for (const std::int32_t v : t) {
      if (v < 0 || static_cast<std::size_t>(v) >= points.size()) {
        diagnostics.error(SourceRange{}, "tetrahedron " + std::to_string(e) + " refers to vertex " + std::to_string(v) +
                                             " of " + std::to_string(points.size()) +
                                             "; repair the mesh first (repair_mesh)");
        return std::nullopt;
      }
    }
    double x[4][3], longest = 0.0;
    for (std::size_t a = 0; a < 4; ++a)
      for (std::size_t i = 0; i < 3; ++i) x[a][i] = points[static_cast<std::size_t>(t[a])][i];
    for (std::size_t a = 0; a < 4; ++a)
      for (std::size_t b = a + 1; b < 4; ++b)
        longest = std::max(longest, distance(points[static_cast<std::size_t>(t[a])], points[static_cast<std::size_t>(t[b])]));
    const double volume = kernels::tetrahedron_volume(x);
    // The mesh check's test for a degenerate element (docs/simulator.md), and the orientation every mesh keeps.
    if (!(volume > 1e-9 * longest * longest * longest)) {
      diagnostics.error(SourceRange{}, "tetrahedron " + std::to_string(e) + " (vertices " + std::to_string(t[0]) + ", " +
                                           std::to_string(t[1]) + ", " + std::to_string(t[2]) + ", " +
                                           std::to_string(t[3]) + ") has rest volume " + format_number(volume) +
                                           " m^3; an element needs a positive volume: repair the mesh (repair_mesh "
                                           "drops degenerate and re-orients inverted elements)");
      return std::nullopt;
    }
    // Dm = [X1 - X0, X2 - X0, X3 - X0] (columns); its inverse by the adjugate, det Dm = 6 V.
    double dm[9];
    for (std::size_t i = 0; i < 3; ++i)
      for (std::size_t a = 0; a < 3; ++a) dm[3 * i + a] = x[a + 1][i] - x[0][i];
    const double det = kernels::determinant3(dm);
    double* inverse = field.rest_inverse.data() + 9 * e;
    inverse[0] = (dm[4] * dm[8] - dm[5] * dm[7]) / det;
    inverse[1] = (dm[2] * dm[7] - dm[1] * dm[8]) / det;
    inverse[2] = (dm[1] * dm[5] - dm[2] * dm[4]) / det;
    inverse[3] = (dm[5] * dm[6] - dm[3] * dm[8]) / det;
    inverse[4] = (dm[0] * dm[8] - dm[2] * dm[6]) / det;
    inverse[5] = (dm[2] * dm[3] - dm[0] * dm[5]) / det;
    inverse[6] = (dm[3] * dm[7] - dm[4] * dm[6]) / det;
    inverse[7] = (dm[1] * dm[6] - dm[0] * dm[7]) / det;
    inverse[8] = (dm[0] * dm[4] - dm[1] * dm[3]) / det;
    field.rest_volume[e] = volume;
  }
  field.corner_offset.assign(points.size() + 1, 0);
  for (const Tetrahedron& t : tetrahedra)
    for (const std::int32_t v : t) ++field.corner_offset[static_cast<std::size_t>(v) + 1];
  for (std::size_t v = 0; v < points.size(); ++v) field.corner_offset[v + 1] += field.corner_offset[v];
  field.corner_index.resize(4 * count);
  field.corner_slot.resize(4 * count);
  std::vector<std::int32_t> next(field.corner_offset.begin(), field.corner_offset.end() - 1);
  for (std::size_t e = 0; e < count; ++e)
    for (std::size_t c = 0; c < 4; ++c) {
      const std::int32_t slot = next[static_cast<std::size_t>(tetrahedra[e][c])]++;
      field.corner_index[static_cast<std::size_t>(slot)] = static_cast<std::int32_t>(4 * e + c);
      field.corner_slot[4 * e + c] = slot;
    }
  return field;
}

kernels::TetrahedronMaterial<double> tetrahedron_material(const TetrahedronField& field, std::size_t element) {
  kernels::TetrahedronMaterial<double> m{};
  m.law = field.law;
  m.rest_inverse = field.rest_inverse.data() + 9 * element;
  m.rest_volume = field.rest_volume[element];
  m.youngs_modulus = field.youngs_modulus.empty() ? 0.0 : field.youngs_modulus[element];
  m.poisson_ratio = field.poisson_ratio.empty() ? 0.0 : field.poisson_ratio[element];
  m.bulk_modulus = field.bulk_modulus.empty() ? 0.0 : field.bulk_modulus[element];
  m.stiffness_damping = field.stiffness_damping.empty() ? 0.0 : field.stiffness_damping[element];
  m.strain_table = nullptr;
  return m;
}

void assign_element_damping(TetrahedronField& field, const std::vector<double>& vertex_mass, double ratio,
                            double rayleigh_stiffness) {
  field.stiffness_damping.clear();
  if (ratio == 0.0 && rayleigh_stiffness == 0.0) return;
  double total_mass = 0.0, total_volume = 0.0;
  for (const double m : vertex_mass) total_mass += m;
  for (const double v : field.rest_volume) total_volume += v;
  const double density = total_volume > 0.0 ? total_mass / total_volume : 0.0;
  field.stiffness_damping.resize(field.size());
  for (std::size_t e = 0; e < field.size(); ++e) {
    const kernels::TetrahedronMaterial<double> m = tetrahedron_material(field, e);
    const double modulus = m.youngs_modulus;
    const double stiffness = kernels::tetrahedron_stiffness_bound(m, modulus);
    const double corner_mass = density * field.rest_volume[e] / 4.0;
    const double omega = std::sqrt(stiffness / corner_mass);
    field.stiffness_damping[e] = (omega > 0.0 ? 2.0 * ratio / omega : 0.0) + rayleigh_stiffness;
  }
}

std::optional<VolumeTermCalibration> calibrate_volume_term(double youngs_modulus, double poisson_ratio,
                                                           StiffnessMapping mapping, const SourceRange& where,
                                                           DiagnosticList& diagnostics) {
  if (!(poisson_ratio >= 0.25 && poisson_ratio <= 0.499)) {
    diagnostics.error(where, "material.poisson_ratio: " + format_number(poisson_ratio) +
                                 " cannot be reached by springs with the volume term: central springs have nu = 1/4 "
                                 "(Cauchy relation lambda = mu) and the volume term can only add to lambda; give a "
                                 "ratio in [0.25, 0.499], or use model: corotational_fem for any ratio in [0, 0.499]");
    return std::nullopt;
  }
  if (mapping != StiffnessMapping::VanGelder1998 && mapping != StiffnessMapping::LloydSzekelyHarders2007) {
    diagnostics.error(where, "the volume term needs a Young's modulus mapping (van_gelder_1998 or "
                             "lloyd_szekely_harders_2007) for the springs beside it");
    return std::nullopt;
  }
  double mu = 0.0, lambda = 0.0;
  kernels::lame_parameters(youngs_modulus, poisson_ratio, mu, lambda);
  // mu_springs = (2/5) c E_s with c = 1 (Van Gelder) or 24/25 (Lloyd).
  const double c = mapping == StiffnessMapping::LloydSzekelyHarders2007 ? 24.0 / 25.0 : 1.0;
  VolumeTermCalibration calibration;
  calibration.spring_modulus = 2.5 * mu / c;
  calibration.bulk_modulus = lambda - mu;
  return calibration;
}

InversionCount count_inverted_tetrahedra(const std::vector<Tetrahedron>& tetrahedra,
                                         const std::vector<Point3>& positions) {
  InversionCount result;
  for (std::size_t e = 0; e < tetrahedra.size(); ++e) {
    double x[4][3];
    for (std::size_t a = 0; a < 4; ++a)
      for (std::size_t i = 0; i < 3; ++i) x[a][i] = positions[static_cast<std::size_t>(tetrahedra[e][a])][i];
    if (kernels::tetrahedron_volume(x) > 0.0) continue;
    if (result.count == 0) result.first = static_cast<std::int32_t>(e);
    ++result.count;
  }
  return result;
}

}  // namespace fmpc::sim

// What the tetrahedron field contributes to the host-side sums both backends share (double): internal forces at
// chosen vertices (probes), elastic energy, element stresses for frames, and the inversion message.
#include <cmath>
#include <sstream>

#include "kernels/tetrahedron_math.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

namespace {

// Element e's material as the kernels read it, with the strain table where the co-rotational law uses one.
kernels::TetrahedronMaterial<double> material_with_table(const SimulationSetup& setup, std::size_t e,
                                                         const kernels::StrainTableView& table) {
  kernels::TetrahedronMaterial<double> m = tetrahedron_material(*setup.tetrahedron_field, e);
  if (table.strain && m.law == kernels::TetrahedronLaw::CorotationalLinear) m.strain_table = &table;
  return m;
}

kernels::StrainTableView table_of(const SimulationSetup& setup) {
  return setup.strain_stiffness ? strain_table_view(*setup.strain_stiffness) : kernels::StrainTableView{nullptr, nullptr, 0};
}

void corners(const SimulationSetup& setup, std::size_t e, const std::vector<Point3>& points, double out[4][3]) {
  for (std::size_t a = 0; a < 4; ++a)
    for (std::size_t i = 0; i < 3; ++i) out[a][i] = points[static_cast<std::size_t>(setup.tetrahedra[e][a])][i];
}

}  // namespace

const char* to_string(ForceModel model) {
  switch (model) {
    case ForceModel::Springs:
      return "springs";
    case ForceModel::CorotationalFem:
      return "corotational_fem";
  }
  return "springs";
}

std::vector<Point3> internal_forces(const SimulationSetup& setup, const std::vector<Point3>& positions,
                                    const std::vector<Point3>& velocities, const std::vector<double>& stiffness,
                                    const std::vector<std::int32_t>& vertices) {
  std::vector<Point3> out(vertices.size(), Point3{0.0, 0.0, 0.0});
  const SpringNetwork& net = setup.springs;
  const kernels::SpringLawParameters<double> law{setup.law, setup.basafa_k2_over_k1, setup.basafa_xc};
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const auto v = static_cast<std::size_t>(vertices[i]);
    for (auto e = net.adjacency_offset[v]; e < net.adjacency_offset[v + 1]; ++e) {
      const auto s = static_cast<std::size_t>(net.adjacency_spring[static_cast<std::size_t>(e)]);
      const auto o = static_cast<std::size_t>(adjacency_neighbour(net, v, static_cast<std::size_t>(e)));
      double f[3];
      kernels::spring_force_on_vertex(positions[o][0] - positions[v][0], positions[o][1] - positions[v][1],
                                      positions[o][2] - positions[v][2], velocities[o][0] - velocities[v][0],
                                      velocities[o][1] - velocities[v][1], velocities[o][2] - velocities[v][2],
                                      net.rest_length[s], stiffness[s], net.damping.empty() ? 0.0 : net.damping[s],
                                      law, f[0], f[1], f[2]);
      for (std::size_t axis = 0; axis < 3; ++axis) out[i][axis] += f[axis];
    }
  }
  if (!setup.tetrahedron_field) return out;
  const TetrahedronField& field = *setup.tetrahedron_field;
  const kernels::StrainTableView table = table_of(setup);
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const auto v = static_cast<std::size_t>(vertices[i]);
    for (auto k = field.corner_offset[v]; k < field.corner_offset[v + 1]; ++k) {
      const auto corner = static_cast<std::size_t>(field.corner_index[static_cast<std::size_t>(k)]);
      const std::size_t e = corner / 4, c = corner % 4;
      double x[4][3], u[4][3], f[4][3];
      corners(setup, e, positions, x);
      corners(setup, e, velocities, u);
      kernels::tetrahedron_forces(material_with_table(setup, e, table), x, u, f);
      for (std::size_t axis = 0; axis < 3; ++axis) out[i][axis] += f[c][axis];
    }
  }
  return out;
}

double element_elastic_energy(const SimulationSetup& setup, const std::vector<Point3>& positions) {
  if (!setup.tetrahedron_field) return 0.0;
  const TetrahedronField& field = *setup.tetrahedron_field;
  const kernels::StrainTableView table = table_of(setup);
  double energy = 0.0;
  for (std::size_t e = 0; e < field.size(); ++e) {
    double x[4][3];
    corners(setup, e, positions, x);
    energy += kernels::tetrahedron_elastic_energy(material_with_table(setup, e, table), x);
  }
  return energy;
}

std::vector<double> element_von_mises_stress(const SimulationSetup& setup, const std::vector<Point3>& positions) {
  std::vector<double> out;
  if (!setup.tetrahedron_field) return out;
  const TetrahedronField& field = *setup.tetrahedron_field;
  const kernels::StrainTableView table = table_of(setup);
  out.resize(field.size());
  for (std::size_t e = 0; e < field.size(); ++e) {
    const kernels::TetrahedronMaterial<double> m = material_with_table(setup, e, table);
    double x[4][3];
    corners(setup, e, positions, x);
    if (m.law == kernels::TetrahedronLaw::VolumePreservation) {
      // A pure pressure has no deviatoric part: its von Mises stress is zero; the pressure's magnitude is what the
      // volume term adds to the springs' (unrepresented) stress, so that is reported.
      out[e] = std::abs(m.bulk_modulus * (kernels::tetrahedron_volume(x) - m.rest_volume) / m.rest_volume);
      continue;
    }
    double modulus = m.youngs_modulus;
    if (m.strain_table) {
      double F[9], R[9], stretch[3];
      kernels::corner_gradient(x, m.rest_inverse, F);
      kernels::rotation_and_stretches(F, R, stretch);
      modulus = kernels::strain_table_modulus(table, kernels::principal_strain_of_largest_magnitude(stretch));
    }
    double sigma[9];
    kernels::corotational_stress(m.rest_inverse, modulus, m.poisson_ratio, x, sigma);
    out[e] = kernels::von_mises_stress(sigma);
  }
  return out;
}

std::string inversion_message(const SimulationSetup& setup, const InversionReport& report) {
  std::ostringstream message;
  const Tetrahedron& t = setup.tetrahedra[static_cast<std::size_t>(report.first_element)];
  message << "tetrahedron " << report.first_element << " (vertices " << t[0] << ", " << t[1] << ", " << t[2] << ", "
          << t[3] << ") turned inside out ";
  if (report.first_step == 0) message << "at the start";
  else message << "at step " << report.first_step << " (t = " << report.first_time << " s)";
  message << " (" << report.current_count << " inverted then)";
  if (setup.model == ForceModel::Springs && !setup.tetrahedron_field) {
    message << "; springs cannot tell an element from its mirror image: give the springs a volume term "
               "(springs: {volume_term: true}) or use model: corotational_fem";
  } else {
    message << "; the load is too large for the mesh here: refine it, lower the load, or raise the stiffness";
  }
  return message.str();
}

}  // namespace fmpc::sim

// What the element terms contribute to the host-side sums both backends share (double): internal forces at chosen
// vertices (probes), elastic energy, element stress outputs for frames, the model's name and the inversion message.
// Generic over the laws: each term's law is visited once per call (kernels/element_laws.h).
#include <sstream>

#include "runtime/fem/element_law_registry.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

namespace {

kernels::StrainTableView table_of(const SimulationSetup& setup) {
  return setup.strain_stiffness ? strain_table_view(*setup.strain_stiffness) : kernels::StrainTableView{nullptr, nullptr, 0};
}

// visit(Law, view) for each element term in list order, its view reading the strain table where its law does.
template <typename Visit>
void for_each_term(const SimulationSetup& setup, const kernels::StrainTableView& table, Visit visit) {
  for (std::size_t t = 0; t < setup.elements.terms.size(); ++t) {
    const kernels::ElementTermView<double> view = element_term_view(setup.elements, t, &table);
    kernels::visit_element_law(view.law, [&](auto element_law) { visit(element_law, view); });
  }
}

}  // namespace

std::string model_name(const SimulationSetup& setup) {
  if (setup.springs.size() > 0 || setup.elements.empty()) return "springs";
  const char* keyword = element_law_row(setup.elements.terms.front().law).model_keyword;
  return keyword != nullptr ? keyword : "springs";
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
  if (setup.elements.empty()) return out;
  const ElementGeometry& geometry = setup.elements.geometry;
  const kernels::StrainTableView table = table_of(setup);
  // Per vertex the terms' corner forces in the backends' order: for each corner, term after term.
  std::vector<kernels::ElementTermView<double>> views;
  for (std::size_t t = 0; t < setup.elements.terms.size(); ++t)
    views.push_back(element_term_view(setup.elements, t, &table));
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const auto v = static_cast<std::size_t>(vertices[i]);
    for (auto k = geometry.corner_offset[v]; k < geometry.corner_offset[v + 1]; ++k) {
      const auto corner = static_cast<std::size_t>(geometry.corner_index[static_cast<std::size_t>(k)]);
      const std::size_t e = corner / 4, c = corner % 4;
      double x[4][3], u[4][3], corner_force[3] = {0.0, 0.0, 0.0};
      tetrahedron_corners(setup.tetrahedra, e, positions, x);
      tetrahedron_corners(setup.tetrahedra, e, velocities, u);
      for (std::size_t t = 0; t < views.size(); ++t) {
        kernels::visit_element_law(views[t].law, [&](auto element_law) {
          using Law = decltype(element_law);
          double f[4][3];
          Law::forces(Law::material(views[t], static_cast<int>(e)), x, u, f);
          // The first term's force as it is, later ones added: the element pass's corner slot.
          for (std::size_t axis = 0; axis < 3; ++axis)
            corner_force[axis] = t == 0 ? f[c][axis] : corner_force[axis] + f[c][axis];
        });
      }
      for (std::size_t axis = 0; axis < 3; ++axis) out[i][axis] += corner_force[axis];
    }
  }
  return out;
}

double element_elastic_energy(const SimulationSetup& setup, const std::vector<Point3>& positions) {
  double energy = 0.0;
  for_each_term(setup, table_of(setup), [&](auto element_law, const kernels::ElementTermView<double>& view) {
    using Law = decltype(element_law);
    double term_energy = 0.0;
    for (std::size_t e = 0; e < setup.tetrahedra.size(); ++e) {
      double x[4][3];
      tetrahedron_corners(setup.tetrahedra, e, positions, x);
      term_energy += Law::energy(Law::material(view, static_cast<int>(e)), x);
    }
    energy += term_energy;
  });
  return energy;
}

std::vector<ElementStressOutput> element_stress_outputs(const SimulationSetup& setup,
                                                        const std::vector<Point3>& positions) {
  std::vector<ElementStressOutput> out;
  for_each_term(setup, table_of(setup), [&](auto element_law, const kernels::ElementTermView<double>& view) {
    using Law = decltype(element_law);
    ElementStressOutput output{Law::kStressOutput, std::vector<double>(setup.tetrahedra.size())};
    for (std::size_t e = 0; e < setup.tetrahedra.size(); ++e) {
      double x[4][3];
      tetrahedron_corners(setup.tetrahedra, e, positions, x);
      output.values[e] = Law::stress_output(Law::material(view, static_cast<int>(e)), x);
    }
    out.push_back(std::move(output));
  });
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
  if (setup.elements.empty()) {
    message << "; springs cannot tell an element from its mirror image: give the springs a volume term "
               "(springs: {volume_term: true}) or use model: "
            << default_fem_law().model_keyword;
  } else {
    message << "; the load is too large for the mesh here: refine it, lower the load, or raise the stiffness";
  }
  return message.str();
}

}  // namespace fmpc::sim

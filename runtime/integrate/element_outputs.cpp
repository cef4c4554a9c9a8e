// What the element terms contribute to the host-side sums both backends share (double): internal forces at chosen
// vertices (probes), elastic energy, element stress outputs for frames, the model's name and the inversion message.
// Generic over the element kinds and laws: each term's are visited once per call (kernels/element_laws.h).
#include <sstream>

#include "kernels/element_laws.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

namespace {

kernels::StrainTableView table_of(const SimulationSetup& setup) {
  return setup.strain_stiffness ? strain_table_view(*setup.strain_stiffness)
                                : kernels::StrainTableView{nullptr, nullptr, 0};
}

// visit(Element, Law, view) for each element term in list order, its view reading the strain table where its law
// does and its kind's nodal pass at `positions` where it has one.
template <typename Visit>
void for_each_term(const SimulationSetup& setup, const kernels::StrainTableView& table,
                   const std::vector<Point3>& positions, Visit visit) {
  for (std::size_t t = 0; t < setup.elements.terms.size(); ++t) {
    kernels::ElementTermView<double> view = element_term_view(setup.elements, t, &table);
    const NodalField nodal = nodal_field(setup.elements.geometry, view, positions);
    nodal.attach(view);
    kernels::visit_element_term(view.element, view.law,
                                [&](auto kind, auto element_law) { visit(kind, element_law, view); });
  }
}

}  // namespace

std::string model_name(const SimulationSetup& setup) {
  if (setup.springs.size() > 0 || setup.elements.empty()) return "springs";
  const char* keyword = element_law_row(setup.elements.terms.front().law).model_keyword;
  return keyword != nullptr && setup.elements.geometry.kind == default_element_kind().kind ? keyword : "fem";
}

std::vector<Point3> internal_forces(const SimulationSetup& setup, const std::vector<Point3>& positions,
                                    const std::vector<Point3>& velocities, const std::vector<double>& stiffness,
                                    const std::vector<std::int32_t>& vertices, const ElementTermStates* states) {
  std::vector<Point3> out(vertices.size(), Point3{0.0, 0.0, 0.0});
  const SpringNetwork& net = setup.springs;
  const kernels::SpringLawParameters<double> law{setup.law, setup.basafa_k2_over_k1, setup.basafa_xc};
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const auto v = static_cast<std::size_t>(vertices[i]);
    for (auto e = net.adjacency_offset[v]; e < net.adjacency_offset[v + 1]; ++e) {
      const auto s = static_cast<std::size_t>(net.adjacency_spring[static_cast<std::size_t>(e)]);
      const auto o = static_cast<std::size_t>(adjacency_neighbour(net, v, static_cast<std::size_t>(e)));
      double f[3];
      kernels::spring_force_on_vertex(
          positions[o][0] - positions[v][0], positions[o][1] - positions[v][1], positions[o][2] - positions[v][2],
          velocities[o][0] - velocities[v][0], velocities[o][1] - velocities[v][1], velocities[o][2] - velocities[v][2],
          net.rest_length[s], stiffness[s], net.damping.empty() ? 0.0 : net.damping[s], law, f[0], f[1], f[2]);
      for (std::size_t axis = 0; axis < 3; ++axis) out[i][axis] += f[axis];
    }
  }
  if (setup.elements.empty()) return out;
  const ElementGeometry& geometry = setup.elements.geometry;
  const kernels::StrainTableView table = table_of(setup);
  // Per vertex the terms' node forces in the backends' order: for each node, term after term.
  std::vector<kernels::ElementTermView<double>> views;
  std::vector<NodalField> nodal;
  nodal.reserve(setup.elements.terms.size());
  for (std::size_t t = 0; t < setup.elements.terms.size(); ++t) {
    views.push_back(element_term_view(setup.elements, t, &table));
    nodal.push_back(nodal_field(geometry, views.back(), positions));
    nodal.back().attach(views.back());
    // The stress at the state's time t_n (the start-of-step constants: the convolution's stress exactly).
    const ElementTerm& term = setup.elements.terms[t];
    const int width = point_state_width(term);
    if (states == nullptr || width == 0 || t >= states->size() || (*states)[t].empty()) continue;
    const int points = static_cast<int>((*states)[t].size()) / width;
    views.back().state = {const_cast<double*>((*states)[t].data()), width, points};
    views.back().prony = prony_constants(term.prony, 0.0, false);
  }
  const auto N = static_cast<std::size_t>(geometry.nodes_per_element);
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const auto v = static_cast<std::size_t>(vertices[i]);
    for (auto k = geometry.corner_offset[v]; k < geometry.corner_offset[v + 1]; ++k) {
      const auto entry = static_cast<std::size_t>(geometry.corner_index[static_cast<std::size_t>(k)]);
      const std::size_t e = entry / N, c = entry % N;
      double node_force[3] = {0.0, 0.0, 0.0};
      for (std::size_t t = 0; t < views.size(); ++t) {
        kernels::visit_element_term(views[t].element, views[t].law, [&](auto kind, auto element_law) {
          using Element = decltype(kind);
          constexpr int M = Element::kNodes;
          double x[M][3], u[M][3], f[M][3];
          element_node_rows<M>(geometry, e, positions, x);
          element_node_rows<M>(geometry, e, velocities, u);
          // Velocities only where the term is damped, as the element pass reads them.
          Element::template forces<decltype(element_law)>(views[t], static_cast<int>(e), x,
                                                          views[t].stiffness_damping ? u : nullptr, f);
          // The first term's force as it is, later ones added: the element pass's node slot.
          for (std::size_t axis = 0; axis < 3; ++axis)
            node_force[axis] = t == 0 ? f[c][axis] : node_force[axis] + f[c][axis];
        });
      }
      for (std::size_t axis = 0; axis < 3; ++axis) out[i][axis] += node_force[axis];
    }
  }
  return out;
}

double element_elastic_energy(const SimulationSetup& setup, const std::vector<Point3>& positions) {
  double energy = 0.0;
  const ElementGeometry& geometry = setup.elements.geometry;
  for_each_term(setup, table_of(setup), positions, [&](auto kind, auto element_law, const kernels::ElementTermView<double>& view) {
    using Element = decltype(kind);
    double term_energy = 0.0;
    for (std::size_t e = 0; e < geometry.size(); ++e) {
      double x[Element::kNodes][3];
      element_node_rows<Element::kNodes>(geometry, e, positions, x);
      term_energy += Element::template energy<decltype(element_law)>(view, static_cast<int>(e), x);
    }
    energy += term_energy;
  });
  return energy;
}

std::vector<ElementStressOutput> element_stress_outputs(const SimulationSetup& setup,
                                                        const std::vector<Point3>& positions) {
  std::vector<ElementStressOutput> out;
  const ElementGeometry& geometry = setup.elements.geometry;
  for_each_term(setup, table_of(setup), positions, [&](auto kind, auto element_law, const kernels::ElementTermView<double>& view) {
    using Element = decltype(kind);
    using Law = decltype(element_law);
    ElementStressOutput output{Law::kStressOutput, std::vector<double>(geometry.size())};
    for (std::size_t e = 0; e < geometry.size(); ++e) {
      double x[Element::kNodes][3];
      element_node_rows<Element::kNodes>(geometry, e, positions, x);
      output.values[e] = Element::template stress_output<Law>(view, static_cast<int>(e), x);
    }
    out.push_back(std::move(output));
  });
  return out;
}

std::string inversion_message(const SimulationSetup& setup, const InversionReport& report) {
  std::ostringstream message;
  const Tetrahedron& t = setup.tetrahedra[static_cast<std::size_t>(report.first_element)];
  // A kind beyond the tetrahedron's corners is named: its test is its own (a quadratic element's Jacobian at its
  // quadrature points), which can fail while its corner tetrahedron is positive.
  const int kind = setup.elements.empty() ? kernels::kTetrahedronKind : setup.elements.geometry.kind;
  if (kind == kernels::kTetrahedronKind)
    message << "tetrahedron " << report.first_element << " (vertices ";
  else
    message << element_kind_row(kind).keyword << " element " << report.first_element << " (corners ";
  message << t[0] << ", " << t[1] << ", " << t[2] << ", " << t[3] << ") turned inside out ";
  if (report.first_step == 0)
    message << "at the start";
  else
    message << "at step " << report.first_step << " (t = " << report.first_time << " s)";
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

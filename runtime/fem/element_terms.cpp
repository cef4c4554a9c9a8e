#include "runtime/fem/element_terms.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "diagnostics/number_format.h"

namespace fmpc::sim {

std::optional<ElementGeometry> element_geometry(const std::vector<Point3>& points,
                                                const std::vector<Tetrahedron>& tetrahedra, int kind,
                                                DiagnosticList& diagnostics) {
  ElementGeometry geometry;
  const std::size_t count = tetrahedra.size();
  geometry.rest_inverse.resize(9 * count);
  geometry.rest_volume.resize(count);
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
    tetrahedron_corners(tetrahedra, e, points, x);
    for (std::size_t a = 0; a < 4; ++a)
      for (std::size_t b = a + 1; b < 4; ++b)
        longest =
            std::max(longest, distance(points[static_cast<std::size_t>(t[a])], points[static_cast<std::size_t>(t[b])]));
    const double volume = kernels::tetrahedron_volume(x);
    // The mesh check's test for a degenerate element (docs/simulator.md), and the orientation every mesh keeps.
    if (!(volume > 1e-9 * longest * longest * longest)) {
      diagnostics.error(SourceRange{}, "tetrahedron " + std::to_string(e) + " (vertices " + std::to_string(t[0]) +
                                           ", " + std::to_string(t[1]) + ", " + std::to_string(t[2]) + ", " +
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
    double* inverse = geometry.rest_inverse.data() + 9 * e;
    inverse[0] = (dm[4] * dm[8] - dm[5] * dm[7]) / det;
    inverse[1] = (dm[2] * dm[7] - dm[1] * dm[8]) / det;
    inverse[2] = (dm[1] * dm[5] - dm[2] * dm[4]) / det;
    inverse[3] = (dm[5] * dm[6] - dm[3] * dm[8]) / det;
    inverse[4] = (dm[0] * dm[8] - dm[2] * dm[6]) / det;
    inverse[5] = (dm[2] * dm[3] - dm[0] * dm[5]) / det;
    inverse[6] = (dm[3] * dm[7] - dm[4] * dm[6]) / det;
    inverse[7] = (dm[1] * dm[6] - dm[0] * dm[7]) / det;
    inverse[8] = (dm[0] * dm[4] - dm[1] * dm[3]) / det;
    geometry.rest_volume[e] = volume;
  }
  geometry.kind = kind;
  kernels::visit_element_term(kind, 0, [&](auto element_kind, auto) {
    using Element = decltype(element_kind);
    geometry.nodes_per_element = Element::kNodes;
    geometry.nodes.reserve(static_cast<std::size_t>(Element::kNodes) * count);
    // Each mesh edge's node once, numbered in the order the elements meet them.
    std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> edge_vertex;
    for (const Tetrahedron& t : tetrahedra) {
      geometry.nodes.insert(geometry.nodes.end(), t.begin(), t.end());
      if constexpr (Element::kEdgeNodes > 0) {
        for (int m = 0; m < Element::kEdgeNodes; ++m) {
          const std::int32_t a = t[static_cast<std::size_t>(Element::edge_end(m, 0))];
          const std::int32_t b = t[static_cast<std::size_t>(Element::edge_end(m, 1))];
          const auto key = std::make_pair(std::min(a, b), std::max(a, b));
          auto found = edge_vertex.find(key);
          if (found == edge_vertex.end()) {
            const auto index = static_cast<std::int32_t>(points.size() + geometry.added_vertex_ends.size());
            geometry.added_vertex_ends.push_back({key.first, key.second});
            found = edge_vertex.emplace(key, index).first;
          }
          geometry.nodes.push_back(found->second);
        }
      }
    }
  });
  build_node_csr(geometry, points.size() + geometry.added_vertex_ends.size());
  return geometry;
}

std::vector<Point3> with_added_vertices(const std::vector<Point3>& points, const ElementGeometry& geometry) {
  std::vector<Point3> out = points;
  out.reserve(points.size() + geometry.added_vertex_ends.size());
  for (const auto& ends : geometry.added_vertex_ends) {
    const Point3& a = points[static_cast<std::size_t>(ends[0])];
    const Point3& b = points[static_cast<std::size_t>(ends[1])];
    out.push_back({0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])});
  }
  return out;
}

std::vector<double> element_lumped_masses(const ElementGeometry& geometry, std::size_t vertex_count, double density) {
  std::vector<double> mass(vertex_count, 0.0);
  kernels::visit_element_term(geometry.kind, 0, [&](auto element_kind, auto) {
    using Element = decltype(element_kind);
    constexpr auto N = static_cast<std::size_t>(Element::kNodes);
    for (std::size_t e = 0; e < geometry.size(); ++e)
      for (std::size_t a = 0; a < N; ++a)
        mass[static_cast<std::size_t>(geometry.nodes[N * e + a])] +=
            density * geometry.rest_volume[e] * Element::kMassFraction[a];
  });
  return mass;
}

void build_node_csr(ElementGeometry& geometry, std::size_t vertex_count) {
  const std::size_t entries = geometry.nodes.size();
  geometry.corner_offset.assign(vertex_count + 1, 0);
  for (const std::int32_t v : geometry.nodes) ++geometry.corner_offset[static_cast<std::size_t>(v) + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) geometry.corner_offset[v + 1] += geometry.corner_offset[v];
  geometry.corner_index.resize(entries);
  geometry.corner_slot.resize(entries);
  std::vector<std::int32_t> next(geometry.corner_offset.begin(), geometry.corner_offset.end() - 1);
  for (std::size_t k = 0; k < entries; ++k) {
    const std::int32_t slot = next[static_cast<std::size_t>(geometry.nodes[k])]++;
    geometry.corner_index[static_cast<std::size_t>(slot)] = static_cast<std::int32_t>(k);
    geometry.corner_slot[k] = slot;
  }
}

kernels::ElementTermView<double> element_term_view(const ElementTerms& terms, std::size_t term,
                                                   const kernels::StrainTableView* table) {
  const ElementTerm& t = terms.terms[term];
  kernels::ElementTermView<double> view{};
  view.law = t.law;
  view.element = terms.geometry.kind;
  view.count = static_cast<int>(terms.geometry.size());
  view.corners = terms.geometry.nodes.data();
  view.corner_slot = terms.geometry.corner_slot.data();
  view.rest_inverse = terms.geometry.rest_inverse.data();
  view.rest_volume = terms.geometry.rest_volume.data();
  for (int p = 0; p < kernels::kMostLawParameters; ++p)
    view.parameter[p] = t.parameter[p].empty() ? nullptr : t.parameter[p].data();
  view.stiffness_damping = t.stiffness_damping.empty() ? nullptr : t.stiffness_damping.data();
  view.strain_table = table && reads_strain_table(t) ? *table : kernels::StrainTableView{nullptr, nullptr, 0};
  for (std::size_t i = 0; i < t.prony.size() && i < static_cast<std::size_t>(kernels::kMostPronyTerms); ++i)
    view.prony_weight[i] = t.prony[i].element_weight.empty() ? nullptr : t.prony[i].element_weight.data();
  return view;
}

void NodalField::attach(kernels::ElementTermView<double>& view) const {
  view.nodal_pressure = pressure.empty() ? nullptr : pressure.data();
  view.nodal_dilatation = dilatation.empty() ? nullptr : dilatation.data();
}

NodalField nodal_field(const ElementGeometry& geometry, const kernels::ElementTermView<double>& view,
                       const std::vector<Point3>& positions) {
  NodalField field;
  if (!kernels::element_kind_has_nodal_pass(view.element)) return field;
  const std::size_t n = positions.size();
  std::vector<double> x(n), y(n), z(n);
  for (std::size_t v = 0; v < n; ++v) {
    x[v] = positions[v][0];
    y[v] = positions[v][1];
    z[v] = positions[v][2];
  }
  const kernels::StateView<double> state{x.data(), y.data(), z.data(), nullptr, nullptr, nullptr};
  std::vector<kernels::CornerForce<double>> shares(geometry.nodes.size());
  kernels::visit_element_term(view.element, view.law, [&](auto kind, auto element_law) {
    for (int e = 0; e < view.count; ++e)
      kernels::element_nodal_shares<decltype(kind), decltype(element_law)>(e, view, state, shares.data());
  });
  const kernels::CornerForceView<double> gathered{geometry.corner_offset.data(), geometry.corner_index.data(),
                                                  shares.data()};
  field.pressure.resize(n);
  field.dilatation.resize(n);
  for (std::size_t v = 0; v < n; ++v)
    kernels::nodal_pressure_at(static_cast<int>(v), gathered, field.pressure[v], field.dilatation[v]);
  return field;
}

kernels::PronyConstants<double> prony_constants(const std::vector<PronyTerm>& prony, double dt, bool step_end_stress) {
  kernels::PronyConstants<double> c{};
  c.count = static_cast<int>(std::min<std::size_t>(prony.size(), kernels::kMostPronyTerms));
  double scale = 1.0;
  for (int i = 0; i < c.count; ++i) {
    const PronyTerm& term = prony[static_cast<std::size_t>(i)];
    const bool per_element = !term.element_weight.empty();
    const double weight = per_element ? 1.0 : term.weight;
    if (dt > 0.0) {
      const double ratio = dt / term.time;
      c.decay[i] = std::exp(-ratio);
      // (1 - exp(-r)) / r without the cancellation of 1 - exp(-r) at small r.
      c.gain[i] = weight * (-std::expm1(-ratio) / ratio);
    } else {
      c.decay[i] = 1.0;
      c.gain[i] = weight;
    }
    if (per_element)
      c.stress_scale_per_weight[i] = step_end_stress ? c.gain[i] - 1.0 : 0.0;
    else
      scale += c.gain[i] - weight;
    c.stress_decay[i] = step_end_stress ? c.decay[i] : 1.0;
    c.stress_gain[i] = step_end_stress ? c.gain[i] : weight;
  }
  c.stress_scale = step_end_stress ? scale : 1.0;
  return c;
}

int point_state_width(const ElementTerm& term) {
  return term.prony.empty() ? 0 : kernels::prony_state_width(static_cast<int>(term.prony.size()));
}

int points_per_element(int kind) {
  return kernels::visit_element_term(kind, 0, [](auto element_kind, auto) { return decltype(element_kind)::kPoints; });
}

bool has_point_state(const ElementTerms& terms) {
  for (const ElementTerm& term : terms.terms)
    if (point_state_width(term) > 0) return true;
  return false;
}

bool reads_strain_table(const ElementTerm& term) {
  return kernels::visit_element_law(term.law,
                                    [](auto element_law) { return decltype(element_law)::kStrainTableModulus; });
}

void assign_element_damping(const ElementGeometry& geometry, ElementTerm& term, const std::vector<double>& vertex_mass,
                            double ratio, double rayleigh_stiffness) {
  term.stiffness_damping.clear();
  if (ratio == 0.0 && rayleigh_stiffness == 0.0) return;
  double total_mass = 0.0, total_volume = 0.0;
  for (const double m : vertex_mass) total_mass += m;
  for (const double v : geometry.rest_volume) total_volume += v;
  const double density = total_volume > 0.0 ? total_mass / total_volume : 0.0;
  std::vector<double> damping(geometry.size());
  kernels::ElementTermView<double> view{};
  view.law = term.law;
  view.element = geometry.kind;
  view.count = static_cast<int>(geometry.size());
  view.corners = geometry.nodes.data();
  view.corner_slot = geometry.corner_slot.data();
  view.rest_inverse = geometry.rest_inverse.data();
  view.rest_volume = geometry.rest_volume.data();
  for (int p = 0; p < kernels::kMostLawParameters; ++p)
    view.parameter[p] = term.parameter[p].empty() ? nullptr : term.parameter[p].data();
  view.stiffness_damping = nullptr;
  view.strain_table = {nullptr, nullptr, 0};
  kernels::visit_element_term(geometry.kind, term.law, [&](auto kind, auto element_law) {
    using Element = decltype(kind);
    using Law = decltype(element_law);
    for (std::size_t e = 0; e < geometry.size(); ++e) {
      const double stiffness = Element::template stiffness_bound<Law>(view, static_cast<int>(e));
      // The element's lightest node: its own fastest mode moves that node most.
      double fraction = Element::kMassFraction[0];
      for (const double f : Element::kMassFraction) fraction = std::min(fraction, f);
      const double corner_mass = density * geometry.rest_volume[e] * fraction;
      const double omega = std::sqrt(stiffness / corner_mass);
      damping[e] = (omega > 0.0 ? 2.0 * ratio / omega : 0.0) + rayleigh_stiffness;
    }
  });
  term.stiffness_damping = std::move(damping);
}

void tetrahedron_corners(const std::vector<Tetrahedron>& tetrahedra, std::size_t e, const std::vector<Point3>& points,
                         double out[4][3]) {
  for (std::size_t a = 0; a < 4; ++a)
    for (std::size_t i = 0; i < 3; ++i) out[a][i] = points[static_cast<std::size_t>(tetrahedra[e][a])][i];
}

}  // namespace fmpc::sim

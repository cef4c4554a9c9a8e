#include <cmath>

#include "diagnostics/number_format.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

namespace {
// The element terms as the backends read them: a known element kind and law (kernels::visit_element_term takes any
// index), at most what the GPU backend holds, each of its law's parameters and its damping one per element, finite
// (a builder from runtime/fem/element_law_registry.h checks the physical ranges with the scene's names; this catches
// setups built by hand), and the geometry's arrays parallel to the tetrahedra, its nodes existing vertices.
// At most kMostPronyTerms terms, each weight in (0, 1) and time positive and finite, the weights summing below 1 (a
// solid keeps a long-term modulus g_inf = 1 - sum g_i > 0). A weight per element (element_weight: one per element)
// may be 0 at an element (that term does not relax there); the sum is checked at every element.
bool validate_prony(const std::vector<PronyTerm>& prony, std::size_t count, const std::string& name,
                    const SourceRange& range, DiagnosticList& diagnostics) {
  if (prony.size() > static_cast<std::size_t>(kernels::kMostPronyTerms)) {
    diagnostics.error(range, name + " has " + std::to_string(prony.size()) + " Prony terms; at most " +
                                 std::to_string(kernels::kMostPronyTerms) + " are allowed");
    return false;
  }
  bool per_element = false;
  for (std::size_t i = 0; i < prony.size(); ++i) {
    const PronyTerm& term = prony[i];
    if (!(term.time > 0.0) || !std::isfinite(term.time) ||
        (term.element_weight.empty() && !(term.weight > 0.0 && term.weight < 1.0))) {
      diagnostics.error(range, name + ": Prony term " + std::to_string(i) + " has weight " +
                                   format_number(term.weight) + " and time " + format_number(term.time) +
                                   " s; a weight is in (0, 1) and a time positive and finite");
      return false;
    }
    if (term.element_weight.empty()) continue;
    per_element = true;
    if (term.element_weight.size() != count) {
      diagnostics.error(range, name + ": Prony term " + std::to_string(i) + " has " +
                                   std::to_string(term.element_weight.size()) + " weights for " +
                                   std::to_string(count) + " elements; give one per element or none");
      return false;
    }
    for (std::size_t e = 0; e < count; ++e) {
      const double g = term.element_weight[e];
      if (g >= 0.0 && g < 1.0) continue;
      diagnostics.error(range, name + ": Prony term " + std::to_string(i) + " has weight " + format_number(g) +
                                   " at element " + std::to_string(e) + "; a weight per element is in [0, 1)");
      return false;
    }
  }
  for (std::size_t e = 0; e < (per_element ? count : 1); ++e) {
    double sum = 0.0;
    for (const PronyTerm& term : prony) sum += prony_weight_at(term, e);
    if (sum < 1.0) continue;
    diagnostics.error(range, name + ": the Prony weights sum to " + format_number(sum) +
                                 (per_element ? " at element " + std::to_string(e) : std::string()) +
                                 "; they must sum below 1 (the long-term modulus is 1 - sum g_i of the law's)");
    return false;
  }
  return true;
}

bool validate_element_terms(const SimulationSetup& setup, const SourceRange& range, DiagnosticList& diagnostics) {
  const ElementTerms& elements = setup.elements;
  if (elements.empty()) return true;
  const std::size_t count = setup.tetrahedra.size();
  const ElementGeometry& geometry = elements.geometry;
  if (geometry.kind < 0 || geometry.kind >= kernels::ElementKinds::count) {
    diagnostics.error(range, "the element terms' geometry has element kind " + std::to_string(geometry.kind) +
                                 ", which is not one of the " + std::to_string(kernels::ElementKinds::count) +
                                 " element kinds");
    return false;
  }
  const int nodes =
      kernels::visit_element_term(geometry.kind, 0, [](auto kind, auto) { return decltype(kind)::kNodes; });
  const auto entries = static_cast<std::size_t>(nodes) * count;
  if (geometry.nodes_per_element != nodes || geometry.nodes.size() != entries || geometry.size() != count ||
      geometry.rest_inverse.size() != 9 * count || geometry.corner_offset.size() != setup.rest_positions.size() + 1 ||
      geometry.corner_index.size() != entries || geometry.corner_slot.size() != entries) {
    diagnostics.error(range, "the element terms' geometry does not match the " + std::to_string(count) +
                                 " tetrahedra; build it with element_geometry from the same mesh");
    return false;
  }
  for (const std::int32_t v : geometry.nodes)
    if (v < 0 || static_cast<std::size_t>(v) >= setup.rest_positions.size()) {
      diagnostics.error(range, "the element terms' geometry has node " + std::to_string(v) + " of " +
                                   std::to_string(setup.rest_positions.size()) + " vertices");
      return false;
    }
  // What the kind does not run yet on either backend (element_kind_limits; what CUDA alone does not run, the CUDA
  // engine refuses: runtime/gpu/gpu_engine_upload.cpp).
  const ElementKindLimits limits = element_kind_limits(geometry.kind);
  const std::string kind = std::string("fem.element ") + element_kind_row(geometry.kind).keyword;
  if (limits.implicit_euler && setup.integrator == Integrator::ImplicitEuler) {
    diagnostics.error(range, kind + " " + limits.implicit_euler + "; choose an explicit integrator or fem.element "
                                  "quadratic, which also does not lock");
    return false;
  }
  if (limits.strain_table && setup.strain_stiffness) {
    diagnostics.error(range, kind + " " + limits.strain_table + "; give material.youngs_modulus or use fem.element "
                                  "quadratic");
    return false;
  }
  if (elements.terms.size() > static_cast<std::size_t>(kernels::kMostElementTerms)) {
    diagnostics.error(range, std::to_string(elements.terms.size()) + " element terms given; a model takes at most " +
                                 std::to_string(kernels::kMostElementTerms));
    return false;
  }
  for (std::size_t t = 0; t < elements.terms.size(); ++t) {
    const ElementTerm& term = elements.terms[t];
    const std::string name = "element term " + std::to_string(t);
    if (term.law < 0 || term.law >= kernels::ElementLaws::count) {
      diagnostics.error(range, name + " has law " + std::to_string(term.law) + ", which is not one of the " +
                                   std::to_string(kernels::ElementLaws::count) + " element laws");
      return false;
    }
    const int parameters =
        kernels::visit_element_law(term.law, [](auto element_law) { return decltype(element_law)::kParameterCount; });
    for (int p = 0; p < kernels::kMostLawParameters; ++p) {
      const std::vector<double>& values = term.parameter[p];
      if (values.size() != (p < parameters ? count : 0)) {
        diagnostics.error(range, name + " has " + std::to_string(values.size()) + " values of parameter " +
                                     std::to_string(p) + " for " + std::to_string(count) +
                                     " tetrahedra; its law takes " + std::to_string(parameters) +
                                     " parameters, one per element each");
        return false;
      }
      for (const double value : values)
        if (!std::isfinite(value)) {
          diagnostics.error(range, name + " has a NaN or infinite parameter " + std::to_string(p));
          return false;
        }
    }
    if (!term.stiffness_damping.empty() && term.stiffness_damping.size() != count) {
      diagnostics.error(range, name + " has " + std::to_string(term.stiffness_damping.size()) + " damping values for " +
                                   std::to_string(count) + " tetrahedra; give one each or none");
      return false;
    }
    for (const double beta : term.stiffness_damping)
      if (!(beta >= 0.0) || !std::isfinite(beta)) {
        diagnostics.error(
            range, name + " has stiffness damping " + std::to_string(beta) + "; it must be finite and non-negative");
        return false;
      }
    if (!validate_prony(term.prony, count, name, range, diagnostics)) return false;
  }
  return true;
}
}  // namespace

bool validate_setup(const SimulationSetup& setup, DiagnosticList& diagnostics) {
  const std::size_t errors_before = diagnostics.error_count();
  SourceRange range;
  const std::size_t n = setup.rest_positions.size();
  const SpringNetwork& net = setup.springs;
  const auto size_error = [&](const char* what, std::size_t given) {
    diagnostics.error(range, std::string(what) + ": " + std::to_string(given) + " given for " + std::to_string(n) +
                                 " vertices; give one per vertex or none");
  };
  if (setup.mass.size() != n) size_error("masses", setup.mass.size());
  if (!setup.initial_positions.empty() && setup.initial_positions.size() != n) {
    size_error("initial positions", setup.initial_positions.size());
  }
  if (!setup.initial_velocities.empty() && setup.initial_velocities.size() != n) {
    size_error("initial velocities", setup.initial_velocities.size());
  }
  if (!setup.external_forces.empty() && setup.external_forces.size() != n) {
    size_error("external forces", setup.external_forces.size());
  }
  if (!setup.fixed_axes.empty() && setup.fixed_axes.size() != n) size_error("fixed axes", setup.fixed_axes.size());
  for (std::size_t v = 0; v < setup.fixed_axes.size(); ++v) {
    if (setup.fixed_axes[v] > 7) {
      diagnostics.error(range, "vertex " + std::to_string(v) + " has fixed-axes mask " +
                                   std::to_string(setup.fixed_axes[v]) + "; a mask holds bits 0 (x), 1 (y), 2 (z)");
      break;
    }
  }
  for (std::size_t v = 0; v < setup.mass.size() && v < n; ++v) {
    if (!(setup.mass[v] > 0.0) || !std::isfinite(setup.mass[v])) {
      diagnostics.error(range, "vertex " + std::to_string(v) + " has mass " + std::to_string(setup.mass[v]) +
                                   "; every vertex needs a positive, finite mass");
      break;
    }
  }
  for (std::size_t v = 0; v < n; ++v) {
    if (!finite_point(setup.rest_positions[v]) ||
        (!setup.initial_positions.empty() && !finite_point(setup.initial_positions[v])) ||
        (!setup.initial_velocities.empty() && !finite_point(setup.initial_velocities[v])) ||
        (!setup.external_forces.empty() && !finite_point(setup.external_forces[v]))) {
      diagnostics.error(range, "vertex " + std::to_string(v) +
                                   " starts with a NaN or infinite position, velocity or "
                                   "force; fix the initial state");
      break;
    }
  }
  if (net.vertex_count != n) {
    diagnostics.error(range, "the spring network has " + std::to_string(net.vertex_count) + " vertices but the setup " +
                                 std::to_string(n) + "; build the springs from the same mesh");
  }
  const std::size_t m = net.size();
  const bool damped = !net.damping.empty();
  if (net.second.size() != m || net.rest_length.size() != m || net.stiffness.size() != m ||
      (damped && net.damping.size() != m)) {
    diagnostics.error(range,
                      "the spring network is incomplete (rest lengths and stiffness are needed for every spring, and "
                      "damping for every spring or none); call compute_rest_lengths, assign_stiffness and "
                      "assign_damping");
    return false;
  }
  if (net.adjacency_offset.size() != net.vertex_count + 1 || net.adjacency_spring.size() != 2 * m) {
    diagnostics.error(range, "the spring adjacency is missing; call build_adjacency");
    return false;
  }
  for (std::size_t s = 0; s < m; ++s) {
    const auto a = net.first[s], b = net.second[s];
    if (a < 0 || b < 0 || static_cast<std::size_t>(a) >= n || static_cast<std::size_t>(b) >= n || a == b) {
      diagnostics.error(range, "spring " + std::to_string(s) + " joins vertices " + std::to_string(a) + " and " +
                                   std::to_string(b) + ", which is not a pair of distinct vertices of the mesh");
      return false;
    }
    if (!(net.rest_length[s] > 0.0) || !std::isfinite(net.rest_length[s])) {
      diagnostics.error(range, "spring " + std::to_string(s) + " (vertices " + std::to_string(a) + ", " +
                                   std::to_string(b) + ") has rest length " + std::to_string(net.rest_length[s]) +
                                   "; rest lengths must be positive: merge duplicate vertices");
      return false;
    }
    const double damping = damped ? net.damping[s] : 0.0;
    if (!(net.stiffness[s] >= 0.0) || !std::isfinite(net.stiffness[s]) || !(damping >= 0.0) ||
        !std::isfinite(damping)) {
      diagnostics.error(range, "spring " + std::to_string(s) + " has stiffness " + std::to_string(net.stiffness[s]) +
                                   " and damping " + std::to_string(damping) +
                                   "; both must be finite and non-negative");
      return false;
    }
  }
  // Every CSR entry of vertex v names a spring at v: the gathers take the entry's other endpoint from the spring.
  if (net.adjacency_offset.front() != 0 || static_cast<std::size_t>(net.adjacency_offset.back()) != 2 * m) {
    diagnostics.error(range,
                      "the spring adjacency's offsets do not span its 2 x springs entries; call build_adjacency");
    return false;
  }
  for (std::size_t v = 0; v < net.vertex_count; ++v) {
    const auto begin = net.adjacency_offset[v], end = net.adjacency_offset[v + 1];
    if (end < begin) {
      diagnostics.error(range, "the spring adjacency's offsets decrease at vertex " + std::to_string(v));
      return false;
    }
    for (auto e = begin; e < end; ++e) {
      const auto s = net.adjacency_spring[static_cast<std::size_t>(e)];
      if (s < 0 || static_cast<std::size_t>(s) >= m ||
          (static_cast<std::size_t>(net.first[static_cast<std::size_t>(s)]) != v &&
           static_cast<std::size_t>(net.second[static_cast<std::size_t>(s)]) != v)) {
        diagnostics.error(range, "the spring adjacency of vertex " + std::to_string(v) + " lists spring " +
                                     std::to_string(s) + ", which does not end at it; call build_adjacency");
        return false;
      }
    }
  }
  for (const auto v : setup.fixed_vertices) {
    if (v < 0 || static_cast<std::size_t>(v) >= n) {
      diagnostics.error(range, "fixed vertex " + std::to_string(v) + " does not exist (the mesh has " +
                                   std::to_string(n) + " vertices, numbered from 0)");
    }
  }
  for (const auto v : setup.recorded_vertices) {
    if (v < 0 || static_cast<std::size_t>(v) >= n) {
      diagnostics.error(range, "recorded vertex " + std::to_string(v) + " does not exist (the mesh has " +
                                   std::to_string(n) + " vertices, numbered from 0)");
    }
  }
  if (!validate_element_terms(setup, range, diagnostics)) return false;
  if (setup.law == kernels::SpringLaw::BasafaFarahmand &&
      (!(setup.basafa_k2_over_k1 >= 0.0) || !(setup.basafa_xc > 0.0))) {
    diagnostics.error(range, "the Basafa-Farahmand law needs K2/K1 >= 0 and Xc > 0");
  }
  if (!(setup.nodal_damping_gamma0 >= 0.0) || !(setup.nodal_damping_gamma1 >= 0.0)) {
    diagnostics.error(range, "nodal damping gamma0 and gamma1 must be non-negative");
  }
  if (setup.time_step && (!(*setup.time_step > 0.0) || !std::isfinite(*setup.time_step))) {
    diagnostics.error(range, "the time step must be a positive, finite number of seconds (or auto)");
  }
  if (!(setup.stability_margin > 0.0 && setup.stability_margin <= 1.0)) {
    diagnostics.error(range, "the stability margin must lie in (0, 1]");
  }
  if (setup.implicit.max_iterations < 0 || !(setup.implicit.tolerance > 0.0 && setup.implicit.tolerance < 1.0)) {
    diagnostics.error(range, "implicit Euler needs a non-negative CG iteration cap (0: twice the unknowns) and a "
                             "relative tolerance in (0, 1)");
  }
  if (setup.implicit.contact_rounds < 1 || setup.implicit.contact_rounds > kernels::kMostContactRounds) {
    diagnostics.error(range, "implicit Euler's contact rounds (implicit.contact_rounds) must be from 1 to " +
                                 std::to_string(kernels::kMostContactRounds) + ", got " +
                                 std::to_string(setup.implicit.contact_rounds));
  }
  if (diagnostics.error_count() != errors_before) return false;
  return validate_loads(setup, diagnostics) && validate_tools(setup, diagnostics);
}

}  // namespace fmpc::sim

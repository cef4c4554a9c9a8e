#include "runtime/fem/fem_model_builder.h"

#include <cmath>
#include <string>

#include "diagnostics/number_format.h"
#include "runtime/fem/element_law_registry.h"

namespace fmpc::sim {

namespace {

// One value per element from a vector of one value or one per element; an error names what was given.
std::optional<std::vector<double>> per_element(const std::vector<double>& values, std::size_t count, const char* what,
                                               DiagnosticList& diagnostics) {
  if (values.size() == 1) return std::vector<double>(count, values.front());
  if (values.size() == count) return values;
  diagnostics.error(SourceRange{}, std::string(what) + ": " + std::to_string(values.size()) + " values for " +
                                       std::to_string(count) + " tetrahedra; give one, or one per tetrahedron");
  return std::nullopt;
}

}  // namespace

std::vector<Point3> tetrahedron_centroids(const Mesh& mesh) {
  std::vector<Point3> out(mesh.tetrahedra.size());
  for (std::size_t e = 0; e < out.size(); ++e)
    for (std::size_t i = 0; i < 3; ++i) {
      double sum = 0.0;
      for (const auto v : mesh.tetrahedra[e]) sum += mesh.points[static_cast<std::size_t>(v)][i];
      out[e][i] = sum / 4.0;
    }
  return out;
}

std::optional<SimulationSetup> build_fem_model(const Mesh& mesh, const FemModelSpec& spec, DiagnosticList& diagnostics) {
  SourceRange range;
  range.file = mesh.source;
  if (!(spec.length_unit > 0.0) || !std::isfinite(spec.length_unit)) {
    diagnostics.error(range, "the length unit must be a positive number of metres per mesh unit");
    return std::nullopt;
  }
  if (mesh.tetrahedra.empty()) {
    diagnostics.error(range,
                      "a finite-element model needs tetrahedra; the mesh has none (a surface mesh can only be "
                      "simulated with springs)");
    return std::nullopt;
  }
  const std::size_t count = mesh.tetrahedra.size();
  const auto youngs = per_element(spec.youngs_modulus, count, "Young's modulus", diagnostics);
  const auto poisson = per_element(spec.poisson_ratio, count, "Poisson ratio", diagnostics);
  if (!youngs || !poisson) return std::nullopt;
  ElementMaterial material;
  material.youngs_modulus = std::move(*youngs);
  material.poisson_ratio = std::move(*poisson);
  material.where = range;
  const ElementLawRow& row = element_law_row(spec.law);
  auto build = row.build(material, diagnostics);
  if (!build) return std::nullopt;
  Mesh scaled = mesh;
  for (Point3& p : scaled.points)
    for (double& coordinate : p) coordinate *= spec.length_unit;
  SimulationSetup setup;
  setup.rest_positions = scaled.points;
  setup.tetrahedra = scaled.tetrahedra;
  setup.springs.vertex_count = scaled.points.size();
  setup.springs.adjacency_offset.assign(scaled.points.size() + 1, 0);
  auto geometry = element_geometry(scaled.points, scaled.tetrahedra, diagnostics);
  if (!geometry) return std::nullopt;
  if (geometry->kind != spec.element) {
    diagnostics.error(range, std::string("internal error: element kind '") + element_kind_row(spec.element).keyword +
                                 "' has no geometry builder in runtime/fem (element_geometry builds '" +
                                 element_kind_row(geometry->kind).keyword + "')");
    return std::nullopt;
  }
  setup.elements.geometry = std::move(*geometry);
  setup.mass = lumped_masses(scaled, spec.mass, diagnostics);
  if (setup.mass.empty()) return std::nullopt;
  if (!(spec.damping_ratio >= 0.0) || !(spec.rayleigh_stiffness >= 0.0)) {
    diagnostics.error(range, "damping ratio and Rayleigh stiffness damping must be finite and non-negative");
    return std::nullopt;
  }
  build->term.prony = spec.prony;
  if (!add_element_term(setup, std::move(build->term), spec.damping_ratio, spec.rayleigh_stiffness, diagnostics))
    return std::nullopt;
  return setup;
}

bool add_element_term(SimulationSetup& setup, ElementTerm term, double damping_ratio, double rayleigh_stiffness,
                      DiagnosticList& diagnostics) {
  if (setup.tetrahedra.empty()) {
    diagnostics.error(SourceRange{}, std::string("an element term (") + element_law_row(term.law).keyword +
                                         ") acts on tetrahedra; the mesh has none (it is a surface mesh)");
    return false;
  }
  if (setup.elements.empty()) {
    auto geometry = element_geometry(setup.rest_positions, setup.tetrahedra, diagnostics);
    if (!geometry) return false;
    setup.elements.geometry = std::move(*geometry);
  }
  assign_element_damping(setup.elements.geometry, term, setup.mass, damping_ratio, rayleigh_stiffness);
  setup.elements.terms.push_back(std::move(term));
  return true;
}

}  // namespace fmpc::sim

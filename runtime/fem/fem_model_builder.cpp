#include "runtime/fem/fem_model_builder.h"

#include <algorithm>
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
  if (spec.element < 0 || spec.element >= kernels::ElementKinds::count) {
    diagnostics.error(range, "element kind " + std::to_string(spec.element) + " is not one of the " +
                                 std::to_string(kernels::ElementKinds::count) + " element kinds");
    return std::nullopt;
  }
  // The element kind's range of Poisson ratios, and its locking warning (once, for the largest ratio).
  const ElementKindRow& kind = element_kind_row(spec.element);
  const double largest_nu = *std::max_element(material.poisson_ratio.begin(), material.poisson_ratio.end());
  const SourceRange& nu_where = spec.poisson_where.file.empty() ? range : spec.poisson_where;
  const std::string kind_name = std::string("fem.element ") + kind.keyword;
  if (largest_nu > kind.largest_poisson_ratio) {
    diagnostics.error(nu_where, spec.poisson_field + ": " + format_number(largest_nu) + " is above " +
                                    format_number(kind.largest_poisson_ratio) + ", the most " + kind_name +
                                    " takes; use fem: {element: quadratic} (up to 0.4999) for nearly incompressible "
                                    "tissue");
    return std::nullopt;
  }
  if (largest_nu > kind.locking_poisson_ratio)
    diagnostics.warning(nu_where, "element-locking",
                        spec.poisson_field + " " + format_number(largest_nu) + ": " + kind_name +
                            " locks (is too stiff) above nu = " + format_number(kind.locking_poisson_ratio) + "; " +
                            kind.locking_note,
                        {"use fem: {element: quadratic} for nearly incompressible tissue"});
  const ElementLawRow& row = element_law_row(spec.law);
  auto build = row.build(material, diagnostics);
  if (!build) return std::nullopt;
  Mesh scaled = mesh;
  for (Point3& p : scaled.points)
    for (double& coordinate : p) coordinate *= spec.length_unit;
  SimulationSetup setup;
  auto geometry = element_geometry(scaled.points, scaled.tetrahedra, spec.element, diagnostics);
  if (!geometry) return std::nullopt;
  setup.rest_positions = with_added_vertices(scaled.points, *geometry);
  setup.tetrahedra = scaled.tetrahedra;
  setup.springs.vertex_count = setup.rest_positions.size();
  setup.springs.adjacency_offset.assign(setup.rest_positions.size() + 1, 0);
  setup.mass = lumped_masses(scaled, spec.mass, diagnostics);
  if (setup.mass.empty()) return std::nullopt;
  if (!geometry->added_vertex_ends.empty()) {
    // The kind's own lumping at the mesh's density (a total mass gives rho = M / V).
    double total_mass = 0.0, total_volume = 0.0;
    for (const double m : setup.mass) total_mass += m;
    for (const double v : geometry->rest_volume) total_volume += v;
    const double density = spec.mass.source == MassSpec::Source::Density ? spec.mass.value : total_mass / total_volume;
    setup.mass = element_lumped_masses(*geometry, setup.rest_positions.size(), density);
  }
  setup.elements.geometry = std::move(*geometry);
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
  if (setup.elements.geometry.nodes.empty()) {
    // Beside springs: linear tetrahedra (the first kind), on the springs' own vertices.
    auto geometry = element_geometry(setup.rest_positions, setup.tetrahedra, 0, diagnostics);
    if (!geometry) return false;
    setup.elements.geometry = std::move(*geometry);
  }
  assign_element_damping(setup.elements.geometry, term, setup.mass, damping_ratio, rayleigh_stiffness);
  setup.elements.terms.push_back(std::move(term));
  return true;
}

void extend_to_added_vertices(SimulationSetup& setup, std::size_t mesh_vertices) {
  const auto& ends = setup.elements.geometry.added_vertex_ends;
  if (ends.empty()) return;
  const std::size_t total = mesh_vertices + ends.size();
  const auto in = [](const std::vector<std::int32_t>& sorted, std::int32_t v) {
    return std::binary_search(sorted.begin(), sorted.end(), v);
  };
  std::vector<std::int32_t> fixed = setup.fixed_vertices;
  std::sort(fixed.begin(), fixed.end());
  std::vector<std::int32_t> probe;
  if (setup.probe && setup.probe->mode == ProbeLoad::Mode::Displacement) {
    probe = setup.probe->vertices;
    std::sort(probe.begin(), probe.end());
  }
  const auto midpoint = [&](std::vector<Point3>& values) {
    if (values.size() != mesh_vertices) return;
    values.resize(total);
    for (std::size_t i = 0; i < ends.size(); ++i)
      for (std::size_t axis = 0; axis < 3; ++axis)
        values[mesh_vertices + i][axis] = 0.5 * (values[static_cast<std::size_t>(ends[i][0])][axis] +
                                                 values[static_cast<std::size_t>(ends[i][1])][axis]);
  };
  midpoint(setup.initial_positions);
  midpoint(setup.initial_velocities);
  if (setup.external_forces.size() == mesh_vertices) setup.external_forces.resize(total, Point3{0.0, 0.0, 0.0});
  if (setup.fixed_axes.size() == mesh_vertices) {
    setup.fixed_axes.resize(total, 0);
    for (std::size_t i = 0; i < ends.size(); ++i)
      setup.fixed_axes[mesh_vertices + i] = static_cast<std::uint8_t>(
          setup.fixed_axes[static_cast<std::size_t>(ends[i][0])] & setup.fixed_axes[static_cast<std::size_t>(ends[i][1])]);
  }
  for (std::size_t i = 0; i < ends.size(); ++i) {
    const auto v = static_cast<std::int32_t>(mesh_vertices + i);
    if (in(fixed, ends[i][0]) && in(fixed, ends[i][1])) setup.fixed_vertices.push_back(v);
    if (in(probe, ends[i][0]) && in(probe, ends[i][1])) setup.probe->vertices.push_back(v);
  }
}

}  // namespace fmpc::sim

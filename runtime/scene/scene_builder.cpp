#include "runtime/scene/scene_builder.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <thread>

#include "compiler/frontend/rule_file_loader.h"
#include "diagnostics/number_format.h"
#include "kernels/table_math.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/fem/fem_model_builder.h"
#include "runtime/io/input_file.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/mesh/mesh_check.h"
#include "runtime/mesh/mesh_refinement.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/scene/parameter_binding.h"
#include "runtime/scene/scene_meshing.h"
#include "runtime/scene/spring_model_builder.h"

namespace fmpc::sim {

std::optional<double> ray_triangle_hit(const Point3& origin, const Point3& direction, const Point3& a, const Point3& b,
                                       const Point3& c) {
  const auto sub = [](const Point3& p, const Point3& q) { return Point3{p[0] - q[0], p[1] - q[1], p[2] - q[2]}; };
  const auto cross = [](const Point3& p, const Point3& q) {
    return Point3{p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]};
  };
  const auto dot = [](const Point3& p, const Point3& q) { return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]; };
  const Point3 edge1 = sub(b, a), edge2 = sub(c, a);
  const Point3 p = cross(direction, edge2);
  const double determinant = dot(edge1, p);
  const double scale = std::sqrt(dot(edge1, edge1) * dot(edge2, edge2) * dot(direction, direction));
  if (!(std::abs(determinant) > 1e-12 * scale)) return std::nullopt;  // parallel to the triangle
  const double inverse = 1.0 / determinant;
  const Point3 s = sub(origin, a);
  const double u = dot(s, p) * inverse;
  if (u < 0.0 || u > 1.0) return std::nullopt;
  const Point3 q = cross(s, edge1);
  const double v = dot(direction, q) * inverse;
  if (v < 0.0 || u + v > 1.0) return std::nullopt;
  const double t = dot(edge2, q) * inverse;
  if (t < 0.0) return std::nullopt;
  return t;
}

namespace {

std::string point_text(const Point3& p) {
  return "(" + format_number(p[0]) + ", " + format_number(p[1]) + ", " + format_number(p[2]) + ")";
}

std::string bounds_text(const Mesh& mesh) {
  Point3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
            std::numeric_limits<double>::infinity()};
  Point3 hi{-lo[0], -lo[1], -lo[2]};
  for (const Point3& p : mesh.points) {
    for (std::size_t i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], p[i]);
      hi[i] = std::max(hi[i], p[i]);
    }
  }
  return "the mesh spans " + point_text(lo) + " to " + point_text(hi) + " (mesh units)";
}

// The diagonal of the mesh's bounding box (mesh units): the scale a scene's lengths are held against.
double mesh_size(const Mesh& mesh) {
  if (mesh.points.empty()) return 0.0;
  Point3 low = mesh.points.front(), high = low;
  for (const Point3& p : mesh.points)
    for (std::size_t a = 0; a < 3; ++a) low[a] = std::min(low[a], p[a]), high[a] = std::max(high[a], p[a]);
  return distance(low, high);
}

// "N times the mesh's size (S mesh units, its bounding box's diagonal)".
std::string against_mesh_size(double length, double size) {
  return significant_digits(length / size, 3) + " times the mesh's size (" + significant_digits(size, 3) +
         " mesh units, its bounding box's diagonal)";
}

std::optional<Mesh> load_mesh(const Scene& scene, BuiltScene& built, DiagnosticList& diagnostics) {
  switch (scene.mesh.kind) {
    case SceneMesh::Kind::Surface: return mesh_scene_surface(scene, built, diagnostics);
    case SceneMesh::Kind::File: {
      DiagnosticList mesh_diagnostics;
      auto mesh = read_mesh_file(scene.mesh.file, mesh_diagnostics);
      diagnostics.append(mesh_diagnostics);
      if (!mesh && mesh_diagnostics.empty())
        diagnostics.error(scene.range_of("mesh.file"), "mesh.file: cannot read '" + scene.mesh.file + "'");
      return mesh;
    }
    case SceneMesh::Kind::Box: {
      Mesh mesh = generate_box(scene.mesh.box, diagnostics);
      if (diagnostics.has_errors()) return std::nullopt;
      return mesh;
    }
    case SceneMesh::Kind::Ellipsoid: {
      Mesh mesh = generate_ellipsoid(scene.mesh.ellipsoid, diagnostics);
      if (diagnostics.has_errors()) return std::nullopt;
      return mesh;
    }
  }
  return std::nullopt;
}

// Old (file) vertex index -> repaired index; an error names the field when it is out of range or was removed.
std::optional<std::int32_t> remap(std::int32_t index, const std::vector<std::int32_t>& new_index, const Scene& scene,
                                  const std::string& field, DiagnosticList& diagnostics) {
  if (index < 0 || static_cast<std::size_t>(index) >= new_index.size()) {
    diagnostics.error(scene.range_of(field), field + ": vertex " + std::to_string(index) +
                                                 " is out of range; the mesh has " + std::to_string(new_index.size()) +
                                                 " vertices (0 to " + std::to_string(new_index.size() - 1) + ")");
    return std::nullopt;
  }
  const std::int32_t mapped = new_index[static_cast<std::size_t>(index)];
  if (mapped < 0) {
    diagnostics.error(scene.range_of(field), field + ": vertex " + std::to_string(index) +
                                                 " belongs to no element (the mesh repair removed it); pick another");
    return std::nullopt;
  }
  return mapped;
}

bool inside(const SceneBox& box, const Point3& p) {
  for (std::size_t i = 0; i < 3; ++i)
    if (p[i] < box.min[i] || p[i] > box.max[i]) return false;
  return true;
}

// The vertices a split surface (mesh.split_surface) added on edges whose two ends `indices` name (split_selection),
// as file indices; none without a split. The indices are in range (the caller checked them).
std::vector<std::int32_t> split_midpoints_of(const std::optional<MeshingRun>& meshing,
                                             const std::vector<std::int32_t>& indices, std::size_t vertex_count) {
  std::vector<std::int32_t> added;
  if (!meshing || !meshing->result.split || indices.empty()) return added;
  std::vector<unsigned char> named(vertex_count, 0);
  for (const auto index : indices) named[static_cast<std::size_t>(index)] = 1;
  split_selection(*meshing->result.split, meshing->result.surface_vertices, named);
  for (std::size_t v = meshing->result.surface_vertices; v < named.size(); ++v)
    if (named[v]) added.push_back(static_cast<std::int32_t>(v));
  return added;
}

// The vertices a selection (of `fixed` or a `hold` entry) names; errors name `prefix`.box or .plane when one holds
// no vertex. Indices name the surface's vertices; where the meshing split the surface (mesh.split_surface), a
// midpoint of an edge whose ends are both named is named too (split_selection).
std::optional<std::vector<std::int32_t>> selected_vertices(const Scene& scene, const SceneFixed& selection,
                                                           const std::string& prefix, const Mesh& mesh,
                                                           const std::vector<std::int32_t>& new_index,
                                                           const std::optional<MeshingRun>& meshing,
                                                           DiagnosticList& diagnostics) {
  std::vector<unsigned char> fixed(mesh.points.size(), 0);
  bool ok = true;
  for (const auto index : selection.indices) {
    const auto mapped = remap(index, new_index, scene, prefix + ".indices", diagnostics);
    if (mapped) fixed[static_cast<std::size_t>(*mapped)] = 1;
    ok = ok && mapped;
  }
  if (ok)
    for (const auto v : split_midpoints_of(meshing, selection.indices, new_index.size())) {
      const std::int32_t mapped = new_index[static_cast<std::size_t>(v)];
      if (mapped >= 0) fixed[static_cast<std::size_t>(mapped)] = 1;
    }
  for (const SceneBox& box : selection.boxes) {
    std::size_t count = 0;
    for (std::size_t v = 0; v < mesh.points.size(); ++v) {
      if (!inside(box, mesh.points[v])) continue;
      fixed[v] = 1;
      ++count;
    }
    if (count == 0) {
      diagnostics.error(scene.range_of(prefix + ".box"), prefix + ".box: no vertex lies in the box " +
                                                             point_text(box.min) + " to " + point_text(box.max) + "; " +
                                                             bounds_text(mesh));
      ok = false;
    }
  }
  for (const SceneFixed::Plane& plane : selection.planes) {
    const Point3& n = plane.normal;
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    std::size_t count = 0;
    for (std::size_t v = 0; v < mesh.points.size(); ++v) {
      const Point3& p = mesh.points[v];
      const double signed_distance =
          ((p[0] - plane.point[0]) * n[0] + (p[1] - plane.point[1]) * n[1] + (p[2] - plane.point[2]) * n[2]) / length;
      if (std::abs(signed_distance) > plane.tolerance) continue;
      fixed[v] = 1;
      ++count;
    }
    // A slab thicker than the whole mesh is a unit mistake (a tolerance meant in millimetres on a mesh in metres):
    // it selects whatever lies near the plane across the whole mesh, without a word.
    const double size = mesh_size(mesh);
    if (count > 0 && size > 0.0 && plane.tolerance > size)
      diagnostics.warning(scene.range_of(plane.field + ".tolerance"), "scene-scale",
                          plane.field + ".tolerance: " + format_number(plane.tolerance) + " is " +
                              against_mesh_size(plane.tolerance, size) + ": the plane selects " +
                              std::to_string(count) + " of the " + std::to_string(mesh.points.size()) +
                              " vertices, every one within that distance of it",
                          {"the tolerance is in mesh units (mesh.units); a plane through a face needs a small "
                           "fraction of an edge, e.g. 1e-6 of the mesh's size"});
    if (count == 0) {
      diagnostics.error(scene.range_of(prefix + ".plane"),
                        prefix + ".plane: no vertex lies within " + format_number(plane.tolerance) +
                            " of the plane through " + point_text(plane.point) + " with normal " +
                            point_text(plane.normal) + "; raise 'tolerance' or move the plane (" + bounds_text(mesh) +
                            ")");
      ok = false;
    }
  }
  if (!ok) return std::nullopt;
  std::vector<std::int32_t> out;
  for (std::size_t v = 0; v < fixed.size(); ++v)
    if (fixed[v]) out.push_back(static_cast<std::int32_t>(v));
  return out;
}

// The surface the ray can hit: boundary triangles of a tetrahedral mesh, or the triangles of a surface mesh.
std::optional<std::vector<std::int32_t>> pick_by_ray(const Scene& scene, const SceneProbe& probe, const Mesh& mesh,
                                                     DiagnosticList& diagnostics) {
  const std::vector<Triangle> surface = mesh.tetrahedra.empty() ? mesh.triangles : boundary_triangles(mesh);
  double best = std::numeric_limits<double>::infinity();
  std::size_t hit_triangle = 0;
  for (std::size_t t = 0; t < surface.size(); ++t) {
    const Triangle& tri = surface[t];
    const auto hit = ray_triangle_hit(probe.ray_origin, probe.ray_direction, mesh.points[static_cast<std::size_t>(tri[0])],
                                      mesh.points[static_cast<std::size_t>(tri[1])],
                                      mesh.points[static_cast<std::size_t>(tri[2])]);
    if (hit && *hit < best) {
      best = *hit;
      hit_triangle = t;
    }
  }
  if (!std::isfinite(best)) {
    diagnostics.error(scene.range_of("loads.probe.ray"), "loads.probe.ray: the ray from " + point_text(probe.ray_origin) +
                                                             " along " + point_text(probe.ray_direction) +
                                                             " hits no surface of the mesh; " + bounds_text(mesh));
    return std::nullopt;
  }
  const Point3 hit{probe.ray_origin[0] + best * probe.ray_direction[0],
                   probe.ray_origin[1] + best * probe.ray_direction[1],
                   probe.ray_origin[2] + best * probe.ray_direction[2]};
  std::vector<unsigned char> on_surface(mesh.points.size(), 0);
  for (const Triangle& tri : surface)
    for (const auto v : tri) on_surface[static_cast<std::size_t>(v)] = 1;
  std::vector<std::int32_t> picked;
  for (std::size_t v = 0; v < mesh.points.size(); ++v)
    if (on_surface[v] && distance(mesh.points[v], hit) <= probe.radius) picked.push_back(static_cast<std::int32_t>(v));
  // A radius out of the mesh's scale is a unit mistake: beyond the whole mesh it picks the whole surface in reach; a
  // positive one that reaches no vertex picks one corner, as radius 0 does. Neither said so.
  const double size = mesh_size(mesh);
  if (size > 0.0 && probe.radius > size)
    diagnostics.warning(scene.range_of("loads.probe.radius"), "scene-scale",
                        "loads.probe.radius: " + format_number(probe.radius) + " is " +
                            against_mesh_size(probe.radius, size) + ": the probe picks " +
                            std::to_string(picked.size()) + " surface vertices, all in reach of the hit",
                        {"the radius is in mesh units (mesh.units)"});
  if (probe.radius > 0.0 && picked.empty()) {
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t v = 0; v < mesh.points.size(); ++v)
      if (on_surface[v]) nearest = std::min(nearest, distance(mesh.points[v], hit));
    diagnostics.warning(scene.range_of("loads.probe.radius"), "scene-scale",
                        "loads.probe.radius: no surface vertex lies within " + format_number(probe.radius) +
                            " of the point the ray hits (the nearest is " + significant_digits(nearest, 3) +
                            " away): the probe takes the hit triangle's nearest corner alone, as with radius 0",
                        {"the radius is in mesh units (mesh.units); give at least " + significant_digits(nearest, 3) +
                         " to pick the vertices around the hit"});
  }
  if (picked.empty()) {  // radius 0 or smaller than the triangle: the hit triangle's nearest corner
    const Triangle& tri = surface[hit_triangle];
    std::int32_t nearest = tri[0];
    for (const auto v : tri)
      if (distance(mesh.points[static_cast<std::size_t>(v)], hit) <
          distance(mesh.points[static_cast<std::size_t>(nearest)], hit))
        nearest = v;
    picked.push_back(nearest);
  }
  return picked;
}

struct Selection {
  const FuzzySystem* system = nullptr;
  int output = -1;
  std::vector<int> bound;  // material.bind's other outputs
};

// Young's modulus's output among `outputs` of `what` ("system 'liver'", "the table"): material.output, the output
// material.bind gives youngs_modulus, or the only output.
std::optional<int> select_output(const Scene& scene, const std::vector<std::string>& outputs, const std::string& what,
                                 DiagnosticList& diagnostics) {
  const SceneMaterial& material = scene.material;
  if (material.output.empty() && material.bind.empty()) {
    if (outputs.size() == 1) return 0;
    const std::string field = material.source == SceneMaterial::Source::Table ? "material.table" : "material.rules";
    diagnostics.error(scene.range_of(field), "material.output: " + what + " has " + std::to_string(outputs.size()) +
                                                 " outputs; name the Young's modulus with 'output'");
    return std::nullopt;
  }
  for (const ParameterBinding& bound : material.bind)
    if (bound.parameter == "youngs_modulus")
      return output_index(scene, outputs, bound.output, "material.bind.youngs_modulus.output", what, diagnostics);
  return output_index(scene, outputs, material.output, "material.output", what, diagnostics);
}

std::optional<Selection> select_rules(const Scene& scene, const RuleFile& rules, DiagnosticList& diagnostics) {
  Selection selection;
  const SceneMaterial& material = scene.material;
  std::vector<std::string> names;
  for (const FuzzySystem& s : rules.systems) names.push_back(s.name);
  if (material.system.empty()) {
    if (rules.systems.size() != 1) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      diagnostics.error(scene.range_of("material.rules"), "material.system: the rule file holds " +
                                                              std::to_string(rules.systems.size()) +
                                                              " systems (" + list + "); name one with 'system'");
      return std::nullopt;
    }
    selection.system = &rules.systems.front();
  } else {
    for (const FuzzySystem& s : rules.systems)
      if (s.name == material.system) selection.system = &s;
    if (!selection.system) {
      std::vector<std::string> notes;
      if (auto suggestion = closest_name(material.system, names)) notes.push_back("did you mean '" + *suggestion + "'?");
      diagnostics.error(scene.range_of("material.system"),
                        "material.system: the rule file has no system '" + material.system + "'", notes);
      return std::nullopt;
    }
  }
  const FuzzySystem& system = *selection.system;
  std::vector<std::string> outputs;
  for (const Variable& v : system.outputs) outputs.push_back(v.name);
  const std::string what = "system '" + system.name + "'";
  const auto output = select_output(scene, outputs, what, diagnostics);
  const auto bound = bound_output_indices(scene, outputs, what, diagnostics);
  if (!output || !bound) return std::nullopt;
  selection.output = *output;
  selection.bound = *bound;
  return selection;
}

std::optional<int> select_table_output(const Scene& scene, const LookupTable& table, DiagnosticList& diagnostics) {
  return select_output(scene, table.output_names, "the table", diagnostics);
}

// Where each spring sits, for regions: its midpoint in mesh units.
std::vector<Point3> spring_midpoints(const SimulationSetup& setup, double length_unit) {
  std::vector<Point3> midpoints(setup.springs.size());
  for (std::size_t s = 0; s < midpoints.size(); ++s) {
    const Point3& a = setup.rest_positions[static_cast<std::size_t>(setup.springs.first[s])];
    const Point3& b = setup.rest_positions[static_cast<std::size_t>(setup.springs.second[s])];
    for (std::size_t i = 0; i < 3; ++i) midpoints[s][i] = (a[i] + b[i]) / 2.0 / length_unit;  // back to mesh units
  }
  return midpoints;
}

// The fuzzy material: a modulus per material point (spring midpoints or element centroids, mesh units) or a strain
// table, from the rules or the compiled table.
std::optional<MaterialBinding> bind_fuzzy_material(const Scene& scene, const std::vector<Point3>& points,
                                                   MaterialPoint kind, BuiltScene& built, const LoadedRules* loaded,
                                                   DiagnosticList& diagnostics) {
  const std::string field =
      scene.material.source == SceneMaterial::Source::Table ? "material.table" : "material.rules";
  const bool is_table = scene.material.source == SceneMaterial::Source::Table;
  if (!is_table && loaded != nullptr && loaded->path == scene.material.file) {
    built.sources.emplace_back(loaded->path, loaded->text);
    const auto selection = select_rules(scene, loaded->rules, diagnostics);
    if (!selection) return std::nullopt;
    return bind_rules(*selection->system, selection->output, scene, points, kind, diagnostics, selection->bound);
  }
  std::string read_error;
  const auto text = read_input_file(scene.material.file, is_table ? kMaxTableFileBytes : kMaxRuleFileBytes,
                                    is_table ? "table file" : "rule file", read_error);
  if (!text) {
    diagnostics.error(scene.range_of(field),
                      field + ": " + read_error + " (relative paths are relative to the scene file's folder)");
    return std::nullopt;
  }
  if (scene.material.source == SceneMaterial::Source::Table) {
    const auto table = parse_fzt(scene.material.file, *text, diagnostics);
    if (!table) return std::nullopt;
    const auto output = select_table_output(scene, *table, diagnostics);
    const auto bound = bound_output_indices(scene, table->output_names, "the table", diagnostics);
    if (!output || !bound) return std::nullopt;
    return bind_table(*table, *output, scene, points, kind, diagnostics, *bound);
  }
  built.sources.emplace_back(scene.material.file, *text);
  DiagnosticList rule_diagnostics;
  const RuleFile rules = load_rule_file(scene.material.file, *text, rule_diagnostics);
  // Lint-free loading: only the rule file's errors matter here (fmpc check reports the rest).
  for (const Diagnostic& d : rule_diagnostics.items())
    if (d.severity == Severity::Error) diagnostics.add(d);
  if (rule_diagnostics.has_errors()) {
    diagnostics.error(scene.range_of("material.rules"),
                      "material.rules: '" + scene.material.file + "' has errors (above); fix them with fmpc check");
    return std::nullopt;
  }
  const auto selection = select_rules(scene, rules, diagnostics);
  if (!selection) return std::nullopt;
  return bind_rules(*selection->system, selection->output, scene, points, kind, diagnostics, selection->bound);
}

// A regional value at each point (mesh units): the first region containing it, else the default.
std::optional<std::vector<double>> regional_values(const RegionalValue& value, const std::vector<Point3>& points,
                                                   const Scene& scene, const std::string& field,
                                                   DiagnosticList& diagnostics) {
  std::vector<double> out(points.size(), value.value);
  for (std::size_t i = 0; i < points.size(); ++i) {
    bool found = false;
    for (const RegionValue& region : value.regions) {
      if (!inside(region.box, points[i])) continue;
      out[i] = region.value;
      found = true;
      break;
    }
    if (found || value.has_default) continue;
    diagnostics.error(scene.range_of(field), field + ": element " + std::to_string(i) + " (centroid " +
                                                 point_text(points[i]) +
                                                 ") lies in no region and there is no default; add 'default'");
    return std::nullopt;
  }
  return out;
}

// A finite-element model of the scene's element law: Young's modulus per element from the material source (at each
// element's centroid for regions), the Poisson ratio, masses and damping.
std::optional<SimulationSetup> build_fem(const Scene& scene, BuiltScene& built, const LoadedRules* loaded,
                                         DiagnosticList& diagnostics) {
  const SceneMaterial& material = scene.material;
  const std::vector<Point3> centroids = tetrahedron_centroids(built.mesh);
  FemModelSpec spec;
  spec.law = scene.element_law;
  spec.poisson_where = scene.range_of("material.poisson_ratio");
  spec.element = scene.element_kind;
  // "FEM (law corotational, element linear)": the registry's names, as the scene writes them.
  const std::string model = std::string("FEM (law ") + element_law_row(scene.element_law).keyword + ", element " +
                            element_kind_row(scene.element_kind).keyword + ")";
  spec.length_unit = scene.mesh.unit;
  spec.mass = scene.mass;
  spec.damping_ratio = scene.damping.ratio;
  spec.rayleigh_stiffness = scene.rayleigh.stiffness;
  spec.prony = material.prony;
  const RegionalValue poisson = material.poisson_ratio.value_or(RegionalValue{kDefaultPoissonRatio, true, {}});
  const auto nu = regional_values(poisson, centroids, scene, "material.poisson_ratio", diagnostics);
  if (!nu) return std::nullopt;
  spec.poisson_ratio = *nu;
  std::optional<StrainStiffnessTable> strain_table;
  switch (material.source) {
    case SceneMaterial::Source::YoungsModulus:
      spec.youngs_modulus = {material.value * 1000.0};  // kPa -> Pa
      built.stiffness_description = model + " with E = " + format_number(material.value) + " kPa";
      break;
    case SceneMaterial::Source::Rules:
    case SceneMaterial::Source::Table: {
      built.material = bind_fuzzy_material(scene, centroids, MaterialPoint::ElementCentroid, built, loaded, diagnostics);
      if (!built.material) return std::nullopt;
      const MaterialBinding& binding = *built.material;
      if (!binding.bound.empty()) {
        ElementMaterial bound;
        bound.youngs_modulus = std::move(spec.youngs_modulus);
        bound.poisson_ratio = std::move(spec.poisson_ratio);
        if (!apply_bound_parameters(scene, element_law_row(scene.element_law), binding, centroids, bound, spec.prony,
                                    diagnostics))
          return std::nullopt;
        spec.youngs_modulus = std::move(bound.youngs_modulus);
        spec.poisson_ratio = std::move(bound.poisson_ratio);
      }
      if (binding.strain.empty()) {
        spec.youngs_modulus = binding.modulus_per_spring;  // one per material point: here, per element
        built.stiffness_description =
            model + " with E from '" + binding.system + "' output '" + binding.output +
            "': " + format_number(binding.modulus_min / 1000.0) +
            (binding.modulus_min == binding.modulus_max ? "" : " to " + format_number(binding.modulus_max / 1000.0)) +
            " kPa";
      } else {
        StrainStiffnessTable table;
        table.strain = binding.strain;
        table.modulus = binding.strain_modulus;
        spec.youngs_modulus = {strain_table_rest_modulus(table)};
        strain_table = std::move(table);
        built.stiffness_description = model + " with E(principal strain) from '" + binding.system + "' output '" +
                                      binding.output + "', " + std::to_string(binding.strain.size()) +
                                      "-point table: " + format_number(binding.modulus_min / 1000.0) + " to " +
                                      format_number(binding.modulus_max / 1000.0) + " kPa";
      }
      break;
    }
    case SceneMaterial::Source::Stiffness:
    case SceneMaterial::Source::StiffnessOverLength:
      return std::nullopt;  // refused by the scene parser
  }
  std::string nu_text = poisson.regions.empty() ? format_number(poisson.value) : "per region";
  if (built.material)
    for (std::size_t b = 0; b < material.bind.size(); ++b) {
      if (material.bind[b].parameter != "poisson_ratio") continue;
      const auto [low, high] = std::minmax_element(spec.poisson_ratio.begin(), spec.poisson_ratio.end());
      nu_text = format_number(*low) + (*low == *high ? "" : " to " + format_number(*high)) + " from '" +
                built.material->system + "' output '" + material.bind[b].output + "'";
      spec.poisson_where = scene.range_of("material.bind.poisson_ratio.output");
      spec.poisson_field = "material.bind.poisson_ratio (output '" + material.bind[b].output + "')";
    }
  built.stiffness_description += ", nu = " + nu_text;
  if (!spec.prony.empty()) {
    built.stiffness_description += "; viscoelastic, Prony series (g, tau)";
    for (const PronyTerm& term : spec.prony) {
      std::string weight = format_number(term.weight);
      if (!term.element_weight.empty()) {
        const auto low = *std::min_element(term.element_weight.begin(), term.element_weight.end());
        weight = format_number(low) + " to " + weight + " per element";
      }
      built.stiffness_description += " (" + weight + ", " + format_number(term.time) + " s)";
    }
  }
  auto setup = build_fem_model(built.mesh, spec, diagnostics);
  if (!setup) return std::nullopt;
  setup->strain_stiffness = std::move(strain_table);
  return setup;
}

// Springs with the element law that goes beside them (springs: {volume_term: true}) reaching the scene's Poisson
// ratio: the law's builder gives each element its parameters at the element's Young's modulus (at its centroid; one
// value for a constant material) and the factor the springs' stiffness is scaled by.
bool add_term_beside_springs(const Scene& scene, const BuiltScene& built, const LoadedRules* loaded,
                             SimulationSetup& setup, std::string& description, DiagnosticList& diagnostics) {
  const SceneMaterial& material = scene.material;
  const SourceRange where = scene.range_of("springs");
  const std::string fem = default_fem_law().model_keyword;
  if (built.mesh.tetrahedra.empty()) {
    diagnostics.error(where, "springs.volume_term: the volume term acts on tetrahedra; this mesh has only triangles");
    return false;
  }
  if (material.source == SceneMaterial::Source::Stiffness ||
      material.source == SceneMaterial::Source::StiffnessOverLength) {
    diagnostics.error(where, "springs.volume_term: the volume term is calibrated from Young's modulus and the Poisson "
                             "ratio; give material.youngs_modulus, rules or table instead of spring constants");
    return false;
  }
  if (setup.strain_stiffness) {
    diagnostics.error(where, "springs.volume_term: a strain-dependent modulus is not supported with the volume term; "
                             "use model: " + fem + " for strain-dependent tissue");
    return false;
  }
  const RegionalValue poisson = material.poisson_ratio.value_or(RegionalValue{kDefaultPoissonRatio, true, {}});
  if (!poisson.regions.empty()) {
    diagnostics.error(scene.range_of("material.poisson_ratio"),
                      "material.poisson_ratio: springs with the volume term take one ratio for the whole scene; use "
                      "model: " + fem + " for a ratio per region");
    return false;
  }
  // Young's modulus per element: constant, or the rules at each element's centroid.
  ElementMaterial element_material;
  element_material.youngs_modulus.assign(built.mesh.tetrahedra.size(), material.value * 1000.0);
  element_material.poisson_ratio.assign(built.mesh.tetrahedra.size(), poisson.value);
  element_material.spring_mapping = material.mapping;
  element_material.where = scene.range_of("material.poisson_ratio");
  if (built.material) {
    if (built.material->modulus_min == built.material->modulus_max) {
      std::fill(element_material.youngs_modulus.begin(), element_material.youngs_modulus.end(),
                built.material->modulus_min);
    } else {
      BuiltScene scratch;
      const auto per_element = bind_fuzzy_material(scene, tetrahedron_centroids(built.mesh), MaterialPoint::ElementCentroid,
                                                    scratch, loaded, diagnostics);
      if (!per_element) return false;
      element_material.youngs_modulus = per_element->modulus_per_spring;
    }
  }
  auto build = element_law_beside_springs().build(element_material, diagnostics);
  if (!build) return false;
  for (double& k : setup.springs.stiffness) k *= build->spring_modulus_scale;
  if (!add_element_term(setup, std::move(build->term), scene.damping.ratio, scene.rayleigh.stiffness, diagnostics))
    return false;
  description += build->description;
  return true;
}

std::optional<SimulationSetup> build_springs(const Scene& scene, BuiltScene& built, const LoadedRules* loaded,
                                             DiagnosticList& diagnostics) {
  const SceneMaterial& material = scene.material;
  if (!material.prony.empty()) {
    diagnostics.error(scene.range_of("material.viscoelastic"),
                      "material.viscoelastic acts on an element law; a spring network has none: use a finite-element "
                      "model (model: corotational_fem), or remove 'viscoelastic'");
    return std::nullopt;
  }
  SpringModelSpec model;
  model.length_unit = scene.mesh.unit;
  model.triangle_springs = scene.triangle_springs;
  model.mass = scene.mass;
  model.damping = scene.damping;
  model.stiffness.thickness = material.thickness;
  model.stiffness.flexion_fraction = material.flexion_fraction;
  switch (material.source) {
    case SceneMaterial::Source::Stiffness:
      model.stiffness.mapping = StiffnessMapping::Uniform;
      model.stiffness.value = material.value;
      built.stiffness_description = "uniform k = " + format_number(material.value) + " N/m";
      break;
    case SceneMaterial::Source::StiffnessOverLength:
      model.stiffness.mapping = StiffnessMapping::StiffnessOverLength;
      model.stiffness.value = material.value;
      built.stiffness_description = "k = " + format_number(material.value) + " N / rest length (SOFA)";
      break;
    case SceneMaterial::Source::YoungsModulus:
      model.stiffness.mapping = material.mapping;
      model.stiffness.value = material.value * 1000.0;  // kPa -> Pa
      built.stiffness_description =
          std::string(mapping_citation(material.mapping)) + " with E = " + format_number(material.value) + " kPa";
      break;
    case SceneMaterial::Source::Rules:
    case SceneMaterial::Source::Table:
      // Springs first (their midpoints place them in regions); k for E = 1 Pa is each spring's mapping factor.
      model.stiffness.mapping = material.mapping;
      model.stiffness.value = 1.0;
      break;
  }
  auto setup = build_spring_model(built.mesh, model, diagnostics);
  if (!setup) return std::nullopt;
  setup->tetrahedra = built.mesh.tetrahedra;
  if (material.source == SceneMaterial::Source::Rules || material.source == SceneMaterial::Source::Table) {
    built.material = bind_fuzzy_material(scene, spring_midpoints(*setup, scene.mesh.unit), MaterialPoint::SpringMidpoint,
                                         built, loaded, diagnostics);
    if (!built.material) return std::nullopt;
    const std::vector<double> factor = setup->springs.stiffness;
    const MaterialBinding& binding = *built.material;
    if (binding.strain.empty()) {
      for (std::size_t s = 0; s < factor.size(); ++s) setup->springs.stiffness[s] = binding.modulus_per_spring[s] * factor[s];
      built.stiffness_description = std::string(mapping_citation(material.mapping)) + " with E from '" +
                                    binding.system + "' output '" + binding.output +
                                    "': " + format_number(binding.modulus_min / 1000.0) +
                                    (binding.modulus_min == binding.modulus_max
                                         ? ""
                                         : " to " + format_number(binding.modulus_max / 1000.0)) +
                                    " kPa";
    } else {
      StrainStiffnessTable table;
      table.strain = binding.strain;
      table.modulus = binding.strain_modulus;
      table.stiffness_per_modulus = factor;
      // The rest stiffness (strain 0) sets the damping coefficients.
      const double rest_modulus = strain_table_rest_modulus(table);
      for (std::size_t s = 0; s < factor.size(); ++s) setup->springs.stiffness[s] = rest_modulus * factor[s];
      setup->strain_stiffness = std::move(table);
      built.stiffness_description = std::string(mapping_citation(material.mapping)) + " with E(strain) from '" +
                                    binding.system + "' output '" +
                                    binding.output + "', " + std::to_string(binding.strain.size()) +
                                    "-point table over strain " + format_number(binding.strain.front()) + " to " +
                                    format_number(binding.strain.back()) + ": " +
                                    format_number(binding.modulus_min / 1000.0) + " to " +
                                    format_number(binding.modulus_max / 1000.0) + " kPa";
    }
    if (!assign_damping(setup->springs, setup->mass, scene.damping, diagnostics)) return std::nullopt;
  }
  if (scene.volume_term) {
    if (!add_term_beside_springs(scene, built, loaded, *setup, built.stiffness_description, diagnostics))
      return std::nullopt;
    // The springs were scaled to the calibrated modulus: their dashpots follow.
    if (!assign_damping(setup->springs, setup->mass, scene.damping, diagnostics)) return std::nullopt;
  }
  // Rayleigh's stiffness-proportional part: c += beta k on every spring.
  if (scene.rayleigh.stiffness > 0.0) {
    SpringNetwork& net = setup->springs;
    if (net.damping.empty()) net.damping.assign(net.size(), 0.0);
    for (std::size_t s = 0; s < net.size(); ++s) net.damping[s] += scene.rayleigh.stiffness * net.stiffness[s];
  }
  return setup;
}

std::optional<BuiltScene> finish_scene(const Scene& scene, const MeshRepairResult& repair, BuiltScene built,
                                       SimulationSetup setup_value, std::size_t errors, DiagnosticList& diagnostics) {
  std::optional<SimulationSetup> setup = std::move(setup_value);
  const auto fixed =
      selected_vertices(scene, scene.fixed, "fixed", built.mesh, repair.new_vertex_index, built.meshing, diagnostics);
  if (fixed) setup->fixed_vertices = *fixed;
  for (const SceneHold& hold : scene.holds) {
    const auto held = selected_vertices(scene, hold.selection, hold.field, built.mesh, repair.new_vertex_index,
                                        built.meshing, diagnostics);
    if (!held) continue;
    if (setup->fixed_axes.empty()) setup->fixed_axes.assign(built.mesh.points.size(), 0);
    for (const auto v : *held)
      setup->fixed_axes[static_cast<std::size_t>(v)] =
          static_cast<std::uint8_t>(setup->fixed_axes[static_cast<std::size_t>(v)] | hold.axes);
  }
  if (scene.probe) {
    const SceneProbe& probe = *scene.probe;
    std::optional<std::vector<std::int32_t>> picked;
    if (probe.by_ray) {
      picked = pick_by_ray(scene, probe, built.mesh, diagnostics);
    } else {
      picked.emplace();
      for (const auto index : probe.indices) {
        const auto mapped = remap(index, repair.new_vertex_index, scene, "loads.probe.indices", diagnostics);
        if (!mapped) {
          picked.reset();
          break;
        }
        if (std::find(picked->begin(), picked->end(), *mapped) != picked->end()) {
          diagnostics.error(scene.range_of("loads.probe.indices"),
                            "loads.probe.indices: vertex " + std::to_string(index) + " is given twice");
          picked.reset();
          break;
        }
        picked->push_back(*mapped);
      }
      // A split surface's midpoints between picked vertices move with them (as fixed ones stay, above).
      if (picked)
        for (const auto v : split_midpoints_of(built.meshing, probe.indices, repair.new_vertex_index.size())) {
          const std::int32_t mapped = repair.new_vertex_index[static_cast<std::size_t>(v)];
          if (mapped >= 0) picked->push_back(mapped);
        }
    }
    if (picked && fixed) {
      for (const auto v : *picked) {
        if (!std::binary_search(fixed->begin(), fixed->end(), v)) continue;
        diagnostics.error(scene.range_of("loads.probe"), "loads.probe: vertex " + std::to_string(v) +
                                                             " is picked by the probe and also fixed; a vertex can be "
                                                             "one or the other");
        picked.reset();
        break;
      }
    }
    if (picked && probe.mode == ProbeLoad::Mode::Displacement) {
      // A travel far outside the mesh's scale is a unit mistake (5 m on a mesh in millimetres ran and reported
      // 5,000 mm), and a travel given at once is an instant step; both ran without a word.
      // The travel is in metres, the mesh in its own units: the size is compared in metres.
      const double size = mesh_size(built.mesh) * scene.mesh.unit;
      const double travel = std::sqrt(probe.target[0] * probe.target[0] + probe.target[1] * probe.target[1] +
                                      probe.target[2] * probe.target[2]);
      if (size > 0.0 && (travel > size || (travel > 0.0 && travel < 1e-6 * size)))
        diagnostics.warning(scene.range_of("loads.probe.displacement"), "probe-load",
                            "loads.probe.displacement: the probe travels " + format_number(travel) + " m, " +
                                significant_digits(travel / size, 3) + " times the mesh's size (" + significant_digits(size, 3) +
                                " m, its bounding box's diagonal)" +
                                (travel > size ? ", further than the whole mesh" : ", below what float can resolve") +
                                ": displacements are in metres whatever mesh.units says",
                            {"check the units: 5 mm is 0.005"});
      if (probe.ramp == 0.0)
        diagnostics.warning(scene.range_of("loads.probe"), "probe-load",
                            "loads.probe.ramp is 0: the probe moves its whole travel in the first step, an instant "
                            "step that shakes the mesh (and its reaction force) at the highest frequencies",
                            {"give a ramp of several of the mesh's vibration periods, e.g. a tenth of the duration"});
    }
    if (picked) {
      ProbeLoad load;
      load.mode = probe.mode;
      load.vertices = *picked;
      load.target = probe.target;
      load.ramp_time = probe.ramp;
      load.cycles = probe.cycles;
      setup->probe = load;
    }
  }
  extend_to_added_vertices(*setup, built.mesh.points.size());
  // Tools: mesh units to metres; Simulation::create checks that none starts inside the tissue.
  for (const SceneTool& scene_tool : scene.tools) {
    RigidTool tool;
    tool.name = scene_tool.name;
    tool.shape = scene_tool.shape;
    tool.radius = scene_tool.radius * scene.mesh.unit;
    tool.length = scene_tool.length * scene.mesh.unit;
    tool.range = scene.range_of(scene_tool.field);
    for (ToolKeyframe keyframe : scene_tool.path) {
      for (double& coordinate : keyframe.pose.position) coordinate *= scene.mesh.unit;
      tool.path.push_back(keyframe);
    }
    setup->tools.push_back(std::move(tool));
  }
  setup->contact_stiffness_ratio = scene.contact_stiffness_ratio;
  setup->contact_damping_ratio = scene.contact_damping_ratio;
  setup->gravity = scene.gravity;
  setup->law = scene.law.law;
  setup->basafa_k2_over_k1 = scene.law.k2_over_k1;
  setup->basafa_xc = scene.law.xc;
  setup->nodal_damping_gamma0 = scene.law.gamma0;
  setup->nodal_damping_gamma1 = scene.law.gamma1;
  setup->integrator = scene.integrator;
  setup->precision = scene.precision;
  setup->time_step = scene.dt;
  setup->time_step_range = scene.range_of("dt");
  setup->source_range = SourceRange{scene.path, 0, 0, 0, 0};
  setup->mass_damping = scene.rayleigh.mass;
  setup->on_inversion = scene.on_inversion;
  setup->implicit = scene.solver;
  // Automatic: one thread below 10,000 vertices (implicit Euler: 2,000, its step being a linear solve), where a
  // step takes microseconds and handing work to other threads costs more than it saves; otherwise up to 8.
  const std::size_t serial_below = scene.integrator == Integrator::ImplicitEuler ? 2000 : 10000;
  setup->threads = scene.threads > 0 ? scene.threads
                   : built.mesh.points.size() < serial_below
                       ? 1u
                       : std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  if (diagnostics.error_count() != errors) return std::nullopt;
  built.setup = std::move(*setup);
  return built;
}

}  // namespace

double strain_table_rest_modulus(const StrainStiffnessTable& table) {
  const kernels::StrainTableView view{table.strain.data(), table.modulus.data(), static_cast<int>(table.strain.size())};
  return kernels::strain_table_modulus(view, 0.0);
}

std::optional<BuiltScene> build_scene(const Scene& scene, DiagnosticList& diagnostics, unsigned refinements,
                                      const LoadedRules* rules) {
  const std::size_t errors = diagnostics.error_count();
  BuiltScene built;
  auto mesh = load_mesh(scene, built, diagnostics);
  if (!mesh) return std::nullopt;
  const MeshRepairResult repair = repair_mesh(*mesh);
  std::vector<std::string> repaired;
  for (const MeshFinding& finding : repair.findings)
    if (finding.repaired) repaired.push_back(finding_message(finding));
  if (!repaired.empty()) {
    std::vector<std::string> notes(repaired.begin(), repaired.begin() + std::min<std::ptrdiff_t>(5, static_cast<std::ptrdiff_t>(repaired.size())));
    if (repaired.size() > 5) notes.push_back("... and " + std::to_string(repaired.size() - 5) + " more");
    diagnostics.warning(scene.range_of("mesh"), "mesh-repaired",
                        "mesh: " + std::to_string(repaired.size()) + " defect(s) repaired before building springs",
                        notes);
  }
  built.mesh = std::move(*mesh);
  if (scene.mesh.refinements > 0) {
    // Checked before the refinement allocates: each level multiplies the tetrahedra by 8.
    const double refined = static_cast<double>(built.mesh.tetrahedra.size()) * std::pow(8.0, scene.mesh.refinements);
    if (refined > static_cast<double>(kMaxRefinedTetrahedra)) {
      diagnostics.error(scene.range_of("mesh.refinements"),
                        "mesh.refinements: " + std::to_string(built.mesh.tetrahedra.size()) + " tetrahedra refined " +
                            std::to_string(scene.mesh.refinements) + " times make " + format_number(refined) +
                            ", above the limit of " + std::to_string(kMaxRefinedTetrahedra) + "; refine less");
      return std::nullopt;
    }
  }
  for (unsigned level = 0; level < scene.mesh.refinements + refinements; ++level)
    built.mesh = subdivide_tetrahedra(built.mesh);
  std::optional<SimulationSetup> setup =
      scene.model == ForceModel::Elements ? build_fem(scene, built, rules, diagnostics)
                                                 : build_springs(scene, built, rules, diagnostics);
  if (!setup) return std::nullopt;
  return finish_scene(scene, repair, std::move(built), std::move(*setup), errors, diagnostics);
}

}  // namespace fmpc::sim

#include "runtime/scene/scene_builder.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <thread>

#include "compiler/frontend/rule_file_loader.h"
#include "diagnostics/number_format.h"
#include "kernels/table_math.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/mesh/mesh_check.h"
#include "runtime/mesh/mesh_reader.h"
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

std::optional<std::string> read_file(const std::string& path, const SourceRange& where, const std::string& field,
                                     DiagnosticList& diagnostics) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    diagnostics.error(where, field + ": cannot read '" + path + "': " + std::strerror(errno) +
                                 " (relative paths are relative to the scene file's folder)");
    return std::nullopt;
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

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

std::optional<Mesh> load_mesh(const Scene& scene, DiagnosticList& diagnostics) {
  switch (scene.mesh.kind) {
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

std::optional<std::vector<std::int32_t>> fixed_vertices(const Scene& scene, const Mesh& mesh,
                                                        const std::vector<std::int32_t>& new_index,
                                                        DiagnosticList& diagnostics) {
  std::vector<unsigned char> fixed(mesh.points.size(), 0);
  bool ok = true;
  for (const auto index : scene.fixed.indices) {
    const auto mapped = remap(index, new_index, scene, "fixed.indices", diagnostics);
    if (mapped) fixed[static_cast<std::size_t>(*mapped)] = 1;
    ok = ok && mapped;
  }
  for (const SceneBox& box : scene.fixed.boxes) {
    std::size_t count = 0;
    for (std::size_t v = 0; v < mesh.points.size(); ++v) {
      if (!inside(box, mesh.points[v])) continue;
      fixed[v] = 1;
      ++count;
    }
    if (count == 0) {
      diagnostics.error(scene.range_of("fixed.box"), "fixed.box: no vertex lies in the box " + point_text(box.min) +
                                                         " to " + point_text(box.max) + "; " + bounds_text(mesh));
      ok = false;
    }
  }
  for (const SceneFixed::Plane& plane : scene.fixed.planes) {
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
    if (count == 0) {
      diagnostics.error(scene.range_of("fixed.plane"),
                        "fixed.plane: no vertex lies within " + format_number(plane.tolerance) + " of the plane through " +
                            point_text(plane.point) + " with normal " + point_text(plane.normal) +
                            "; raise 'tolerance' or move the plane (" + bounds_text(mesh) + ")");
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
};

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
  if (material.output.empty()) {
    if (outputs.size() != 1) {
      diagnostics.error(scene.range_of("material.rules"), "material.output: system '" + system.name + "' has " +
                                                              std::to_string(outputs.size()) +
                                                              " outputs; name the Young's modulus with 'output'");
      return std::nullopt;
    }
    selection.output = 0;
  } else {
    selection.output = system.find_output(material.output);
    if (selection.output < 0) {
      std::vector<std::string> notes;
      if (auto suggestion = closest_name(material.output, outputs)) notes.push_back("did you mean '" + *suggestion + "'?");
      diagnostics.error(scene.range_of("material.output"),
                        "material.output: system '" + system.name + "' has no output '" + material.output + "'", notes);
      return std::nullopt;
    }
  }
  return selection;
}

std::optional<int> select_table_output(const Scene& scene, const LookupTable& table, DiagnosticList& diagnostics) {
  if (scene.material.output.empty()) {
    if (table.output_names.size() == 1) return 0;
    diagnostics.error(scene.range_of("material.table"), "material.output: the table has " +
                                                            std::to_string(table.output_names.size()) +
                                                            " outputs; name the Young's modulus with 'output'");
    return std::nullopt;
  }
  for (std::size_t i = 0; i < table.output_names.size(); ++i)
    if (table.output_names[i] == scene.material.output) return static_cast<int>(i);
  std::vector<std::string> notes;
  if (auto suggestion = closest_name(scene.material.output, table.output_names))
    notes.push_back("did you mean '" + *suggestion + "'?");
  diagnostics.error(scene.range_of("material.output"),
                    "material.output: the table has no output '" + scene.material.output + "'", notes);
  return std::nullopt;
}

// The fuzzy material: per-spring modulus or a strain table, from the rules or the compiled table.
std::optional<MaterialBinding> bind_fuzzy_material(const Scene& scene, const SimulationSetup& setup,
                                                   double length_unit, BuiltScene& built,
                                                   DiagnosticList& diagnostics) {
  const std::string field =
      scene.material.source == SceneMaterial::Source::Table ? "material.table" : "material.rules";
  const auto text = read_file(scene.material.file, scene.range_of(field), field, diagnostics);
  if (!text) return std::nullopt;
  std::vector<Point3> midpoints(setup.springs.size());
  for (std::size_t s = 0; s < midpoints.size(); ++s) {
    const Point3& a = setup.rest_positions[static_cast<std::size_t>(setup.springs.first[s])];
    const Point3& b = setup.rest_positions[static_cast<std::size_t>(setup.springs.second[s])];
    for (std::size_t i = 0; i < 3; ++i) midpoints[s][i] = (a[i] + b[i]) / 2.0 / length_unit;  // back to mesh units
  }
  if (scene.material.source == SceneMaterial::Source::Table) {
    const auto table = parse_fzt(scene.material.file, *text, diagnostics);
    if (!table) return std::nullopt;
    const auto output = select_table_output(scene, *table, diagnostics);
    if (!output) return std::nullopt;
    return bind_table(*table, *output, scene, midpoints, diagnostics);
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
  return bind_rules(*selection->system, selection->output, scene, midpoints, diagnostics);
}

}  // namespace

std::optional<BuiltScene> build_scene(const Scene& scene, DiagnosticList& diagnostics) {
  const std::size_t errors = diagnostics.error_count();
  BuiltScene built;
  auto mesh = load_mesh(scene, diagnostics);
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

  const SceneMaterial& material = scene.material;
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
  if (material.source == SceneMaterial::Source::Rules || material.source == SceneMaterial::Source::Table) {
    built.material = bind_fuzzy_material(scene, *setup, scene.mesh.unit, built, diagnostics);
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
      std::vector<const double*> breakpoints{table.strain.data()};
      const int counts[1] = {static_cast<int>(table.strain.size())};
      TableView<double> view;
      view.axes = 1;
      view.outputs = 1;
      view.counts = counts;
      view.breakpoints = breakpoints.data();
      view.values = table.modulus.data();
      const double zero = 0.0;
      double rest_modulus = 0.0;
      interpolate_table(view, &zero, &rest_modulus);
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

  const auto fixed = fixed_vertices(scene, built.mesh, repair.new_vertex_index, diagnostics);
  if (fixed) setup->fixed_vertices = *fixed;
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
    if (picked) {
      ProbeLoad load;
      load.mode = probe.mode;
      load.vertices = *picked;
      load.target = probe.target;
      load.ramp_time = probe.ramp;
      setup->probe = load;
    }
  }
  setup->gravity = scene.gravity;
  setup->law = scene.law.law;
  setup->basafa_k2_over_k1 = scene.law.k2_over_k1;
  setup->basafa_xc = scene.law.xc;
  setup->nodal_damping_gamma0 = scene.law.gamma0;
  setup->nodal_damping_gamma1 = scene.law.gamma1;
  setup->integrator = scene.integrator;
  setup->precision = scene.precision;
  setup->time_step = scene.dt;
  // Automatic: one thread below 10,000 vertices, where a step takes microseconds and handing work to other
  // threads costs more than it saves; otherwise up to 8.
  setup->threads = scene.threads > 0 ? scene.threads
                   : built.mesh.points.size() < 10000
                       ? 1u
                       : std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  if (diagnostics.error_count() != errors) return std::nullopt;
  built.setup = std::move(*setup);
  return built;
}

}  // namespace fmpc::sim

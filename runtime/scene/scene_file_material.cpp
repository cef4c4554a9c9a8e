#include "runtime/scene/scene_file_parser.h"

#include <cmath>
#include <initializer_list>

#include "diagnostics/number_format.h"
#include "runtime/io/input_file.h"

namespace fmpc::sim {

void SceneParser::parse_mesh(const YAML::Node& node) {
  remember(node, "mesh");
  const std::vector<std::string> meshing_keys = {"size_far", "size_near", "near_distance", "grading",
                                                 "radius_edge_ratio", "min_dihedral", "keep_surface",
                                                 "split_surface", "smooth_intersections", "refine_near"};
  std::vector<std::string> allowed = {"file", "box", "ellipsoid", "surface", "units", "refinements"};
  allowed.insert(allowed.end(), meshing_keys.begin(), meshing_keys.end());
  if (!check_map(node, "mesh", allowed)) return;
  SceneMesh& mesh = scene_.mesh;
  const int kind = one_of(node, "mesh", {"file", "box", "ellipsoid", "surface"});
  if (kind != 3)
    for (const std::string& key : meshing_keys)
      if (node[key]) error(node[key], "mesh." + key, "'" + key + "' sets how a surface is meshed; it needs 'surface'");
  switch (kind) {
    case 0:
      if (auto file = text(node["file"], "mesh.file")) {
        mesh.kind = SceneMesh::Kind::File;
        mesh.file = resolve(*file);
        check_input_file(node["file"], "mesh.file", mesh.file, kMaxMeshFileBytes, "mesh file");
      }
      break;
    case 1: {
      mesh.kind = SceneMesh::Kind::Box;
      const YAML::Node box = node["box"];
      remember(box, "mesh.box");
      if (!check_map(box, "mesh.box", {"size", "min", "cells"})) break;
      if (!box["size"]) error(box, "mesh.box", "a box needs 'size' [x, y, z] (mesh units)");
      else if (auto size = vector3(box["size"], "mesh.box.size", " (mesh units)")) {
        if (!((*size)[0] > 0.0 && (*size)[1] > 0.0 && (*size)[2] > 0.0))
          error(box["size"], "mesh.box.size", "every size must be positive");
        mesh.box.size = *size;
      }
      if (box["min"])
        if (auto min = vector3(box["min"], "mesh.box.min", " (mesh units)")) mesh.box.minimum = *min;
      if (box["cells"]) {
        const YAML::Node cells = box["cells"];
        if (!cells.IsSequence() || cells.size() != 3) {
          error(cells, "mesh.box.cells", "expected three cell counts [nx, ny, nz] from 1 to 1000, got " +
                                             describe(cells));
        } else {
          int* counts[3] = {&mesh.box.cells_x, &mesh.box.cells_y, &mesh.box.cells_z};
          for (std::size_t i = 0; i < 3; ++i)
            if (auto n = integer(cells[i], "mesh.box.cells", 1, 1000)) *counts[i] = static_cast<int>(*n);
          if (const auto too_large = generated_mesh_too_large(tetrahedron_count(mesh.box)))
            error(cells, "mesh.box.cells", "[" + std::to_string(mesh.box.cells_x) + ", " +
                                               std::to_string(mesh.box.cells_y) + ", " +
                                               std::to_string(mesh.box.cells_z) + "] " + *too_large +
                                               ": use fewer cells");
        }
      }
      break;
    }
    case 2: {
      mesh.kind = SceneMesh::Kind::Ellipsoid;
      const YAML::Node ellipsoid = node["ellipsoid"];
      remember(ellipsoid, "mesh.ellipsoid");
      if (!check_map(ellipsoid, "mesh.ellipsoid", {"radii", "centre", "resolution"})) break;
      if (!ellipsoid["radii"]) error(ellipsoid, "mesh.ellipsoid", "an ellipsoid needs 'radii' [x, y, z] (mesh units)");
      else if (auto radii = vector3(ellipsoid["radii"], "mesh.ellipsoid.radii", " (mesh units)")) {
        if (!((*radii)[0] > 0.0 && (*radii)[1] > 0.0 && (*radii)[2] > 0.0))
          error(ellipsoid["radii"], "mesh.ellipsoid.radii", "every radius must be positive");
        mesh.ellipsoid.radii = *radii;
      }
      if (ellipsoid["centre"])
        if (auto centre = vector3(ellipsoid["centre"], "mesh.ellipsoid.centre", " (mesh units)"))
          mesh.ellipsoid.centre = *centre;
      if (ellipsoid["resolution"])
        if (auto n = integer(ellipsoid["resolution"], "mesh.ellipsoid.resolution", 1, 200)) {
          mesh.ellipsoid.resolution = static_cast<int>(*n);
          if (const auto too_large = generated_mesh_too_large(tetrahedron_count(mesh.ellipsoid)))
            error(ellipsoid["resolution"], "mesh.ellipsoid.resolution",
                  std::to_string(*n) + " " + *too_large + ": use a smaller resolution");
        }
      break;
    }
    case 3:
      if (auto file = text(node["surface"], "mesh.surface")) {
        mesh.kind = SceneMesh::Kind::Surface;
        mesh.file = resolve(*file);
        check_input_file(node["surface"], "mesh.surface", mesh.file, kMaxMeshFileBytes, "mesh file");
      }
      parse_surface_meshing(node);
      break;
    default:
      break;
  }
  if (node["refinements"]) {
    remember(node["refinements"], "mesh.refinements");
    if (auto n = integer(node["refinements"], "mesh.refinements", 0, kMaxSceneMeshRefinements))
      mesh.refinements = static_cast<unsigned>(*n);
  }
  if (node["units"]) {
    const YAML::Node units = node["units"];
    remember(units, "mesh.units");
    double value = 0.0;
    if (units.IsScalar() && units.Scalar() == "m") mesh.unit = 1.0;
    else if (units.IsScalar() && units.Scalar() == "cm") mesh.unit = 0.01;
    else if (units.IsScalar() && units.Scalar() == "mm") mesh.unit = 0.001;
    else if (units.IsScalar() && YAML::convert<double>::decode(units, value) && std::isfinite(value) && value > 0.0)
      mesh.unit = value;
    else
      error(units, "mesh.units", describe(units) + " is not a unit; use m, cm, mm or a positive number of metres "
                                                   "per mesh unit");
  }
}

void SceneParser::parse_surface_meshing(const YAML::Node& node) {
  SceneSurfaceMeshing& surface = scene_.mesh.surface;
  VolumeMeshOptions& options = surface.options;
  if (node["size_far"])
    if (auto v = positive(node["size_far"], "mesh.size_far", " (mesh units)")) {
      options.size.size_far = *v;
      surface.size_far_given = true;
    }
  if (node["size_near"])
    if (auto v = positive(node["size_near"], "mesh.size_near", " (mesh units)")) {
      options.size.size_near = *v;
      surface.size_near_given = true;
    }
  if (surface.size_far_given && surface.size_near_given && options.size.size_near > options.size.size_far)
    error(node["size_near"], "mesh.size_near", format_number(options.size.size_near) + " exceeds size_far (" +
                                                   format_number(options.size.size_far) + "); the near size is the fine one");
  if (node["near_distance"])
    if (auto v = non_negative(node["near_distance"], "mesh.near_distance", " (mesh units)")) options.size.near_distance = *v;
  if (node["grading"])
    if (auto v = positive(node["grading"], "mesh.grading", " (mesh units of size per mesh unit of distance)"))
      options.size.grading = *v;
  if (node["radius_edge_ratio"])
    if (auto v = number(node["radius_edge_ratio"], "mesh.radius_edge_ratio", "a number from 1 to 10")) {
      if (*v >= 1.0 && *v <= 10.0) options.max_radius_edge_ratio = *v;
      else error(node["radius_edge_ratio"], "mesh.radius_edge_ratio",
                 format_number(*v) + " is not from 1 to 10; Delaunay refinement needs at least 1 (1.2 to 2 is usual)");
    }
  if (node["min_dihedral"])
    if (auto v = number(node["min_dihedral"], "mesh.min_dihedral", "a number of degrees from 0 to 30")) {
      if (*v >= 0.0 && *v <= 30.0) options.min_dihedral_degrees = *v;
      else error(node["min_dihedral"], "mesh.min_dihedral", format_number(*v) + " is not from 0 to 30 degrees");
    }
  if (node["keep_surface"])
    if (auto v = boolean(node["keep_surface"], "mesh.keep_surface")) options.keep_surface = *v;
  if (node["split_surface"])
    if (auto v = boolean(node["split_surface"], "mesh.split_surface")) {
      options.split_surface = *v;
      if (*v && !options.keep_surface)
        error(node["split_surface"], "mesh.split_surface",
              "splits a kept surface; without keep_surface: true the mesher splits the surface itself: set "
              "keep_surface: true or leave split_surface out");
    }
  if (node["smooth_intersections"])
    if (auto v = boolean(node["smooth_intersections"], "mesh.smooth_intersections")) options.smooth_intersections = *v;
  if (const YAML::Node near = node["refine_near"]) {
    remember(near, "mesh.refine_near");
    if (!near.IsSequence() || near.size() > kMaxSizeSources) {
      error(near, "mesh.refine_near", "expected a list of points [x, y, z] and segments [x, y, z, x, y, z] (mesh "
                                      "units), at most " + std::to_string(kMaxSizeSources));
      return;
    }
    for (std::size_t i = 0; i < near.size(); ++i) {
      const std::string field = "mesh.refine_near[" + std::to_string(i) + "]";
      const YAML::Node item = near[i];
      std::vector<double> values;
      if (item.IsSequence() && (item.size() == 3 || item.size() == 6))
        for (std::size_t k = 0; k < item.size(); ++k)
          if (auto v = number(item[k], field, "a coordinate (mesh units)")) values.push_back(*v);
      if (values.size() != 3 && values.size() != 6) {
        if (!(item.IsSequence() && (item.size() == 3 || item.size() == 6)))
          error(item, field, "expected a point [x, y, z] or a segment [x, y, z, x, y, z] (mesh units), got " +
                                 describe(item));
        continue;
      }
      SizeSegment segment;
      segment.a = {values[0], values[1], values[2]};
      segment.b = values.size() == 6 ? Point3{values[3], values[4], values[5]} : segment.a;
      options.size.sources.push_back(segment);
    }
  }
}

void SceneParser::parse_material(const YAML::Node& node) {
  remember(node, "material");
  if (!check_map(node, "material", {"youngs_modulus", "stiffness", "stiffness_over_length", "rules", "table",
                                    "system", "output", "patient", "inputs", "strain_axis", "thickness",
                                    "flexion_fraction", "mapping", "poisson_ratio", "viscoelastic", "bind"}))
    return;
  SceneMaterial& material = scene_.material;
  const std::vector<std::string> sources = {"youngs_modulus", "stiffness", "stiffness_over_length", "rules", "table"};
  const int source = one_of(node, "material", sources);
  if (source < 0) return;
  material.source = static_cast<SceneMaterial::Source>(source);
  const std::string key = sources[static_cast<std::size_t>(source)];
  const std::string field = "material." + key;
  switch (material.source) {
    case SceneMaterial::Source::YoungsModulus:
      if (auto v = positive(node[key], field, " (kPa)")) material.value = *v;
      break;
    case SceneMaterial::Source::Stiffness:
      if (auto v = positive(node[key], field, " (N/m)")) material.value = *v;
      break;
    case SceneMaterial::Source::StiffnessOverLength:
      if (auto v = positive(node[key], field, " (N)")) material.value = *v;
      break;
    case SceneMaterial::Source::Rules:
    case SceneMaterial::Source::Table:
      if (auto file = text(node[key], field)) {
        material.file = resolve(*file);
        if (material.source == SceneMaterial::Source::Rules)
          check_input_file(node[key], field, material.file, kMaxRuleFileBytes, "rule file");
        else
          check_input_file(node[key], field, material.file, kMaxTableFileBytes, "table file");
      }
      break;
  }
  const bool fuzzy = material.source == SceneMaterial::Source::Rules || material.source == SceneMaterial::Source::Table;
  for (const char* only_fuzzy : {"system", "output", "inputs", "strain_axis", "bind"}) {
    if (node[only_fuzzy] && !fuzzy)
      error(node[only_fuzzy], std::string("material.") + only_fuzzy, "only allowed with 'rules' or 'table'");
  }
  if (node["system"] && material.source == SceneMaterial::Source::Table)
    error(node["system"], "material.system", "only allowed with 'rules' (a table holds one system)");
  if (node["system"])
    if (auto v = text(node["system"], "material.system")) material.system = *v;
  if (node["output"])
    if (auto v = text(node["output"], "material.output")) material.output = *v;
  if (node["patient"])
    if (auto v = text(node["patient"], "material.patient")) material.patient = *v;
  if (node["mapping"]) {
    if (material.source == SceneMaterial::Source::Stiffness ||
        material.source == SceneMaterial::Source::StiffnessOverLength) {
      error(node["mapping"], "material.mapping",
            "only allowed with 'youngs_modulus', 'rules' or 'table' (it maps Young's modulus to spring constants)");
    } else {
      const std::vector<std::string> names = {scene_name(StiffnessMapping::VanGelder1998),
                                              scene_name(StiffnessMapping::LloydSzekelyHarders2007)};
      material.mapping_given = true;
      if (auto i = keyword(node["mapping"], "material.mapping", names, "a Young's modulus mapping"))
        material.mapping = *i == 0 ? StiffnessMapping::VanGelder1998 : StiffnessMapping::LloydSzekelyHarders2007;
    }
  }
  if (node["poisson_ratio"]) material.poisson_ratio = poisson_ratio(node["poisson_ratio"]);
  if (node["viscoelastic"]) parse_viscoelastic(node["viscoelastic"], node["bind"]);
  if (node["thickness"])
    if (auto v = positive(node["thickness"], "material.thickness", " (m)")) material.thickness = *v;
  if (node["flexion_fraction"])
    if (auto v = non_negative(node["flexion_fraction"], "material.flexion_fraction", "")) material.flexion_fraction = *v;
  if (fuzzy && !node["inputs"])
    error(node, "material.inputs", "missing; bind every input of the rules to a constant, regions or strain");
  if (node["inputs"] && fuzzy) parse_inputs(node["inputs"]);
  if (node["bind"] && fuzzy) parse_bind(node);
  bool has_strain = false;
  for (const auto& b : material.bindings) has_strain = has_strain || b.kind == InputBinding::Kind::Strain;
  if (node["strain_axis"] && fuzzy) {
    const YAML::Node axis = node["strain_axis"];
    remember(axis, "material.strain_axis");
    if (!has_strain) error(axis, "material.strain_axis", "only allowed when an input is bound to 'strain'");
    if (material.source == SceneMaterial::Source::Table)
      error(axis, "material.strain_axis", "not allowed with 'table' (the table's own breakpoints are used)");
    if (check_map(axis, "material.strain_axis", {"min", "max", "points"})) {
      StrainAxis strain_axis;
      if (axis["min"])
        if (auto v = number(axis["min"], "material.strain_axis.min", "a number (strain)")) strain_axis.min = *v;
      if (axis["max"])
        if (auto v = number(axis["max"], "material.strain_axis.max", "a number (strain)")) strain_axis.max = *v;
      if (axis["points"])
        if (auto v = integer(axis["points"], "material.strain_axis.points", 2, 100000))
          strain_axis.points = static_cast<int>(*v);
      if (!(strain_axis.min < strain_axis.max))
        error(axis, "material.strain_axis", "'min' must be below 'max'");
      material.strain_axis = strain_axis;
    }
  }
}

// `regions: [{box: {min, max}, value: NUMBER}, ...]` of a map; false after an error.
bool SceneParser::parse_regions(const YAML::Node& value, const std::string& field, std::vector<RegionValue>& out) {
  const YAML::Node regions = value["regions"];
  if (!regions || !regions.IsSequence() || regions.size() == 0) {
    error(regions ? regions : value, field + ".regions", "expected a list of {box: {min, max}, value: NUMBER}");
    return false;
  }
  for (std::size_t r = 0; r < regions.size(); ++r) {
    const std::string region_field = field + ".regions[" + std::to_string(r) + "]";
    if (!check_map(regions[r], region_field, {"box", "value"})) continue;
    if (!regions[r]["box"] || !regions[r]["value"]) {
      error(regions[r], region_field, "a region needs 'box' and 'value'");
      continue;
    }
    const auto region_box = box(regions[r]["box"], region_field + ".box");
    const auto region_value = number(regions[r]["value"], region_field + ".value", "a number");
    if (region_box && region_value) out.push_back({*region_box, *region_value});
  }
  return true;
}

// `viscoelastic: {prony: [{weight: g, time: tau}, ...]}`: 1 to kMostPronyTerms terms, each weight in (0, 1) and
// time (s) positive, the weights summing below 1 (the long-term modulus 1 - sum g_i of the law's instantaneous one).
void SceneParser::parse_viscoelastic(const YAML::Node& node, const YAML::Node& bind) {
  const std::string field = "material.viscoelastic";
  remember(node, field);
  if (!check_map(node, field, {"prony"})) return;
  const YAML::Node list = node["prony"];
  const std::string expected = "a list of 1 to " + std::to_string(kernels::kMostPronyTerms) +
                               " Prony terms {weight: g, time: tau (s)}";
  if (!list || !list.IsSequence() || list.size() == 0 ||
      list.size() > static_cast<std::size_t>(kernels::kMostPronyTerms)) {
    error(list ? list : node, field + ".prony", "expected " + expected);
    return;
  }
  remember(list, field + ".prony");
  std::vector<PronyTerm> prony;
  double sum = 0.0;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string term_field = field + ".prony[" + std::to_string(i) + "]";
    if (!check_map(list[i], term_field, {"weight", "time"})) return;
    // A weight material.bind gives (viscoelastic.prony[I].weight) is set when the scene is built (from the rules).
    const std::string bound_key = "viscoelastic.prony[" + std::to_string(i) + "].weight";
    const bool bound = bind && bind.IsMap() && bind[bound_key];
    if (bound && list[i]["weight"]) {
      error(list[i]["weight"], term_field + ".weight",
            "also bound by material.bind." + bound_key + "; give the weight one source: remove one of the two");
      return;
    }
    if ((!list[i]["weight"] && !bound) || !list[i]["time"]) {
      error(list[i], term_field, "a Prony term needs 'weight' and 'time'");
      return;
    }
    const auto time = positive(list[i]["time"], term_field + ".time", " (s)");
    if (!time) return;
    if (bound) {
      prony.push_back({0.0, *time});
      continue;
    }
    const auto weight = number(list[i]["weight"], term_field + ".weight", "a number in (0, 1)");
    if (!weight) return;
    if (!(*weight > 0.0 && *weight < 1.0)) {
      error(list[i]["weight"], term_field + ".weight",
            format_number(*weight) + " is not in (0, 1): a weight is the fraction of the instantaneous stress that "
                                     "relaxes with this time constant");
      return;
    }
    sum += *weight;
    prony.push_back({*weight, *time});
  }
  if (!(sum < 1.0)) {
    error(list, field + ".prony",
          "the weights sum to " + format_number(sum) +
              "; they must sum below 1 (the long-term modulus is 1 - sum g_i times the law's instantaneous one)");
    return;
  }
  scene_.material.prony = std::move(prony);
}

// A Poisson ratio in [0, 0.4999]: a number, or {regions: [...], default: NUMBER}. The element kind's own limit (the
// linear tetrahedron's 0.499) is checked where the model is built (build_fem_model).
std::optional<RegionalValue> SceneParser::poisson_ratio(const YAML::Node& node) {
  const std::string field = "material.poisson_ratio";
  remember(node, field);
  const std::string allowed = "a number in [0, 0.4999]";
  const auto in_range = [&](const YAML::Node& at, const std::string& where, double v) {
    if (v >= 0.0 && v <= 0.4999) return true;
    error(at, where, "expected " + allowed + " (0.5 is incompressible, which no element here represents; linear "
                     "tetrahedra take at most 0.499), got " + format_number(v));
    return false;
  };
  RegionalValue out;
  if (node.IsMap()) {
    if (!check_map(node, field, {"regions", "default"})) return std::nullopt;
    out.has_default = false;
    if (node["default"]) {
      const auto v = number(node["default"], field + ".default", allowed);
      if (!v || !in_range(node["default"], field + ".default", *v)) return std::nullopt;
      out.value = *v;
      out.has_default = true;
    }
    if (!parse_regions(node, field, out.regions)) return std::nullopt;
    for (std::size_t r = 0; r < out.regions.size(); ++r)
      if (!in_range(node["regions"][r]["value"], field + ".regions[" + std::to_string(r) + "].value",
                    out.regions[r].value))
        return std::nullopt;
    return out;
  }
  const auto v = number(node, field, allowed + " or {regions: [...], default: NUMBER}");
  if (!v || !in_range(node, field, *v)) return std::nullopt;
  out.value = *v;
  return out;
}

// `bind: {PARAMETER: OUTPUT, ...}`: which output gives each parameter. Whether the element law has the parameter is
// checked when the scene is built (the law's registry row); here the map's shape, that Young's modulus is bound (the
// rules are its source), and that no parameter is also given by its own field.
void SceneParser::parse_bind(const YAML::Node& material) {
  const YAML::Node node = material["bind"];
  const std::string field = "material.bind";
  remember(node, field);
  if (!node.IsMap() || node.size() == 0) {
    error(node, field, "expected a map from a material parameter to an output of the rules, e.g. "
                       "{youngs_modulus: stiffness, poisson_ratio: compressibility}");
    return;
  }
  bool youngs_modulus = false;
  for (auto it = node.begin(); it != node.end(); ++it) {
    ParameterBinding binding;
    binding.parameter = it->first.Scalar();
    const std::string key = field + "." + binding.parameter;
    remember(it->first, key);
    const auto output = text(it->second, key + ".output");
    if (!output) continue;
    binding.output = *output;
    youngs_modulus = youngs_modulus || binding.parameter == "youngs_modulus";
    if (binding.parameter != "youngs_modulus" && material[binding.parameter])
      error(material[binding.parameter], "material." + binding.parameter,
            "also bound by " + key + "; give the parameter one source: remove one of the two");
    scene_.material.bind.push_back(std::move(binding));
  }
  if (!youngs_modulus)
    error(node, field, "youngs_modulus is not bound; the rules are the material's source of Young's modulus: bind it "
                       "to one of their outputs (bind: {youngs_modulus: OUTPUT, ...})");
  if (material["output"])
    error(material["output"], "material.output",
          "not allowed with 'bind' (which names every output used); bind Young's modulus with "
          "bind: {youngs_modulus: OUTPUT}");
}

void SceneParser::parse_inputs(const YAML::Node& node) {
  remember(node, "material.inputs");
  if (!node.IsMap() || node.size() == 0) {
    error(node, "material.inputs", "expected a map from input name to a number, 'strain' or {regions: ...}");
    return;
  }
  int strain_bindings = 0;
  for (auto it = node.begin(); it != node.end(); ++it) {
    InputBinding binding;
    binding.input = it->first.Scalar();
    const std::string field = "material.inputs." + binding.input;
    remember(it->first, field);
    const YAML::Node value = it->second;
    double number_value = 0.0;
    if (value.IsScalar() && value.Scalar() == "strain") {
      binding.kind = InputBinding::Kind::Strain;
      ++strain_bindings;
      if (strain_bindings > 1) error(value, field, "only one input can be bound to 'strain'");
    } else if (value.IsScalar() && YAML::convert<double>::decode(value, number_value) && std::isfinite(number_value)) {
      binding.kind = InputBinding::Kind::Constant;
      binding.value = number_value;
    } else if (value.IsMap()) {
      binding.kind = InputBinding::Kind::PerRegion;
      if (!check_map(value, field, {"regions", "default"})) continue;
      if (value["default"]) {
        if (auto v = number(value["default"], field + ".default", "a number")) {
          binding.value = *v;
          binding.has_default = true;
        }
      }
      if (!parse_regions(value, field, binding.regions)) continue;
    } else {
      error(value, field, "expected a number, 'strain' or {regions: [...], default: NUMBER}, got " + describe(value));
      continue;
    }
    remember(it->first, field);
    scene_.material.bindings.push_back(std::move(binding));
  }
}

// What only springs have is refused with the co-rotational FEM, naming the field.
void SceneParser::check_fem_fields(const YAML::Node& root) {
  const std::string why = " has no meaning for model: " + model_keyword(scene_) + " (it is a spring setting)";
  const YAML::Node material = root["material"];
  if (material && material.IsMap()) {
    for (const char* key : {"stiffness", "stiffness_over_length"})
      if (material[key])
        error(material[key], std::string("material.") + key,
              "a finite-element model takes Young's modulus (youngs_modulus, rules or table), not spring constants");
    // A mapping beside spring constants already has its own error (it needs Young's modulus).
    const bool modulus = material["youngs_modulus"] || material["rules"] || material["table"];
    for (const char* key : {"mapping", "thickness", "flexion_fraction"})
      if (material[key] && (modulus || std::string(key) != "mapping"))
        error(material[key], std::string("material.") + key, why.substr(1));
  }
  if (root["springs"]) error(root["springs"], "springs", why.substr(1));
  if (root["law"])
    error(root["law"], "law", why.substr(1) + "; the FEM's material is its element law (fem: {law: ...})");
  const YAML::Node damping = root["damping"];
  if (damping && damping.IsMap()) {
    for (const char* key : {"coefficient", "natural_frequency"})
      if (damping[key])
        error(damping[key], std::string("damping.") + key,
              "a per-spring dashpot setting; the FEM is damped by 'ratio' (each element's fastest mode) and "
              "'rayleigh'");
  }
}

void SceneParser::parse_mass(const YAML::Node& node) {
  remember(node, "mass");
  if (!check_map(node, "mass", {"density", "total", "thickness"})) return;
  switch (one_of(node, "mass", {"density", "total"})) {
    case 0:
      scene_.mass.source = MassSpec::Source::Density;
      if (auto v = positive(node["density"], "mass.density", " (kg/m^3)")) scene_.mass.value = *v;
      break;
    case 1:
      scene_.mass.source = MassSpec::Source::TotalMass;
      if (auto v = positive(node["total"], "mass.total", " (kg)")) scene_.mass.value = *v;
      break;
    default:
      break;
  }
  if (node["thickness"])
    if (auto v = positive(node["thickness"], "mass.thickness", " (m)")) scene_.mass.thickness = *v;
}

void SceneParser::parse_damping(const YAML::Node& node) {
  remember(node, "damping");
  if (node.IsScalar() && node.Scalar() == "none") {
    scene_.damping.rule = DampingSpec::Rule::Fixed;
    scene_.damping.value = 0.0;
    return;
  }
  if (!node.IsMap()) {
    error(node, "damping", "expected 'none' or a map with 'ratio' (and optionally 'natural_frequency') or "
                           "'coefficient', and/or 'rayleigh'");
    return;
  }
  if (!check_map(node, "damping", {"ratio", "natural_frequency", "coefficient", "rayleigh"})) return;
  if (node["rayleigh"]) {
    const YAML::Node rayleigh = node["rayleigh"];
    remember(rayleigh, "damping.rayleigh");
    if (check_map(rayleigh, "damping.rayleigh", {"mass", "stiffness"})) {
      if (!rayleigh["mass"] && !rayleigh["stiffness"])
        error(rayleigh, "damping.rayleigh", "give 'mass' (alpha, 1/s) and/or 'stiffness' (beta, s)");
      if (rayleigh["mass"])
        if (auto v = non_negative(rayleigh["mass"], "damping.rayleigh.mass", " (1/s)")) scene_.rayleigh.mass = *v;
      if (rayleigh["stiffness"])
        if (auto v = non_negative(rayleigh["stiffness"], "damping.rayleigh.stiffness", " (s)"))
          scene_.rayleigh.stiffness = *v;
    }
    if (!node["ratio"] && !node["coefficient"]) {
      // Rayleigh alone: no ratio damping beside it.
      scene_.damping.rule = DampingSpec::Rule::DampingRatio;
      scene_.damping.ratio = 0.0;
      if (node["natural_frequency"])
        error(node["natural_frequency"], "damping.natural_frequency", "only allowed with 'ratio'");
      return;
    }
  }
  switch (one_of(node, "damping", {"ratio", "coefficient"})) {
    case 0:
      if (auto v = non_negative(node["ratio"], "damping.ratio", "")) scene_.damping.ratio = *v;
      scene_.damping.rule = DampingSpec::Rule::DampingRatio;
      if (node["natural_frequency"]) {
        scene_.damping.rule = DampingSpec::Rule::ThesisNaturalFrequency;
        if (auto v = positive(node["natural_frequency"], "damping.natural_frequency", " (rad/s)"))
          scene_.damping.natural_frequency = *v;
      }
      break;
    case 1:
      if (node["natural_frequency"])
        error(node["natural_frequency"], "damping.natural_frequency", "only allowed with 'ratio'");
      scene_.damping.rule = DampingSpec::Rule::Fixed;
      if (auto v = non_negative(node["coefficient"], "damping.coefficient", " (N s/m)")) scene_.damping.value = *v;
      break;
    default:
      break;
  }
}

void SceneParser::parse_springs(const YAML::Node& node) {
  remember(node, "springs");
  if (node.IsMap() && node["shear"]) {
    // The thesis names shear springs (section 3.2.1) but gives no rule for them; its flexion springs are the
    // across-edge diagonals that cloth models call shear springs (docs/simulator.md, Springs).
    error(node["shear"], "springs.shear",
          "the thesis gives no rule for shear springs on a triangle mesh; its flexion springs (Fig. 3.4) join the "
          "two vertices across each shared edge, the diagonal that cloth models call a shear spring: use "
          "'flexion' (and 'bending' for springs that skip a vertex)");
    return;
  }
  if (!check_map(node, "springs", {"structural", "flexion", "bending", "bending_min_angle", "volume_term"})) return;
  if (node["volume_term"])
    if (auto v = boolean(node["volume_term"], "springs.volume_term")) scene_.volume_term = *v;
  if (node["structural"])
    if (auto v = boolean(node["structural"], "springs.structural")) scene_.triangle_springs.structural = *v;
  if (node["flexion"])
    if (auto v = boolean(node["flexion"], "springs.flexion")) scene_.triangle_springs.flexion = *v;
  if (node["bending"])
    if (auto v = boolean(node["bending"], "springs.bending")) scene_.triangle_springs.bending = *v;
  if (node["bending_min_angle"]) {
    const YAML::Node angle = node["bending_min_angle"];
    if (auto v = number(angle, "springs.bending_min_angle", "an angle from 90 to 180 (degrees)")) {
      if (*v < 90.0 || *v > 180.0)
        error(angle, "springs.bending_min_angle",
              "expected an angle from 90 to 180 (degrees), got " + format_number(*v));
      else
        scene_.triangle_springs.bending_min_angle_degrees = *v;
    }
  }
}

void SceneParser::parse_law(const YAML::Node& node) {
  remember(node, "law");
  static const std::vector<std::string> names = {"linear", "basafa_farahmand"};
  if (node.IsScalar()) {
    if (auto i = keyword(node, "law", names, "a spring law"))
      scene_.law.law = *i == 0 ? kernels::SpringLaw::LinearDashpot : kernels::SpringLaw::BasafaFarahmand;
    return;
  }
  if (!check_map(node, "law", names)) return;
  if (node["linear"] || node.size() != 1) {
    error(node, "law", "expected 'linear', 'basafa_farahmand' or {basafa_farahmand: {k2_over_k1, xc, gamma0, gamma1}}");
    return;
  }
  const YAML::Node bf = node["basafa_farahmand"];
  scene_.law.law = kernels::SpringLaw::BasafaFarahmand;
  if (!check_map(bf, "law.basafa_farahmand", {"k2_over_k1", "xc", "gamma0", "gamma1"})) return;
  if (bf["k2_over_k1"])
    if (auto v = non_negative(bf["k2_over_k1"], "law.basafa_farahmand.k2_over_k1", "")) scene_.law.k2_over_k1 = *v;
  if (bf["xc"])
    if (auto v = positive(bf["xc"], "law.basafa_farahmand.xc", " (strain)")) scene_.law.xc = *v;
  if (bf["gamma0"])
    if (auto v = non_negative(bf["gamma0"], "law.basafa_farahmand.gamma0", " (N s/m)")) scene_.law.gamma0 = *v;
  if (bf["gamma1"])
    if (auto v = non_negative(bf["gamma1"], "law.basafa_farahmand.gamma1", " (N s/m^2)")) scene_.law.gamma1 = *v;
}

}  // namespace fmpc::sim

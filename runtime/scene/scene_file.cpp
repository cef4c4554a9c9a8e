#include "runtime/scene/scene_file.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <limits>

#include "diagnostics/number_format.h"

namespace fmpc::sim {

const char* to_string(SceneBackend backend) {
  switch (backend) {
    case SceneBackend::Auto: return "auto";
    case SceneBackend::Cpu: return "cpu";
    case SceneBackend::Cuda: return "cuda";
  }
  return "auto";
}

const char* scene_name(Integrator integrator) {
  switch (integrator) {
    case Integrator::ForwardEuler: return "forward_euler";
    case Integrator::SemiImplicitEuler: return "semi_implicit_euler";
    case Integrator::VelocityVerlet: return "velocity_verlet";
    case Integrator::RungeKutta4: return "rk4";
    case Integrator::ImplicitEuler: return "implicit_euler";
  }
  return "semi_implicit_euler";
}

const char* scene_name(StiffnessMapping mapping) {
  switch (mapping) {
    case StiffnessMapping::Uniform: return "uniform";
    case StiffnessMapping::StiffnessOverLength: return "stiffness_over_length";
    case StiffnessMapping::VanGelder1998: return "van_gelder_1998";
    case StiffnessMapping::LloydSzekelyHarders2007: return "lloyd_szekely_harders_2007";
  }
  return "van_gelder_1998";
}

SourceRange Scene::range_of(const std::string& field) const {
  const auto found = ranges.find(field);
  if (found != ranges.end()) return found->second;
  SourceRange range;
  range.file = path;
  return range;
}

namespace {

std::string join_names(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) text += i + 1 == names.size() ? " or " : ", ";
    text += names[i];
  }
  return text;
}

class SceneParser {
 public:
  SceneParser(const std::string& path, Scene& scene, DiagnosticList& diagnostics)
      : path_(path), scene_(scene), diagnostics_(diagnostics) {}

  SourceRange range(const YAML::Node& node) const {
    SourceRange r;
    r.file = path_;
    const YAML::Mark mark = node.Mark();
    if (mark.line >= 0) {
      r.line = mark.line + 1;
      r.column = mark.column + 1;
      r.end_line = r.line;
      r.end_column = r.column + 1;
    }
    return r;
  }

  void error(const YAML::Node& node, const std::string& field, const std::string& message,
             std::vector<std::string> notes = {}) {
    diagnostics_.error(range(node), field + ": " + message, std::move(notes));
  }

  void remember(const YAML::Node& node, const std::string& field) { scene_.ranges[field] = range(node); }

  // Every key of `node` must be one of `allowed`; returns false when `node` is not a map.
  bool check_map(const YAML::Node& node, const std::string& field, const std::vector<std::string>& allowed) {
    if (!node.IsMap()) {
      error(node, field, "expected a map with " + join_names(quoted(allowed)));
      return false;
    }
    for (auto it = node.begin(); it != node.end(); ++it) {
      const std::string key = it->first.Scalar();
      bool known = false;
      for (const auto& name : allowed) known = known || name == key;
      if (known) continue;
      std::vector<std::string> notes;
      if (auto suggestion = closest_name(key, allowed)) notes.push_back("did you mean '" + *suggestion + "'?");
      const std::string where = field.empty() ? "" : " in " + field;
      diagnostics_.error(range(it->first), (field.empty() ? key : field + "." + key) + ": unknown key" + where +
                                               "; allowed: " + join_names(quoted(allowed)),
                         notes);
    }
    return true;
  }

  static std::vector<std::string> quoted(const std::vector<std::string>& names) {
    std::vector<std::string> out;
    for (const auto& n : names) out.push_back("'" + n + "'");
    return out;
  }

  // Exactly one of `keys` present in `node`; returns its index or -1 after an error.
  int one_of(const YAML::Node& node, const std::string& field, const std::vector<std::string>& keys) {
    int found = -1;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (!node[keys[i]]) continue;
      if (found >= 0) {
        error(node[keys[i]], field, "give only one of " + join_names(quoted(keys)));
        return -1;
      }
      found = static_cast<int>(i);
    }
    if (found < 0) error(node, field, "give one of " + join_names(quoted(keys)));
    return found;
  }

  std::optional<double> number(const YAML::Node& node, const std::string& field, const std::string& allowed) {
    remember(node, field);
    double value = 0.0;
    if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value)) {
      error(node, field, "expected " + allowed + ", got " + describe(node));
      return std::nullopt;
    }
    return value;
  }

  std::optional<double> positive(const YAML::Node& node, const std::string& field, const std::string& unit) {
    const auto value = number(node, field, "a positive number" + unit);
    if (value && !(*value > 0.0)) {
      error(node, field, "expected a positive number" + unit + ", got " + format_number(*value));
      return std::nullopt;
    }
    return value;
  }

  std::optional<double> non_negative(const YAML::Node& node, const std::string& field, const std::string& unit) {
    const auto value = number(node, field, "a non-negative number" + unit);
    if (value && !(*value >= 0.0)) {
      error(node, field, "expected a non-negative number" + unit + ", got " + format_number(*value));
      return std::nullopt;
    }
    return value;
  }

  std::optional<long long> integer(const YAML::Node& node, const std::string& field, long long min, long long max) {
    remember(node, field);
    const std::string allowed = "an integer from " + std::to_string(min) + " to " + std::to_string(max);
    double value = 0.0;
    if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value) ||
        value != std::floor(value) || value < static_cast<double>(min) || value > static_cast<double>(max)) {
      error(node, field, "expected " + allowed + ", got " + describe(node));
      return std::nullopt;
    }
    return static_cast<long long>(value);
  }

  std::optional<bool> boolean(const YAML::Node& node, const std::string& field) {
    remember(node, field);
    bool value = false;
    if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value)) {
      error(node, field, "expected true or false, got " + describe(node));
      return std::nullopt;
    }
    return value;
  }

  std::optional<std::string> text(const YAML::Node& node, const std::string& field) {
    remember(node, field);
    if (!node.IsScalar() || node.Scalar().empty()) {
      error(node, field, "expected a non-empty text, got " + describe(node));
      return std::nullopt;
    }
    return node.Scalar();
  }

  // One of `names` (a keyword); the error lists them and suggests the closest.
  std::optional<std::size_t> keyword(const YAML::Node& node, const std::string& field,
                                     const std::vector<std::string>& names, const std::string& what) {
    remember(node, field);
    if (node.IsScalar()) {
      for (std::size_t i = 0; i < names.size(); ++i)
        if (node.Scalar() == names[i]) return i;
    }
    std::vector<std::string> notes;
    if (node.IsScalar())
      if (auto suggestion = closest_name(node.Scalar(), names)) notes.push_back("did you mean '" + *suggestion + "'?");
    error(node, field, describe(node) + " is not " + what + "; use " + join_names(names), notes);
    return std::nullopt;
  }

  std::optional<Point3> vector3(const YAML::Node& node, const std::string& field, const std::string& unit) {
    remember(node, field);
    Point3 p{};
    if (!node.IsSequence() || node.size() != 3) {
      error(node, field, "expected three numbers [x, y, z]" + unit + ", got " + describe(node));
      return std::nullopt;
    }
    for (std::size_t i = 0; i < 3; ++i) {
      double value = 0.0;
      if (!node[i].IsScalar() || !YAML::convert<double>::decode(node[i], value) || !std::isfinite(value)) {
        error(node[i], field, "expected three numbers [x, y, z]" + unit + ", got " + describe(node[i]));
        return std::nullopt;
      }
      p[i] = value;
    }
    return p;
  }

  std::optional<std::vector<std::int32_t>> indices(const YAML::Node& node, const std::string& field) {
    remember(node, field);
    if (!node.IsSequence() || node.size() == 0) {
      error(node, field, "expected a list of vertex indices (integers >= 0), got " + describe(node));
      return std::nullopt;
    }
    std::vector<std::int32_t> out;
    for (std::size_t i = 0; i < node.size(); ++i) {
      const auto value = integer(node[i], field, 0, std::numeric_limits<std::int32_t>::max());
      if (!value) return std::nullopt;
      out.push_back(static_cast<std::int32_t>(*value));
    }
    remember(node, field);
    return out;
  }

  std::optional<SceneBox> box(const YAML::Node& node, const std::string& field) {
    remember(node, field);
    if (!check_map(node, field, {"min", "max"})) return std::nullopt;
    if (!node["min"] || !node["max"]) {
      error(node, field, "a box needs 'min' and 'max' corners [x, y, z] (mesh units)");
      return std::nullopt;
    }
    const auto lo = vector3(node["min"], field + ".min", " (mesh units)");
    const auto hi = vector3(node["max"], field + ".max", " (mesh units)");
    if (!lo || !hi) return std::nullopt;
    for (std::size_t i = 0; i < 3; ++i) {
      if ((*lo)[i] > (*hi)[i]) {
        error(node, field, "'min' must not exceed 'max' on any axis");
        return std::nullopt;
      }
    }
    return SceneBox{*lo, *hi};
  }

  static std::string describe(const YAML::Node& node) {
    if (!node || node.IsNull()) return "nothing";
    if (node.IsScalar()) return "'" + node.Scalar() + "'";
    if (node.IsSequence()) return "a list of " + std::to_string(node.size());
    return "a map";
  }

  std::string resolve(const std::string& file) const {
    namespace fs = std::filesystem;
    const fs::path given(file);
    if (given.is_absolute()) return given.lexically_normal().string();
    return (fs::path(path_).parent_path() / given).lexically_normal().string();
  }

  void parse(const YAML::Node& root) {
    if (!root.IsMap()) {
      diagnostics_.error(range(root), "a scene file is a YAML map with 'mesh', 'material' and the other keys of "
                                      "docs/scenes.md");
      return;
    }
    check_map(root, "", {"name", "mesh", "material", "mass", "damping", "springs", "law", "fixed", "loads",
                         "integrator", "dt", "duration", "backend", "precision", "threads", "outputs"});
    if (root["name"]) {
      if (auto name = text(root["name"], "name")) scene_.name = *name;
    }
    if (!root["mesh"]) diagnostics_.error(range(root), "mesh: missing; give a mesh file or a generated box or ellipsoid");
    else parse_mesh(root["mesh"]);
    if (!root["material"]) diagnostics_.error(range(root), "material: missing; give youngs_modulus, stiffness, "
                                                           "stiffness_over_length, rules or table");
    else parse_material(root["material"]);
    if (root["mass"]) parse_mass(root["mass"]);
    if (root["damping"]) parse_damping(root["damping"]);
    if (root["springs"]) parse_springs(root["springs"]);
    if (root["law"]) parse_law(root["law"]);
    if (root["fixed"]) parse_fixed(root["fixed"]);
    if (root["loads"]) parse_loads(root["loads"]);
    if (root["integrator"]) {
      static const std::vector<std::string> names = {"forward_euler", "semi_implicit_euler", "velocity_verlet", "rk4",
                                                     "implicit_euler"};
      static const Integrator values[] = {Integrator::ForwardEuler, Integrator::SemiImplicitEuler,
                                          Integrator::VelocityVerlet, Integrator::RungeKutta4,
                                          Integrator::ImplicitEuler};
      if (auto i = keyword(root["integrator"], "integrator", names, "an integrator")) scene_.integrator = values[*i];
    }
    if (root["dt"]) {
      const YAML::Node dt = root["dt"];
      remember(dt, "dt");
      if (dt.IsScalar() && dt.Scalar() == "auto") {
        scene_.dt.reset();
      } else {
        double value = 0.0;
        if (!dt.IsScalar() || !YAML::convert<double>::decode(dt, value) || !std::isfinite(value) || !(value > 0.0))
          error(dt, "dt", "expected 'auto' or a positive time step in seconds, got " + describe(dt));
        else
          scene_.dt = value;
      }
    }
    if (root["duration"]) {
      if (auto value = positive(root["duration"], "duration", " of seconds")) scene_.duration = *value;
    }
    if (root["backend"]) {
      static const std::vector<std::string> names = {"auto", "cpu", "cuda"};
      if (auto i = keyword(root["backend"], "backend", names, "a backend"))
        scene_.backend = static_cast<SceneBackend>(*i);
    }
    if (root["precision"]) {
      static const std::vector<std::string> names = {"float", "double"};
      if (auto i = keyword(root["precision"], "precision", names, "a precision"))
        scene_.precision = *i == 0 ? Precision::Float : Precision::Double;
    }
    if (root["threads"]) {
      if (auto value = integer(root["threads"], "threads", 0, 256)) scene_.threads = static_cast<unsigned>(*value);
    }
    if (root["outputs"]) parse_outputs(root["outputs"]);
  }

  void parse_mesh(const YAML::Node& node) {
    remember(node, "mesh");
    if (!check_map(node, "mesh", {"file", "box", "ellipsoid", "units"})) return;
    SceneMesh& mesh = scene_.mesh;
    switch (one_of(node, "mesh", {"file", "box", "ellipsoid"})) {
      case 0:
        if (auto file = text(node["file"], "mesh.file")) {
          mesh.kind = SceneMesh::Kind::File;
          mesh.file = resolve(*file);
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
          if (auto n = integer(ellipsoid["resolution"], "mesh.ellipsoid.resolution", 1, 200))
            mesh.ellipsoid.resolution = static_cast<int>(*n);
        break;
      }
      default:
        break;
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

  void parse_material(const YAML::Node& node) {
    remember(node, "material");
    if (!check_map(node, "material", {"youngs_modulus", "stiffness", "stiffness_over_length", "rules", "table",
                                      "system", "output", "patient", "inputs", "strain_axis", "thickness",
                                      "flexion_fraction", "mapping"}))
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
        if (auto file = text(node[key], field)) material.file = resolve(*file);
        break;
    }
    const bool fuzzy = material.source == SceneMaterial::Source::Rules || material.source == SceneMaterial::Source::Table;
    for (const char* only_fuzzy : {"system", "output", "inputs", "strain_axis"}) {
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
        if (auto i = keyword(node["mapping"], "material.mapping", names, "a Young's modulus mapping"))
          material.mapping = *i == 0 ? StiffnessMapping::VanGelder1998 : StiffnessMapping::LloydSzekelyHarders2007;
      }
    }
    if (node["thickness"])
      if (auto v = positive(node["thickness"], "material.thickness", " (m)")) material.thickness = *v;
    if (node["flexion_fraction"])
      if (auto v = non_negative(node["flexion_fraction"], "material.flexion_fraction", "")) material.flexion_fraction = *v;
    if (fuzzy && !node["inputs"])
      error(node, "material.inputs", "missing; bind every input of the rules to a constant, regions or strain");
    if (node["inputs"] && fuzzy) parse_inputs(node["inputs"]);
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

  void parse_inputs(const YAML::Node& node) {
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
        const YAML::Node regions = value["regions"];
        if (!regions || !regions.IsSequence() || regions.size() == 0) {
          error(regions ? regions : value, field + ".regions", "expected a list of {box: {min, max}, value: NUMBER}");
          continue;
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
          if (region_box && region_value) binding.regions.push_back({*region_box, *region_value});
        }
      } else {
        error(value, field, "expected a number, 'strain' or {regions: [...], default: NUMBER}, got " + describe(value));
        continue;
      }
      remember(it->first, field);
      scene_.material.bindings.push_back(std::move(binding));
    }
  }

  void parse_mass(const YAML::Node& node) {
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

  void parse_damping(const YAML::Node& node) {
    remember(node, "damping");
    if (node.IsScalar() && node.Scalar() == "none") {
      scene_.damping.rule = DampingSpec::Rule::Fixed;
      scene_.damping.value = 0.0;
      return;
    }
    if (!node.IsMap()) {
      error(node, "damping", "expected 'none' or a map with 'ratio' (and optionally 'natural_frequency') or "
                             "'coefficient'");
      return;
    }
    if (!check_map(node, "damping", {"ratio", "natural_frequency", "coefficient"})) return;
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

  void parse_springs(const YAML::Node& node) {
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
    if (!check_map(node, "springs", {"structural", "flexion", "bending", "bending_min_angle"})) return;
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

  void parse_law(const YAML::Node& node) {
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

  // A map or a list of maps.
  template <typename ParseOne>
  void one_or_list(const YAML::Node& node, const std::string& field, ParseOne parse_one) {
    if (node.IsSequence()) {
      for (std::size_t i = 0; i < node.size(); ++i) parse_one(node[i], field + "[" + std::to_string(i) + "]");
    } else {
      parse_one(node, field);
    }
  }

  void parse_fixed(const YAML::Node& node) {
    remember(node, "fixed");
    if (!check_map(node, "fixed", {"indices", "box", "plane"})) return;
    if (node["indices"])
      if (auto v = indices(node["indices"], "fixed.indices")) scene_.fixed.indices = *v;
    if (node["box"]) {
      remember(node["box"], "fixed.box");
      one_or_list(node["box"], "fixed.box", [&](const YAML::Node& b, const std::string& field) {
        if (auto parsed = box(b, field)) scene_.fixed.boxes.push_back(*parsed);
      });
    }
    if (node["plane"]) {
      remember(node["plane"], "fixed.plane");
      one_or_list(node["plane"], "fixed.plane", [&](const YAML::Node& p, const std::string& field) {
        if (!check_map(p, field, {"point", "normal", "tolerance"})) return;
        if (!p["point"] || !p["normal"]) {
          error(p, field, "a plane needs 'point' and 'normal' [x, y, z] (mesh units)");
          return;
        }
        SceneFixed::Plane plane;
        const auto point = vector3(p["point"], field + ".point", " (mesh units)");
        const auto normal = vector3(p["normal"], field + ".normal", "");
        if (!point || !normal) return;
        if ((*normal)[0] == 0.0 && (*normal)[1] == 0.0 && (*normal)[2] == 0.0) {
          error(p["normal"], field + ".normal", "the normal must not be zero");
          return;
        }
        plane.point = *point;
        plane.normal = *normal;
        if (p["tolerance"]) {
          const auto tolerance = non_negative(p["tolerance"], field + ".tolerance", " (mesh units)");
          if (!tolerance) return;
          plane.tolerance = *tolerance;
        }
        scene_.fixed.planes.push_back(plane);
      });
    }
  }

  void parse_loads(const YAML::Node& node) {
    remember(node, "loads");
    if (!check_map(node, "loads", {"gravity", "probe"})) return;
    if (node["gravity"])
      if (auto g = vector3(node["gravity"], "loads.gravity", " (m/s^2)")) scene_.gravity = *g;
    if (!node["probe"]) return;
    const YAML::Node p = node["probe"];
    remember(p, "loads.probe");
    if (!check_map(p, "loads.probe", {"indices", "ray", "radius", "displacement", "force", "ramp"})) return;
    SceneProbe probe;
    bool ok = true;
    switch (one_of(p, "loads.probe", {"indices", "ray"})) {
      case 0:
        if (auto v = indices(p["indices"], "loads.probe.indices")) probe.indices = *v;
        else ok = false;
        break;
      case 1: {
        probe.by_ray = true;
        const YAML::Node ray = p["ray"];
        remember(ray, "loads.probe.ray");
        if (!check_map(ray, "loads.probe.ray", {"origin", "direction"}) || !ray["origin"] || !ray["direction"]) {
          if (ray.IsMap()) error(ray, "loads.probe.ray", "a ray needs 'origin' and 'direction' [x, y, z] (mesh units)");
          ok = false;
          break;
        }
        const auto origin = vector3(ray["origin"], "loads.probe.ray.origin", " (mesh units)");
        const auto direction = vector3(ray["direction"], "loads.probe.ray.direction", "");
        if (!origin || !direction) {
          ok = false;
          break;
        }
        if ((*direction)[0] == 0.0 && (*direction)[1] == 0.0 && (*direction)[2] == 0.0) {
          error(ray["direction"], "loads.probe.ray.direction", "the direction must not be zero");
          ok = false;
          break;
        }
        probe.ray_origin = *origin;
        probe.ray_direction = *direction;
        break;
      }
      default:
        ok = false;
    }
    if (p["radius"]) {
      if (!probe.by_ray) error(p["radius"], "loads.probe.radius", "only allowed with 'ray'");
      if (auto v = non_negative(p["radius"], "loads.probe.radius", " (mesh units)")) probe.radius = *v;
    }
    switch (one_of(p, "loads.probe", {"displacement", "force"})) {
      case 0:
        probe.mode = ProbeLoad::Mode::Displacement;
        if (auto v = vector3(p["displacement"], "loads.probe.displacement", " (m)")) probe.target = *v;
        else ok = false;
        break;
      case 1:
        probe.mode = ProbeLoad::Mode::Force;
        if (auto v = vector3(p["force"], "loads.probe.force", " (N)")) probe.target = *v;
        else ok = false;
        break;
      default:
        ok = false;
    }
    if (p["ramp"]) {
      if (auto v = non_negative(p["ramp"], "loads.probe.ramp", " of seconds")) probe.ramp = *v;
    }
    if (ok) scene_.probe = probe;
  }

  void parse_outputs(const YAML::Node& node) {
    remember(node, "outputs");
    if (!check_map(node, "outputs", {"directory", "frames", "vtu", "samples", "csv", "summary", "plot"})) return;
    SceneOutputs& out = scene_.outputs;
    if (node["directory"])
      if (auto v = text(node["directory"], "outputs.directory")) out.directory = *v;
    if (node["frames"])
      if (auto v = integer(node["frames"], "outputs.frames", 0, 100000)) out.frames = static_cast<int>(*v);
    if (node["vtu"]) {
      static const std::vector<std::string> names = {"binary", "ascii"};
      if (auto i = keyword(node["vtu"], "outputs.vtu", names, "a VTU encoding"))
        out.vtu = *i == 0 ? VtuFormat::Binary : VtuFormat::Ascii;
    }
    if (node["samples"])
      if (auto v = integer(node["samples"], "outputs.samples", 0, 1000000)) out.samples = static_cast<int>(*v);
    if (node["csv"])
      if (auto v = boolean(node["csv"], "outputs.csv")) out.csv = *v;
    if (node["summary"])
      if (auto v = boolean(node["summary"], "outputs.summary")) out.summary = *v;
    if (node["plot"])
      if (auto v = boolean(node["plot"], "outputs.plot")) out.plot = *v;
  }

 private:
  std::string path_;
  Scene& scene_;
  DiagnosticList& diagnostics_;
};

}  // namespace

std::optional<Scene> parse_scene(const std::string& path, const std::string& text, DiagnosticList& diagnostics) {
  Scene scene;
  scene.path = path;
  scene.name = std::filesystem::path(path).stem().string();
  const std::size_t errors = diagnostics.error_count();
  SceneParser parser(path, scene, diagnostics);
  try {
    const YAML::Node root = YAML::Load(text);
    parser.parse(root);
  } catch (const YAML::Exception& e) {
    SourceRange range;
    range.file = path;
    if (e.mark.line >= 0) {
      range.line = e.mark.line + 1;
      range.column = e.mark.column + 1;
      range.end_line = range.line;
      range.end_column = range.column + 1;
    }
    diagnostics.error(range, "invalid YAML: " + e.msg);
  }
  if (diagnostics.error_count() != errors) return std::nullopt;
  return scene;
}

}  // namespace fmpc::sim

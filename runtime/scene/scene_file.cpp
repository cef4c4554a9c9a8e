#include "runtime/scene/scene_file.h"

#include <sys/stat.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <sstream>
#include <unordered_map>

#include "diagnostics/number_format.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/io/input_file.h"

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

std::string model_keyword(const Scene& scene) {
  if (scene.model == ForceModel::Springs) return "springs";
  return element_law_row(scene.element_law).model_keyword;
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

SourceRange mark_range(const std::string& path, const YAML::Mark& mark) {
  SourceRange r;
  r.file = path;
  if (mark.line >= 0) {
    r.line = mark.line + 1;
    r.column = mark.column + 1;
    r.end_line = r.line;
    r.end_column = r.column + 1;
  }
  return r;
}

// A pass over the YAML events before the document is built: yaml-cpp keeps the last of two equal keys silently
// (`material` given twice would use one of them), so duplicates are found here, with both positions. The pass also
// bounds the nesting depth and counts the documents (a scene is one). Aliases are events, not copies, so a
// "billion laughs" file costs what its text costs.
class SceneYamlScan : public YAML::EventHandler {
 public:
  struct TooDeep {
    YAML::Mark mark;
  };

  SceneYamlScan(const std::string& path, DiagnosticList& diagnostics) : path_(path), diagnostics_(diagnostics) {}

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { node_done(mark, nullptr); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { node_done(mark, nullptr); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t, const std::string& value) override {
    node_done(mark, &value);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    open(mark, false);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    open(mark, true);
  }
  void OnMapEnd() override { close(); }

 private:
  struct Frame {
    bool map = false;
    bool expecting_key = true;
    std::size_t items = 0;
    std::string field;  // "loads.probe", "fixed.box[1]"
    std::string pending_key;
    std::unordered_map<std::string, YAML::Mark> keys;
  };

  std::string child_field() const {
    if (frames_.empty()) return "";
    const Frame& parent = frames_.back();
    if (parent.map) return parent.field.empty() ? parent.pending_key : parent.field + "." + parent.pending_key;
    return parent.field + "[" + std::to_string(parent.items) + "]";
  }

  void open(const YAML::Mark& mark, bool map) {
    if (frames_.size() >= kMaxSceneNesting) throw TooDeep{mark};
    Frame frame;
    frame.map = map;
    frame.field = child_field();
    frames_.push_back(std::move(frame));
  }

  void close() {
    frames_.pop_back();
    node_done(YAML::Mark(), nullptr);
  }

  // A whole node has been read at the level of frames_.back(): a key or a value of a map, or a list item.
  void node_done(const YAML::Mark& mark, const std::string* scalar) {
    if (frames_.empty()) return;
    Frame& frame = frames_.back();
    if (!frame.map) {
      ++frame.items;
      return;
    }
    if (!frame.expecting_key) {
      frame.expecting_key = true;
      return;
    }
    frame.expecting_key = false;
    frame.pending_key = scalar ? *scalar : std::string();
    if (!scalar) return;  // a complex key: the scene parser reports it as unknown
    const auto [first, inserted] = frame.keys.emplace(*scalar, mark);
    if (inserted) return;
    const std::string field = frame.field.empty() ? *scalar : frame.field + "." + *scalar;
    diagnostics_.error(mark_range(path_, mark), field + ": duplicate key; YAML keeps only one of the two, so remove one",
                       {"first given here: " + std::to_string(first->second.line + 1) + ":" +
                        std::to_string(first->second.column + 1)});
  }

  std::string path_;
  DiagnosticList& diagnostics_;
  std::vector<Frame> frames_;
};

class SceneParser {
 public:
  SceneParser(const std::string& path, Scene& scene, DiagnosticList& diagnostics)
      : path_(path), scene_(scene), diagnostics_(diagnostics) {}

  SourceRange range(const YAML::Node& node) const { return mark_range(path_, node.Mark()); }

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
      // A hostile key can be megabytes long: the message shows its start.
      const std::string shown = key.size() > 60 ? key.substr(0, 60) + "..." : key;
      diagnostics_.error(range(it->first), (field.empty() ? shown : field + "." + shown) + ": unknown key" + where +
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
    if (node.Scalar().find('\0') != std::string::npos) {
      error(node, field, "the text contains a NUL byte (\\0), which no file name or label may hold; remove it");
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

  // A file named by the scene must be a regular file within its reader's limit (docs/limits.md). Checked here so
  // that the error points at the field; a missing file is left to the reader, which says where it looked.
  void check_input_file(const YAML::Node& node, const std::string& field, const std::string& file, std::size_t limit,
                        const std::string& what) {
    struct stat info {};
    if (::stat(file.c_str(), &info) != 0) return;
    if (!S_ISREG(info.st_mode)) {
      error(node, field, "'" + file + "' is " + (S_ISDIR(info.st_mode) ? "a directory" : "not a regular file") +
                             " (a device, FIFO or socket), not a " + what + "; give the path of a regular file");
    } else if (static_cast<unsigned long long>(info.st_size) > limit) {
      error(node, field, "'" + file + "' is larger than " + byte_size_text(limit) + ", the limit for a " + what);
    }
  }

  void parse(const YAML::Node& root) {
    if (!root.IsMap()) {
      diagnostics_.error(range(root), "a scene file is a YAML map with 'mesh', 'material' and the other keys of "
                                      "docs/scenes.md");
      return;
    }
    check_map(root, "", {"name", "model", "mesh", "material", "mass", "damping", "springs", "law", "fixed", "hold",
                         "loads", "integrator", "dt", "duration", "backend", "precision", "threads", "outputs",
                         "on_inversion"});
    if (root["name"]) {
      if (auto name = text(root["name"], "name")) {
        if (const auto problem = output_name_problem(*name))
          error(root["name"], "name", "'" + *name + "' " + *problem);
        else
          scene_.name = *name;
      }
    } else if (const auto problem = output_name_problem(scene_.name)) {
      diagnostics_.error(range(root), "name: the scene file's name '" + scene_.name + "' " + *problem +
                                          "; give the scene a 'name'");
    }
    if (root["model"]) {
      // "springs", then each element law's model keyword, in the registry's order.
      std::vector<std::string> names = {"springs"};
      std::vector<int> laws = {-1};
      for (const ElementLawRow& row : element_law_rows()) {
        if (row.model_keyword == nullptr) continue;
        names.push_back(row.model_keyword);
        laws.push_back(row.law);
      }
      if (auto i = keyword(root["model"], "model", names, "a force model")) {
        scene_.model = *i == 0 ? ForceModel::Springs : ForceModel::Elements;
        if (*i > 0) scene_.element_law = laws[*i];
      }
    }
    if (root["on_inversion"]) {
      static const std::vector<std::string> names = {"warn", "stop"};
      if (auto i = keyword(root["on_inversion"], "on_inversion", names, "what to do when an element turns inside out"))
        scene_.on_inversion = *i == 0 ? InversionPolicy::Warn : InversionPolicy::Stop;
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
    if (root["hold"]) parse_hold(root["hold"]);
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
    if (scene_.model == ForceModel::Elements) check_fem_fields(root);
    if (scene_.model == ForceModel::Springs && scene_.material.poisson_ratio && !scene_.volume_term) {
      diagnostics_.error(scene_.range_of("material.poisson_ratio"),
                         "material.poisson_ratio: springs alone have nu = 1/4 (central springs obey the Cauchy "
                         "relation lambda = mu); add the volume term (springs: {volume_term: true}) to reach another "
                         "ratio, or use model: corotational_fem");
    }
    if (scene_.dt && root["dt"]) {
      const double steps = std::ceil(scene_.duration / *scene_.dt);
      if (!(steps <= kMaxSimulationSteps))
        error(root["dt"], "dt", "duration " + format_number(scene_.duration) + " s / dt " + format_number(*scene_.dt) +
                                    " s is " + format_number(steps) + " steps; the limit is " +
                                    format_number(kMaxSimulationSteps) + ": raise dt or shorten the duration");
    }
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
                                      "flexion_fraction", "mapping", "poisson_ratio"}))
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
        material.mapping_given = true;
        if (auto i = keyword(node["mapping"], "material.mapping", names, "a Young's modulus mapping"))
          material.mapping = *i == 0 ? StiffnessMapping::VanGelder1998 : StiffnessMapping::LloydSzekelyHarders2007;
      }
    }
    if (node["poisson_ratio"]) material.poisson_ratio = poisson_ratio(node["poisson_ratio"]);
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

  // `regions: [{box: {min, max}, value: NUMBER}, ...]` of a map; false after an error.
  bool parse_regions(const YAML::Node& value, const std::string& field, std::vector<RegionValue>& out) {
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

  // A Poisson ratio in [0, 0.499]: a number, or {regions: [...], default: NUMBER}.
  std::optional<RegionalValue> poisson_ratio(const YAML::Node& node) {
    const std::string field = "material.poisson_ratio";
    remember(node, field);
    const std::string allowed = "a number in [0, 0.499]";
    const auto in_range = [&](const YAML::Node& at, const std::string& where, double v) {
      if (v >= 0.0 && v <= 0.499) return true;
      error(at, where, "expected " + allowed + " (0.5 is incompressible, which linear tetrahedra cannot represent "
                       "without locking), got " + format_number(v));
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

  // What only springs have is refused with the co-rotational FEM, naming the field.
  void check_fem_fields(const YAML::Node& root) {
    const std::string why = " has no meaning for model: corotational_fem (it is a spring setting)";
    const YAML::Node material = root["material"];
    if (material && material.IsMap()) {
      for (const char* key : {"stiffness", "stiffness_over_length"})
        if (material[key])
          error(material[key], std::string("material.") + key,
                "the co-rotational FEM takes Young's modulus (youngs_modulus, rules or table), not spring constants");
      // A mapping beside spring constants already has its own error (it needs Young's modulus).
      const bool modulus = material["youngs_modulus"] || material["rules"] || material["table"];
      for (const char* key : {"mapping", "thickness", "flexion_fraction"})
        if (material[key] && (modulus || std::string(key) != "mapping"))
          error(material[key], std::string("material.") + key, why.substr(1));
    }
    if (root["springs"]) error(root["springs"], "springs", why.substr(1));
    if (root["law"]) error(root["law"], "law", why.substr(1) + "; the FEM's material is linear elastic (co-rotated)");
    const YAML::Node damping = root["damping"];
    if (damping && damping.IsMap()) {
      for (const char* key : {"coefficient", "natural_frequency"})
        if (damping[key])
          error(damping[key], std::string("damping.") + key,
                "a per-spring dashpot setting; the FEM is damped by 'ratio' (each element's fastest mode) and "
                "'rayleigh'");
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
        if (!parse_regions(value, field, binding.regions)) continue;
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
    parse_selection(node, "fixed", scene_.fixed);
  }

  // `hold`: one map or a list of maps, each with the selectors of `fixed` and `axes: [x, y, z]` (the axes held).
  void parse_hold(const YAML::Node& node) {
    remember(node, "hold");
    one_or_list(node, "hold", [&](const YAML::Node& entry, const std::string& field) {
      if (!check_map(entry, field, {"indices", "box", "plane", "axes"})) return;
      SceneHold hold;
      hold.field = field;
      remember(entry, field);
      const YAML::Node axes = entry["axes"];
      if (!axes || !axes.IsSequence() || axes.size() == 0) {
        error(axes ? axes : entry, field + ".axes", "expected the held axes, a list of x, y and z (e.g. [z])");
        return;
      }
      for (std::size_t i = 0; i < axes.size(); ++i) {
        static const std::vector<std::string> names = {"x", "y", "z"};
        if (auto axis = keyword(axes[i], field + ".axes", names, "an axis"))
          hold.axes = static_cast<std::uint8_t>(hold.axes | (1u << *axis));
      }
      if (!entry["indices"] && !entry["box"] && !entry["plane"]) {
        error(entry, field, "give the vertices to hold: 'indices', 'box' or 'plane'");
        return;
      }
      parse_selection(entry, field, hold.selection);
      scene_.holds.push_back(std::move(hold));
    });
  }

  // The vertex selectors of `fixed` and `hold` entries: indices, boxes, planes.
  void parse_selection(const YAML::Node& node, const std::string& prefix, SceneFixed& out) {
    if (node["indices"])
      if (auto v = indices(node["indices"], prefix + ".indices")) out.indices = *v;
    if (node["box"]) {
      remember(node["box"], prefix + ".box");
      one_or_list(node["box"], prefix + ".box", [&](const YAML::Node& b, const std::string& field) {
        if (auto parsed = box(b, field)) out.boxes.push_back(*parsed);
      });
    }
    if (node["plane"]) {
      remember(node["plane"], prefix + ".plane");
      one_or_list(node["plane"], prefix + ".plane", [&](const YAML::Node& p, const std::string& field) {
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
        out.planes.push_back(plane);
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
    if (!check_map(node, "outputs",
                   {"directory", "frames", "vtu", "samples", "csv", "summary", "plot", "precision_check"}))
      return;
    SceneOutputs& out = scene_.outputs;
    if (node["precision_check"]) {
      static const std::vector<std::string> names = {"auto", "on", "off"};
      if (auto i = keyword(node["precision_check"], "outputs.precision_check", names, "auto, on or off"))
        out.precision_check = *i == 0   ? SceneOutputs::PrecisionCheck::Auto
                              : *i == 1 ? SceneOutputs::PrecisionCheck::On
                                        : SceneOutputs::PrecisionCheck::Off;
    }
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

std::optional<std::size_t> planned_step_count(const Scene& scene, double dt, DiagnosticList& diagnostics) {
  if (scene.steps) {
    if (static_cast<double>(*scene.steps) <= kMaxSimulationSteps) return *scene.steps;
    diagnostics.error(scene.range_of("steps"), "steps: " + std::to_string(*scene.steps) + " is above the limit of " +
                                                   format_number(kMaxSimulationSteps) + " steps");
    return std::nullopt;
  }
  // The factor keeps a duration that is an exact multiple of dt from gaining a step to rounding.
  const double steps = std::ceil(scene.duration / dt * (1.0 - 1e-12));
  if (dt > 0.0 && steps <= kMaxSimulationSteps) return static_cast<std::size_t>(steps);
  diagnostics.error(scene.range_of(scene.ranges.count("duration") ? "duration" : "dt"),
                    "duration " + format_number(scene.duration) + " s at dt " + format_number(dt) + " s" +
                        (scene.dt ? "" : " (dt auto, from the stability limit)") + " is " + format_number(steps) +
                        " steps; the limit is " + format_number(kMaxSimulationSteps) +
                        ": shorten the duration or raise dt");
  return std::nullopt;
}

std::optional<std::string> output_name_problem(const std::string& name) {
  if (name.empty()) return std::string("is empty");
  if (name == "." || name == "..") return std::string("names a folder, not a file");
  if (name.size() > kMaxSceneNameBytes)
    return "is " + std::to_string(name.size()) + " bytes long; the limit is " + std::to_string(kMaxSceneNameBytes) +
           " (the output files add to it and a file name must stay under 255)";
  for (const char c : name) {
    if (c == '/' || c == '\\')
      return std::string("contains a path separator; the name becomes file names inside the output folder "
                         "(-o DIR), so it may not lead out of it: use letters, digits, '-', '_' and '.'");
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      return std::string("contains a control character (a NUL byte, a newline, ...); use letters, digits, '-', '_' "
                         "and '.'");
  }
  return std::nullopt;
}

std::optional<Scene> parse_scene(const std::string& path, const std::string& text, DiagnosticList& diagnostics) {
  Scene scene;
  scene.path = path;
  scene.name = std::filesystem::path(path).stem().string();
  const std::size_t errors = diagnostics.error_count();
  SceneParser parser(path, scene, diagnostics);
  try {
    {
      std::istringstream stream(text);
      YAML::Parser events(stream);
      SceneYamlScan scan(path, diagnostics);
      if (events.HandleNextDocument(scan)) {
        // A second document would be ignored by YAML::Load.
        SceneYamlScan rest(path, diagnostics);
        if (events.HandleNextDocument(rest))
          diagnostics.error(SourceRange{path, 0, 0, 0, 0},
                            "the file holds more than one YAML document ('---'); a scene file is one document");
      }
    }
    if (diagnostics.error_count() == errors) {
      const YAML::Node root = YAML::Load(text);
      parser.parse(root);
    }
  } catch (const SceneYamlScan::TooDeep& too_deep) {
    diagnostics.error(mark_range(path, too_deep.mark),
                      "the YAML nests deeper than " + std::to_string(kMaxSceneNesting) +
                          " levels; a scene needs about 6: check the indentation and brackets");
  } catch (const YAML::Exception& e) {
    diagnostics.error(mark_range(path, e.mark), "invalid YAML: " + e.msg);
  }
  if (diagnostics.error_count() != errors) return std::nullopt;
  return scene;
}

}  // namespace fmpc::sim

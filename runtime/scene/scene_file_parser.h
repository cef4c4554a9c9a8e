#pragma once
// The reader of a scene file's built YAML document (parse_scene, scene_file.h): every section into its Scene field,
// each value checked for type and range with the field named in the error. Internal to the scene-file reader; its
// definitions lie by job in
//   scene_file_fields.cpp    typed values (numbers, integers, keywords, vectors, boxes, files) and map checks
//   scene_file_run.cpp       the document's top level and the run's settings (integrator, dt, backend, outputs)
//   scene_file_material.cpp  mesh, material (sources, bindings, regions, Poisson ratio), mass, damping, springs, law
//   scene_file_loads.cpp     fixed and held vertices, gravity and the probe
//   scene_file_tools.cpp     rigid tools and their contact
#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/scene/scene_file.h"

namespace fmpc::sim {

class SceneParser {
 public:
  SceneParser(const std::string& path, Scene& scene, DiagnosticList& diagnostics)
      : path_(path), scene_(scene), diagnostics_(diagnostics) {}

  // The whole document; errors go to the diagnostics, and the scene keeps what was read without one.
  void parse(const YAML::Node& root);

 private:
  // ---- typed values (scene_file_fields.cpp): each remembers where its field was written (Scene::ranges) and
  // returns nullopt after an error naming the field and what is allowed ----
  SourceRange range(const YAML::Node& node) const;
  void error(const YAML::Node& node, const std::string& field, const std::string& message,
             std::vector<std::string> notes = {});
  void remember(const YAML::Node& node, const std::string& field);
  // Every key of `node` must be one of `allowed`; returns false when `node` is not a map.
  bool check_map(const YAML::Node& node, const std::string& field, const std::vector<std::string>& allowed);
  static std::vector<std::string> quoted(const std::vector<std::string>& names);
  // Exactly one of `keys` present in `node`; returns its index or -1 after an error.
  int one_of(const YAML::Node& node, const std::string& field, const std::vector<std::string>& keys);
  std::optional<double> number(const YAML::Node& node, const std::string& field, const std::string& allowed);
  std::optional<double> positive(const YAML::Node& node, const std::string& field, const std::string& unit);
  std::optional<double> non_negative(const YAML::Node& node, const std::string& field, const std::string& unit);
  std::optional<long long> integer(const YAML::Node& node, const std::string& field, long long min, long long max);
  std::optional<bool> boolean(const YAML::Node& node, const std::string& field);
  std::optional<std::string> text(const YAML::Node& node, const std::string& field);
  // One of `names` (a keyword); the error lists them and suggests the closest.
  std::optional<std::size_t> keyword(const YAML::Node& node, const std::string& field,
                                     const std::vector<std::string>& names, const std::string& what);
  std::optional<Point3> vector3(const YAML::Node& node, const std::string& field, const std::string& unit);
  std::optional<std::vector<std::int32_t>> indices(const YAML::Node& node, const std::string& field);
  std::optional<SceneBox> box(const YAML::Node& node, const std::string& field);
  static std::string describe(const YAML::Node& node);
  // `file` resolved against the scene file's folder.
  std::string resolve(const std::string& file) const;
  // A file named by the scene must be a regular file within its reader's limit (docs/limits.md).
  void check_input_file(const YAML::Node& node, const std::string& field, const std::string& file, std::size_t limit,
                        const std::string& what);
  // A map or a list of maps: parse_one(entry, field) on each, `field[i]` for list items.
  template <typename ParseOne>
  void one_or_list(const YAML::Node& node, const std::string& field, ParseOne parse_one) {
    if (node.IsSequence()) {
      for (std::size_t i = 0; i < node.size(); ++i) parse_one(node[i], field + "[" + std::to_string(i) + "]");
    } else {
      parse_one(node, field);
    }
  }

  // ---- the run's settings (scene_file_run.cpp) ----
  void parse_outputs(const YAML::Node& node);
  void parse_solver(const YAML::Node& node);

  // ---- mesh, material and the material's companions (scene_file_material.cpp) ----
  void parse_mesh(const YAML::Node& node);
  // `surface`'s companions: the size field, quality bounds, keep_surface, smooth_intersections, refine_near.
  void parse_surface_meshing(const YAML::Node& node);
  void parse_material(const YAML::Node& node);
  bool parse_regions(const YAML::Node& value, const std::string& field, std::vector<RegionValue>& out);
  std::optional<RegionalValue> poisson_ratio(const YAML::Node& node);
  // `bind`: material.bind, whose viscoelastic.prony[I].weight keys stand for a term's weight.
  void parse_viscoelastic(const YAML::Node& node, const YAML::Node& bind);
  void parse_inputs(const YAML::Node& node);
  void parse_bind(const YAML::Node& material);
  void check_fem_fields(const YAML::Node& root);
  void parse_mass(const YAML::Node& node);
  void parse_damping(const YAML::Node& node);
  void parse_springs(const YAML::Node& node);
  void parse_law(const YAML::Node& node);
  // `fem: {law, element}` (model: fem), through the law and element-kind registries.
  void parse_fem(const YAML::Node& node);

  // ---- loads (scene_file_loads.cpp) ----
  void parse_fixed(const YAML::Node& node);
  void parse_hold(const YAML::Node& node);
  void parse_selection(const YAML::Node& node, const std::string& prefix, SceneFixed& out);
  void parse_loads(const YAML::Node& node);

  // ---- rigid tools (scene_file_tools.cpp) ----
  void parse_tools(const YAML::Node& node);
  // A path's point (timed) or a fixed pose; the orientation defaults to the previous point's.
  std::optional<ToolKeyframe> parse_keyframe(const YAML::Node& node, const std::string& field, bool timed,
                                             const ToolKeyframe* previous);
  void parse_contact(const YAML::Node& node);

  std::string path_;
  Scene& scene_;
  DiagnosticList& diagnostics_;
};

}  // namespace fmpc::sim

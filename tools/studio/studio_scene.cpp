#include "tools/studio/studio_scene.h"

#include <cstdlib>
#include <unistd.h>

#include "compiler/frontend/rule_file_loader.h"
#include "diagnostics/number_format.h"
#include "runtime/io/input_file.h"
#include "runtime/mesh/mesh.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "runtime/scene/scene_run.h"

namespace fmpc::studio {

namespace fs = std::filesystem;

namespace {

// YAML single-quoted scalar: '' stands for '.
std::string yaml_quoted(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("''") : std::string(1, c);
  return quoted + "'";
}

// rulesets/scenes/liver_indentation.yaml, the demo, with the rules and the patient given.
std::string demo_scene(const fs::path& rules, const FuzzySystem& system, const std::vector<double>& inputs) {
  std::string bindings;
  for (std::size_t i = 0; i < inputs.size(); ++i)
    bindings += (i ? ", " : "") + yaml_quoted(system.inputs[i].name) + ": " + format_number(inputs[i]);
  return "name: liver_indentation\n"
         "mesh:\n"
         "  box: {size: [0.04, 0.04, 0.02], cells: [8, 8, 4]}\n"
         "  units: m\n"
         "material:\n"
         "  rules: " + yaml_quoted(rules.string()) + "\n"
         "  system: " + yaml_quoted(system.name) + "\n"
         "  inputs: {" + bindings + "}\n"
         "mass: {density: 1060}\n"
         "damping: {ratio: 0.9}\n"
         "fixed:\n"
         "  plane: {point: [0, 0, 0], normal: [0, 0, 1]}\n"
         "loads:\n"
         "  probe:\n"
         "    ray: {origin: [0.02, 0.02, 0.05], direction: [0, 0, -1]}\n"
         "    radius: 0.0051\n"
         "    displacement: [0, 0, -0.004]\n"
         "    ramp: 1.0\n"
         "integrator: semi_implicit_euler\n"
         "dt: auto\n"
         "duration: 1.2\n"
         "precision: float\n";
}

std::string rendered(const DiagnosticList& diagnostics, const SourceFiles& sources) {
  std::string text;
  for (const Diagnostic& d : diagnostics.items()) text += render(d, sources) + "\n";
  return text;
}

Json points_json(const std::vector<sim::Point3>& points) {
  Json flat = Json::array();
  for (const sim::Point3& p : points)
    for (double c : p) flat.push_back(c);
  return flat;
}

// A folder the run may write into (it writes nothing with every output off), removed afterwards.
struct TemporaryFolder {
  fs::path path;
  TemporaryFolder() {
    std::string pattern = (fs::temp_directory_path() / "fmpc-studio-XXXXXX").string();
    if (mkdtemp(pattern.data())) path = pattern;
  }
  ~TemporaryFolder() {
    std::error_code code;
    if (!path.empty()) fs::remove_all(path, code);
  }
};

}  // namespace

std::optional<Json> run_patient_scene(const fs::path& rules_path, const std::string& rules_text,
                                      const FuzzySystem& system, const std::vector<double>& inputs,
                                      const std::optional<fs::path>& scene_path, std::string& error) {
  SourceFiles sources;
  DiagnosticList diagnostics;
  std::string text;
  std::string path = "demo scene (liver_indentation)";
  if (scene_path) {
    path = scene_path->string();
    const std::optional<std::string> read = sim::read_input_file(path, sim::kMaxSceneFileBytes, "scene file", error);
    if (!read) return std::nullopt;
    text = *read;
  } else {
    text = demo_scene(rules_path, system, inputs);
  }
  sources.add(path, text);
  std::optional<sim::Scene> scene = sim::parse_scene(path, text, diagnostics);
  if (!scene) {
    error = rendered(diagnostics, sources);
    return std::nullopt;
  }
  // The editor's rules and the patient, where the scene's material is this rule file.
  std::error_code code;
  const bool these_rules = scene->material.source == sim::SceneMaterial::Source::Rules &&
                           fs::equivalent(scene->material.file, rules_path, code);
  sim::LoadedRules loaded;
  if (these_rules) {
    loaded.path = scene->material.file;
    loaded.text = rules_text;
    DiagnosticList ignored;
    loaded.rules = load_rule_file(loaded.path, rules_text, ignored);
    for (sim::InputBinding& binding : scene->material.bindings) {
      const int input = system.find_input(binding.input);
      if (input >= 0 && binding.kind == sim::InputBinding::Kind::Constant)
        binding.value = inputs[static_cast<std::size_t>(input)];
    }
  }
  scene->outputs = sim::SceneOutputs{};
  scene->outputs.frames = 0;
  scene->outputs.samples = 200;
  scene->outputs.csv = false;
  scene->outputs.summary = false;
  scene->outputs.plot = false;
  scene->outputs.precision_check = sim::SceneOutputs::PrecisionCheck::Off;
  scene->backend = sim::SceneBackend::Cpu;
  std::optional<sim::BuiltScene> built = sim::build_scene(*scene, diagnostics, 0, these_rules ? &loaded : nullptr);
  if (built)
    for (const auto& [file, source] : built->sources) sources.add(file, source);
  if (built && built->mesh.vertex_count() > kMaxSceneVertices)
    diagnostics.error(scene->range_of("mesh"), "the mesh has " + std::to_string(built->mesh.vertex_count()) +
                                                   " vertices; the studio runs scenes of at most " +
                                                   std::to_string(kMaxSceneVertices) + ": use fmpc simulate");
  TemporaryFolder folder;
  std::optional<sim::SceneRunResult> result;
  if (built && !diagnostics.has_errors() && !folder.path.empty()) {
    sim::SceneRunOptions options;
    options.output_directory = folder.path.string();
    options.backend = "cpu";
    result = sim::run_scene(*scene, *built, options, diagnostics);
  }
  if (!result) {
    error = rendered(diagnostics, sources);
    if (error.empty()) error = "the scene could not run";
    return std::nullopt;
  }
  Json curve = Json::array();
  for (const sim::ProbeCurvePoint& p : result->probe_curve) curve.push_back({p.time, p.displacement, p.force});
  Json triangles = Json::array();
  for (const sim::Triangle& t : sim::boundary_triangles(built->mesh))
    for (std::int32_t v : t) triangles.push_back(v);
  Json json;
  json["scene"] = scene->name;
  json["patient_and_rules_used"] = these_rules;
  json["rules"] = scene->material.file;
  json["stiffness"] = built->stiffness_description;
  json["completed"] = result->completed;
  json["steps"] = result->steps_taken;
  json["time_step"] = result->stability.time_step;
  json["wall_seconds"] = result->wall_seconds;
  json["max_displacement"] = result->max_displacement;
  json["probe_curve"] = curve;  // [time s, displacement m, force N]
  json["rest"] = points_json(built->setup.rest_positions);
  json["final"] = points_json(result->final_positions);
  json["triangles"] = triangles;
  json["warnings"] = rendered(diagnostics, sources);
  return json;
}

}  // namespace fmpc::studio

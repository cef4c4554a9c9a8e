#include "runtime/scene/scene_file.h"

#include <yaml-cpp/yaml.h>

#include <filesystem>

#include "diagnostics/number_format.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/scene/scene_file_parser.h"
#include "runtime/scene/scene_file_yaml.h"

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
  const char* keyword = element_law_row(scene.element_law).model_keyword;
  return keyword != nullptr && scene.element_kind == default_element_kind().kind ? keyword : "fem";
}

SourceRange Scene::range_of(const std::string& field) const {
  const auto found = ranges.find(field);
  if (found != ranges.end()) return found->second;
  SourceRange range;
  range.file = path;
  return range;
}

std::optional<std::size_t> planned_step_count(const Scene& scene, double dt, DiagnosticList& diagnostics) {
  if (scene.steps) {
    if (static_cast<double>(*scene.steps) <= kMaxSimulationSteps) return *scene.steps;
    diagnostics.error(scene.range_of("steps"), "steps: " + std::to_string(*scene.steps) + " is above the limit of " +
                                                   format_number(kMaxSimulationSteps) + " steps");
    return std::nullopt;
  }
  const double steps = steps_covering(scene.duration, dt);
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
    scan_scene_yaml(path, text, diagnostics);
    if (diagnostics.error_count() == errors) {
      const YAML::Node root = YAML::Load(text);
      parser.parse(root);
    }
  } catch (const YAML::Exception& e) {
    diagnostics.error(mark_range(path, e.mark), "invalid YAML: " + e.msg);
  }
  if (diagnostics.error_count() != errors) return std::nullopt;
  return scene;
}

}  // namespace fmpc::sim

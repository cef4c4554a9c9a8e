// fmpc::runtime::Session (runtime/session/session.h): a scene loaded and built once, its sim::Simulation, and the
// material swap that rebuilds the scene with another rule file or table.
#include "runtime/session/session.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "compiler/backend/table/lookup_table.h"
#include "diagnostics/number_format.h"
#include "runtime/io/input_file.h"
#include "runtime/io/rule_file_input.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "runtime/scene/scene_run.h"

namespace fmpc::runtime {

namespace {

SourceRange argument(const std::string& name) { return SourceRange{"argument '" + name + "'", 0, 0, 0, 0}; }

std::string name_list(std::vector<std::string> names) {
  std::sort(names.begin(), names.end());
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out.empty() ? "none" : out;
}

// The inputs of the system a material file gives the scene's material (its `system`, or the only one), or nullopt
// after an error; the file's text goes to `sources`.
std::optional<std::vector<std::string>> material_inputs(const std::string& file, bool table,
                                                        const sim::SceneMaterial& material, SourceFiles& sources,
                                                        DiagnosticList& diagnostics) {
  std::vector<std::string> names;
  if (table) {
    std::string error;
    const auto text = sim::read_input_file(file, sim::kMaxTableFileBytes, "table file", error);
    if (!text) {
      diagnostics.error(argument("file"), error);
      return std::nullopt;
    }
    const auto parsed = parse_fzt(file, *text, diagnostics);
    if (!parsed) return std::nullopt;
    for (const Variable& input : table_interface(*parsed).inputs) names.push_back(input.name);
    return names;
  }
  sim::LoadedRuleFile loaded = sim::load_rule_file_from_disk(file);
  if (!loaded.readable || loaded.diagnostics.has_errors()) {
    for (const Diagnostic& d : loaded.diagnostics.items())
      if (d.severity == Severity::Error) diagnostics.add(d);
    if (loaded.readable) {
      std::string error;
      if (const auto text = sim::read_input_file(file, sim::kMaxRuleFileBytes, "rule file", error))
        sources.add(file, *text);
    }
    diagnostics.error(argument("file"), "'" + file + "' cannot be read as rules (above); fix it with fmpc check");
    return std::nullopt;
  }
  const FuzzySystem* system = nullptr;
  for (const FuzzySystem& candidate : loaded.rules.systems)
    if (material.system.empty() ? loaded.rules.systems.size() == 1 : candidate.name == material.system)
      system = &candidate;
  if (system == nullptr) {
    std::vector<std::string> systems;
    for (const FuzzySystem& candidate : loaded.rules.systems) systems.push_back(candidate.name);
    diagnostics.error(argument("file"), "'" + file + "' has " +
                                            (material.system.empty() ? std::to_string(systems.size()) + " systems (" +
                                                                           name_list(systems) + ") where the scene "
                                                                           "names none"
                                                                     : "no system '" + material.system + "' (it has " +
                                                                           name_list(systems) + ")") +
                                            "; the new rules must give the system the scene's material uses");
    return std::nullopt;
  }
  for (const Variable& input : system->inputs) names.push_back(input.name);
  return names;
}

}  // namespace

Session::Session() = default;
Session::~Session() = default;

std::unique_ptr<Session> Session::open(const std::string& path, DiagnosticList& diagnostics,
                                       const SessionOptions& options) {
  std::string error;
  const auto text = sim::read_input_file(path, sim::kMaxSceneFileBytes, "scene file", error);
  if (!text) {
    diagnostics.error(SourceRange{path, 0, 0, 0, 0}, error);
    return nullptr;
  }
  return from_scene(path, *text, diagnostics, options);
}

std::unique_ptr<Session> Session::from_yaml(const std::string& text, const std::string& path,
                                            DiagnosticList& diagnostics, const SessionOptions& options) {
  if (text.size() > sim::kMaxSceneFileBytes) {
    diagnostics.error(SourceRange{path, 0, 0, 0, 0}, "the scene text is " + std::to_string(text.size()) +
                                                         " bytes; a scene takes at most " +
                                                         std::to_string(sim::kMaxSceneFileBytes));
    return nullptr;
  }
  return from_scene(path, text, diagnostics, options);
}

std::unique_ptr<Session> Session::from_scene(const std::string& path, const std::string& text,
                                             DiagnosticList& diagnostics, const SessionOptions& options) {
  std::unique_ptr<Session> session(new Session());
  session->sources_.add(path, text);
  std::optional<sim::Scene> scene = sim::parse_scene(path, text, diagnostics);
  if (!scene) return nullptr;
  sim::Backend backend = options.backend == SessionOptions::Backend::Cuda ? sim::Backend::Cuda : sim::Backend::Cpu;
  if (options.backend == SessionOptions::Backend::Auto) {
    const std::optional<sim::BackendChoice> choice = sim::choose_backend(*scene, diagnostics);
    if (!choice) return nullptr;
    backend = sim::run_backend(choice->backend);
  }
  std::optional<sim::BuiltScene> built = sim::build_scene(*scene, diagnostics);
  if (!built) return nullptr;
  for (const auto& [file, source] : built->sources) session->sources_.add(file, source);
  if (!session->create_simulation(std::move(built->setup), backend, diagnostics)) return nullptr;
  session->scene_ = std::make_unique<sim::Scene>(std::move(*scene));
  return session;
}

std::unique_ptr<Session> Session::from_setup(sim::SimulationSetup setup, DiagnosticList& diagnostics,
                                             const SessionOptions& options) {
  std::unique_ptr<Session> session(new Session());
  const sim::Backend backend =
      options.backend == SessionOptions::Backend::Cuda ? sim::Backend::Cuda : sim::Backend::Cpu;
  if (!session->create_simulation(std::move(setup), backend, diagnostics)) return nullptr;
  return session;
}

bool Session::create_simulation(sim::SimulationSetup setup, sim::Backend backend, DiagnosticList& diagnostics) {
  sim::SimulationOptions options;
  options.backend = backend;
  std::vector<sim::SimulationSetup> scenes;
  scenes.push_back(std::move(setup));
  simulation_ = sim::Simulation::create(std::move(scenes), options, diagnostics);
  return simulation_ != nullptr;
}

bool Session::step(std::size_t steps, DiagnosticList& diagnostics) { return simulation_->advance(steps, diagnostics); }

bool Session::step_to(double time, DiagnosticList& diagnostics) {
  const double dt = time_step();
  if (!std::isfinite(time)) {
    diagnostics.error(argument("time"), "the time " + format_number(time) + " s is not finite");
    return false;
  }
  if (!(time > this->time())) return true;
  const double steps = sim::steps_covering(time - this->time(), dt);
  if (!(steps <= sim::kMaxSimulationSteps)) {
    diagnostics.error(argument("time"), "reaching " + format_number(time) + " s from " + format_number(this->time()) +
                                            " s takes " + format_number(steps) + " steps of " + format_number(dt) +
                                            " s; one call takes at most " +
                                            format_number(sim::kMaxSimulationSteps));
    return false;
  }
  return step(static_cast<std::size_t>(steps), diagnostics);
}

bool Session::step_to_averaging(double time, std::vector<ToolReading>& mean, DiagnosticList& diagnostics,
                                std::vector<ToolReading>* end) {
  const double dt = time_step();
  if (!std::isfinite(time)) {
    diagnostics.error(argument("time"), "the time " + format_number(time) + " s is not finite");
    return false;
  }
  const double ahead = time > this->time() ? sim::steps_covering(time - this->time(), dt) : 0.0;
  if (!(ahead <= sim::kMaxSimulationSteps)) return step_to(time, diagnostics);  // step_to's error
  const auto steps = static_cast<std::size_t>(ahead);
  // The weight of the readings at a step's start and at its end in the force the step applies.
  double start_weight = 1.0, end_weight = 0.0;
  switch (simulation_->setup().integrator) {
    case sim::Integrator::ImplicitEuler: start_weight = 0.0, end_weight = 1.0; break;
    case sim::Integrator::VelocityVerlet:
    case sim::Integrator::RungeKutta4: start_weight = 0.5, end_weight = 0.5; break;
    default: break;
  }
  std::vector<ToolReading> reading = tool_readings(diagnostics);
  if (reading.size() != tool_count()) return false;
  std::vector<ToolReading> sum(reading.size());
  const auto add = [&](const std::vector<ToolReading>& now, double weight) {
    for (std::size_t t = 0; t < now.size(); ++t) {
      for (int i = 0; i < 3; ++i) {
        sum[t].force[i] += weight * now[t].force[i];
        sum[t].torque[i] += weight * now[t].torque[i];
      }
      sum[t].contacts = std::max(sum[t].contacts, now[t].contacts);
      sum[t].deepest = std::max(sum[t].deepest, now[t].deepest);
    }
  };
  for (std::size_t k = 0; k < steps; ++k) {
    add(reading, start_weight);
    if (!step(1, diagnostics)) return false;
    reading = tool_readings(diagnostics);
    if (reading.size() != tool_count()) return false;
    add(reading, end_weight);
  }
  if (steps == 0) {
    mean = reading;
  } else {
    for (ToolReading& tool : sum)
      for (int i = 0; i < 3; ++i) {
        tool.force[i] /= static_cast<double>(steps);  // the impulse sum over dt each, over steps x dt
        tool.torque[i] /= static_cast<double>(steps);
      }
    mean = std::move(sum);
  }
  if (end != nullptr) *end = std::move(reading);
  return true;
}

double Session::time() const { return simulation_->time(); }
double Session::time_step() const { return simulation_->stability().time_step; }
std::size_t Session::steps_taken() const { return simulation_->steps_taken(); }
sim::Backend Session::backend() const { return simulation_->backend(); }
const sim::StabilityReport& Session::stability() const { return simulation_->stability(); }

std::size_t Session::tool_count() const { return simulation_->setup().tools.size(); }

std::optional<std::size_t> Session::find_tool(const std::string& name) const {
  const std::vector<sim::RigidTool>& tools = simulation_->setup().tools;
  for (std::size_t t = 0; t < tools.size(); ++t)
    if (tools[t].name == name) return t;
  return std::nullopt;
}

bool Session::set_tool_pose(std::size_t tool, const ToolPose& pose, DiagnosticList& diagnostics) {
  return simulation_->set_tool_pose(0, tool, pose, diagnostics);
}

const std::vector<ToolPose>& Session::tool_poses() const { return simulation_->tool_poses(); }

std::vector<ToolReading> Session::tool_readings(DiagnosticList& diagnostics) const {
  return simulation_->tool_readings(0, diagnostics);
}

std::size_t Session::vertex_count() const { return simulation_->setup().rest_positions.size(); }

std::vector<Point3> Session::positions(DiagnosticList& diagnostics) const { return simulation_->positions(diagnostics); }

std::vector<Point3> Session::velocities(DiagnosticList& diagnostics) const {
  return simulation_->velocities(diagnostics);
}

std::optional<DevicePositions> Session::device_positions(DiagnosticList& diagnostics) const {
  return simulation_->device_positions(0, diagnostics);
}

std::optional<Energies> Session::energies(DiagnosticList& diagnostics) const {
  const auto kinetic = simulation_->kinetic_energy(diagnostics);
  const auto elastic = simulation_->elastic_energy(diagnostics);
  const auto potential = simulation_->potential_energy(diagnostics);
  if (!kinetic || !elastic || !potential) return std::nullopt;
  return Energies{*kinetic, *elastic, *potential};
}

const sim::InversionReport& Session::inversions() const { return simulation_->inversions(); }

bool Session::swap_material(const std::string& file, DiagnosticList& diagnostics) {
  if (!scene_) {
    diagnostics.error(argument("file"), "this session was made from a setup, which has no scene to build with '" +
                                            file + "'; pass a setup built with the new material instead");
    return false;
  }
  const sim::SceneMaterial& material = scene_->material;
  if (material.source != sim::SceneMaterial::Source::Rules && material.source != sim::SceneMaterial::Source::Table) {
    diagnostics.error(argument("file"), "the scene's material is not a rule file or a table (it gives the stiffness "
                                        "itself), so it has no inputs to evaluate '" + file +
                                            "' with; give the scene material.rules or material.table");
    return false;
  }
  const bool table = std::filesystem::path(file).extension() == ".fzt";
  const auto inputs = material_inputs(file, table, material, sources_, diagnostics);
  if (!inputs) return false;
  std::vector<std::string> bound;
  for (const sim::InputBinding& binding : material.bindings) bound.push_back(binding.input);
  std::vector<std::string> given = *inputs;
  std::sort(given.begin(), given.end());
  std::sort(bound.begin(), bound.end());
  if (given != bound) {
    diagnostics.error(argument("file"), "'" + file + "' takes the inputs " + name_list(given) +
                                            ", but the scene binds " + name_list(bound) +
                                            "; the material was not replaced (a new rule file must keep the inputs "
                                            "the scene's material.inputs bind)");
    return false;
  }
  sim::Scene scene = *scene_;
  scene.material.file = file;
  scene.material.source = table ? sim::SceneMaterial::Source::Table : sim::SceneMaterial::Source::Rules;
  std::optional<sim::BuiltScene> built = sim::build_scene(scene, diagnostics);
  if (built)
    for (const auto& [path, source] : built->sources) sources_.add(path, source);
  if (!built) {
    diagnostics.error(argument("file"), "the scene could not be built with '" + file +
                                            "' (above); the material was not replaced");
    return false;
  }
  if (!simulation_->replace_material(0, built->setup, diagnostics)) return false;
  *scene_ = std::move(scene);
  return true;
}

bool Session::swap_material(const sim::SimulationSetup& material, DiagnosticList& diagnostics) {
  return simulation_->replace_material(0, material, diagnostics);
}

std::string Session::render(const DiagnosticList& diagnostics) const { return render_all(diagnostics, sources_); }

}  // namespace fmpc::runtime

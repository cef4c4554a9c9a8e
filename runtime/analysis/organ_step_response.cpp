#include "runtime/analysis/organ_step_response.h"

#include <cmath>
#include <string>

#include "diagnostics/number_format.h"
#include "runtime/integrate/simulation.h"
#include "runtime/scene/scene_builder.h"

namespace fmpc::sim {

namespace {

double norm(const Point3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

double dot(const Point3& a, const Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// The probe's field, or the scene file where the scene wrote none.
SourceRange probe_range(const Scene& scene) {
  return scene.ranges.count("loads.probe") ? scene.range_of("loads.probe") : scene.range_of("loads");
}

}  // namespace

bool check_organ_scene(const Scene& scene, DiagnosticList& diagnostics) {
  const std::size_t errors_before = diagnostics.error_count();
  if (!scene.probe) {
    std::vector<std::string> notes = {
        "add a probe that picks the vertices the force is shared by, e.g. loads: {probe: {ray: {origin: [...], "
        "direction: [...]}, radius: R, force: [0, 0, -1]}} (docs/scenes.md)"};
    if (!scene.tools.empty())
      notes.insert(notes.begin(), "the scene's tools follow their paths; a force cannot drive them");
    diagnostics.error(scene.range_of(scene.ranges.count("loads") ? "loads" : "name"),
                      "the scene '" + scene.name +
                          "' has no probe (loads.probe): the thesis's experiment applies its step force through one",
                      std::move(notes));
  } else if (!organ_probe_direction(*scene.probe)) {
    diagnostics.error(probe_range(scene),
                      "loads.probe pushes in no direction (its target is zero and it picks by index): the step "
                      "force needs one",
                      {"give the probe a displacement or force along the push, or pick it by a ray"});
  }
  using Source = SceneMaterial::Source;
  const Source source = scene.material.source;
  if (source != Source::YoungsModulus && source != Source::Rules && source != Source::Table) {
    const char* field = source == Source::Stiffness ? "material.stiffness" : "material.stiffness_over_length";
    diagnostics.error(scene.range_of(scene.ranges.count(field) ? field : "material"),
                      std::string(field) + " gives spring constants; the controllers' output is a Young's modulus, "
                                           "which only a material given by youngs_modulus, rules or table takes");
  }
  return diagnostics.error_count() == errors_before;
}

std::optional<Point3> organ_probe_direction(const SceneProbe& probe) {
  const double target = norm(probe.target);
  if (target > 0.0 && std::isfinite(target))
    return Point3{probe.target[0] / target, probe.target[1] / target, probe.target[2] / target};
  const double ray = norm(probe.ray_direction);
  if (probe.by_ray && ray > 0.0 && std::isfinite(ray))
    return Point3{probe.ray_direction[0] / ray, probe.ray_direction[1] / ray, probe.ray_direction[2] / ray};
  return std::nullopt;
}

std::optional<MassPointResponse> simulate_organ_step(const Scene& scene, double modulus,
                                                     const LiverBenchmarkOptions& options,
                                                     DiagnosticList& diagnostics) {
  if (!check_organ_scene(scene, diagnostics)) return std::nullopt;
  if (!(modulus > 0.0) || !std::isfinite(modulus)) {
    diagnostics.error(SourceRange{}, "the organ's Young's modulus is " + format_number(modulus) +
                                         " Pa; it must be positive and finite");
    return std::nullopt;
  }
  if (!(options.duration > 0.0) || !std::isfinite(options.duration) || !std::isfinite(options.force) ||
      options.samples < 2 || options.samples > kLiverBenchmarkSamplesMax) {
    diagnostics.error(SourceRange{}, "the organ's run needs a positive duration, a finite force and 2 to " +
                                         std::to_string(kLiverBenchmarkSamplesMax) + " samples");
    return std::nullopt;
  }
  const Point3 direction = *organ_probe_direction(*scene.probe);
  Scene organ = scene;
  SceneMaterial& material = organ.material;
  material.source = SceneMaterial::Source::YoungsModulus;
  material.value = modulus / 1000.0;  // kPa
  material.file.clear();
  material.bindings.clear();
  material.strain_axis.reset();
  organ.duration = options.duration;
  organ.steps.reset();
  std::optional<BuiltScene> built = build_scene(organ, diagnostics);
  if (!built) return std::nullopt;
  if (!built->setup.probe) {
    diagnostics.error(probe_range(scene), "loads.probe picked no vertex of the built mesh; the step force needs some");
    return std::nullopt;
  }
  ProbeLoad& load = *built->setup.probe;
  load.mode = ProbeLoad::Mode::Force;
  load.target = {options.force * direction[0], options.force * direction[1], options.force * direction[2]};
  load.ramp_time = 0.0;
  load.cycles = 0;
  const std::vector<std::int32_t> probe_vertices = load.vertices;
  const auto simulation = Simulation::create(built->setup, diagnostics);
  if (!simulation) return std::nullopt;
  const auto steps = planned_step_count(organ, simulation->stability(0).time_step, diagnostics);
  if (!steps) return std::nullopt;
  if (*steps + 1 < options.samples) {
    diagnostics.error(scene.range_of("dt"), "the scene's step " + format_number(simulation->stability(0).time_step) +
                                                " s gives " + std::to_string(*steps) + " steps over " +
                                                format_number(options.duration) + " s, fewer than the " +
                                                std::to_string(options.samples - 1) + " sample intervals",
                      {"take fewer samples or a smaller step"});
    return std::nullopt;
  }
  MassPointResponse response;
  response.displacement.name = scene.name + " probe displacement (E = " + format_number(modulus / 1000.0) + " kPa)";
  response.velocity.name = scene.name + " probe velocity (E = " + format_number(modulus / 1000.0) + " kPa)";
  for (const std::size_t step : evenly_spaced_steps(options.samples, *steps)) {
    if (step > simulation->steps_taken() && !simulation->advance(step - simulation->steps_taken(), diagnostics))
      return std::nullopt;
    const ProbeReading reading = simulation->probe_reading(diagnostics);
    const std::vector<Point3> velocities = simulation->velocities(diagnostics);
    Point3 mean{0.0, 0.0, 0.0};
    for (const std::int32_t v : probe_vertices)
      for (int axis = 0; axis < 3; ++axis) mean[axis] += velocities[static_cast<std::size_t>(v)][axis];
    for (double& component : mean) component /= static_cast<double>(probe_vertices.size());
    response.displacement.time.push_back(simulation->time());
    response.displacement.value.push_back(dot(reading.displacement, direction));
    response.velocity.time.push_back(simulation->time());
    response.velocity.value.push_back(dot(mean, direction));
  }
  return response;
}

}  // namespace fmpc::sim

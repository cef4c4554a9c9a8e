#include "runtime/scene/simulation_trade.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <thread>
#include <tuple>
#include <utility>

#include "diagnostics/number_format.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/io/memory_limit.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/mesh/mesh_refinement.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/trade_runs.h"

namespace fmpc::sim {

int TradeModel::rank() const {
  if (element_law < 0) return mapping == StiffnessMapping::LloydSzekelyHarders2007 ? 1 : 0;
  const int laws = static_cast<int>(element_law_rows().size());
  return 2 + element_law + (element_law_row(element_law).beside_springs ? 0 : laws);
}

std::vector<TradeModel> trade_models() {
  std::vector<TradeModel> models{TradeModel{-1, StiffnessMapping::VanGelder1998},
                                 TradeModel{-1, StiffnessMapping::LloydSzekelyHarders2007}};
  for (const ElementLawRow& row : element_law_rows()) models.push_back(TradeModel{row.law, StiffnessMapping::VanGelder1998});
  std::sort(models.begin(), models.end());
  return models;
}

TradeForceSource trade_probe_force_source(const Scene& scene) {
  if (scene.probe && scene.probe->mode == ProbeLoad::Mode::Displacement) return TradeForceSource::Probe;
  if (scene.tools.empty()) return TradeForceSource::None;
  const std::vector<ToolKeyframe>& path = scene.tools.front().path;
  return !path.empty() && path.front().pose.position != path.back().pose.position ? TradeForceSource::Tool
                                                                                  : TradeForceSource::None;
}

TradeModel trade_reference_model() { return TradeModel{default_fem_law().law, StiffnessMapping::VanGelder1998}; }

std::string trade_model_name(const TradeModel& model) {
  if (model.element_law >= 0) return element_law_row(model.element_law).trade_name;
  return model.mapping == StiffnessMapping::LloydSzekelyHarders2007 ? "springs_lloyd" : "springs_van_gelder";
}

std::optional<TradeModel> parse_trade_model(const std::string& name) {
  for (const TradeModel& model : trade_models())
    if (name == trade_model_name(model)) return model;
  return std::nullopt;
}

const std::vector<TradeAxisRow>& trade_axes() {
  static const std::vector<TradeAxisRow> rows{
      {TradeAxis::Laws, "laws", "--models", "the scene's own model"},
      {TradeAxis::Elements, "elements", "--elements", "the scene's element kind (linear for a spring scene)"},
      {TradeAxis::Meshes, "meshes", "--meshes", "the scene's mesh (graded, when it comes from a surface)"},
      {TradeAxis::Precisions, "precisions", "--precisions", "the scene's precision"},
      {TradeAxis::Integrators, "integrators", "--integrators",
       "the scene's integrator at the automatic step (implicit Euler: at 4 of them)"},
      {TradeAxis::Refinements, "refinements", "--refinements", "0: the scene's mesh as it is"},
  };
  return rows;
}

std::optional<TradeAxis> parse_trade_axis(const std::string& name) {
  for (const TradeAxisRow& row : trade_axes())
    if (name == row.name) return row.axis;
  return std::nullopt;
}

namespace {

// |a - b| / |b| as TradeErrors, over the compared vertices.
TradeErrors compare(const std::vector<Point3>& got, double got_force, const std::vector<Point3>& reference,
                    double reference_force, bool probe) {
  TradeErrors errors;
  double largest_difference = 0.0, largest_reference = 0.0, sum_difference = 0.0, sum_reference = 0.0;
  for (std::size_t v = 0; v < reference.size() && v < got.size(); ++v) {
    const double d = distance(got[v], reference[v]);
    const double r = std::sqrt(reference[v][0] * reference[v][0] + reference[v][1] * reference[v][1] +
                               reference[v][2] * reference[v][2]);
    largest_difference = std::max(largest_difference, d);
    largest_reference = std::max(largest_reference, r);
    sum_difference += d * d;
    sum_reference += r * r;
  }
  errors.displacement_max = largest_difference / largest_reference;
  errors.displacement_rms = std::sqrt(sum_difference / sum_reference);
  if (probe) errors.probe_force = std::abs(got_force - reference_force) / std::abs(reference_force);
  return errors;
}

// The largest error of the measures kept.
double measured(const TradeErrors& errors, const TradeMeasures& measures) {
  double value = measures.displacement ? errors.displacement_max : 0.0;
  if (measures.probe_force && errors.probe_force) value = std::max(value, *errors.probe_force);
  return value;
}

// Whether every kept measure is at most `bound` (a NaN never is).
bool within(const TradeErrors& errors, const TradeMeasures& measures, double bound) {
  if (measures.displacement && !(errors.displacement_max <= bound)) return false;
  if (measures.probe_force && !(errors.probe_force && *errors.probe_force <= bound)) return false;
  return true;
}

// What the scene must be for every model to be built from it and compared; errors name the field.
bool check_comparable(const Scene& scene, const std::vector<TradeModel>& models, DiagnosticList& diagnostics) {
  const std::size_t errors = diagnostics.error_count();
  const std::string why = "fmpc trade compares force models against a finite-element reference";
  if (scene.material.source == SceneMaterial::Source::Stiffness ||
      scene.material.source == SceneMaterial::Source::StiffnessOverLength)
    diagnostics.error(scene.range_of("material"),
                      "material: " + why + ", which needs Young's modulus; give material.youngs_modulus, rules or "
                      "table instead of spring constants");
  if (scene.law.law != kernels::SpringLaw::LinearDashpot || scene.law.gamma0 != 0.0 || scene.law.gamma1 != 0.0)
    diagnostics.error(scene.range_of("law"), "law: " + why + ", which is linear elastic; a spring law or nodal "
                                             "damping has no counterpart there: remove `law` to compare");
  if (scene.damping.rule != DampingSpec::Rule::DampingRatio)
    diagnostics.error(scene.range_of("damping"),
                      "damping: " + why + ", which is damped by `ratio` and `rayleigh`; per-spring dashpot settings "
                      "(coefficient, natural_frequency) have no counterpart there");
  // A law beside springs takes one Poisson ratio and no strain-dependent modulus (scene_builder's checks).
  for (const TradeModel& model : models) {
    if (model.element_law < 0 || !element_law_row(model.element_law).beside_springs) continue;
    const std::string name = trade_model_name(model);
    for (const InputBinding& binding : scene.material.bindings)
      if (binding.kind == InputBinding::Kind::Strain)
        diagnostics.error(scene.range_of("material.inputs." + binding.input),
                          "material.inputs." + binding.input + ": the " + name + " variant cannot take a "
                          "strain-dependent modulus; leave it out with --models");
    if (scene.material.poisson_ratio && !scene.material.poisson_ratio->regions.empty())
      diagnostics.error(scene.range_of("material.poisson_ratio"),
                        "material.poisson_ratio: the " + name + " variant takes one ratio for the whole "
                        "scene; leave it out with --models");
  }
  return diagnostics.error_count() == errors;
}

// The scene's own model as a trade model.
TradeModel scene_model(const Scene& scene) {
  if (scene.model == ForceModel::Elements) return TradeModel{scene.element_law, StiffnessMapping::VanGelder1998};
  if (scene.volume_term) return TradeModel{element_law_beside_springs().law, StiffnessMapping::VanGelder1998};
  return TradeModel{-1, scene.material.mapping};
}

// Whether the scene's mesh is graded from a surface: then its uniform counterpart (size_near everywhere) differs.
bool graded_surface(const Scene& scene) {
  const SceneSurfaceMeshing& surface = scene.mesh.surface;
  return scene.mesh.kind == SceneMesh::Kind::Surface && surface.size_near_given &&
         (!surface.size_far_given || surface.options.size.size_near < surface.options.size.size_far);
}

bool varies(const SimulationTradeOptions& options, TradeAxis axis) {
  return std::find(options.axes.begin(), options.axes.end(), axis) != options.axes.end();
}

// Every axis's values: the options' where the axis varies, the scene's own where it does not.
struct TradeAxesValues {
  std::vector<TradeModel> models;
  std::vector<int> element_kinds;
  std::vector<TradeMesh> meshes;
  std::vector<Precision> precisions;
  std::vector<TradeIntegrator> integrators;
  std::vector<unsigned> refinements;
};

std::optional<TradeAxesValues> axes_values(const Scene& scene, const SimulationTradeOptions& options,
                                           DiagnosticList& diagnostics) {
  TradeAxesValues values;
  const SourceRange nowhere{};
  values.models = varies(options, TradeAxis::Laws) ? options.models : std::vector<TradeModel>{scene_model(scene)};
  if (varies(options, TradeAxis::Elements)) {
    values.element_kinds = options.element_kinds;
    if (values.element_kinds.empty())
      for (const ElementKindRow& row : element_kind_rows()) values.element_kinds.push_back(row.kind);
  } else {
    values.element_kinds = {scene.model == ForceModel::Elements ? scene.element_kind : default_element_kind().kind};
  }
  values.meshes = {TradeMesh::Scene};
  if (varies(options, TradeAxis::Meshes)) {
    const bool uniform = std::find(options.meshes.begin(), options.meshes.end(), TradeMesh::Uniform) != options.meshes.end();
    if (uniform && graded_surface(scene)) values.meshes = options.meshes;
    else if (uniform && options.meshes_given)
      diagnostics.error(scene.range_of("mesh"),
                        "mesh: --meshes uniform compares a mesh graded from a surface with its uniform counterpart; "
                        "this scene's mesh is not graded (it needs mesh: {surface} with size_near below size_far, "
                        "docs/meshing.md): leave out --meshes");
  }
  values.precisions = varies(options, TradeAxis::Precisions) ? options.precisions
                                                             : std::vector<Precision>{scene.precision};
  values.integrators =
      varies(options, TradeAxis::Integrators)
          ? options.integrators
          : std::vector<TradeIntegrator>{{scene.integrator, scene.integrator == Integrator::ImplicitEuler ? 4.0 : 1.0}};
  values.refinements = varies(options, TradeAxis::Refinements) ? options.refinements : std::vector<unsigned>{0};
  if (values.models.empty() || values.element_kinds.empty() || values.meshes.empty() || values.precisions.empty() ||
      values.integrators.empty() || values.refinements.empty())
    diagnostics.error(nowhere, "--models, --elements, --meshes, --precisions, --integrators and --refinements each "
                               "need at least one value");
  for (const TradeIntegrator& integrator : values.integrators)
    if (!(integrator.dt_factor > 0.0) || !std::isfinite(integrator.dt_factor))
      diagnostics.error(nowhere, "--integrators: the step factor of " + std::string(scene_name(integrator.integrator)) +
                                     " must be a positive number, got " + format_number(integrator.dt_factor));
  if (diagnostics.has_errors()) return std::nullopt;
  return values;
}

// The measures a decision keeps: the options', or the displacement and (with a displacement probe) the probe force.
std::optional<TradeMeasures> resolved_measures(const Scene& scene, const SimulationTradeOptions& options,
                                               DiagnosticList& diagnostics) {
  const bool probe = trade_probe_force_source(scene) != TradeForceSource::None;
  TradeMeasures measures;
  measures.probe_force = probe;
  if (options.measures) {
    measures = *options.measures;
    if (measures.probe_force && !probe) {
      diagnostics.error(scene.range_of(scene.probe ? "loads.probe" : "loads"),
                        std::string(scene.probe ? "loads.probe: this probe is given a force, not a displacement"
                                                : "loads: the scene has no probe") +
                            ", so there is no probe force to compare; --error probe_force needs loads.probe with a "
                            "displacement or a tool whose path moves it: use --error displacement");
      return std::nullopt;
    }
    if (!measures.displacement && !measures.probe_force) {
      diagnostics.error(SourceRange{}, "--error: name displacement, probe_force or both");
      return std::nullopt;
    }
  }
  return measures;
}

// What the runs cost, checked before they run: every run's steps, the largest run's memory, the work in all.
class TradePlanner {
 public:
  TradePlanner(const Scene& scene, TradeScenes& scenes, double duration, bool reference_factor_named)
      : scene_(scene), scenes_(scenes), duration_(duration), reference_factor_named_(reference_factor_named) {}

  // The work of each key (element-steps), after checking each; nullopt after an error.
  std::optional<std::vector<double>> check(const std::vector<RunKey>& keys, const std::vector<RunKey>& variants,
                                           TradePlan& plan, DiagnosticList& diagnostics) {
    const SourceRange nowhere{};
    const MemoryLimit memory = memory_limit();
    std::vector<double> work(keys.size());
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const RunKey& key = keys[i];
      BuildKey coarse = key.build;
      coarse.refinements = 0;
      const std::shared_ptr<const BuiltRun> built = scenes_.get(coarse, diagnostics);
      if (!built) return std::nullopt;
      const double scale = std::pow(8.0, key.build.refinements);
      const double tetrahedra = static_cast<double>(built->scene.mesh.tetrahedra.size()) * scale;
      const double step = key.dt_factor * built->automatic_step / std::pow(2.0, key.build.refinements);
      const double steps = std::max(1.0, steps_covering(duration_, step));
      SimulationSetup setup = built->scene.setup;
      setup.precision = key.precision;
      setup.integrator = key.integrator;
      // The run's arrays, and the refined mesh and its setup while it is built (generated_mesh.h's measured figure).
      const double memory_bytes = trade_memory_estimate(setup, built->edges) * scale +
                                  static_cast<double>(kEstimatedBytesPerTetrahedron) * tetrahedra;
      const bool reference_run = std::find(variants.begin(), variants.end(), key) == variants.end();
      if (!(steps <= kMaxSimulationSteps)) {
        diagnostics.error(nowhere, "the run " + run_label(key) + " would take " + significant_digits(steps, 3) +
                                       " steps (" + significant_digits(duration_, 3) + " s at about " +
                                       significant_digits(duration_ / steps, 3) + " s a step); the limit is " +
                                       format_number(kMaxSimulationSteps) + " steps a run, as for simulate",
                          {"shorten --duration, or raise " +
                           std::string(reference_run ? (reference_factor_named_ ? "--reference-dt-factor"
                                                                                : "--max-error")
                                                     : "the step factor of --integrators " +
                                                           std::string(scene_name(key.integrator)))});
        return std::nullopt;
      }
      if (memory.bytes > 0 && memory_bytes > static_cast<double>(memory.bytes)) {
        diagnostics.error(scene_.range_of("mesh"),
                          "mesh: the run " + run_label(key) + " needs an estimated " + gibibytes_text(memory_bytes) +
                              " (" + significant_digits(tetrahedra, 3) + " tetrahedra); the limit is " +
                              memory.source + ", " + gibibytes_text(static_cast<double>(memory.bytes)),
                          {"lower --refinements or --reference-refinements, or coarsen the mesh"});
        return std::nullopt;
      }
      work[i] = tetrahedra * steps;
      plan.runs += 1;
      plan.element_steps += work[i];
      plan.largest_tetrahedra = std::max(plan.largest_tetrahedra, tetrahedra);
      plan.largest_steps = std::max(plan.largest_steps, steps);
      plan.largest_memory_bytes = std::max(plan.largest_memory_bytes, memory_bytes);
    }
    if (!(plan.element_steps <= kMaxTradeWork)) {
      diagnostics.error(nowhere, "the trade's " + std::to_string(plan.runs) + " runs would take about " +
                                     significant_digits(plan.element_steps, 3) + " element-steps (tetrahedra x "
                                     "steps); the limit is " + format_number(kMaxTradeWork),
                        {"fewer --refinements, models, precisions or integrators, a larger step factor, or a shorter "
                         "--duration"});
      return std::nullopt;
    }
    return work;
  }

  // The scene's tetrahedra refined `level` times.
  double tetrahedra(const BuildKey& key, DiagnosticList& diagnostics) {
    BuildKey coarse = key;
    coarse.refinements = 0;
    const std::shared_ptr<const BuiltRun> built = scenes_.get(coarse, diagnostics);
    return built ? static_cast<double>(built->scene.mesh.tetrahedra.size()) * std::pow(8.0, key.refinements) : 0.0;
  }

 private:
  const Scene& scene_;
  TradeScenes& scenes_;
  double duration_;
  bool reference_factor_named_;
};

// The reference's runs at one refinement level and step: itself, its step check (twice the step) and its mesh
// check (one refinement coarser; none on the scene's own mesh).
struct ReferenceRuns {
  RunKey reference, time_check;
  std::optional<RunKey> mesh_check;
};

ReferenceRuns reference_runs(const BuildKey& build, double dt_factor) {
  ReferenceRuns runs;
  runs.reference = RunKey{build, Precision::Double, Integrator::SemiImplicitEuler, dt_factor};
  runs.time_check = runs.reference;
  runs.time_check.dt_factor = 2.0 * dt_factor;
  if (build.refinements > 0) {
    runs.mesh_check = runs.reference;
    runs.mesh_check->build.refinements = build.refinements - 1;
  }
  return runs;
}

}  // namespace

std::optional<SimulationTradeResult> run_simulation_trade(const Scene& scene, const SimulationTradeOptions& options,
                                                          DiagnosticList& diagnostics) {
  const std::size_t errors = diagnostics.error_count();
  const SourceRange nowhere{};
  const std::optional<TradeAxesValues> values = axes_values(scene, options, diagnostics);
  if (!values) return std::nullopt;
  // Its step check runs at twice the factor, which must stay within the automatic (stable) step.
  if (!(options.reference_dt_factor > 0.0) || !(options.reference_dt_factor <= 0.5))
    diagnostics.error(nowhere, "--reference-dt-factor must be in (0, 0.5] (its check runs at twice it), got " +
                                   format_number(options.reference_dt_factor));
  if (options.max_error && !(*options.max_error > 0.0 && *options.max_error <= 1.0))
    diagnostics.error(nowhere, "--max-error must be a relative error in (0, 1] (0.05 is 5%), got " +
                                   format_number(*options.max_error));
  const unsigned finest = *std::max_element(values->refinements.begin(), values->refinements.end());
  const unsigned reference_level =
      options.reference_refinements.value_or(std::max(finest, options.max_error ? 1u : finest));
  if (std::max(finest, reference_level) > kMaxTradeRefinements)
    diagnostics.error(nowhere, "--refinements and --reference-refinements go up to " +
                                   std::to_string(kMaxTradeRefinements) + " (each multiplies the tetrahedra by 8)");
  if (reference_level < finest)
    diagnostics.error(nowhere, "--reference-refinements " + std::to_string(reference_level) +
                                   " is coarser than the finest variant (--refinements up to " + std::to_string(finest) +
                                   "); the reference must be at least as fine");
  const double duration = options.duration.value_or(scene.duration);
  if (!(duration > 0.0) || !std::isfinite(duration))
    diagnostics.error(nowhere, "--duration must be a positive number of seconds, got " + format_number(duration));
  const std::optional<TradeMeasures> measures = resolved_measures(scene, options, diagnostics);
  if (diagnostics.error_count() != errors || !measures || !check_comparable(scene, values->models, diagnostics))
    return std::nullopt;

  // The reference: the scene's own finite-element law and element kind (a spring scene: the default law on linear
  // tetrahedra), in double, semi-implicit Euler, on the scene's mesh refined.
  const TradeModel own = scene_model(scene);
  BuildKey reference_build;
  reference_build.model = trade_has_springs(own) ? trade_reference_model() : own;
  reference_build.element_kind = scene.model == ForceModel::Elements ? scene.element_kind : default_element_kind().kind;
  reference_build.refinements = reference_level;
  if (const char* refusal =
          options.gpu ? cuda_refusal(element_kind_limits(reference_build.element_kind), false) : nullptr) {
    diagnostics.error(scene.range_of("fem"), std::string("--gpu: the reference is the scene's element kind, fem.element ") +
                                                 element_kind_row(reference_build.element_kind).keyword + ", which " +
                                                 refusal + "; run the trade on the CPU (leave out --gpu)");
    return std::nullopt;
  }

  // The scene's own mesh, sized before anything is refined.
  std::size_t compared_vertices = 0;
  {
    DiagnosticList build_diagnostics;
    // The scene's own model (a membrane of springs builds, and is refused below as a mesh without tetrahedra).
    BuildKey coarse_key = reference_build;
    coarse_key.refinements = 0;
    if (trade_has_springs(own)) {
      coarse_key.model = own;
      coarse_key.element_kind = -1;
    }
    const auto coarse = build_scene(trade_variant_scene(scene, coarse_key, duration), build_diagnostics);
    if (!coarse) {
      diagnostics.append(build_diagnostics);
      return std::nullopt;
    }
    if (coarse->mesh.tetrahedra.empty()) {
      diagnostics.error(scene.range_of("mesh"), "mesh: fmpc trade compares force models on tetrahedra; this mesh has "
                                                "only triangles (a membrane or a surface): give a volume mesh");
      return std::nullopt;
    }
    const double largest = static_cast<double>(coarse->mesh.tetrahedra.size()) * std::pow(8.0, reference_level);
    if (largest > static_cast<double>(kMaxTradeTetrahedra)) {
      diagnostics.error(scene.range_of("mesh"),
                        "mesh: " + std::to_string(coarse->mesh.tetrahedra.size()) + " tetrahedra refined " +
                            std::to_string(reference_level) + " times make " + format_number(largest) +
                            ", above the trade's limit of " + std::to_string(kMaxTradeTetrahedra) +
                            "; lower --refinements or --reference-refinements, or coarsen the mesh");
      return std::nullopt;
    }
    // A mesh from a surface is compared at the surface's vertices (the first ones of every mesh of it: graded,
    // uniform, refined); any other at the scene's own vertices (a refinement keeps them first).
    compared_vertices = coarse->meshing ? coarse->meshing->result.surface_vertices : coarse->mesh.points.size();
  }

  std::vector<RunKey> variants;
  for (const TradeModel& model : values->models)
    for (const int kind : trade_has_springs(model) ? std::vector<int>{-1} : values->element_kinds)
      for (const TradeMesh mesh : values->meshes)
        for (const unsigned refinements : values->refinements)
          for (const Precision precision : values->precisions)
            for (const TradeIntegrator& integrator : values->integrators)
              variants.push_back(RunKey{BuildKey{model, kind, mesh, refinements}, precision, integrator.integrator,
                                        integrator.dt_factor});
  std::sort(variants.begin(), variants.end());
  variants.erase(std::unique(variants.begin(), variants.end()), variants.end());
  // The table lists every variant; those the engines do not run (element_kind_limits: a kind on CUDA or with implicit
  // Euler) are skipped with the registry's reason, as are finer ones that cannot win (below).
  const std::vector<RunKey> listed = variants;
  std::map<RunKey, std::string> skipped;
  variants.erase(std::remove_if(variants.begin(), variants.end(),
                                [&](const RunKey& key) {
                                  if (key.build.element_kind < 0) return false;
                                  const ElementKindLimits limits = element_kind_limits(key.build.element_kind);
                                  const bool implicit = key.integrator == Integrator::ImplicitEuler;
                                  const char* refusal = options.gpu ? cuda_refusal(limits, implicit) : nullptr;
                                  if (!refusal && implicit) refusal = limits.implicit_euler;
                                  if (!refusal) return false;
                                  skipped[key] = std::string("skipped: fem.element ") +
                                                 element_kind_row(key.build.element_kind).keyword + " " + refusal;
                                  return true;
                                }),
                 variants.end());

  TradeScenes scenes(scene, duration);
  TradePlanner planner(scene, scenes, duration, !options.max_error);
  TradeExecution execution;
  execution.gpu = options.gpu;
  execution.batch = options.batch;
  execution.threads = options.threads > 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  execution.duration = duration;
  execution.compared_vertices = compared_vertices;
  execution.prefix_seconds = options.prefix_seconds;

  SimulationTradeResult result;
  result.scene_name = scene.name;
  result.duration = duration;
  result.coarse_vertices = compared_vertices;
  result.max_error = options.max_error;
  result.measures = *measures;
  result.backend = options.gpu ? "CUDA, the runs in batches"
                               : options.batch ? "the CPU, the runs in batches"
                                               : "the CPU, " + std::to_string(execution.threads) +
                                                     " run(s) side by side, one thread each";

  // Rounds: the reference, its checks and the variants on the coarsest mesh; with --max-error the reference is then
  // refined (or its step halved) while an estimate is above a fifth of it. Then the variants on finer meshes, level
  // by level: with --max-error, one whose run one refinement coarser took more than an eighth of the cheapest
  // variant's that meets it (CPU seconds) is skipped (a refinement costs 8 times the elements and at least as many
  // steps: it cannot be faster). With --max-error on the CPU the variants wait for the final reference and go level
  // by level cheapest first (execute_cheapest_first), each level bounded by the cheapest run meeting E so far.
  std::map<RunKey, RunOutcome> outcomes;
  const bool cheapest_first = options.max_error && !options.gpu && !options.batch;
  std::map<RunKey, TradeSkip> estimated_skips;
  std::map<RunKey, std::pair<double, std::size_t>> estimates;  // CPU seconds, from its first steps
  double work_before = 0.0;
  double reference_factor = options.reference_dt_factor;
  ReferenceRuns current = reference_runs(reference_build, reference_factor);
  const unsigned coarsest = *std::min_element(values->refinements.begin(), values->refinements.end());
  const auto unrun = [&](std::vector<RunKey> keys) {
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    keys.erase(std::remove_if(keys.begin(), keys.end(), [&](const RunKey& k) { return outcomes.count(k) > 0; }),
               keys.end());
    return keys;
  };
  {
    // What everything will cost, said (and checked against the limits) before anything runs.
    std::vector<RunKey> all{current.reference, current.time_check};
    if (current.mesh_check) all.push_back(*current.mesh_check);
    all.insert(all.end(), variants.begin(), variants.end());
    all = unrun(all);
    TradePlan plan;
    if (!planner.check(all, variants, plan, diagnostics)) return std::nullopt;
    plan.cheapest_first = cheapest_first;
    if (options.plan) options.plan(plan);
  }
  std::size_t runs_planned = 0;
  // Runs `keys` (those not run yet) on the execution, or cheapest first within `bound` (the CPU seconds of the
  // cheapest run known to meet E; `meets` judges a run); false after an error.
  const auto run_keys = [&](const std::vector<RunKey>& wanted, const std::string& what,
                            const std::function<bool(const RunOutcome&)>& meets = {}, double bound = HUGE_VAL) {
    const std::vector<RunKey> keys = unrun(wanted);
    TradePlan round_plan;
    const auto work = planner.check(keys, variants, round_plan, diagnostics);
    if (!work) return false;
    runs_planned += keys.size();
    if (options.progress) options.progress(outcomes.size(), runs_planned, what);
    const double round_work = round_plan.element_steps;
    const auto done = [&](double work_done) {
      if (options.work_progress) options.work_progress(work_before + work_done, work_before + round_work);
    };
    std::vector<std::optional<RunOutcome>> ran;
    if (meets) {
      CheapestFirstRuns cheapest = execute_cheapest_first(keys, *work, scenes, execution, meets, bound, done, diagnostics);
      for (std::size_t i = 0; i < keys.size(); ++i) {
        if (cheapest.skips[i]) estimated_skips.emplace(keys[i], *cheapest.skips[i]);
        if (!std::isnan(cheapest.estimates[i]))
          estimates.emplace(keys[i], std::make_pair(cheapest.estimates[i], cheapest.prefix_steps[i]));
      }
      ran = std::move(cheapest.outcomes);
    } else {
      ran = execute_trade_runs(keys, *work, scenes, execution, done, diagnostics);
    }
    work_before += round_work;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (!ran[i] && estimated_skips.count(keys[i]) > 0) continue;
      if (!ran[i]) return false;
      outcomes.emplace(keys[i], std::move(*ran[i]));
    }
    return true;
  };
  for (std::size_t round = 0;; ++round) {
    std::vector<RunKey> keys{current.reference, current.time_check};
    if (current.mesh_check) keys.push_back(*current.mesh_check);
    if (round == 0 && !cheapest_first)
      for (const RunKey& key : variants)
        if (key.build.refinements == coarsest || !options.max_error) keys.push_back(key);
    if (!run_keys(keys, (round == 0 ? "reference " : "reference round " + std::to_string(round + 1) + ", ") +
                            run_label(current.reference)))
      return std::nullopt;
    const RunOutcome& ref = outcomes.at(current.reference);
    const std::string name = run_label(current.reference);
    if (!ref.row.completed) {
      diagnostics.error(scene.range_of("model"), "the reference (" + name + ") did not complete: " + ref.row.failure);
      return std::nullopt;
    }
    // Rounding moves a block at rest by about 1e-16 of its size: what moves less than 1e-9 of it does not move.
    if (!(ref.row.final_max_displacement > 1e-9 * ref.extent)) {
      diagnostics.error(scene.range_of("loads"), "the reference (" + name + ") does not move: no displacement to "
                                                 "compare; give the scene a load (probe, gravity or forces)");
      return std::nullopt;
    }
    result.has_probe_force =
        trade_probe_force_source(scene) != TradeForceSource::None && ref.row.final_probe_force != 0.0;
    const auto errors_of = [&](const RunOutcome& outcome) {
      return compare(outcome.displacement, outcome.row.final_probe_force, ref.displacement,
                     ref.row.final_probe_force, result.has_probe_force);
    };
    for (const auto& [key, label] : {std::make_pair(current.time_check, "step check"),
                                     std::make_pair(current.mesh_check.value_or(current.reference), "mesh check")}) {
      const RunOutcome& check = outcomes.at(key);
      if (!check.row.completed) {
        diagnostics.error(scene.range_of("model"), "the reference's " + std::string(label) + " (" + run_label(key) +
                                                       ") did not complete: " + check.row.failure);
        return std::nullopt;
      }
    }
    result.reference_time_difference = errors_of(outcomes.at(current.time_check));
    result.reference_mesh_difference.reset();
    if (current.mesh_check) result.reference_mesh_difference = errors_of(outcomes.at(*current.mesh_check));
    const double step_estimate = measured(result.reference_time_difference, *measures);
    const double mesh_estimate =
        result.reference_mesh_difference ? measured(*result.reference_mesh_difference, *measures) : 0.0;
    result.reference_rounds.push_back(name + ": step estimate " + trade_percent(step_estimate) + ", mesh estimate " +
                                      (current.mesh_check ? trade_percent(mesh_estimate) : std::string("none")) + " (" +
                                      significant_digits(ref.row.cpu_seconds, 3) + " s of one core)");
    if (!options.max_error) break;
    const double target = *options.max_error / 5.0;
    const bool refine = mesh_estimate > target, halve = step_estimate > target;
    if (!refine && !halve) break;
    // The next round: a refinement multiplies the reference's work by 16 (8 times the tetrahedra, twice the steps),
    // a halved step by 2, each with its checks (about half again).
    BuildKey next_build = current.reference.build;
    if (refine) ++next_build.refinements;
    const double next_factor = halve ? reference_factor / 2.0 : reference_factor;
    const double next_seconds = ref.row.cpu_seconds * (refine ? 16.0 : 1.0) * (halve ? 2.0 : 1.0) * 1.5;
    std::string cannot;
    if (refine && next_build.refinements > kMaxTradeRefinements)
      cannot = "refinement " + std::to_string(next_build.refinements) + " is past the trade's limit of " +
               std::to_string(kMaxTradeRefinements);
    else if (refine && planner.tetrahedra(next_build, diagnostics) > static_cast<double>(kMaxTradeTetrahedra))
      cannot = "refinement " + std::to_string(next_build.refinements) + " would make " +
               format_number(planner.tetrahedra(next_build, diagnostics)) + " tetrahedra, above the trade's limit of " +
               std::to_string(kMaxTradeTetrahedra);
    else if (next_seconds > options.max_reference_seconds)
      cannot = std::string(refine ? "refinement " + std::to_string(next_build.refinements) : "a halved step") +
               " would take about " + significant_digits(next_seconds, 2) + " s of one core (from this round's " +
               significant_digits(ref.row.cpu_seconds, 3) + " s), above --max-reference-seconds " +
               format_number(options.max_reference_seconds);
    if (!cannot.empty()) {
      const double floor = 5.0 * std::max(step_estimate, mesh_estimate);
      diagnostics.error(nowhere, "--max-error " + trade_percent(*options.max_error) + ": the reference cannot be refined "
                                 "until its own estimated error is under a fifth of it (" + trade_percent(target) + "): " +
                                 name + " has a " + (refine ? "mesh" : "step") + " estimate of " +
                                 trade_percent(refine ? mesh_estimate : step_estimate) + ", and " + cannot,
                        {"ask for --max-error " + trade_percent(floor) + " or more (five times the reference's estimate)" +
                             (cannot.find("--max-reference-seconds") != std::string::npos
                                  ? ", or allow the reference more time with --max-reference-seconds"
                                  : ", or start from a finer mesh")});
      return std::nullopt;
    }
    reference_factor = next_factor;
    current = reference_runs(next_build, next_factor);
  }
  // The finer variants, level by level (with --max-error; without it they ran in the first round).
  std::vector<unsigned> levels = values->refinements;
  std::sort(levels.begin(), levels.end());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  for (const unsigned level : levels) {
    if (!options.max_error || (level == coarsest && !cheapest_first)) continue;
    const RunOutcome& ref = outcomes.at(current.reference);
    const auto meets = [&](const RunOutcome& outcome) {
      return within(compare(outcome.displacement, outcome.row.final_probe_force, ref.displacement,
                            ref.row.final_probe_force, result.has_probe_force),
                    *measures, *options.max_error);
    };
    double best_wall = HUGE_VAL;
    std::string best;
    for (const RunKey& key : variants) {
      const auto it = outcomes.find(key);
      if (it == outcomes.end() || !it->second.row.completed) continue;
      if (meets(it->second) && it->second.row.cpu_seconds < best_wall) {
        best_wall = it->second.row.cpu_seconds;
        best = run_label(key);
      }
    }
    std::vector<RunKey> wave;
    for (const RunKey& key : variants) {
      if (key.build.refinements != level) continue;
      RunKey coarser = key;
      coarser.build.refinements = level - 1;
      // The coarser run's cost: measured, or (skipped cheapest first) its estimate or its prefix's time.
      std::string coarser_cost;
      if (const auto it = level > coarsest ? outcomes.find(coarser) : outcomes.end();
          it != outcomes.end() && it->second.row.completed && 8.0 * it->second.row.cpu_seconds > best_wall)
        coarser_cost = " took " + significant_digits(it->second.row.cpu_seconds, 3) + " s";
      else if (const auto e = level > coarsest ? estimated_skips.find(coarser) : estimated_skips.end();
               e != estimated_skips.end() && 8.0 * e->second.seconds > best_wall)
        coarser_cost = std::string(e->second.prefix ? "'s first steps took " : " was estimated at ") +
                       significant_digits(e->second.seconds, 3) + " s (skipped)";
      if (!coarser_cost.empty()) {
        skipped[key] = "skipped: " + run_label(coarser) + coarser_cost + ", and one refinement costs at least 8 "
                       "times that; " + best + ", which meets --max-error, took " + significant_digits(best_wall, 3) +
                       " s";
        continue;
      }
      wave.push_back(key);
    }
    const std::string what = "variants on refinement " + std::to_string(level);
    if (!(cheapest_first ? run_keys(wave, what + ", cheapest first", meets, best_wall) : run_keys(wave, what)))
      return std::nullopt;
  }
  if (options.progress) options.progress(outcomes.size(), outcomes.size(), "done");

  const RunOutcome& ref = outcomes.at(current.reference);
  const auto errors_of = [&](const RunOutcome& outcome) {
    return compare(outcome.displacement, outcome.row.final_probe_force, ref.displacement, ref.row.final_probe_force,
                   result.has_probe_force);
  };
  const ElementKindRow& reference_kind = element_kind_row(current.reference.build.element_kind);
  result.reference_description =
      std::string(element_law_row(current.reference.build.model.element_law).keyword) + " FEM on " +
      reference_kind.keyword + " elements, double, semi-implicit Euler at " + format_number(reference_factor) +
      " x its automatic step (dt " + significant_digits(ref.row.dt, 3) + " s), the scene's mesh refined " +
      std::to_string(current.reference.build.refinements) + " time" +
      (current.reference.build.refinements == 1 ? "" : "s") + " (" + std::to_string(ref.row.vertices) +
      " vertices, " + std::to_string(ref.row.tetrahedra) + " tetrahedra)";
  SimulationTradeRow reference_row = ref.row;
  reference_row.reference = true;
  reference_row.variant = "reference: " + reference_row.variant;
  if (!result.has_probe_force) reference_row.errors.probe_force.reset();
  else reference_row.errors.probe_force = 0.0;
  result.rows.push_back(reference_row);
  std::vector<std::pair<std::size_t, TradeSkip>> skipped_by_estimate;  // row, why: worded once the choice is made
  for (const RunKey& key : listed) {
    const auto estimated = estimated_skips.find(key);
    if (estimated != estimated_skips.end()) skipped_by_estimate.emplace_back(result.rows.size(), estimated->second);
    if (const auto it = skipped.find(key); it != skipped.end() || estimated != estimated_skips.end()) {
      SimulationTradeRow row;
      row.variant = run_label(key);
      row.model = key.build.model;
      row.element_kind = key.build.element_kind;
      row.mesh = key.build.mesh;
      row.precision = key.precision;
      row.integrator = {key.integrator, key.dt_factor};
      row.refinements = key.build.refinements;
      if (it != skipped.end()) row.skipped = it->second;
      if (const auto e = estimates.find(key); e != estimates.end())
        std::tie(row.estimated_seconds, row.estimate_steps) = e->second;
      result.rows.push_back(row);
      continue;
    }
    SimulationTradeRow row = outcomes.at(key).row;
    if (row.completed) row.errors = errors_of(outcomes.at(key));
    if (const auto e = estimates.find(key); e != estimates.end())
      std::tie(row.estimated_seconds, row.estimate_steps) = e->second;
    result.rows.push_back(row);
  }
  if (options.max_error) {
    for (std::size_t i = 1; i < result.rows.size(); ++i) {
      const SimulationTradeRow& row = result.rows[i];
      if (!meets_max_error(result, row)) continue;
      ++result.meeting;
      if (!result.chosen || row.cpu_seconds < result.rows[*result.chosen].cpu_seconds) result.chosen = i;
    }
    // Skipped by an estimate only while a run meeting E cost less (CheapestFirstSchedule): the chosen one cost at
    // most that.
    for (const auto& [index, skip] : skipped_by_estimate)
      result.rows[index].skipped =
          "skipped: " + std::string(skip.prefix ? "its first steps already took " : "estimated ") +
          significant_digits(skip.seconds, 3) + " s of CPU time, above " +
          (result.chosen ? "the chosen " + result.rows[*result.chosen].variant + "'s " +
                               significant_digits(result.rows[*result.chosen].cpu_seconds, 3) + " s"
                         : std::string("a run that met --max-error"));
  }
  return result;
}

bool meets_max_error(const SimulationTradeResult& result, const SimulationTradeRow& row) {
  return result.max_error && row.completed && !row.reference && within(row.errors, result.measures, *result.max_error);
}

}  // namespace fmpc::sim

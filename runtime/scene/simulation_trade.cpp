#include "runtime/scene/simulation_trade.h"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <tuple>
#include <utility>

#include "diagnostics/number_format.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/io/memory_limit.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/mesh/mesh_refinement.h"
#include "runtime/scene/scene_builder.h"

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

std::vector<std::string> simulation_trade_columns() {
  return {"variant",          "model",       "precision",  "integrator",
          "dt_s",             "vertices",    "displacement_max_rel_error",
          "displacement_rms_rel_error",      "probe_force_rel_error",
          "steps_per_second", "memory_bytes", "mapping",   "refinements",
          "tetrahedra",       "steps",       "inverted_elements", "status"};
}

namespace {

// CPU time of the whole process (every thread the stepping uses): on a shared machine wall time counts the other
// processes too.
double process_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

std::string short_model(const TradeModel& model) {
  if (model.element_law >= 0) return element_law_row(model.element_law).trade_label;
  return model.mapping == StiffnessMapping::LloydSzekelyHarders2007 ? "springs LSH" : "springs VG";
}

// Whether the model has springs (alone or with a law beside them).
bool has_springs(const TradeModel& model) {
  return model.element_law < 0 || element_law_row(model.element_law).beside_springs;
}

const char* short_integrator(Integrator integrator) {
  switch (integrator) {
    case Integrator::ForwardEuler:
      return "FE";
    case Integrator::SemiImplicitEuler:
      return "SIE";
    case Integrator::VelocityVerlet:
      return "VV";
    case Integrator::RungeKutta4:
      return "RK4";
    case Integrator::ImplicitEuler:
      return "IE";
  }
  return "?";
}

// One run: what it is (the map key orders and deduplicates runs).
struct RunKey {
  TradeModel model = trade_reference_model();
  Precision precision = Precision::Double;
  Integrator integrator = Integrator::SemiImplicitEuler;
  double dt_factor = 1.0;
  unsigned refinements = 0;

  auto tied() const { return std::make_tuple(refinements, model, precision, integrator, dt_factor); }
  bool operator<(const RunKey& other) const { return tied() < other.tied(); }
};

std::string label(const RunKey& key) {
  std::string text = short_model(key.model) + (key.precision == Precision::Float ? " f32 " : " f64 ") +
                     short_integrator(key.integrator);
  if (key.dt_factor != 1.0) text += " x" + significant_digits(key.dt_factor, 3);
  return text + " r" + std::to_string(key.refinements);
}

struct RunOutcome {
  SimulationTradeRow row;
  std::vector<Point3> displacement;  // of the coarse vertices at the final time
  double extent = 0.0;               // m, the diagonal of the rest positions' bounding box
};

Scene variant_scene(const Scene& scene, const TradeModel& model, double duration) {
  Scene variant = scene;
  variant.duration = duration;
  variant.steps.reset();
  variant.volume_term = model.element_law >= 0 && element_law_row(model.element_law).beside_springs;
  variant.model = has_springs(model) ? ForceModel::Springs : ForceModel::Elements;
  if (!has_springs(model)) variant.element_law = model.element_law;
  if (model.element_law < 0) variant.material.mapping = model.mapping;
  return variant;
}

double dot(const Point3& a, const Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Bytes of the arrays the CPU stepping reads and writes, in the run's precision (indices 4 bytes): the vertex state
// and its loads, the model's per-spring and per-element arrays with their CSR, and the integrator's extra vectors;
// implicit Euler adds its assembled sparse matrix (9 entries per vertex and per edge twice, double value + int
// index) and its conjugate-gradient vectors. Not counted: the setup kept in double, the worker pool, the allocator.
double memory_estimate(const SimulationSetup& setup, std::size_t edges) {
  const double real = setup.precision == Precision::Float ? 4.0 : 8.0;
  const auto vertices = static_cast<double>(setup.rest_positions.size());
  const auto springs = static_cast<double>(setup.springs.size());
  const auto elements = static_cast<double>(setup.tetrahedra.size());
  // position, velocity, rest, acceleration (3 each), mass, held axes; the inversion replay's checkpoint (3 x 3).
  double bytes = vertices * (12.0 * real + real + 1.0);
  if (!setup.tetrahedra.empty()) bytes += vertices * 9.0 * real + elements * 16.0;
  if (!setup.external_forces.empty()) bytes += vertices * 3.0 * real;
  // Springs: rest length, stiffness, damping; CSR offset, spring and neighbour per endpoint.
  if (springs > 0.0)
    bytes += springs * (real * (setup.springs.damping.empty() ? 2.0 : 3.0)) + (vertices + 1.0) * 4.0 + springs * 16.0;
  if (!setup.elements.empty()) {
    // Dm^-1 and V0, each term's parameters and damping, the corner forces.
    double per_element = 9.0 + 1.0 + 12.0;
    for (const ElementTerm& term : setup.elements.terms) {
      for (const std::vector<double>& parameter : term.parameter) per_element += parameter.empty() ? 0.0 : 1.0;
      per_element += term.stiffness_damping.empty() ? 0.0 : 1.0;
    }
    bytes += elements * per_element * real + (vertices + 1.0) * 4.0 + elements * 16.0;
  }
  switch (setup.integrator) {
    case Integrator::VelocityVerlet:
      bytes += vertices * 9.0 * real;
      break;
    case Integrator::RungeKutta4:
      bytes += vertices * (9.0 + 24.0) * real;
      break;
    case Integrator::ImplicitEuler: {
      const double entries = 9.0 * (vertices + 2.0 * static_cast<double>(edges));
      bytes += entries * (8.0 + 4.0) + entries * 16.0;  // the matrix and its triplets
      bytes += vertices * 3.0 * 8.0 * 7.0;              // right-hand side, solution, r, p, q, z, Jacobi diagonal
      break;
    }
    case Integrator::ForwardEuler:
    case Integrator::SemiImplicitEuler:
      break;
  }
  return bytes;
}

// |a - b| / |b| as TradeErrors, over the first `count` vertices.
TradeErrors compare(const std::vector<Point3>& got, double got_force, const std::vector<Point3>& reference,
                    double reference_force, bool probe) {
  TradeErrors errors;
  double largest_difference = 0.0, largest_reference = 0.0, sum_difference = 0.0, sum_reference = 0.0;
  for (std::size_t v = 0; v < reference.size() && v < got.size(); ++v) {
    const double d = distance(got[v], reference[v]);
    const double r = std::sqrt(dot(reference[v], reference[v]));
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

// What the scene must be for every model to be built from it and compared; errors name the field.
bool check_comparable(const Scene& scene, const SimulationTradeOptions& options, DiagnosticList& diagnostics) {
  const std::size_t errors = diagnostics.error_count();
  const std::string why = "fmpc trade compares force models against the co-rotational FEM";
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
  for (const TradeModel& model : options.models) {
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

class TradeRunner {
 public:
  TradeRunner(const Scene& scene, double duration) : scene_(scene), duration_(duration) {}

  // The scene built for `model` on `refinements`, the last one kept (runs are ordered by refinement and model).
  const BuiltScene* built(const TradeModel& model, unsigned refinements, DiagnosticList& diagnostics) {
    if (built_ && built_model_ == model && built_refinements_ == refinements) return &*built_;
    built_.reset();
    DiagnosticList build_diagnostics;
    auto scene = build_scene(variant_scene(scene_, model, duration_), build_diagnostics, refinements);
    if (!scene) {
      for (const Diagnostic& d : build_diagnostics.items())
        if (d.severity == Severity::Error) diagnostics.error(d.range, d.message, d.notes);
      diagnostics.error(scene_.range_of("model"), "the " + trade_model_name(model) +
                                                       " variant cannot be built from this scene (above); leave it "
                                                       "out with --models");
      return nullptr;
    }
    built_ = std::move(scene);
    built_model_ = model;
    built_refinements_ = refinements;
    edges_ = distinct_edge_count(built_->mesh);
    // Semi-implicit Euler's automatic step on this model and mesh: what every variant's step is a factor of.
    SimulationSetup setup = built_->setup;
    setup.integrator = Integrator::SemiImplicitEuler;
    setup.precision = Precision::Double;
    setup.time_step.reset();
    DiagnosticList stability_diagnostics;
    const auto report = check_stability(setup, stability_diagnostics);
    automatic_step_ = report ? report->time_step : 0.0;
    if (!report || !(automatic_step_ > 0.0) || !std::isfinite(automatic_step_)) {
      for (const Diagnostic& d : stability_diagnostics.items())
        if (d.severity == Severity::Error) diagnostics.error(d.range, d.message, d.notes);
      diagnostics.error(scene_.range_of("model"), "the " + trade_model_name(model) +
                                                       " variant has no automatic step to scale (above)");
      built_.reset();
      return nullptr;
    }
    return &*built_;
  }

  // What `key` will cost, from the scene's own mesh (see TradePlan); nullopt when the model cannot be built.
  struct Estimate {
    double tetrahedra = 0.0, steps = 0.0, memory_bytes = 0.0;
  };
  std::optional<Estimate> estimate(const RunKey& key, DiagnosticList& diagnostics) {
    const BuiltScene* scene = built(key.model, 0, diagnostics);
    if (!scene) return std::nullopt;
    const double scale = std::pow(8.0, key.refinements);
    Estimate e;
    e.tetrahedra = static_cast<double>(scene->mesh.tetrahedra.size()) * scale;
    const double step = key.dt_factor * automatic_step_ / std::pow(2.0, key.refinements);
    e.steps = std::max(1.0, std::ceil(duration_ / step * (1.0 - 1e-12)));
    SimulationSetup setup = scene->setup;
    setup.precision = key.precision;
    setup.integrator = key.integrator;
    // The run's arrays, and the refined mesh and its setup while it is built (generated_mesh.h's measured figure).
    e.memory_bytes = memory_estimate(setup, edges_) * scale +
                     static_cast<double>(kEstimatedBytesPerTetrahedron) * e.tetrahedra;
    return e;
  }

  // Runs one variant to the duration; nullopt when it could not be built (errors appended). A run that stops
  // (non-finite, inversion under on_inversion: stop, a conjugate gradient at its cap) is an outcome saying why.
  // `stepped` is told (steps taken, steps of the run) every hundredth of the run.
  std::optional<RunOutcome> run(const RunKey& key, std::size_t coarse_vertices, DiagnosticList& diagnostics,
                                const std::function<void(std::size_t, std::size_t)>& stepped = {}) {
    const BuiltScene* scene = built(key.model, key.refinements, diagnostics);
    if (!scene) return std::nullopt;
    RunOutcome outcome;
    SimulationTradeRow& row = outcome.row;
    row.variant = label(key);
    row.model = key.model;
    row.mapping = key.model.element_law < 0 ? key.model.mapping : scene_.material.mapping;
    row.precision = key.precision;
    row.integrator = {key.integrator, key.dt_factor};
    row.refinements = key.refinements;
    row.vertices = scene->mesh.points.size();
    row.tetrahedra = scene->mesh.tetrahedra.size();
    SimulationSetup setup = scene->setup;
    setup.precision = key.precision;
    setup.integrator = key.integrator;
    setup.threads = 1;
    // A whole number of steps ending at the duration, each at most dt_factor x the automatic step.
    const double step = key.dt_factor * automatic_step_;
    row.steps = static_cast<std::size_t>(std::max(1.0, std::ceil(duration_ / step * (1.0 - 1e-12))));
    row.dt = duration_ / static_cast<double>(row.steps);
    setup.time_step = row.dt;
    setup.step_count = row.steps;
    row.memory_bytes = memory_estimate(setup, edges_);
    Point3 low = setup.rest_positions.front(), high = low;
    for (const Point3& p : setup.rest_positions)
      for (std::size_t a = 0; a < 3; ++a) low[a] = std::min(low[a], p[a]), high[a] = std::max(high[a], p[a]);
    outcome.extent = distance(low, high);
    DiagnosticList run_diagnostics;
    auto simulation = Simulation::create(setup, run_diagnostics);
    if (simulation) {
      const double start = process_cpu_seconds();
      // In hundredths, so that progress is told during a run of hours (advance resumes where it stopped).
      const std::size_t chunk = std::max<std::size_t>(1, row.steps / 100);
      row.completed = true;
      for (std::size_t done = 0; done < row.steps && row.completed;) {
        const std::size_t now = std::min(chunk, row.steps - done);
        row.completed = simulation->advance(now, run_diagnostics);
        done += now;
        if (stepped) stepped(done, row.steps);
      }
      row.cpu_seconds = process_cpu_seconds() - start;
      row.steps_per_second = static_cast<double>(simulation->steps_taken()) / std::max(row.cpu_seconds, 1e-9);
      row.inverted_elements = simulation->inversions().largest_count;
      const std::vector<Point3> positions = simulation->positions(run_diagnostics);
      outcome.displacement.resize(coarse_vertices);
      for (std::size_t v = 0; v < coarse_vertices; ++v) {
        const Point3& start_point = start_position(setup, v);
        for (std::size_t a = 0; a < 3; ++a) outcome.displacement[v][a] = positions[v][a] - start_point[a];
        row.final_max_displacement = std::max(row.final_max_displacement,
                                              std::sqrt(dot(outcome.displacement[v], outcome.displacement[v])));
      }
      if (setup.probe && setup.probe->mode == ProbeLoad::Mode::Displacement) {
        const double length = std::sqrt(dot(setup.probe->target, setup.probe->target));
        if (length > 0.0) row.final_probe_force = dot(simulation->probe_reading(run_diagnostics).force, setup.probe->target) / length;
      }
    }
    if (!row.completed) {
      for (const Diagnostic& d : run_diagnostics.items())
        if (d.severity == Severity::Error) {
          row.failure = d.message;
          break;
        }
      if (row.failure.empty()) row.failure = "did not complete";
    }
    return outcome;
  }

 private:
  const Scene& scene_;
  double duration_;
  std::optional<BuiltScene> built_;
  TradeModel built_model_ = trade_reference_model();
  unsigned built_refinements_ = 0;
  std::size_t edges_ = 0;
  double automatic_step_ = 0.0;
};

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"') quoted += '"';
    quoted += c == '\n' ? ' ' : c;
  }
  return quoted + "\"";
}

std::string model_column(const TradeModel& model) {
  return model.element_law >= 0 ? trade_model_name(model) : std::string("springs");
}

std::string status_text(const SimulationTradeRow& row) {
  if (!row.completed) return "failed: " + row.failure;
  if (row.inverted_elements > 0) return "completed, " + std::to_string(row.inverted_elements) + " inverted elements";
  return "completed";
}

}  // namespace

std::optional<SimulationTradeResult> run_simulation_trade(const Scene& scene, const SimulationTradeOptions& options,
                                                          DiagnosticList& diagnostics) {
  const std::size_t errors = diagnostics.error_count();
  const SourceRange nowhere{};
  if (options.models.empty() || options.precisions.empty() || options.integrators.empty() ||
      options.refinements.empty()) {
    diagnostics.error(nowhere, "--models, --precisions, --integrators and --refinements each need at least one value");
    return std::nullopt;
  }
  for (const TradeIntegrator& integrator : options.integrators)
    if (!(integrator.dt_factor > 0.0) || !std::isfinite(integrator.dt_factor))
      diagnostics.error(nowhere, "--integrators: the step factor of " + std::string(scene_name(integrator.integrator)) +
                                     " must be a positive number, got " + format_number(integrator.dt_factor));
  // Its step check runs at twice the factor, which must stay within the automatic (stable) step.
  if (!(options.reference_dt_factor > 0.0) || !(options.reference_dt_factor <= 0.5))
    diagnostics.error(nowhere, "--reference-dt-factor must be in (0, 0.5] (its check runs at twice it), got " +
                                   format_number(options.reference_dt_factor));
  const unsigned finest = *std::max_element(options.refinements.begin(), options.refinements.end());
  const unsigned reference_level = options.reference_refinements.value_or(finest);
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
  if (diagnostics.error_count() != errors || !check_comparable(scene, options, diagnostics)) return std::nullopt;

  // The scene's own mesh, sized before anything is refined.
  std::size_t coarse_vertices = 0;
  {
    DiagnosticList build_diagnostics;
    const auto coarse = build_scene(variant_scene(scene, TradeModel{}, duration), build_diagnostics);
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
    coarse_vertices = coarse->mesh.points.size();
  }

  // Every run once: the reference, its two convergence checks, the variants.
  const RunKey reference{trade_reference_model(), Precision::Double, Integrator::SemiImplicitEuler,
                         options.reference_dt_factor, reference_level};
  RunKey time_check = reference;
  time_check.dt_factor = 2.0 * options.reference_dt_factor;
  std::optional<RunKey> mesh_check;
  if (reference_level > 0) {
    mesh_check = reference;
    mesh_check->refinements = reference_level - 1;
  }
  std::vector<RunKey> variants;
  for (const TradeModel model : options.models)
    for (const unsigned refinements : options.refinements)
      for (const Precision precision : options.precisions)
        for (const TradeIntegrator& integrator : options.integrators)
          variants.push_back({model, precision, integrator.integrator, integrator.dt_factor, refinements});
  std::vector<RunKey> planned = variants;
  planned.push_back(time_check);
  if (mesh_check) planned.push_back(*mesh_check);
  std::sort(planned.begin(), planned.end());
  planned.erase(std::unique(planned.begin(), planned.end(),
                            [](const RunKey& a, const RunKey& b) { return !(a < b) && !(b < a); }),
                planned.end());
  planned.erase(std::remove_if(planned.begin(), planned.end(),
                               [&](const RunKey& k) { return !(k < reference) && !(reference < k); }),
                planned.end());
  planned.insert(planned.begin(), reference);  // first: nothing is compared without it

  TradeRunner runner(scene, duration);
  // The plan, checked before anything runs: every run's steps, the largest run's memory, the work in all.
  TradePlan plan;
  plan.runs = planned.size();
  std::vector<double> work(planned.size());
  const MemoryLimit memory = memory_limit();
  for (std::size_t i = 0; i < planned.size(); ++i) {
    const RunKey& key = planned[i];
    const auto estimate = runner.estimate(key, diagnostics);
    if (!estimate) return std::nullopt;
    // The reference and its checks take their step from --reference-dt-factor, the variants from --integrators.
    const bool reference_run = std::none_of(variants.begin(), variants.end(),
                                            [&](const RunKey& v) { return !(v < key) && !(key < v); });
    if (!(estimate->steps <= kMaxSimulationSteps)) {
      diagnostics.error(nowhere, "the run " + label(key) + " would take " + significant_digits(estimate->steps, 3) +
                                     " steps (" + significant_digits(duration, 3) + " s at about " +
                                     significant_digits(duration / estimate->steps, 3) + " s a step); the limit is " +
                                     format_number(kMaxSimulationSteps) + " steps a run, as for simulate",
                        {"shorten --duration, or raise " +
                         std::string(reference_run ? "--reference-dt-factor" : "the step factor of --integrators " +
                                                                                   std::string(scene_name(key.integrator)))});
      return std::nullopt;
    }
    if (memory.bytes > 0 && estimate->memory_bytes > static_cast<double>(memory.bytes)) {
      diagnostics.error(scene.range_of("mesh"),
                        "mesh: the run " + label(key) + " needs an estimated " + gibibytes_text(estimate->memory_bytes) +
                            " (" + significant_digits(estimate->tetrahedra, 3) + " tetrahedra); the limit is " +
                            memory.source + ", " + gibibytes_text(static_cast<double>(memory.bytes)),
                        {"lower --refinements or --reference-refinements, or coarsen the mesh"});
      return std::nullopt;
    }
    work[i] = estimate->tetrahedra * estimate->steps;
    plan.element_steps += work[i];
    plan.largest_tetrahedra = std::max(plan.largest_tetrahedra, estimate->tetrahedra);
    plan.largest_steps = std::max(plan.largest_steps, estimate->steps);
    plan.largest_memory_bytes = std::max(plan.largest_memory_bytes, estimate->memory_bytes);
  }
  if (!(plan.element_steps <= kMaxTradeWork)) {
    diagnostics.error(nowhere, "the trade's " + std::to_string(plan.runs) + " runs would take about " +
                                   significant_digits(plan.element_steps, 3) + " element-steps (tetrahedra x steps); the "
                                   "limit is " + format_number(kMaxTradeWork),
                      {"fewer --refinements, models, precisions or integrators, a larger step factor, or a shorter "
                       "--duration"});
    return std::nullopt;
  }
  if (options.plan) options.plan(plan);
  double work_done = 0.0;
  std::map<RunKey, RunOutcome> outcomes;
  for (std::size_t i = 0; i < planned.size(); ++i) {
    if (options.progress) options.progress(i, planned.size(), (i == 0 ? "reference " : "") + label(planned[i]));
    const auto stepped = [&](std::size_t steps, std::size_t steps_in_run) {
      if (options.work_progress)
        options.work_progress(work_done + work[i] * static_cast<double>(steps) / static_cast<double>(steps_in_run),
                              plan.element_steps);
    };
    auto outcome = runner.run(planned[i], coarse_vertices, diagnostics, stepped);
    work_done += work[i];
    if (!outcome) return std::nullopt;
    if (i == 0) {
      if (!outcome->row.completed) {
        diagnostics.error(scene.range_of("model"), "the reference (" + label(reference) + ") did not complete: " +
                                                       outcome->row.failure);
        return std::nullopt;
      }
      // Rounding moves a block at rest by about 1e-16 of its size: what moves less than 1e-9 of it does not move.
      if (!(outcome->row.final_max_displacement > 1e-9 * outcome->extent)) {
        diagnostics.error(scene.range_of("loads"), "the reference (" + label(reference) +
                                                       ") does not move: no displacement to compare; give the scene "
                                                       "a load (probe, gravity or forces)");
        return std::nullopt;
      }
    }
    outcomes.emplace(planned[i], std::move(*outcome));
  }
  if (options.progress) options.progress(planned.size(), planned.size(), "done");

  SimulationTradeResult result;
  result.scene_name = scene.name;
  result.duration = duration;
  result.coarse_vertices = coarse_vertices;
  const RunOutcome& ref = outcomes.at(reference);
  result.has_probe_force =
      scene.probe && scene.probe->mode == ProbeLoad::Mode::Displacement && ref.row.final_probe_force != 0.0;
  const auto errors_of = [&](const RunOutcome& outcome) {
    return compare(outcome.displacement, outcome.row.final_probe_force, ref.displacement, ref.row.final_probe_force,
                   result.has_probe_force);
  };
  result.reference_description = "co-rotational FEM, double, semi-implicit Euler at " +
                                 format_number(options.reference_dt_factor) + " x its automatic step (dt " +
                                 significant_digits(ref.row.dt, 3) + " s), the scene's mesh refined " +
                                 std::to_string(reference_level) + " time" + (reference_level == 1 ? "" : "s") + " (" +
                                 std::to_string(ref.row.vertices) + " vertices, " +
                                 std::to_string(ref.row.tetrahedra) + " tetrahedra)";
  const RunOutcome& time_outcome = outcomes.at(time_check);
  if (!time_outcome.row.completed) {
    diagnostics.error(scene.range_of("model"), "the reference's step check (" + label(time_check) +
                                                   ") did not complete: " + time_outcome.row.failure);
    return std::nullopt;
  }
  result.reference_time_difference = errors_of(time_outcome);
  if (mesh_check) {
    const RunOutcome& mesh_outcome = outcomes.at(*mesh_check);
    if (!mesh_outcome.row.completed) {
      diagnostics.error(scene.range_of("model"), "the reference's mesh check (" + label(*mesh_check) +
                                                     ") did not complete: " + mesh_outcome.row.failure);
      return std::nullopt;
    }
    result.reference_mesh_difference = errors_of(mesh_outcome);
  }
  SimulationTradeRow reference_row = ref.row;
  reference_row.reference = true;
  reference_row.variant = "reference: " + reference_row.variant;
  if (!result.has_probe_force) reference_row.errors.probe_force.reset();
  else reference_row.errors.probe_force = 0.0;
  result.rows.push_back(reference_row);
  for (const RunKey& key : variants) {
    SimulationTradeRow row = outcomes.at(key).row;
    if (row.completed) row.errors = errors_of(outcomes.at(key));
    result.rows.push_back(row);
  }
  return result;
}

std::string simulation_trade_csv(const SimulationTradeResult& result) {
  std::ostringstream csv;
  const std::vector<std::string> columns = simulation_trade_columns();
  for (std::size_t c = 0; c < columns.size(); ++c) csv << (c ? "," : "") << columns[c];
  csv << '\n';
  for (const SimulationTradeRow& row : result.rows) {
    const bool springs = has_springs(row.model);
    const auto error_text = [&](double value) { return row.completed ? format_number(value) : std::string(); };
    csv << csv_field(row.variant) << ',' << model_column(row.model) << ','
        << (row.precision == Precision::Float ? "float" : "double") << ',' << scene_name(row.integrator.integrator)
        << ',' << format_number(row.dt) << ',' << row.vertices << ',' << error_text(row.errors.displacement_max) << ','
        << error_text(row.errors.displacement_rms) << ','
        << (row.completed && row.errors.probe_force ? format_number(*row.errors.probe_force) : "") << ','
        << format_number(row.steps_per_second) << ',' << format_number(row.memory_bytes) << ','
        << (springs ? scene_name(row.mapping) : "") << ',' << row.refinements << ',' << row.tetrahedra << ','
        << row.steps << ',' << row.inverted_elements << ',' << csv_field(status_text(row)) << '\n';
  }
  return csv.str();
}

std::string simulation_trade_markdown(const SimulationTradeResult& result) {
  std::ostringstream md;
  const auto percent = [](double value) { return significant_digits(100.0 * value, 3) + "%"; };
  const auto errors_text = [&](const TradeErrors& e) {
    std::string text = "displacement max " + percent(e.displacement_max) + ", RMS " + percent(e.displacement_rms);
    if (e.probe_force) text += ", probe force " + percent(*e.probe_force);
    return text;
  };
  md << "# fmpc trade: scene " << result.scene_name << "\n\n";
  md << "Every run simulates " << format_number(result.duration)
     << " s on the CPU, one thread; errors are relative, at the final time, against the reference, over the scene's "
     << result.coarse_vertices << " own vertices" << (result.has_probe_force ? " and the probe force" : "")
     << "; speed in steps per CPU second; memory an estimate from the array sizes (docs/trade.md).\n\n";
  md << "Reference: " << result.reference_description << ".\n";
  md << "Its estimated error (its difference from itself with twice the step";
  if (result.reference_mesh_difference) md << ", and on the mesh one refinement coarser";
  md << "; at most the difference if it converges at first order or better): step " << errors_text(result.reference_time_difference);
  if (result.reference_mesh_difference) md << "; mesh " << errors_text(*result.reference_mesh_difference);
  else md << "; mesh: not estimated (the reference is on the scene's own mesh)";
  md << ".\n\n";
  md << "| variant | dt (s) | vertices | displacement max error | displacement RMS error | probe force error | "
        "steps/s | memory | inverted | status |\n";
  md << "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n";
  for (const SimulationTradeRow& row : result.rows) {
    const auto error = [&](double value) { return row.completed ? percent(value) : std::string("-"); };
    md << "| " << row.variant << " | " << significant_digits(row.dt, 3) << " | " << row.vertices << " | "
       << error(row.errors.displacement_max) << " | " << error(row.errors.displacement_rms) << " | "
       << (row.completed && row.errors.probe_force ? percent(*row.errors.probe_force) : "-") << " | "
       << significant_digits(row.steps_per_second, 3) << " | " << significant_digits(row.memory_bytes / 1024.0, 3) << " KiB | "
       << row.inverted_elements << " | " << (row.completed ? "completed" : "failed: " + row.failure) << " |\n";
  }
  return md.str();
}

}  // namespace fmpc::sim

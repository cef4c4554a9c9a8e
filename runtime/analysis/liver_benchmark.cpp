#include "runtime/analysis/liver_benchmark.h"

#include <cmath>

#include "compiler/eval/interpreter.h"
#include "diagnostics/number_format.h"
#include "runtime/integrate/simulation.h"
#include "runtime/scene/material_binding.h"

namespace fmpc::sim {

namespace {

bool positive_finite(double value) { return value > 0.0 && std::isfinite(value); }

bool check_options(const LiverBenchmarkOptions& o, DiagnosticList& diagnostics) {
  const std::size_t errors_before = diagnostics.error_count();
  const auto require_positive = [&](const char* name, double value) {
    if (!positive_finite(value))
      diagnostics.error(SourceRange{}, std::string(name) + " is " + format_number(value) +
                                           "; it must be positive and finite");
  };
  require_positive("mass", o.mass);
  require_positive("duration", o.duration);
  require_positive("time_step", o.time_step);
  require_positive("area_over_length", o.area_over_length);
  require_positive("rest_length", o.rest_length);
  require_positive("benchmark K1", o.benchmark.k1);
  require_positive("benchmark Xc", o.benchmark.xc);
  const auto require_non_negative = [&](const char* name, double value) {
    if (!(value >= 0.0) || !std::isfinite(value))
      diagnostics.error(SourceRange{}, std::string(name) + " is " + format_number(value) +
                                           "; it must be non-negative and finite");
  };
  require_non_negative("benchmark K2", o.benchmark.k2);
  require_non_negative("benchmark gamma0", o.benchmark.gamma0);
  require_non_negative("benchmark gamma1", o.benchmark.gamma1);
  require_non_negative("damping_ratio", o.damping_ratio);
  if (!std::isfinite(o.force))
    diagnostics.error(SourceRange{}, "force is " + format_number(o.force) + "; it must be finite");
  if (o.samples < 2 || o.samples > kLiverBenchmarkSamplesMax)
    diagnostics.error(SourceRange{}, "samples is " + std::to_string(o.samples) + "; give 2 to " +
                                         std::to_string(kLiverBenchmarkSamplesMax));
  if (positive_finite(o.duration) && positive_finite(o.time_step)) {
    const double steps = std::ceil(o.duration / o.time_step - 1e-9);
    if (steps > static_cast<double>(kLiverBenchmarkStepsMax))
      diagnostics.error(SourceRange{}, "duration / time_step is " + format_number(steps) + " steps, more than " +
                                           std::to_string(kLiverBenchmarkStepsMax) + "; take a larger step");
  }
  return diagnostics.error_count() == errors_before;
}

// Two vertices, one spring along z: vertex 0 fixed at the origin, vertex 1 at (0, 0, l0), held in x and y, pulled
// along z by the force.
SimulationSetup mass_point_setup(MassPointLaw law, double stiffness, const LiverBenchmarkOptions& o) {
  SimulationSetup setup;
  setup.rest_positions = {Point3{0.0, 0.0, 0.0}, Point3{0.0, 0.0, o.rest_length}};
  setup.mass = {o.mass, o.mass};
  setup.fixed_vertices = {0};
  setup.fixed_axes = {0, 0b011};
  setup.external_forces = {Point3{0.0, 0.0, 0.0}, Point3{0.0, 0.0, o.force}};
  SpringNetwork& net = setup.springs;
  net.vertex_count = 2;
  net.first = {0};
  net.second = {1};
  net.kind = {SpringKind::TetrahedronEdge};
  net.element_measure = {0.0};
  net.rest_length = {o.rest_length};
  net.stiffness = {stiffness};
  if (law == MassPointLaw::BasafaFarahmand) {
    setup.law = kernels::SpringLaw::BasafaFarahmand;
    setup.basafa_k2_over_k1 = o.benchmark.k2 / o.benchmark.k1;
    setup.basafa_xc = o.benchmark.xc;
    setup.nodal_damping_gamma0 = o.benchmark.gamma0;
    setup.nodal_damping_gamma1 = o.benchmark.gamma1;
  } else if (o.damping_ratio > 0.0) {
    // Eq. (3.6) gamma = 2 zeta k / w with w = sqrt(k / m) of the mass point: 2 zeta sqrt(k m).
    net.damping = {2.0 * o.damping_ratio * std::sqrt(stiffness * o.mass)};
  }
  build_adjacency(net);
  setup.integrator = Integrator::RungeKutta4;
  setup.precision = Precision::Double;
  setup.time_step = o.time_step;
  setup.time_step_range = o.time_step_range;
  return setup;
}

}  // namespace

std::vector<std::size_t> evenly_spaced_steps(std::size_t samples, std::size_t steps) {
  std::vector<std::size_t> at;
  for (std::size_t i = 0; i < samples; ++i) {
    const auto step = static_cast<std::size_t>(
        std::llround(static_cast<double>(i) / static_cast<double>(samples - 1) * static_cast<double>(steps)));
    if (at.empty() || step > at.back()) at.push_back(step);
  }
  return at;
}

std::optional<MassPointResponse> simulate_mass_point(MassPointLaw law, double stiffness,
                                                     const LiverBenchmarkOptions& options,
                                                     DiagnosticList& diagnostics) {
  if (!check_options(options, diagnostics)) return std::nullopt;
  if (!positive_finite(stiffness)) {
    diagnostics.error(SourceRange{}, "the mass point's stiffness is " + format_number(stiffness) +
                                         " N/m; it must be positive and finite");
    return std::nullopt;
  }
  const SimulationSetup setup = mass_point_setup(law, stiffness, options);
  auto simulation = Simulation::create(setup, diagnostics);
  if (!simulation) return std::nullopt;
  const auto steps = static_cast<std::size_t>(std::ceil(options.duration / options.time_step - 1e-9));
  MassPointResponse response;
  const std::string name = law == MassPointLaw::BasafaFarahmand ? "Basafa-Farahmand" : "linear";
  response.displacement.name = name + " displacement (k = " + format_number(stiffness) + " N/m)";
  response.velocity.name = name + " velocity (k = " + format_number(stiffness) + " N/m)";
  for (const std::size_t step : evenly_spaced_steps(options.samples, steps)) {
    if (step > simulation->steps_taken() && !simulation->advance(step - simulation->steps_taken(), diagnostics))
      return std::nullopt;
    const Point3 position = simulation->positions(diagnostics)[1];
    const Point3 velocity = simulation->velocities(diagnostics)[1];
    response.displacement.time.push_back(simulation->time());
    response.displacement.value.push_back(position[2] - options.rest_length);
    response.velocity.time.push_back(simulation->time());
    response.velocity.value.push_back(velocity[2]);
  }
  return response;
}

std::optional<MassPointResponse> simulate_benchmark_reference(const LiverBenchmarkOptions& options,
                                                              DiagnosticList& diagnostics) {
  auto reference = simulate_mass_point(MassPointLaw::BasafaFarahmand, options.benchmark.k1 / options.rest_length,
                                       options, diagnostics);
  if (!reference) return std::nullopt;
  reference->displacement.name = "benchmark displacement";
  reference->velocity.name = "benchmark velocity";
  return reference;
}

std::optional<ControllerRun> compare_modulus_with_benchmark(const std::string& controller, const std::string& patient,
                                                            double modulus, const MassPointResponse& reference,
                                                            const LiverBenchmarkOptions& options,
                                                            DiagnosticList& diagnostics) {
  if (!positive_finite(modulus)) {
    diagnostics.error(SourceRange{}, "controller '" + controller + "' gives " + format_number(modulus) +
                                         " Pa for '" + patient + "'; a stiffness must be positive and finite");
    return std::nullopt;
  }
  ControllerRun run;
  run.controller = controller;
  run.patient = patient;
  run.modulus = modulus;
  run.stiffness = modulus * options.area_over_length;
  auto benchmark = simulate_mass_point(MassPointLaw::BasafaFarahmand, run.stiffness, options, diagnostics);
  auto thesis = simulate_mass_point(MassPointLaw::ThesisLinear, run.stiffness, options, diagnostics);
  if (!benchmark || !thesis) return std::nullopt;
  const auto compare = [&](const Curve& curve, const Curve& with, CurveComparison& into) {
    const auto comparison = compare_curves(curve, with, diagnostics);
    if (comparison) into = *comparison;
    return comparison.has_value();
  };
  if (!compare(benchmark->displacement, reference.displacement, run.benchmark_displacement) ||
      !compare(benchmark->velocity, reference.velocity, run.benchmark_velocity) ||
      !compare(thesis->displacement, reference.displacement, run.thesis_displacement) ||
      !compare(thesis->velocity, reference.velocity, run.thesis_velocity))
    return std::nullopt;
  if (options.organ) {
    run.organ_response = options.organ(modulus, diagnostics);
    if (!run.organ_response || !compare(run.organ_response->displacement, reference.displacement,
                                        run.organ_displacement) ||
        !compare(run.organ_response->velocity, reference.velocity, run.organ_velocity))
      return std::nullopt;
  }
  run.benchmark_response = std::move(*benchmark);
  run.thesis_response = std::move(*thesis);
  return run;
}

std::optional<LiverBenchmarkReport> run_liver_benchmark(const std::vector<LiverController>& controllers,
                                                        const std::vector<LiverPatient>& patients,
                                                        const std::vector<double>& moduli,
                                                        const LiverBenchmarkOptions& options,
                                                        DiagnosticList& diagnostics) {
  if (!check_options(options, diagnostics)) return std::nullopt;
  const double runs = static_cast<double>(controllers.size()) * static_cast<double>(patients.size()) +
                      static_cast<double>(moduli.size()) + 1.0;
  if (runs * static_cast<double>(options.samples) > static_cast<double>(kLiverBenchmarkRunSamplesMax)) {
    diagnostics.error(SourceRange{}, format_number(runs) + " runs of " + std::to_string(options.samples) +
                                         " samples exceed the limit of " +
                                         std::to_string(kLiverBenchmarkRunSamplesMax) +
                                         " runs x samples; take fewer samples, patients or controllers");
    return std::nullopt;
  }
  LiverBenchmarkReport report;
  const std::size_t run_count = controllers.size() * patients.size() + moduli.size();
  auto reference = simulate_benchmark_reference(options, diagnostics);
  if (!reference) return std::nullopt;
  report.reference = std::move(*reference);

  for (const LiverController& controller : controllers) {
    if (!controller.system || controller.system->outputs.empty()) {
      diagnostics.error(SourceRange{}, "controller '" + controller.name + "' has no system with an output");
      return std::nullopt;
    }
    const FuzzySystem& system = *controller.system;
    const Variable& output = system.outputs.front();
    const auto pascals = pascals_per_unit(output.unit);
    if (!pascals) {
      diagnostics.error(output.range, "controller '" + controller.name + "': output '" + output.name + "' is in '" +
                                          output.unit + "', not a stiffness; the stiffness must be in kPa, Pa or MPa");
      return std::nullopt;
    }
    Interpreter interpreter(system);
    for (const LiverPatient& patient : patients) {
      if (patient.readings.size() != system.inputs.size()) {
        diagnostics.error(SourceRange{}, "patient '" + patient.label + "' has " +
                                             std::to_string(patient.readings.size()) + " readings; controller '" +
                                             controller.name + "' has " + std::to_string(system.inputs.size()) +
                                             " inputs");
        return std::nullopt;
      }
      const Evaluation evaluation = interpreter.evaluate(patient.readings);
      for (const int input : evaluation.flags.inputs_out_of_range) {
        const Variable& variable = system.inputs[static_cast<std::size_t>(input)];
        diagnostics.warning(SourceRange{}, "input-out-of-range",
                            "patient '" + patient.label + "': " + variable.name + " = " +
                                format_number(patient.readings[static_cast<std::size_t>(input)]) + " is outside [" +
                                format_number(variable.min) + ", " + format_number(variable.max) +
                                "] of controller '" + controller.name + "'; evaluated as given");
      }
      if (!evaluation.flags.outputs_no_rule_fired.empty())
        diagnostics.warning(SourceRange{}, "no-rule-fired",
                            "patient '" + patient.label + "': no rule of controller '" + controller.name +
                                "' fired; its output is the system's no-fire value");
      if (options.progress) options.progress(report.runs.size(), run_count);
      auto run = compare_modulus_with_benchmark(controller.name, patient.label,
                                                evaluation.outputs.front() * *pascals, report.reference, options,
                                                diagnostics);
      if (!run) return std::nullopt;
      report.runs.push_back(std::move(*run));
    }
  }
  for (const double modulus : moduli) {
    if (options.progress) options.progress(report.runs.size(), run_count);
    auto run = compare_modulus_with_benchmark("constant", "E = " + format_number(modulus / 1000.0) + " kPa", modulus,
                                              report.reference, options, diagnostics);
    if (!run) return std::nullopt;
    report.runs.push_back(std::move(*run));
  }
  return report;
}

}  // namespace fmpc::sim

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "runtime/integrate/simulation.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/mesh/mesh_check.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/scene/spring_model_builder.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

// One mass m on a spring (k, c, rest length 1) to a fixed vertex at the origin, displaced by x0 along x:
// m x'' + c x' + k x = 0 along the spring, exactly (the motion stays on the x axis).
SimulationSetup single_spring(double m, double k, double c, double x0) {
  SimulationSetup setup;
  setup.rest_positions = {{0, 0, 0}, {1, 0, 0}};
  setup.initial_positions = {{0, 0, 0}, {1 + x0, 0, 0}};
  setup.mass = {1.0, m};
  setup.fixed_vertices = {0};
  SpringNetwork& net = setup.springs;
  net.vertex_count = 2;
  net.first = {0};
  net.second = {1};
  net.kind = {SpringKind::TetrahedronEdge};
  net.element_measure = {0.0};
  net.rest_length = {1.0};
  net.stiffness = {k};
  net.damping = {c};
  build_adjacency(net);
  return setup;
}

// Underdamped closed form with v(0) = 0.
double damped_displacement(double m, double k, double c, double x0, double t) {
  const double omega = std::sqrt(k / m);
  const double zeta = c / (2.0 * std::sqrt(k * m));
  const double omega_d = omega * std::sqrt(1.0 - zeta * zeta);
  return std::exp(-zeta * omega * t) *
         (x0 * std::cos(omega_d * t) + zeta * omega * x0 / omega_d * std::sin(omega_d * t));
}

double error_at(Integrator integrator, double h, double end_time) {
  const double m = 1.0, k = 100.0, c = 2.0, x0 = 0.1;  // w = 10 rad/s, zeta = 0.1
  SimulationSetup setup = single_spring(m, k, c, x0);
  setup.integrator = integrator;
  setup.time_step = h;
  setup.step_count = static_cast<std::size_t>(std::llround(end_time / h));
  DiagnosticList diagnostics;
  const SimulationResult result = simulate(setup, diagnostics);
  REQUIRE(result.completed);
  REQUIRE_FALSE(diagnostics.has_errors());
  CHECK(result.positions[1][1] == 0.0);
  return std::abs(result.positions[1][0] - 1.0 - damped_displacement(m, k, c, x0, end_time));
}

}  // namespace

TEST_CASE("single damped spring: every integrator converges to the closed form at its order", "[sim]") {
  struct Case {
    Integrator integrator;
    double h;
    double order;
  };
  const Case cases[] = {{Integrator::ForwardEuler, 1e-3, 1.0},
                        {Integrator::SemiImplicitEuler, 1e-3, 1.0},
                        {Integrator::VelocityVerlet, 4e-3, 2.0},
                        {Integrator::RungeKutta4, 8e-3, 4.0},
                        {Integrator::ImplicitEuler, 1e-3, 1.0}};
  for (const Case& c : cases) {
    CAPTURE(to_string(c.integrator));
    const double e1 = error_at(c.integrator, c.h, 1.0);
    const double e2 = error_at(c.integrator, c.h / 2.0, 1.0);
    const double e3 = error_at(c.integrator, c.h / 4.0, 1.0);
    const double order = std::log2(e2 / e3);
    CAPTURE(e1, e2, e3, order);
    CHECK(e3 < e2);
    CHECK(std::log2(e1 / e2) == Approx(c.order).margin(0.15));
    CHECK(order == Approx(c.order).margin(0.1));
  }
}

TEST_CASE("undamped semi-implicit Euler keeps the energy bounded over a million steps", "[sim]") {
  SimulationSetup setup = single_spring(1.0, 100.0, 0.0, 0.1);  // w = 10
  setup.time_step = 0.005;                                      // w h = 0.05
  setup.step_count = 1000000;
  setup.record_every = 1000;
  DiagnosticList diagnostics;
  const SimulationResult result = simulate(setup, diagnostics);
  REQUIRE(result.completed);
  REQUIRE(result.samples.size() == 1001);
  const double initial = result.samples[0].kinetic_energy + result.samples[0].potential_energy;
  CHECK(initial == Approx(0.5 * 100.0 * 0.01));
  double worst_early = 0.0, worst_late = 0.0;
  for (std::size_t i = 0; i < result.samples.size(); ++i) {
    const double energy = result.samples[i].kinetic_energy + result.samples[i].potential_energy;
    const double deviation = std::abs(energy - initial) / initial;
    (i < 100 ? worst_early : worst_late) = std::max(i < 100 ? worst_early : worst_late, deviation);
  }
  // Symplectic Euler conserves a modified energy: the error oscillates with amplitude about w h / 2, no drift.
  CHECK(worst_late < 0.03);
  CHECK(worst_late < worst_early * 1.1 + 1e-3);
}

TEST_CASE("critical time step: the Gershgorin bound, auto dt, and refusal with the numbers", "[sim]") {
  SimulationSetup setup = single_spring(2.0, 800.0, 0.0, 0.1);
  DiagnosticList diagnostics;
  const auto report = check_stability(setup, diagnostics);
  REQUIRE(report);
  CHECK(report->omega_max == Approx(std::sqrt(2.0 * 800.0 / 2.0)));
  CHECK(report->limiting_vertex == 1);
  CHECK(report->critical_time_step == Approx(2.0 / std::sqrt(800.0)));
  CHECK(report->automatic);
  CHECK(report->time_step == Approx(0.8 * 2.0 / std::sqrt(800.0)));

  setup.time_step = 0.1;
  CHECK_FALSE(check_stability(setup, diagnostics));
  REQUIRE(diagnostics.error_count() == 1);
  CHECK(diagnostics.items()[0].message ==
        "dt: time step 0.1 s exceeds the semi-implicit Euler stability limit 0.0707107 s (h <= 2 / (beta/2 + "
        "sqrt(w^2 + beta^2/4)) with w_max = 28.2843 rad/s at vertex 1, beta_max = 0 1/s); use dt <= 0.0565685 s, "
        "dt auto, or implicit Euler");
  CHECK_FALSE(Simulation::create(setup, diagnostics));

  setup.integrator = Integrator::ForwardEuler;
  setup.time_step.reset();
  DiagnosticList euler;
  CHECK_FALSE(check_stability(setup, euler));
  CHECK_THAT(euler.items()[0].message, Catch::StartsWith("dt auto: forward Euler has no stable step here"));

  setup.integrator = Integrator::RungeKutta4;
  setup.springs.damping = {40.0};  // beta = 2 c / m = 40
  DiagnosticList rk4;
  const auto damped = check_stability(setup, rk4);
  REQUIRE(damped);
  CHECK(damped->critical_time_step == Approx(2.5 / (20.0 + std::sqrt(800.0 + 400.0))));
  setup.integrator = Integrator::ImplicitEuler;
  setup.time_step = 10.0;
  CHECK(check_stability(setup, rk4));

  // The critical step is a real limit: just below it the run stays bounded, a little above it blows up.
  SimulationSetup undamped = single_spring(1.0, 100.0, 0.0, 0.1);
  undamped.refuse_unstable_time_step = false;
  undamped.step_count = 2000;
  undamped.time_step = 0.99 * 2.0 / std::sqrt(100.0);  // exact limit for one spring to a fixed node: w h <= 2
  DiagnosticList below;
  const auto stable = simulate(undamped, below);
  CHECK(stable.completed);
  CHECK(std::abs(stable.positions[1][0] - 1.0) < 1.0);
}

TEST_CASE("NaN and Inf stop the run naming step, vertex and spring", "[sim]") {
  SimulationSetup setup = single_spring(1.0, 100.0, 0.0, 0.1);
  setup.refuse_unstable_time_step = false;
  setup.time_step = 0.5;  // w h = 5: the amplitude grows by about 24 per step
  setup.step_count = 10000;
  DiagnosticList diagnostics;
  const SimulationResult result = simulate(setup, diagnostics);
  CHECK_FALSE(result.completed);
  REQUIRE(result.non_finite);
  CHECK(result.non_finite->vertex == 1);
  CHECK(result.non_finite->spring == 0);
  CHECK(result.non_finite->step > 10);
  CHECK(result.non_finite->step < 1000);
  CHECK(result.steps_taken == result.non_finite->step);
  CHECK(diagnostics.warning_count() == 1);  // the unstable time step
  REQUIRE(diagnostics.error_count() == 1);
  CHECK_THAT(diagnostics.items().back().message,
             Catch::Contains("vertex 1 has a NaN or infinite position or velocity; its most strained spring is 0"));

  SimulationSetup bad_input = single_spring(1.0, 100.0, 0.0, std::nan(""));
  DiagnosticList input;
  CHECK_FALSE(simulate(bad_input, input).completed);
  CHECK_THAT(input.items()[0].message, Catch::StartsWith("vertex 1 starts with a NaN"));
}

TEST_CASE("setup errors: sizes, indices and masses are named", "[sim]") {
  SimulationSetup setup = single_spring(1.0, 100.0, 0.0, 0.1);
  setup.mass = {1.0, 0.0};
  setup.fixed_vertices = {0, 5};
  DiagnosticList diagnostics;
  CHECK_FALSE(validate_setup(setup, diagnostics));
  REQUIRE(diagnostics.error_count() == 2);
  CHECK(diagnostics.items()[0].message == "vertex 1 has mass 0.000000; every vertex needs a positive, finite mass");
  CHECK(diagnostics.items()[1].message == "fixed vertex 5 does not exist (the mesh has 2 vertices, numbered from 0)");
  SimulationSetup no_adjacency = single_spring(1.0, 100.0, 0.0, 0.1);
  no_adjacency.springs.adjacency_offset.clear();
  DiagnosticList missing;
  CHECK_FALSE(validate_setup(no_adjacency, missing));
  CHECK(missing.items()[0].message == "the spring adjacency is missing; call build_adjacency");
  // The gathers take an entry's other end from its spring, so every entry must name a spring at its vertex.
  SimulationSetup foreign = single_spring(1.0, 100.0, 0.0, 0.1);
  foreign.springs.vertex_count = 3;
  foreign.springs.adjacency_offset = {0, 1, 1, 2};
  foreign.mass.push_back(1.0);
  foreign.rest_positions.push_back({2.0, 0.0, 0.0});
  foreign.initial_positions.push_back({2.0, 0.0, 0.0});
  DiagnosticList wrong;
  CHECK_FALSE(validate_setup(foreign, wrong));
  REQUIRE(wrong.error_count() == 1);
  CHECK(wrong.items()[0].message ==
        "the spring adjacency of vertex 2 lists spring 0, which does not end at it; call build_adjacency");
  SimulationSetup short_offsets = single_spring(1.0, 100.0, 0.0, 0.1);
  short_offsets.springs.adjacency_offset = {0, 1, 1};
  DiagnosticList span;
  CHECK_FALSE(validate_setup(short_offsets, span));
  CHECK(span.items()[0].message ==
        "the spring adjacency's offsets do not span its 2 x springs entries; call build_adjacency");
}

namespace {

SimulationSetup sagging_box(int cells, Integrator integrator, Precision precision, unsigned threads) {
  DiagnosticList diagnostics;
  BoxSpec spec;
  spec.cells_x = spec.cells_y = spec.cells_z = cells;
  spec.size = {0.1, 0.1, 0.1};
  const Mesh box = generate_box(spec, diagnostics);
  SpringModelSpec model;
  model.stiffness.value = 5000.0;  // Pa, Van Gelder
  model.mass.value = 1060.0;       // kg/m^3
  auto built = build_spring_model(box, model, diagnostics);
  REQUIRE(built);
  SimulationSetup setup = std::move(*built);
  for (std::size_t v = 0; v < box.points.size(); ++v) {
    if (box.points[v][1] > 0.0999) setup.fixed_vertices.push_back(static_cast<std::int32_t>(v));
  }
  setup.gravity = {0.0, -9.81, 0.0};
  setup.integrator = integrator;
  setup.precision = precision;
  setup.threads = threads;
  REQUIRE_FALSE(diagnostics.has_errors());
  return setup;
}

double lowest_y(const std::vector<Point3>& points) {
  double lowest = 1.0;
  for (const auto& p : points) lowest = std::min(lowest, p[1]);
  return lowest;
}

}  // namespace

TEST_CASE("a box hanging under gravity sags; threads and float give the same answer", "[sim]") {
  SimulationSetup setup = sagging_box(3, Integrator::SemiImplicitEuler, Precision::Double, 1);
  setup.step_count = 400;
  DiagnosticList diagnostics;
  const SimulationResult serial = simulate(setup, diagnostics);
  REQUIRE(serial.completed);
  CHECK(lowest_y(serial.positions) < -1e-4);
  for (const auto v : setup.fixed_vertices) {
    CHECK(serial.positions[static_cast<std::size_t>(v)] == setup.rest_positions[static_cast<std::size_t>(v)]);
  }
  setup.precision = Precision::Float;
  const SimulationResult single = simulate(setup, diagnostics);
  REQUIRE(single.completed);
  for (std::size_t v = 0; v < serial.positions.size(); ++v) {
    CHECK(single.positions[v][1] == Approx(serial.positions[v][1]).margin(1e-5));
  }
  for (const Integrator integrator :
       {Integrator::VelocityVerlet, Integrator::RungeKutta4, Integrator::ImplicitEuler, Integrator::ForwardEuler}) {
    CAPTURE(to_string(integrator));
    SimulationSetup other = sagging_box(3, integrator, Precision::Double, 1);
    other.step_count = 50;
    // Forward Euler amplifies every undamped vibration, so dt auto refuses it without mass damping (docs/scenes.md,
    // `integrator`); the refusal itself is tested in fem_simulation_test.cpp.
    if (integrator == Integrator::ForwardEuler) other.mass_damping = 2.0;
    DiagnosticList other_diagnostics;
    const SimulationResult run = simulate(other, other_diagnostics);
    INFO(render_all(other_diagnostics, {}));
    CHECK(run.completed);
    CHECK_FALSE(other_diagnostics.has_errors());
    CHECK(lowest_y(run.positions) < 0.0);
    if (integrator == Integrator::ImplicitEuler) {
      // 64 vertices: Automatic's trial of the CG converges within what a factorisation costs (docs/simulator.md,
      // "Choosing the solver"), and the CG reaches the tolerance at every step.
      CHECK(run.implicit_solver.method == ImplicitMethod::ConjugateGradient);
      CHECK(run.implicit_solver.capped_steps == 0);
      CHECK(run.implicit_solver.steps == 50);
      CHECK(run.implicit_solver.residual_max <= other.implicit.tolerance);
    }
  }
}

TEST_CASE("the multi-threaded CPU backend is bitwise identical to one thread", "[sim]") {
  SimulationSetup one = sagging_box(16, Integrator::SemiImplicitEuler, Precision::Float, 1);  // 4913 vertices
  one.step_count = 5;
  SimulationSetup four = one;
  four.threads = 4;
  DiagnosticList diagnostics;
  const SimulationResult a = simulate(one, diagnostics);
  const SimulationResult b = simulate(four, diagnostics);
  REQUIRE(a.completed);
  REQUIRE(b.completed);
  CHECK(a.positions == b.positions);
  CHECK(a.velocities == b.velocities);
}

TEST_CASE("implicit Euler is stable far beyond the explicit limit and dissipates energy", "[sim]") {
  SimulationSetup setup = single_spring(1.0, 1.0e4, 0.0, 0.1);  // w = 100
  setup.integrator = Integrator::ImplicitEuler;
  setup.time_step = 0.1;  // w h = 10
  setup.step_count = 20;
  setup.record_every = 2;
  DiagnosticList diagnostics;
  const SimulationResult result = simulate(setup, diagnostics);
  REQUIRE(result.completed);
  CHECK(diagnostics.empty());
  CHECK(std::abs(result.positions[1][0] - 1.0) < 1e-15);
  for (std::size_t i = 1; i < result.samples.size(); ++i) {
    CHECK(result.samples[i].kinetic_energy + result.samples[i].potential_energy <
          result.samples[i - 1].kinetic_energy + result.samples[i - 1].potential_energy);
  }
}

TEST_CASE("Basafa-Farahmand benchmark: nonlinear spring with nodal damping decays", "[sim]") {
  SimulationSetup setup = single_spring(1.0, 0.05, 0.0, 0.3);  // K1 = k l0 = 0.05 N, K2 = 200 K1 = 10 N, Xc = 0.2
  setup.law = fmpc::kernels::SpringLaw::BasafaFarahmand;
  setup.nodal_damping_gamma0 = 2.0;
  setup.nodal_damping_gamma1 = 1000.0;
  setup.step_count = 2000;
  setup.record_every = 2000;
  DiagnosticList diagnostics;
  const SimulationResult result = simulate(setup, diagnostics);
  REQUIRE(result.completed);
  // Initial energy: k l0^2 (Xc^2/2 + r Xc^4/4 + A' (X - Xc) + B' (X - Xc)^2 / 2) with A' = 1.8, B' = 25.
  CHECK(result.samples[0].potential_energy == Approx(0.05 * (0.02 + 0.08 + 1.8 * 0.1 + 25.0 * 0.01 / 2.0)));
  CHECK(result.samples[1].potential_energy + result.samples[1].kinetic_energy < result.samples[0].potential_energy);
  CHECK(result.positions[1][0] > 1.0);  // overdamped by gamma: creeps back without crossing
}

TEST_CASE("SOFA's liver spring scene runs with implicit Euler", "[sim]") {
  const std::string path = std::string(FMPC_SHARED_DATA_DIR) + "/sofa-liver/liver.msh";
  DiagnosticList diagnostics;
  auto mesh = read_mesh_file(path, diagnostics);
  if (!mesh) {
    WARN("skipped: " << path << " is absent (../shared/data is needed for the SOFA meshes)");
    return;
  }
  const auto repair = repair_mesh(*mesh);
  // TutorialForceFieldLiverSprings.scn: k = 4500 / l0, total mass 1, nodes 3 39 64 fixed, gravity -9.81 y,
  // implicit Euler with dt 0.02 (SOFA's Rayleigh damping is replaced by damping ratio 0.9 here).
  SpringModelSpec model;
  model.stiffness.mapping = StiffnessMapping::StiffnessOverLength;
  model.stiffness.value = 4500.0;
  model.mass.source = MassSpec::Source::TotalMass;
  model.mass.value = 1.0;
  auto setup = build_spring_model(*mesh, model, diagnostics);
  REQUIRE(setup);
  for (const int v : {3, 39, 64}) {
    setup->fixed_vertices.push_back(repair.new_vertex_index[static_cast<std::size_t>(v)]);
  }
  setup->gravity = {0.0, -9.81, 0.0};
  setup->integrator = Integrator::ImplicitEuler;
  setup->time_step = 0.02;
  setup->step_count = 25;
  const SimulationResult result = simulate(*setup, diagnostics);
  REQUIRE(result.completed);
  CHECK_FALSE(diagnostics.has_errors());
  double mean_drop = 0.0;
  for (std::size_t v = 0; v < result.positions.size(); ++v) {
    mean_drop += setup->rest_positions[v][1] - result.positions[v][1];
  }
  CHECK(mean_drop / static_cast<double>(result.positions.size()) > 0.0);
}

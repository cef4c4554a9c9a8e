// The pieces both simulator backends share (kernels/integrator_math.h, kernels/strain_table_math.h,
// kernels/implicit_math.h, runtime/integrate/loads.cpp) and what a scene without damping allocates.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "kernels/implicit_math.h"
#include "kernels/integrator_math.h"
#include "kernels/strain_table_math.h"
#include "runtime/integrate/simulation.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/scene/spring_model_builder.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

SimulationSetup hanging_box(double damping_ratio) {
  DiagnosticList diagnostics;
  BoxSpec box;
  box.cells_x = 3;
  box.cells_y = 4;
  box.cells_z = 2;
  box.size = {0.1, 0.1, 0.1};
  const Mesh mesh = generate_box(box, diagnostics);
  SpringModelSpec model;
  model.stiffness.mapping = StiffnessMapping::VanGelder1998;
  model.stiffness.value = 5000.0;
  model.mass.value = 1060.0;
  model.damping.ratio = damping_ratio;
  auto setup = build_spring_model(mesh, model, diagnostics);
  REQUIRE(setup);
  for (std::size_t v = 0; v < setup->rest_positions.size(); ++v) {
    if (setup->rest_positions[v][1] > 0.0999) setup->fixed_vertices.push_back(static_cast<std::int32_t>(v));
  }
  setup->gravity = {0.0, -9.81, 0.0};
  setup->nodal_damping_gamma0 = 1e-3;
  return *setup;
}

bool same_positions(const std::vector<Point3>& a, const std::vector<Point3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Point3)) == 0;
}

}  // namespace

TEST_CASE("loads: a scene without damping has no damping array and runs as zero dashpots", "[sim][loads]") {
  const SimulationSetup undamped = hanging_box(0.0);
  CHECK(undamped.springs.damping.empty());
  SimulationSetup zeros = undamped;
  zeros.springs.damping.assign(zeros.springs.size(), 0.0);
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    for (const Integrator integrator : {Integrator::SemiImplicitEuler, Integrator::ImplicitEuler}) {
      SimulationSetup a = undamped, b = zeros;
      a.precision = b.precision = precision;
      a.integrator = b.integrator = integrator;
      DiagnosticList diagnostics;
      const auto run_a = Simulation::create(a, diagnostics);
      const auto run_b = Simulation::create(b, diagnostics);
      REQUIRE(run_a);
      REQUIRE(run_b);
      REQUIRE(run_a->advance(300, diagnostics));
      REQUIRE(run_b->advance(300, diagnostics));
      CHECK(same_positions(run_a->positions(diagnostics), run_b->positions(diagnostics)));
      CHECK_FALSE(diagnostics.has_errors());
    }
  }
  SimulationSetup wrong = undamped;
  wrong.springs.damping = {1.0};  // neither one per spring nor none
  DiagnosticList diagnostics;
  CHECK_FALSE(validate_setup(wrong, diagnostics));
  CHECK_THAT(diagnostics.items().at(0).message, Catch::Contains("damping for every spring or none"));
}

TEST_CASE("loads: probe ramp share and prescribed state, exact", "[sim][loads]") {
  CHECK(kernels::probe_ramp_share(0.0, 2.0, 0) == 0.0);
  CHECK(kernels::probe_ramp_share(0.5, 2.0, 0) == 0.25);
  CHECK(kernels::probe_ramp_share(2.0, 2.0, 0) == 1.0);
  CHECK(kernels::probe_ramp_share(7.0, 2.0, 0) == 1.0);
  CHECK(kernels::probe_ramp_share(0.0, 0.0, 0) == 1.0);  // no ramp: at once
  const auto prescribe = [](double start, double target, double t, double ramp_time, int cycles, bool before_step,
                            auto& position, auto& velocity) {
    kernels::probe_prescribed_axis(kernels::probe_ramp(t, ramp_time, cycles), start, target, ramp_time, before_step,
                                   position, velocity);
  };
  double position = 0.0, velocity = 0.0;
  prescribe(1.0, -0.5, 1.0, 2.0, 0, true, position, velocity);
  CHECK(position == 0.75);
  CHECK(velocity == -0.25);
  prescribe(1.0, -0.5, 1.0, 2.0, 0, false, position, velocity);  // after a step: at rest
  CHECK(velocity == 0.0);
  prescribe(1.0, -0.5, 3.0, 2.0, 0, true, position, velocity);  // ramp over: held
  CHECK(position == 0.5);
  CHECK(velocity == 0.0);
  prescribe(1.0, -0.5, 0.5, 0.0, 0, true, position, velocity);  // no ramp: at the target at once, at rest
  CHECK(position == 0.5);
  CHECK(velocity == 0.0);
  float single = 0.0f, single_velocity = 0.0f;
  prescribe(0.1, 0.2, 0.5, 1.0, 0, true, single, single_velocity);
  CHECK(single == static_cast<float>(0.1 + 0.5 * 0.2));
  CHECK(single_velocity == 0.2f);
  // Cyclic: a triangle wave of period 2 ramp, `cycles` times, then held at zero.
  CHECK(kernels::probe_ramp_share(0.5, 2.0, 2) == 0.25);
  CHECK(kernels::probe_ramp_share(3.0, 2.0, 2) == 0.5);
  CHECK(kernels::probe_ramp_share(4.0, 2.0, 2) == 0.0);
  CHECK(kernels::probe_ramp_share(5.0, 2.0, 2) == 0.5);
  CHECK(kernels::probe_ramp_share(8.0, 2.0, 2) == 0.0);
  CHECK(kernels::probe_ramp_share(100.0, 2.0, 2) == 0.0);
  const kernels::ProbeRamp rising = kernels::probe_ramp(0.5, 2.0, 2), falling = kernels::probe_ramp(3.0, 2.0, 2),
                           over = kernels::probe_ramp(1e300, 2.0, 2);
  CHECK((rising.moving && !rising.falling));
  CHECK((falling.moving && falling.falling));
  CHECK((!over.moving && over.share == 0.0));  // past the cycles: no period index is computed (1e300 / 4 > 2^63)
  prescribe(1.0, -0.5, 3.0, 2.0, 2, true, position, velocity);  // falling
  CHECK(position == 0.75);
  CHECK(velocity == 0.25);
  prescribe(1.0, -0.5, 9.0, 2.0, 2, true, position, velocity);  // cycles over: at rest
  CHECK(position == 1.0);
  CHECK(velocity == 0.0);
}

TEST_CASE("loads: strain table stiffness interpolates, clamps and propagates NaN", "[sim][loads]") {
  const double strain[3] = {-0.2, 0.0, 0.2};
  const double modulus[3] = {4000.0, 5000.0, 9000.0};
  const kernels::StrainTableView table{strain, modulus, 3};
  // Rest length 2 along x: d = 2 (1 + X).
  CHECK(kernels::strain_table_stiffness(table, 2.0, 0.0, 0.0, 2.0, 0.01) == 50.0);
  CHECK(kernels::strain_table_stiffness(table, 2.2, 0.0, 0.0, 2.0, 0.01) == Approx(70.0).epsilon(1e-14));
  CHECK(kernels::strain_table_stiffness(table, 0.0, 2.4, 0.0, 2.0, 0.01) == 90.0);   // upper end exactly
  CHECK(kernels::strain_table_stiffness(table, 0.0, 0.0, 10.0, 2.0, 0.01) == 90.0);  // above: clamped
  CHECK(kernels::strain_table_stiffness(table, 0.1, 0.0, 0.0, 2.0, 0.01) == 40.0);   // below: clamped
  CHECK(std::isnan(kernels::strain_table_stiffness(table, std::nan(""), 0.0, 0.0, 2.0, 0.01)));
}

TEST_CASE("loads: the critical step with a strain table is the stiffest table value's", "[sim][loads]") {
  SimulationSetup setup = hanging_box(0.9);
  StrainStiffnessTable table;
  table.strain = {-0.2, 0.0, 0.2};
  table.modulus = {4000.0, 5000.0, 9000.0};
  for (const double k : setup.springs.stiffness) table.stiffness_per_modulus.push_back(k / 5000.0);
  SimulationSetup stiffest = setup;
  for (double& k : stiffest.springs.stiffness) k *= 9000.0 / 5000.0;
  setup.strain_stiffness = table;
  DiagnosticList diagnostics;
  const auto with_table = check_stability(setup, diagnostics);
  const auto reference = check_stability(stiffest, diagnostics);
  REQUIRE(with_table);
  REQUIRE(reference);
  CHECK(with_table->omega_max == Approx(reference->omega_max).epsilon(1e-14));
  CHECK(with_table->critical_time_step < check_stability(hanging_box(0.9), diagnostics)->critical_time_step);
}

TEST_CASE("loads: implicit spring blocks are symmetric, sign-free and K_s u = f'(l) u", "[sim][loads]") {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> component(-1.0, 1.0);
  const kernels::SpringLawParameters<double> linear{};
  const kernels::SpringLawParameters<double> basafa{kernels::SpringLaw::BasafaFarahmand, 200.0, 0.2};
  for (int trial = 0; trial < 200; ++trial) {
    const double d[3] = {component(random), component(random), component(random)};
    const double rest = 0.5 + 0.5 * (component(random) + 1.0);
    const auto& law = trial % 2 ? basafa : linear;
    double stiffness[6], system[6], stiffness_flipped[6], system_flipped[6];
    REQUIRE(kernels::implicit_spring_blocks(d[0], d[1], d[2], rest, 30.0, 0.4, law, 0.01, stiffness, system));
    REQUIRE(kernels::implicit_spring_blocks(-d[0], -d[1], -d[2], rest, 30.0, 0.4, law, 0.01, stiffness_flipped,
                                            system_flipped));
    CHECK(std::memcmp(stiffness, stiffness_flipped, sizeof stiffness) == 0);
    CHECK(std::memcmp(system, system_flipped, sizeof system) == 0);
    const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const double u[3] = {d[0] / length, d[1] / length, d[2] / length};
    double ku[3];
    kernels::symmetric_multiply(stiffness, u, ku);
    const double slope = kernels::spring_tension_slope(length, rest, 30.0, law);
    for (int c = 0; c < 3; ++c) CHECK(ku[c] == Approx(slope * u[c]).margin(1e-9 * std::abs(slope)));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) CHECK(kernels::symmetric_index(r, c) == kernels::symmetric_index(c, r));
  }
  double stiffness[6], system[6];
  CHECK_FALSE(kernels::implicit_spring_blocks(1e-12, 0.0, 0.0, 1.0, 30.0, 0.4, linear, 0.01, stiffness, system));
  for (const double value : system) CHECK(value == 0.0);
}

TEST_CASE("loads: the probe reading, shared by both backends", "[sim][loads]") {
  SimulationSetup setup = hanging_box(0.9);
  ProbeLoad probe;
  probe.vertices = {0, 1};
  probe.target = {0.0, 0.004, 0.0};
  probe.ramp_time = 0.1;
  setup.probe = probe;
  std::vector<Point3> positions = setup.rest_positions, velocities(setup.rest_positions.size(), Point3{0, 0, 0});
  positions[0][1] += 0.002;
  positions[1][1] += 0.004;
  const ProbeReading at_rest = read_probe(setup, 0.05, positions, velocities, setup.springs.stiffness);
  CHECK(at_rest.displacement[1] == Approx(0.003));
  CHECK(at_rest.force[1] > 0.0);  // pushing up against the springs
  // A force probe reads its applied share.
  setup.probe->mode = ProbeLoad::Mode::Force;
  const ProbeReading applied = read_probe(setup, 0.05, positions, velocities, setup.springs.stiffness);
  CHECK(applied.force[1] == Approx(0.002));
  // Mismatched sizes (a failed download) read as zeros rather than out of bounds.
  const ProbeReading empty = read_probe(setup, 0.05, {}, {}, {});
  CHECK(empty.force[1] == 0.0);
}

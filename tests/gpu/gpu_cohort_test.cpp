// A cohort on the GPU (fmpc simulate --patients, docs/cohorts.md): a batch of an odd number of probed scenes with
// different stiffness, each with its own probe, gives every scene bitwise the positions, velocities and probe
// readings of its run alone and of the CPU loop (the same FMPC_HD functions in the same order, --fmad=false).
#include "runtime/gpu/gpu_simulation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>

#include "runtime/mesh/generated_mesh.h"
#include "runtime/scene/spring_model_builder.h"
#include "tests/gpu/cpu_gpu_comparison.h"
#include "tests/gpu/gpu_test_harness.h"

using namespace fmpc;
using namespace fmpc::sim;
using namespace fmpc::gpu_test;

namespace {

// The demo's block (4 x 4 x 2 cm, 8 x 8 x 4 cells, base fixed, 1060 kg/m^3, damping ratio 0.9) with Young's
// modulus E, pressed at the centre of its top face: patient p's probe has its own depth, ramp and, for odd p, is a
// force probe, so every ProbeScene field differs between the scenes.
SimulationSetup patient_block(double young_modulus, std::size_t p, Precision precision) {
  DiagnosticList diagnostics;
  BoxSpec box;
  box.cells_x = 8;
  box.cells_y = 8;
  box.cells_z = 4;
  box.size = {0.04, 0.04, 0.02};
  const Mesh mesh = generate_box(box, diagnostics);
  SpringModelSpec model;
  model.stiffness.mapping = StiffnessMapping::VanGelder1998;
  model.stiffness.value = young_modulus;
  model.mass.value = 1060.0;
  model.damping.ratio = 0.9;
  auto setup = build_spring_model(mesh, model, diagnostics);
  SimulationSetup out = setup ? *setup : SimulationSetup{};
  ProbeLoad probe;
  probe.mode = p % 2 == 1 ? ProbeLoad::Mode::Force : ProbeLoad::Mode::Displacement;
  for (std::size_t v = 0; v < out.rest_positions.size(); ++v) {
    const Point3& x = out.rest_positions[v];
    if (x[2] < 1e-9) out.fixed_vertices.push_back(static_cast<std::int32_t>(v));
    if (x[2] > 0.02 - 1e-9 && std::abs(x[0] - 0.02) < 0.0051 && std::abs(x[1] - 0.02) < 0.0051 &&
        std::abs(x[0] - 0.02) + std::abs(x[1] - 0.02) < 0.0051)
      probe.vertices.push_back(static_cast<std::int32_t>(v));
  }
  const double depth = 0.001 + 0.0005 * static_cast<double>(p);
  probe.target = probe.mode == ProbeLoad::Mode::Displacement ? Point3{0.0, 0.0, -depth} : Point3{0.0, 0.0, -0.05 * depth / 0.001};
  probe.ramp_time = 0.01 + 0.002 * static_cast<double>(p);
  out.probe = probe;
  out.precision = precision;
  out.integrator = Integrator::SemiImplicitEuler;
  return out;
}

}  // namespace

FMPC_GPU_TEST(cohort_batch_bitwise, "a batch of 7 probed patients gives each its single-run and CPU bits", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    for (const bool common_step : {true, false}) {
      std::vector<SimulationSetup> scenes;
      for (std::size_t p = 0; p < 7; ++p)
        scenes.push_back(patient_block(4000.0 + 3700.0 * static_cast<double>(p), p, precision));
      FMPC_REQUIRE(scenes.front().probe && scenes.front().probe->vertices.size() == 5);
      if (common_step) {  // as fmpc simulate --patients: the smallest automatic step for every patient
        double smallest = 1.0;
        for (const SimulationSetup& scene : scenes) {
          DiagnosticList ignored;
          const auto report = check_stability(scene, ignored);
          FMPC_REQUIRE(report);
          smallest = std::min(smallest, report->time_step);
        }
        for (SimulationSetup& scene : scenes) scene.time_step = smallest;
      }
      const std::size_t steps = 1500;  // past every ramp: the hold is checked too
      DiagnosticList diagnostics;
      const auto batch = gpu_batch(scenes, gpu::GpuOptions{}, diagnostics);
      FMPC_REQUIRE(batch && batch->advance(700, diagnostics) && batch->advance(steps - 700, diagnostics, 50));
      std::vector<std::vector<Point3>> all_positions, all_velocities;
      FMPC_REQUIRE(batch->scene_states(all_positions, &all_velocities, diagnostics));
      FMPC_REQUIRE(all_positions.size() == scenes.size());
      double largest_cpu_difference = 0.0;
      for (std::size_t s = 0; s < scenes.size(); ++s) {
        const auto single = gpu_simulation(scenes[s], diagnostics);
        FMPC_REQUIRE(single && single->advance(steps, diagnostics));
        const auto cpu = sim::Simulation::create(scenes[s], diagnostics);
        FMPC_REQUIRE(cpu && cpu->advance(steps, diagnostics));
        const std::vector<Point3> positions = batch->positions(s, diagnostics);
        FMPC_EXPECT(bitwise_equal(positions, single->positions(diagnostics)));
        FMPC_EXPECT(bitwise_equal(batch->velocities(s, diagnostics), single->velocities(diagnostics)));
        FMPC_EXPECT(bitwise_equal(all_positions[s], positions));
        FMPC_EXPECT(bitwise_equal(all_velocities[s], single->velocities(diagnostics)));
        FMPC_EXPECT(bitwise_equal(positions, cpu->positions(diagnostics)));
        FMPC_EXPECT(bitwise_equal(batch->velocities(s, diagnostics), cpu->velocities(diagnostics)));
        largest_cpu_difference = std::max(largest_cpu_difference, max_difference(positions, cpu->positions(diagnostics)));
        const ProbeReading in_batch = batch->probe_reading(s, diagnostics), alone = single->probe_reading(diagnostics),
                           on_cpu = cpu->probe_reading(diagnostics);
        for (std::size_t axis = 0; axis < 3; ++axis) {
          FMPC_EXPECT(std::memcmp(&in_batch.force[axis], &alone.force[axis], sizeof(double)) == 0);
          FMPC_EXPECT(std::memcmp(&in_batch.displacement[axis], &alone.displacement[axis], sizeof(double)) == 0);
          FMPC_EXPECT(std::memcmp(&in_batch.force[axis], &on_cpu.force[axis], sizeof(double)) == 0);
        }
        // Each probe moved by its own target (not scene 0's): the probes are the scenes' own.
        const Point3& target = scenes[s].probe->target;
        if (scenes[s].probe->mode == ProbeLoad::Mode::Displacement)
          FMPC_EXPECT_WITHIN(in_batch.displacement[2], target[2], 1e-6);
        else
          FMPC_EXPECT_WITHIN(in_batch.force[2], target[2], 1e-12);
      }
      std::ostringstream line;
      line << name_of(precision) << (common_step ? ", one step for all" : ", each its own step")
           << ": largest |batch - CPU| position " << largest_cpu_difference << " m";
      note(line.str());
      FMPC_EXPECT(!diagnostics.has_errors());
      if (diagnostics.has_errors()) note(describe(diagnostics));
    }
  }
}

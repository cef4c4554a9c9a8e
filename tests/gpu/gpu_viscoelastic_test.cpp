// Per-point state on the CUDA backend: a viscoelastic FEM (kernels/prony_viscoelasticity.h) of every element kind
// against the CPU loop, bitwise for the explicit integrators (the same FMPC_HD update after each step, --fmad=false),
// implicit Euler to the CG tolerance; its checkpoint restores the state, with the weights one per scene or per
// element (the same steps again give the same bits, and the CPU's); a viscoelastic scene runs without persistent
// launches and alone in a batch, as stated.
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/fem/element_law_registry.h"
#include "runtime/gpu/gpu_simulation.h"
#include "runtime/integrate/stepping_engine.h"
#include "tests/gpu/cpu_gpu_comparison.h"
#include "tests/gpu/gpu_test_harness.h"
#include "tests/support/viscoelastic_box.h"

using namespace fmpc;
using namespace fmpc::sim;
using namespace fmpc::gpu_test;

namespace {

// A 0.1 m box of 5 kPa tissue (nu 0.45, two Prony terms with times near the run's length) hanging from its top face
// under gravity, 3 x 5 x 2 cells (odd sizes: blocks partly idle) of element kind `element`, started from a stretched
// state so that the history of the jump at t = 0 is not zero; mass damping where the integrator is forward Euler
// (cpu_gpu_comparison.h). With `weight_per_element`, the first term's weight is 0.3 and 0.1 on alternate elements
// (kernels::prony_weighted; the scene-level path from rules is gpu_parameter_binding_test.cpp's).
SimulationSetup stretched_box(Precision precision, Integrator integrator, int element = 0,
                              bool weight_per_element = false) {
  DiagnosticList diagnostics;
  SimulationSetup out;
  if (auto setup = sim::viscoelastic_box(3, 5, 2, {{0.3, 0.02}, {0.25, 0.2}}, diagnostics, element)) out = *setup;
  if (diagnostics.has_errors()) note("setup: " + describe(diagnostics));
  if (weight_per_element && !out.elements.terms.empty())
    for (std::size_t e = 0; e < out.tetrahedra.size(); ++e)
      out.elements.terms.front().prony.front().element_weight.push_back(e % 2 == 0 ? 0.3 : 0.1);
  out.initial_positions = out.rest_positions;
  for (Point3& p : out.initial_positions) p[1] = 0.1 - (0.1 - p[1]) * 1.05;
  out.precision = precision;
  out.integrator = integrator;
  out.mass_damping = forward_euler_mass_damping(integrator);
  return out;
}

}  // namespace

FMPC_GPU_TEST(viscoelastic_matches_cpu, "a viscoelastic FEM: every integrator matches the CPU, explicit ones bitwise",
              true) {
  for (const ElementKindRow& kind : element_kind_rows())
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      const std::string name = std::string("viscoelastic FEM (") + kind.keyword + " elements), ";
      for (const Integrator integrator : kGpuIntegrators) {
        const SimulationSetup setup = stretched_box(precision, integrator, kind.kind);
        const Difference d = cpu_gpu_difference(setup, 2000, gpu::GpuOptions{});
        std::ostringstream line;
        line << name << to_string(integrator) << ", " << name_of(precision)
             << ": max |GPU - CPU| after 2,000 steps: " << d.positions << " m, " << d.velocities << " m/s";
        note(line.str());
        FMPC_EXPECT(d.positions == 0.0);
        FMPC_EXPECT(d.velocities == 0.0);
      }
      // Implicit Euler where the registry says the CUDA engine runs it (element_kind_limits).
      if (!cuda_refusal(element_kind_limits(kind.kind), true))
        check_implicit_against_cpu(stretched_box(precision, Integrator::ImplicitEuler, kind.kind),
                                   name + name_of(precision));
    }
}

FMPC_GPU_TEST(viscoelastic_checkpoint,
              "the GPU checkpoint restores the per-point state (one weight per scene or per element): the same steps, "
              "the same bits",
              true) {
  for (const ElementKindRow& kind : element_kind_rows())
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      for (const Integrator integrator : kGpuIntegrators)
      for (const bool per_element : {false, true}) {
        const std::vector<SimulationSetup> scenes = {stretched_box(precision, integrator, kind.kind, per_element)};
        DiagnosticList diagnostics;
        const auto stability = check_stability(scenes.front(), diagnostics);
        FMPC_REQUIRE(stability);
        const std::vector<StabilityReport> reports = {*stability};
        const auto engine = gpu::create_engine(scenes, reports, gpu::GpuOptions{}, diagnostics);
        FMPC_REQUIRE(engine);
        FMPC_EXPECT(!engine->launches().persistent);
        FMPC_REQUIRE(engine->run({300}, diagnostics) && engine->save_checkpoint(diagnostics));
        FMPC_REQUIRE(engine->run({700}, diagnostics));
        const auto first = engine->positions(0, diagnostics);
        FMPC_REQUIRE(engine->restore_checkpoint(diagnostics) && engine->steps_taken() == 300);
        FMPC_REQUIRE(engine->run({700}, diagnostics));
        FMPC_EXPECT(bitwise_equal(engine->positions(0, diagnostics), first));
        // And equal to the CPU engine's same sequence (explicit schemes: bitwise).
        const auto cpu = create_cpu_engine(scenes, reports, 1);
        FMPC_REQUIRE(cpu->run({300}, diagnostics) && cpu->save_checkpoint(diagnostics) &&
                     cpu->run({700}, diagnostics) && cpu->restore_checkpoint(diagnostics) &&
                     cpu->run({700}, diagnostics));
        FMPC_EXPECT(bitwise_equal(cpu->positions(0, diagnostics), first));
        FMPC_EXPECT(!diagnostics.has_errors());
      }
    }
}

FMPC_GPU_TEST(viscoelastic_batch_refused, "a viscoelastic scene in a GPU batch of several is refused naming it",
              false) {
  const SimulationSetup scene = stretched_box(Precision::Float, Integrator::SemiImplicitEuler);
  DiagnosticList diagnostics;
  FMPC_EXPECT(!gpu_batch({scene, scene}, gpu::GpuOptions{}, diagnostics));
  FMPC_EXPECT(first_error(diagnostics) ==
              "scene 0: a viscoelastic scene runs on its own on the GPU (its Prony constants depend on the scene's "
              "time step); run it as a simulation of its own");
}

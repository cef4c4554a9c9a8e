// material.bind and strain-bound E on the CUDA backend (docs/scenes.md, "Rules for every parameter"): scenes whose
// Young's modulus and Poisson ratio come per element from two outputs of one rule file, scenes whose first Prony
// weight comes per element from a rule output (the second the scene's), and scenes whose modulus follows the principal
// strain through a strain table, on every element law and kind, give the CPU loop's bits with the explicit integrators
// and its answer to the CG tolerance with implicit Euler.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/fem/element_law_registry.h"
#include "runtime/gpu/gpu_simulation.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "tests/gpu/cpu_gpu_comparison.h"
#include "tests/gpu/gpu_test_harness.h"
#include "tests/support/bound_material_rules.h"

using namespace fmpc;
using namespace fmpc::sim;
using namespace fmpc::gpu_test;

namespace {

// A 2 cm block of 3 x 4 x 3 cells hanging from its top face under gravity, of `law` on `element`; its material
// `material` (YAML lines under material:) reads tissue.fis (E and nu of F), prony.fis (E and Prony weights of F) or
// stiffening.fis (E of strain s).
SimulationSetup bound_block(const std::string& law, const std::string& element, const std::string& material,
                            Precision precision, Integrator integrator) {
  const auto folder = std::filesystem::temp_directory_path() / "fmpc_gpu_bind";
  std::filesystem::create_directories(folder);
  std::ofstream(folder / "tissue.fis") << test_rules::kTwoOutputRules;
  std::ofstream(folder / "stiffening.fis") << test_rules::kStrainStiffeningRules;
  std::ofstream(folder / "prony.fis") << test_rules::kPronyWeightRules;
  const std::string yaml = "mesh: {box: {size: [0.02, 0.02, 0.02], cells: [3, 4, 3]}}\nmodel: fem\nfem: {law: " + law +
                           ", element: " + element + "}\nmaterial:\n" + material +
                           "fixed: {box: {min: [-1, -1, 0.0199], max: [1, 1, 1]}}\nloads: {gravity: [0, 0, -9.81]}\n";
  const std::string path = (folder / "scene.yaml").string();
  std::ofstream(path) << yaml;
  DiagnosticList diagnostics;
  SimulationSetup out;
  if (const auto scene = parse_scene(path, yaml, diagnostics))
    if (const auto built = build_scene(*scene, diagnostics)) out = built->setup;
  if (diagnostics.has_errors()) note("setup: " + describe(diagnostics));
  out.precision = precision;
  out.integrator = integrator;
  out.mass_damping = forward_euler_mass_damping(integrator);
  return out;
}

const char* kBoundMaterial =
    "  rules: tissue.fis\n  inputs:\n    F: {regions: [{box: {min: [0, 0, 0], max: [1, 1, 0.01]}, value: 2}], default: 8}\n"
    "  bind: {youngs_modulus: stiffness, poisson_ratio: nu}\n";
// The first Prony weight 0.24 on the block's lower third and 0.36 above (its time near the run's length), the second
// the scene's: prony_weighted's per-element constants on both backends, the explicit and the implicit ones.
const char* kPronyWeightMaterial =
    "  rules: prony.fis\n  inputs:\n    F: {regions: [{box: {min: [0, 0, 0], max: [1, 1, 0.007]}, value: 2}], default: 8}\n"
    "  viscoelastic: {prony: [{time: 0.005}, {weight: 0.2, time: 0.05}]}\n"
    "  bind:\n    youngs_modulus: stiffness\n    viscoelastic.prony[0].weight: fast\n";
const char* kStrainMaterial = "  rules: stiffening.fis\n  inputs: {s: strain}\n  poisson_ratio: 0.4\n";

}  // namespace

FMPC_GPU_TEST(bound_parameters_match_cpu,
              "E, nu and a Prony weight per element from rule outputs, and E of the principal strain: CUDA equals the "
              "CPU",
              true) {
  for (const ElementLawRow& law : element_law_rows()) {
    if (law.beside_springs) continue;
    for (const ElementKindRow& kind : element_kind_rows())
      for (const char* material : {kBoundMaterial, kPronyWeightMaterial, kStrainMaterial})
        for (const Precision precision : {Precision::Float, Precision::Double}) {
          // What the registry says a kind does not run yet (element_kind_limits).
          const ElementKindLimits limits = element_kind_limits(kind.kind);
          if (material == kStrainMaterial && limits.strain_table) continue;
          const std::string name = std::string(law.keyword) + " on " + kind.keyword + " elements, " +
                                   (material == kBoundMaterial         ? "E and nu bound"
                                    : material == kPronyWeightMaterial ? "Prony weight per element"
                                                                       : "E(strain)") +
                                   ", ";
          for (const Integrator integrator : kGpuIntegrators) {
            const SimulationSetup setup = bound_block(law.keyword, kind.keyword, material, precision, integrator);
            FMPC_REQUIRE(!setup.elements.terms.empty());
            if (material == kPronyWeightMaterial)
              FMPC_REQUIRE(setup.elements.terms.front().prony.at(0).element_weight.size() == setup.tetrahedra.size());
            const Difference d = cpu_gpu_difference(setup, 1000, gpu::GpuOptions{});
            std::ostringstream line;
            line << name << to_string(integrator) << ", " << name_of(precision)
                 << ": max |GPU - CPU| after 1,000 steps: " << d.positions << " m, " << d.velocities << " m/s";
            note(line.str());
            FMPC_EXPECT(d.positions == 0.0);
            FMPC_EXPECT(d.velocities == 0.0);
          }
          if (!cuda_refusal(limits, true))
            check_implicit_against_cpu(bound_block(law.keyword, kind.keyword, material, precision,
                                                   Integrator::ImplicitEuler),
                                       name + name_of(precision));
        }
  }
}

// The thesis's experiment on an organ (runtime/analysis/organ_step_response.h): the pipeline of
// `fmpc thesis-benchmark --scene` on a tiny meshed block (seconds), with golden similarities, the physics it must
// keep (a linear response scales as 1 / E, the force is the one asked), and every refusal with its location.
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

#include "compiler/frontend/rule_file_loader.h"
#include "runtime/analysis/organ_step_response.h"

// Helper names unique: the unity build puts this file beside others' helpers.
namespace {

using fmpc::DiagnosticList;
using fmpc::sim::LiverBenchmarkOptions;

// A 4 x 4 x 2 cm block of 2 x 2 x 1 cells (18 vertices, 24 tetrahedra), base fixed, a probe picked by a ray at the
// top face's centre (its vertex alone), co-rotational FEM, implicit Euler at 10 ms as the meshed liver steps.
const char* const kTinyScene = R"(name: tiny_organ
mesh:
  box: {size: [0.04, 0.04, 0.02], cells: [2, 2, 1]}
  units: m
model: corotational_fem
material:
  youngs_modulus: 20
  poisson_ratio: 0.45
mass: {density: 1060}
damping: {ratio: 0.9}
fixed:
  plane: {point: [0, 0, 0], normal: [0, 0, 1]}
loads:
  probe:
    ray: {origin: [0.02, 0.02, 0.05], direction: [0, 0, -1]}
    radius: 0.001
    displacement: [0, 0, -0.002]
    ramp: 1.0
integrator: implicit_euler
dt: 0.01
duration: 1.2
precision: double
)";

fmpc::sim::Scene parse_organ_scene(const std::string& text) {
  DiagnosticList diagnostics;
  auto scene = fmpc::sim::parse_scene("tiny_organ.yaml", text, diagnostics);
  INFO(fmpc::render_all(diagnostics, fmpc::SourceFiles{}));
  REQUIRE(scene);
  return *scene;
}

// `text` with the first `from` replaced by `to`.
std::string edited_scene(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

fmpc::RuleFile load_controller(const std::string& name) {
  std::ifstream in(std::string(FMPC_SOURCE_DIR) + "/rulesets/liver_fibrosis/" + name);
  std::stringstream text;
  text << in.rdbuf();
  DiagnosticList diagnostics;
  fmpc::RuleFile file = fmpc::load_rule_file(name, text.str(), diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  return file;
}

}  // namespace

TEST_CASE("organ step: the tiny block's probe under the thesis's step force", "[thesis]") {
  const fmpc::sim::Scene scene = parse_organ_scene(kTinyScene);
  LiverBenchmarkOptions options;
  DiagnosticList diagnostics;
  const auto soft = fmpc::sim::simulate_organ_step(scene, 10e3, options, diagnostics);
  const auto stiff = fmpc::sim::simulate_organ_step(scene, 20e3, options, diagnostics);
  INFO(fmpc::render_all(diagnostics, fmpc::SourceFiles{}));
  REQUIRE(soft);
  REQUIRE(stiff);
  CHECK_FALSE(diagnostics.has_errors());
  // The one-mass experiment's samples: 1,001 from 0 to 10 s, every 10 ms (one implicit step each).
  REQUIRE(soft->displacement.time.size() == 1001);
  CHECK(soft->displacement.time.front() == 0.0);
  CHECK(soft->displacement.time.back() == Approx(10.0).epsilon(1e-12));
  CHECK(soft->displacement.value.front() == 0.0);
  CHECK(soft->velocity.value.front() == 0.0);
  // Pushed along the ray (down), so the displacement along the push grows positive and settles (zeta 0.9): the
  // velocity at 10 s is gone, and twice the modulus halves the displacement (linear, small strain).
  const double settled = soft->displacement.value.back();
  CHECK(settled > 1e-4);
  CHECK(std::abs(soft->velocity.value.back()) < 1e-6 * settled);
  // (within 0.5%: the co-rotational law is geometrically nonlinear, and 0.87 mm is 4% of the block's height; it
  // gives 0.13%).
  CHECK(stiff->displacement.value.back() == Approx(settled / 2.0).epsilon(5e-3));
  // Golden: the probe's settled displacement (m) under 1 N on one vertex of E = 10 kPa.
  CHECK(settled == Approx(0.0008692164585261189).epsilon(1e-9));
}

TEST_CASE("organ step: the controllers on the tiny block against the benchmark, golden", "[thesis]") {
  const fmpc::sim::Scene scene = parse_organ_scene(kTinyScene);
  const fmpc::RuleFile mamdani = load_controller("mamdani.fis"), sugeno = load_controller("sugeno.fis"),
                       it2 = load_controller("it2.fis");
  const std::vector<fmpc::sim::LiverController> controllers = {{"mamdani", &mamdani.systems.front()},
                                                               {"sugeno", &sugeno.systems.front()},
                                                               {"it2", &it2.systems.front()}};
  // Patient 3 of example_patients.csv (the meshed liver's own).
  const std::vector<fmpc::sim::LiverPatient> patients = {{"patient 3", {9.7, 9.5, 12.0, 11.0, 11.2}}};
  LiverBenchmarkOptions options;
  options.organ = [&](double modulus, DiagnosticList& diagnostics) {
    return fmpc::sim::simulate_organ_step(scene, modulus, options, diagnostics);
  };
  DiagnosticList diagnostics;
  const auto report = fmpc::sim::run_liver_benchmark(controllers, patients, {}, options, diagnostics);
  INFO(fmpc::render_all(diagnostics, fmpc::SourceFiles{}));
  REQUIRE(report);
  REQUIRE(report->runs.size() == 3);
  // controller, S and r of the probe's displacement and velocity against the benchmark (within 1e-6: the runs are
  // deterministic, the margin is for libm differences between platforms). From `fmpc thesis-benchmark mamdani.fis
  // sugeno.fis it2.fis --patients P3.csv --scene tiny_organ.yaml` (P3.csv: patient 3's row, the scene above).
  // The block is far stiffer than the benchmark (0.87 mm under 1 N at 10 kPa against its 138 mm): S near 0.
  struct Expected {
    const char* controller;
    double displacement, velocity, displacement_correlation, velocity_correlation;
  };
  const Expected expected[] = {
      {"mamdani", 0.008249395, 0.051466806, 0.082052941, -0.023463072},
      {"sugeno", 0.012939205, 0.076068879, 0.083467115, -0.023374043},
      {"it2", 0.009729130, 0.059530232, 0.082559644, -0.023435617},
  };
  for (std::size_t i = 0; i < 3; ++i) {
    const auto& run = report->runs[i];
    INFO(run.controller);
    REQUIRE(run.organ_response);
    CHECK(run.controller == expected[i].controller);
    CHECK(run.organ_displacement.similarity == Approx(expected[i].displacement).margin(1e-6));
    CHECK(run.organ_velocity.similarity == Approx(expected[i].velocity).margin(1e-6));
    REQUIRE(run.organ_displacement.correlation);
    REQUIRE(run.organ_velocity.correlation);
    CHECK(*run.organ_displacement.correlation == Approx(expected[i].displacement_correlation).margin(1e-6));
    CHECK(*run.organ_velocity.correlation == Approx(expected[i].velocity_correlation).margin(1e-6));
  }
}

TEST_CASE("organ step: refusals name the scene's field", "[thesis]") {
  const auto refused = [](const std::string& text, const std::string& expected) {
    const fmpc::sim::Scene scene = parse_organ_scene(text);
    DiagnosticList diagnostics;
    CHECK_FALSE(fmpc::sim::simulate_organ_step(scene, 10e3, LiverBenchmarkOptions{}, diagnostics));
    CHECK_THAT(fmpc::render_all(diagnostics, fmpc::SourceFiles{}), Catch::Contains(expected));
  };
  const std::string without_probe =
      std::string(kTinyScene).substr(0, std::string(kTinyScene).find("loads:")) +
      "tools:\n  - {name: tip, shape: sphere, radius: 0.005, pose: {position: [0.02, 0.02, 0.03]}}\n"
      "integrator: implicit_euler\ndt: 0.01\n";
  refused(without_probe, "tiny_organ.yaml:1:7: error: the scene 'tiny_organ' has no probe (loads.probe)");
  refused(without_probe, "the scene's tools follow their paths; a force cannot drive them");
  refused(edited_scene(edited_scene(edited_scene(kTinyScene, "model: corotational_fem\n", ""), "youngs_modulus: 20",
                                    "stiffness: 20"),
                       "  poisson_ratio: 0.45\n", ""),
          "tiny_organ.yaml:6:14: error: material.stiffness gives spring constants");
  refused(edited_scene(edited_scene(edited_scene(kTinyScene, "ray: {origin: [0.02, 0.02, 0.05], direction: [0, 0, -1]}",
                                                 "indices: [13]"),
                                    "    radius: 0.001\n", ""),
                       "displacement: [0, 0, -0.002]", "displacement: [0, 0, 0]"),
          "error: loads.probe pushes in no direction");
  refused(edited_scene(kTinyScene, "dt: 0.01", "dt: 0.02"),
          "error: the scene's step 0.02 s gives 500 steps over 10 s, fewer than the 1000 sample intervals");

  // A controller whose output is not a stiffness is refused at the output's line, before anything runs.
  DiagnosticList diagnostics;
  const fmpc::RuleFile tipper = fmpc::load_rule_file(
      "tipper.fis",
      "system tipper\n  type mamdani\ninput service in [0, 10] dimensionless\n  good is triangle(start 0, peak 5, "
      "end 10)\noutput tip in [0, 30] \"%\"\n  fair is triangle(start 0, peak 15, end 30)\nrule r1: if service is "
      "good then tip is fair\n",
      diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  CHECK_FALSE(fmpc::sim::run_liver_benchmark({{"tipper", &tipper.systems.front()}}, {{"one", {5.0}}}, {}, {},
                                             diagnostics));
  CHECK_THAT(fmpc::render_all(diagnostics, fmpc::SourceFiles{}),
             Catch::Contains("tipper.fis:5:1: error: controller 'tipper': output 'tip' is in '%', not a stiffness"));
}

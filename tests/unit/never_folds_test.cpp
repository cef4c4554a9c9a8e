// It never folds (issue 26, item 6, CPU side): a cube compressed to half its height and a probe pushed 40 % of a
// block's length into its end, under stable neo-Hookean, keep every tetrahedron positively oriented at every check,
// while the co-rotational law on the same scenes keeps counting and warning as before (on these CI-sized meshes it
// inverts none either); and the 120^3-cell resting block the GPU runs (bench/scenes/resting_block_snh.yaml) runs here
// at 8^3 cells without an inversion. At 120^3 cells that block does fold at its clamped base's corners, where the
// elastic solution is singular and the law's energy is finite at J = 0 (docs/validation.md, "Does the 120^3 block
// fold?"): not at these sizes, and not a case a CI-sized test can hold.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "runtime/mesh/generated_mesh.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "runtime/scene/scene_run.h"
#include "tests/support/generated_program.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

struct Outcome {
  bool completed = false;
  std::size_t largest_inverted = 0;
  int inversion_warnings = 0;
  double max_displacement = 0.0;  // m, the largest at the last step
  std::string errors;
};

Outcome run(const std::string& text, const std::string& name) {
  DiagnosticList diagnostics;
  auto scene = parse_scene("/tmp/" + name + ".yaml", text, diagnostics);
  INFO(render_all(diagnostics, {}));
  REQUIRE(scene);
  scene->outputs.frames = 0;
  scene->outputs.samples = 0;
  scene->outputs.plot = false;
  scene->outputs.precision_check = SceneOutputs::PrecisionCheck::Off;
  const auto built = build_scene(*scene, diagnostics);
  REQUIRE(built);
  // A folder of this run's own: a fixed name collided with a concurrent run of the suite on the same machine.
  const testing::ScratchFolder folder("never_folds_" + name);
  SceneRunOptions options;
  options.output_directory = folder.path().string();
  const auto result = run_scene(*scene, *built, options, diagnostics);
  Outcome out;
  for (const Diagnostic& d : diagnostics.items()) {
    if (d.message.find("turned inside out") != std::string::npos) ++out.inversion_warnings;
    if (d.severity == Severity::Error) out.errors += d.message + "\n";
  }
  if (result) {
    out.completed = result->completed;
    out.largest_inverted = result->inversions.largest_count;
    out.max_displacement = result->final_max_displacement;
  }
  return out;
}

// The law as scenes choose it: model: fem with fem: {law: LAW}.
std::string model(const std::string& law) { return "model: fem\nfem: {law: " + law + ", element: linear}\n"; }

}  // namespace

TEST_CASE("it never folds: a cube compressed to 50 % by a plate keeps every element positive",
          "[fem][snh][scene][heavy]") {
  // A 1 cm cube of 4^3 cells (384 tetrahedra) on a fixed base; its whole top face (25 vertices, picked by index) is
  // pushed down by 5 mm over 0.5 s, then held; implicit Euler.
  BoxSpec box;
  box.size = {0.01, 0.01, 0.01};
  box.cells_x = box.cells_y = box.cells_z = 4;
  DiagnosticList diagnostics;
  const Mesh mesh = generate_box(box, diagnostics);
  std::ostringstream top;
  for (std::size_t v = 0; v < mesh.points.size(); ++v)
    if (std::abs(mesh.points[v][2] - 0.01) < 1e-12) top << (top.tellp() > 0 ? ", " : "") << v;
  const std::string scene =
      "mesh: {box: {size: [0.01, 0.01, 0.01], cells: [4, 4, 4]}, units: m}\n"
      "material: {youngs_modulus: 5, poisson_ratio: 0.45}\nmass: {density: 1060}\ndamping: {ratio: 0.9}\n"
      "fixed: {plane: {point: [0, 0, 0], normal: [0, 0, 1]}}\n"
      "loads: {probe: {indices: [" +
      top.str() +
      "], displacement: [0, 0, -0.005], ramp: 0.5}}\n"
      "integrator: implicit_euler\ndt: 0.005\nduration: 0.7\nprecision: double\n";
  const Outcome stable = run(model("stable_neo_hookean") + scene, "cube_snh");
  INFO(stable.errors);
  CHECK(stable.completed);
  CHECK(stable.largest_inverted == 0);
  CHECK(stable.inversion_warnings == 0);
  CHECK(stable.max_displacement > 0.0049);
  // The explicit path at its automatic step (the rest critical step with its margin) crushes it the same way.
  std::string explicit_scene = scene;
  explicit_scene.replace(explicit_scene.find("integrator: implicit_euler\ndt: 0.005"),
                         std::string("integrator: implicit_euler\ndt: 0.005").size(),
                         "integrator: semi_implicit_euler\ndt: auto");
  const Outcome explicit_run = run(model("stable_neo_hookean") + explicit_scene, "cube_snh_explicit");
  INFO(explicit_run.errors);
  CHECK(explicit_run.completed);
  CHECK(explicit_run.largest_inverted == 0);
  CHECK(explicit_run.max_displacement > 0.0049);
  const Outcome corotational = run(model("corotational") + scene, "cube_corotational");
  CHECK(corotational.completed);
  WARN("cube compressed to 50 %: stable neo-Hookean " << stable.largest_inverted << " inverted, co-rotational "
                                                      << corotational.largest_inverted << " inverted ("
                                                      << corotational.inversion_warnings << " warnings)");
  // The co-rotational law counts what it inverts and warns once per run.
  CHECK(corotational.inversion_warnings == (corotational.largest_inverted > 0 ? 1 : 0));
}

TEST_CASE("it never folds: a probe pushed 40 % of a block's length into its end", "[fem][snh][scene][heavy]") {
  // A 1 x 1 x 2 cm block of 4 x 4 x 8 cells (768 tetrahedra) on a fixed base; a probe picked by a ray at the centre of
  // its top end (the hit vertex and its 4 neighbours) travels 8 mm down over 1 s, then holds.
  const std::string scene =
      "mesh: {box: {size: [0.01, 0.01, 0.02], cells: [4, 4, 8]}, units: m}\n"
      "material: {youngs_modulus: 5, poisson_ratio: 0.45}\nmass: {density: 1060}\ndamping: {ratio: 0.9}\n"
      "fixed: {plane: {point: [0, 0, 0], normal: [0, 0, 1]}}\n"
      "loads: {probe: {ray: {origin: [0.005, 0.005, 0.03], direction: [0, 0, -1]}, radius: 0.0026, "
      "displacement: [0, 0, -0.008], ramp: 1.0}}\n"
      "integrator: implicit_euler\ndt: 0.005\nduration: 1.2\nprecision: double\n";
  const Outcome stable = run(model("stable_neo_hookean") + scene, "probe_snh");
  INFO(stable.errors);
  CHECK(stable.completed);
  CHECK(stable.largest_inverted == 0);
  CHECK(stable.inversion_warnings == 0);
  const Outcome corotational = run(model("corotational") + scene, "probe_corotational");
  CHECK(corotational.completed);
  CHECK(corotational.inversion_warnings == (corotational.largest_inverted > 0 ? 1 : 0));
  WARN("probe 40 % into a block end: stable neo-Hookean " << stable.largest_inverted << " inverted, co-rotational "
                                                          << corotational.largest_inverted << " inverted");
}

TEST_CASE("the resting block of bench/scenes/resting_block_snh.yaml runs on the CPU at 8^3 cells, none inverted",
          "[fem][snh][scene][heavy]") {
  const std::string path = std::string(FMPC_SOURCE_DIR) + "/bench/scenes/resting_block_snh.yaml";
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::string scene = text.str();
  const std::string cells = "cells: [120, 120, 120]";
  REQUIRE(scene.find(cells) != std::string::npos);
  scene.replace(scene.find(cells), cells.size(), "cells: [8, 8, 8]");
  scene += "backend: cpu\nthreads: 1\n";
  const Outcome outcome = run(scene, "resting_block_snh");
  INFO(outcome.errors);
  CHECK(outcome.completed);
  CHECK(outcome.largest_inverted == 0);
  CHECK(outcome.inversion_warnings == 0);
  CHECK(outcome.max_displacement > 0.0);
}

// The simulation trade (runtime/scene/simulation_trade.h, `fmpc trade SCENE.yaml`) on a tiny indentation scene:
// the reference row, the ordering of the models' errors, the reference's convergence estimates, the CSV's columns,
// and the command end to end.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "runtime/fem/element_law_registry.h"
#include "runtime/scene/simulation_trade.h"
#include "tests/support/generated_program.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

namespace fs = std::filesystem;

// 288 tetrahedra, 100 vertices: a 2 x 2 x 1.5 cm block on a fixed base, a probe pressed 0.4 mm into the middle of
// its top face over 50 ms, held for 30 ms.
const char* const kTinyScene =
    "name: tiny_indentation\n"
    "mesh: {box: {size: [0.02, 0.02, 0.015], cells: [4, 4, 3]}, units: m}\n"
    "material: {youngs_modulus: 5}\n"
    "mass: {density: 1000}\n"
    "damping: {ratio: 0.9}\n"
    "fixed: {plane: {point: [0, 0, 0], normal: [0, 0, 1]}}\n"
    "loads:\n"
    "  probe: {ray: {origin: [0.01, 0.01, 0.05], direction: [0, 0, -1]}, radius: 0.0051,\n"
    "          displacement: [0, 0, -0.0004], ramp: 0.05}\n"
    "duration: 0.08\n";

Scene tiny_scene() {
  DiagnosticList diagnostics;
  auto scene = parse_scene("/tmp/fmpc_trade_tiny.yaml", kTinyScene, diagnostics);
  REQUIRE(scene);
  return *scene;
}

const SimulationTradeRow& row_named(const SimulationTradeResult& result, const std::string& variant) {
  const auto it = std::find_if(result.rows.begin(), result.rows.end(),
                               [&](const SimulationTradeRow& row) { return row.variant == variant; });
  REQUIRE(it != result.rows.end());
  return *it;
}

}  // namespace

TEST_CASE("the simulation trade: the reference has no error, the FEM is closer to it than springs", "[heavy][trade][scene]") {
  SimulationTradeOptions options;
  options.models = {*parse_trade_model("springs_van_gelder"), *parse_trade_model("springs_lloyd"),
                    *parse_trade_model("corotational_fem")};
  options.precisions = {Precision::Float, Precision::Double};
  options.integrators = {{Integrator::SemiImplicitEuler, 1.0}};
  options.refinements = {1};
  options.element_kinds = {default_element_kind().kind};
  std::vector<std::string> progress;
  options.progress = [&](std::size_t, std::size_t, const std::string& what) { progress.push_back(what); };
  DiagnosticList diagnostics;
  const auto result = run_simulation_trade(tiny_scene(), options, diagnostics);
  INFO((diagnostics.items().empty() ? std::string() : diagnostics.items().front().message));
  REQUIRE(result);
  CHECK_FALSE(diagnostics.has_errors());
  // One round (the reference, its mesh check FEM f64 SIE x0.5 r0 and six variants, one of which, FEM f64 SIE r1, is
  // its step check, side by side); then "done".
  CHECK(progress.size() == 1 + 1);
  REQUIRE(result->rows.size() == 1 + 6);
  CHECK(result->coarse_vertices == 100);
  CHECK(result->has_probe_force);

  const SimulationTradeRow& reference = result->rows.front();
  CHECK(reference.reference);
  CHECK(reference.variant == "reference: FEM f64 SIE x0.5 r1");
  // V + E: 100 vertices and 467 edges (235 along the axes, 184 face diagonals, 48 cell diagonals).
  CHECK(reference.vertices == 100 + 467);
  CHECK(reference.tetrahedra == 8 * 288);
  CHECK(reference.completed);
  CHECK(reference.errors.displacement_max == 0.0);
  CHECK(reference.errors.displacement_rms == 0.0);
  REQUIRE(reference.errors.probe_force);
  CHECK(*reference.errors.probe_force == 0.0);
  CHECK(reference.final_probe_force > 0.0);  // the probe pushes down, the tissue pushes back along the probe

  // The reference's own estimated error: its step hardly matters, one refinement less does.
  CHECK(result->reference_time_difference.displacement_max < 1e-3);
  REQUIRE(result->reference_mesh_difference);
  CHECK(result->reference_mesh_difference->displacement_rms > 1e-2);

  const SimulationTradeRow& fem = row_named(*result, "FEM f64 SIE r1");
  const SimulationTradeRow& fem_float = row_named(*result, "FEM f32 SIE r1");
  const SimulationTradeRow& van_gelder = row_named(*result, "springs VG f64 SIE r1");
  const SimulationTradeRow& lloyd = row_named(*result, "springs LSH f64 SIE r1");
  for (const SimulationTradeRow& row : result->rows) {
    INFO(row.variant);
    CHECK(row.completed);
    CHECK(row.steps_per_second > 0.0);
    CHECK(row.memory_bytes > 0.0);
    CHECK(row.dt * static_cast<double>(row.steps) == Approx(0.08).epsilon(1e-12));  // every run ends at T
  }
  // The FEM at the automatic step on the reference's mesh is its step check.
  CHECK(fem.errors.displacement_max == result->reference_time_difference.displacement_max);
  CHECK(*fem.errors.probe_force == *result->reference_time_difference.probe_force);
  // On the same mesh the FEM differs from the reference by its step only, springs by their model too.
  for (const SimulationTradeRow* springs : {&van_gelder, &lloyd}) {
    INFO(springs->variant);
    CHECK(fem.errors.displacement_max < 0.1 * springs->errors.displacement_max);
    CHECK(fem.errors.displacement_rms < 0.1 * springs->errors.displacement_rms);
    CHECK(*fem.errors.probe_force < 0.1 * *springs->errors.probe_force);
  }
  // Float rounding costs far less than the model.
  CHECK(fem_float.errors.displacement_rms < 1e-3);
  CHECK(fem_float.memory_bytes < fem.memory_bytes);

  // The CSV: the columns first, exactly, one line per row.
  const std::string csv = simulation_trade_csv(*result);
  const std::string header = csv.substr(0, csv.find('\n'));
  CHECK(header ==
        "variant,model,precision,integrator,dt_s,vertices,displacement_max_rel_error,displacement_rms_rel_error,"
        "probe_force_rel_error,steps_per_second,memory_bytes,mapping,refinements,tetrahedra,steps,inverted_elements,"
        "status,element,mesh,real_time_factor,wall_seconds,meets_max_error,cpu_seconds,estimated_cpu_seconds");
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 1 + 7);
  CHECK(csv.find("\nreference: FEM f64 SIE x0.5 r1,corotational_fem,double,semi_implicit_euler,") != std::string::npos);
  CHECK(csv.find("\nsprings LSH f32 SIE r1,springs,float,semi_implicit_euler,") != std::string::npos);
  CHECK(csv.find(",lloyd_szekely_harders_2007,1,2304,") != std::string::npos);
  const std::string markdown = simulation_trade_markdown(*result);
  CHECK(markdown.find("Reference: corotational FEM on linear elements, double, semi-implicit Euler at 0.5 x its "
                      "automatic step") !=
        std::string::npos);
  CHECK(markdown.find("| reference: FEM f64 SIE x0.5 r1 |") != std::string::npos);
}

TEST_CASE("the simulation trade refuses what it cannot compare, naming the field or the option", "[trade][scene]") {
  const auto first_error = [](const std::string& text, const SimulationTradeOptions& options) {
    DiagnosticList diagnostics;
    auto scene = parse_scene("/tmp/fmpc_trade_refused.yaml", text, diagnostics);
    REQUIRE(scene);
    CHECK_FALSE(run_simulation_trade(*scene, options, diagnostics));
    REQUIRE(diagnostics.has_errors());
    const Diagnostic& d = diagnostics.items().front();
    return std::to_string(d.range.line) + ":" + std::to_string(d.range.column) + ": " + d.message;
  };
  SimulationTradeOptions quick;
  quick.duration = 0.001;
  quick.refinements = {0};
  // Nothing moves: no load.
  const std::string still = "mesh: {box: {size: [0.02, 0.02, 0.02], cells: [1, 1, 1]}, units: m}\n"
                            "material: {youngs_modulus: 5}\nmass: {density: 1000}\nduration: 0.01\n";
  CHECK(first_error(still, quick).find("0:0: the reference (FEM f64 SIE x0.5 r0) does not move") == 0);
  // Refinements beyond the size limit, before anything is built.
  SimulationTradeOptions huge = quick;
  huge.refinements = {3};
  CHECK(first_error("mesh: {box: {size: [1, 1, 1], cells: [20, 20, 20]}, units: m}\nmaterial: {youngs_modulus: 5}\n"
                    "mass: {density: 1000}\n",
                    huge) ==
        "1:7: mesh: 48000 tetrahedra refined 3 times make 24576000, above the trade's limit of 4194304; lower "
        "--refinements or --reference-refinements, or coarsen the mesh");
  // A reference step whose check (twice it) would exceed the automatic step.
  SimulationTradeOptions bad = quick;
  bad.reference_dt_factor = 0.75;
  CHECK(first_error(still, bad) ==
        "0:0: --reference-dt-factor must be in (0, 0.5] (its check runs at twice it), got 0.75");
}

TEST_CASE("fmpc trade SCENE.yaml writes the table, the CSV and the Pareto plot", "[trade][scene]") {
  const testing::ScratchFolder folder("scene_trade");
  const fs::path& dir = folder.path();
  testing::write_text_file(dir / "tiny.yaml", kTinyScene);
  // Two models, both integrators, the scene's mesh, 20 ms: five runs (the reference and four variants, one of
  // which, FEM f64 SIE r0, is the reference's step check).
  std::string command = std::string(FMPC_BINARY) + " trade tiny.yaml --refinements 0 --duration 0.02";
  command += " --models springs_volume_term,corotational_fem --elements linear --precisions double";
  command += " --integrators semi_implicit_euler,implicit_euler:4 --csv t.csv --plot t.png > out.md 2> err.txt";
  const int status = std::system(("cd " + dir.string() + " && " + command).c_str());
  INFO(testing::read_text_file(dir / "err.txt"));
  REQUIRE(status == 0);
  const std::string markdown = testing::read_text_file(dir / "out.md");
  CHECK(markdown.find("# fmpc trade: scene tiny_indentation") == 0);
  CHECK(markdown.find("Every run simulates 0.02 s") != std::string::npos);
  CHECK(markdown.find("| springs+volume f64 IE x4 r0 |") != std::string::npos);
  CHECK(markdown.find("mesh: not estimated (the reference is on the scene's own mesh)") != std::string::npos);
  const std::string csv = testing::read_text_file(dir / "t.csv");
  CHECK(csv.rfind("variant,model,precision,integrator,dt_s,vertices,", 0) == 0);
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 1 + 1 + 4);
  CHECK(testing::read_text_file(dir / "t.png").substr(1, 3) == "PNG");
  // What the runs will cost, before they start (progress lines follow on a pipe only every 10 s: docs/cli.md).
  CHECK(testing::read_text_file(dir / "err.txt").find("fmpc trade: 5 runs, about 1.92e+05 element-steps in all (the "
                                                      "largest run 288 tetrahedra, the longest 235 steps") == 0);
}

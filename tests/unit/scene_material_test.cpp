// Material binding: FIS output (Young's modulus, kPa) per spring from constants and regions, and the k(strain)
// table looked up every step.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "compiler/backend/table/lookup_table.h"
#include "compiler/backend/table/table_builder.h"
#include "compiler/eval/interpreter.h"
#include "compiler/frontend/rule_file_loader.h"
#include "compiler/passes/pipeline.h"
#include "runtime/scene/material_binding.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "tests/support/generated_program.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

std::string read_source(const std::string& relative) {
  std::ifstream in(std::string(FMPC_SOURCE_DIR) + "/" + relative);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

FuzzySystem load_system(const std::string& text) {
  DiagnosticList diagnostics;
  RuleFile file = load_rule_file("test.fis", text, diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(file.systems.size() == 1);
  return file.systems.front();
}

// E = x exactly: one Sugeno rule that always fires, with the linear model x.
const char* kIdentity = R"(system identity
  type sugeno
input x in [0, 100] kPa
  all is gauss(mean 50, sd 1000)
output modulus in [0, 100] kPa
  model is linear(x 1)
rule r1: if x is all then modulus is model
)";

InputBinding constant(const std::string& input, double value) {
  InputBinding b;
  b.input = input;
  b.value = value;
  return b;
}

std::vector<std::string> messages(const DiagnosticList& diagnostics) {
  std::vector<std::string> out;
  for (const Diagnostic& d : diagnostics.items()) out.push_back(d.message);
  return out;
}

}  // namespace

TEST_CASE("constant bindings evaluate the rules once and convert kPa to Pa", "[scene]") {
  const FuzzySystem liver = load_system(read_source("rulesets/liver_fibrosis/mamdani.fis"));
  Scene scene;
  for (const auto& [name, value] : std::vector<std::pair<std::string, double>>{
           {"HCV", 9.7}, {"HBV", 9.5}, {"ALD", 12}, {"CLD", 11}, {"NAFLD", 11.2}})
    scene.material.bindings.push_back(constant(name, value));
  DiagnosticList diagnostics;
  const std::vector<Point3> midpoints(5, Point3{0, 0, 0});
  const auto binding = bind_rules(liver, 0, scene, midpoints, MaterialPoint::SpringMidpoint, diagnostics);
  REQUIRE(binding);
  CHECK(diagnostics.empty());
  const double expected = evaluate(liver, {9.7, 9.5, 12, 11, 11.2}).outputs[0] * 1000.0;
  CHECK(binding->evaluations == 1);
  CHECK(binding->modulus_per_spring == std::vector<double>(5, expected));
  CHECK(binding->modulus_min == expected);
  CHECK(binding->strain.empty());
  CHECK(expected == Approx(20828.38).epsilon(1e-6));  // the demo's patient: F3
}

TEST_CASE("per-region bindings pick the first region containing the spring's midpoint", "[scene]") {
  const FuzzySystem identity = load_system(kIdentity);
  Scene scene;
  InputBinding regions;
  regions.input = "x";
  regions.kind = InputBinding::Kind::PerRegion;
  regions.regions = {{SceneBox{{0, 0, 0}, {1, 1, 1}}, 10.0}, {SceneBox{{0, 0, 0}, {2, 2, 2}}, 20.0}};
  regions.value = 5.0;
  regions.has_default = true;
  scene.material.bindings = {regions};
  DiagnosticList diagnostics;
  const std::vector<Point3> midpoints = {{0.5, 0.5, 0.5}, {1.5, 0.5, 0.5}, {3, 3, 3}, {1, 1, 1}};
  const auto binding = bind_rules(identity, 0, scene, midpoints, MaterialPoint::SpringMidpoint, diagnostics);
  REQUIRE(binding);
  CHECK(binding->evaluations == 3);  // cached per distinct value
  REQUIRE(binding->modulus_per_spring.size() == 4);
  CHECK(binding->modulus_per_spring[0] == Approx(10000.0).epsilon(1e-12));
  CHECK(binding->modulus_per_spring[1] == Approx(20000.0).epsilon(1e-12));
  CHECK(binding->modulus_per_spring[2] == Approx(5000.0).epsilon(1e-12));
  CHECK(binding->modulus_per_spring[3] == Approx(10000.0).epsilon(1e-12));  // on the boundary: inside

  scene.material.bindings[0].has_default = false;
  DiagnosticList missing;
  CHECK_FALSE(bind_rules(identity, 0, scene, midpoints, MaterialPoint::SpringMidpoint, missing));
  CHECK(messages(missing) == std::vector<std::string>{"material.inputs.x: spring 2 (midpoint 3, 3, 3) lies in no "
                                                      "region; add a region that contains it or a 'default'"});
  // The co-rotational FEM (and the springs' volume term) evaluate the material at element centroids.
  DiagnosticList missing_element;
  CHECK_FALSE(bind_rules(identity, 0, scene, midpoints, MaterialPoint::ElementCentroid, missing_element));
  CHECK(messages(missing_element) ==
        std::vector<std::string>{"material.inputs.x: element 2 (centroid 3, 3, 3) lies in no region; add a region "
                                 "that contains it or a 'default'"});
}

TEST_CASE("binding errors name the input and the field", "[scene]") {
  const FuzzySystem liver = load_system(read_source("rulesets/liver_fibrosis/mamdani.fis"));
  Scene scene;
  scene.material.bindings = {constant("HCV", 9.7), constant("HBB", 9.5), constant("ALD", 12), constant("CLD", 11)};
  DiagnosticList diagnostics;
  CHECK_FALSE(bind_rules(liver, 0, scene, {}, MaterialPoint::SpringMidpoint, diagnostics));
  REQUIRE(diagnostics.items().size() == 3);
  CHECK(diagnostics.items()[0].message == "material.inputs.HBB: 'HBB' is not an input of system 'liver_fibrosis'");
  CHECK(diagnostics.items()[0].notes ==
        std::vector<std::string>{"did you mean 'HBV'?", "the inputs of system 'liver_fibrosis' are: HCV, HBV, ALD, CLD, NAFLD"});
  CHECK(diagnostics.items()[1].message ==
        "material.inputs: input 'HBV' of system 'liver_fibrosis' is not bound; give it a number, 'strain' or "
        "{regions: [...], default: NUMBER}");
  CHECK(diagnostics.items()[2].message ==
        "material.inputs: input 'NAFLD' of system 'liver_fibrosis' is not bound; give it a number, 'strain' or "
        "{regions: [...], default: NUMBER}");

  // Out of range: a warning, evaluated as given.
  scene.material.bindings = {constant("HCV", 80), constant("HBV", 9.5), constant("ALD", 12), constant("CLD", 11),
                             constant("NAFLD", 11)};
  DiagnosticList range;
  CHECK(bind_rules(liver, 0, scene, {{0, 0, 0}}, MaterialPoint::SpringMidpoint, range));
  CHECK(messages(range) ==
        std::vector<std::string>{"material.inputs.HCV: 80 is outside the input's range [0, 75]; evaluated as given"});

  const FuzzySystem wrong_unit = load_system(R"(system s
  type sugeno
input x in [0, 1] kPa
  all is gauss(mean 0.5, sd 10)
output k in [0, 1] mm
  c is constant(value 1)
rule r1: if x is all then k is c
)");
  scene.material.bindings = {constant("x", 0.5)};
  DiagnosticList unit;
  CHECK_FALSE(bind_rules(wrong_unit, 0, scene, {{0, 0, 0}}, MaterialPoint::SpringMidpoint, unit));
  CHECK(messages(unit) == std::vector<std::string>{"material.rules: output 'k' of system 's' is in 'mm'; Young's "
                                                   "modulus must be in kPa, Pa or MPa"});
  CHECK(unit.items()[0].notes ==
        std::vector<std::string>{"give the output one of those units in the rule file (and recompile a table)"});
}

TEST_CASE("a strain binding builds modulus(strain) from the interpreter over the strain axis", "[scene]") {
  const FuzzySystem stiffening = load_system(read_source("rulesets/scenes/strain_stiffening.fis"));
  Scene scene;
  InputBinding strain;
  strain.input = "strain";
  strain.kind = InputBinding::Kind::Strain;
  scene.material.bindings = {strain};
  scene.material.strain_axis = StrainAxis{-0.3, 0.3, 61};
  DiagnosticList diagnostics;
  const auto binding = bind_rules(stiffening, 0, scene, {}, MaterialPoint::SpringMidpoint, diagnostics);
  REQUIRE(binding);
  REQUIRE(binding->strain.size() == 61);
  CHECK(binding->strain.front() == -0.3);
  CHECK(binding->strain.back() == 0.3);
  CHECK(binding->strain[30] == Approx(0.0).margin(1e-15));
  for (std::size_t i = 0; i < binding->strain.size(); i += 10)
    CHECK(binding->strain_modulus[i] == evaluate(stiffening, {binding->strain[i]}).outputs[0] * 1000.0);
  // Stiffer stretched than at rest: the table's point.
  CHECK(binding->strain_modulus.back() > 3.0 * binding->strain_modulus[30]);

  // Combined with a per-region binding: refused.
  const FuzzySystem liver = load_system(read_source("rulesets/liver_fibrosis/mamdani.fis"));
  InputBinding regions;
  regions.input = "HBV";
  regions.kind = InputBinding::Kind::PerRegion;
  regions.has_default = true;
  strain.input = "HCV";
  scene.material.bindings = {strain, regions, constant("ALD", 12), constant("CLD", 11), constant("NAFLD", 11)};
  DiagnosticList refused;
  CHECK_FALSE(bind_rules(liver, 0, scene, {{0, 0, 0}}, MaterialPoint::SpringMidpoint, refused));
  CHECK(messages(refused) == std::vector<std::string>{"material.inputs: a 'strain' binding cannot be combined with "
                                                      "per-region bindings; bind the other inputs to constants"});
}

TEST_CASE("the CPU backend looks k(strain) up every step", "[scene]") {
  SimulationSetup setup;
  setup.rest_positions = {{0, 0, 0}, {1, 0, 0}};
  setup.initial_positions = {{0, 0, 0}, {1.2, 0, 0}};  // strain 0.2
  setup.mass = {1.0, 1.0};
  setup.fixed_vertices = {0};
  setup.springs.vertex_count = 2;
  setup.springs.first = {0};
  setup.springs.second = {1};
  setup.springs.kind = {SpringKind::TetrahedronEdge};
  setup.springs.element_measure = {0.0};
  setup.springs.rest_length = {1.0};
  setup.springs.stiffness = {1.0};
  setup.springs.damping = {0.0};
  build_adjacency(setup.springs);
  setup.strain_stiffness = StrainStiffnessTable{{-1.0, 0.0, 1.0}, {30.0, 10.0, 50.0}, {2.0}};
  setup.time_step = 1e-4;
  DiagnosticList diagnostics;
  auto simulation = Simulation::create(setup, diagnostics);
  REQUIRE(simulation);
  // The stability check used the stiffest k the table can give: 50 * 2 = 100 N/m, w = sqrt(2 * 100 / 1).
  CHECK(simulation->stability().omega_max == Approx(std::sqrt(200.0)));
  REQUIRE(simulation->advance(1, diagnostics));
  // Looked up at the start of the step, at strain 0.2: (10 + 0.2 (50 - 10)) * 2.
  CHECK(simulation->current_stiffness(diagnostics) == std::vector<double>{36.0});
  const double x1 = simulation->positions(diagnostics)[1][0];
  REQUIRE(simulation->advance(1, diagnostics));
  const double strain = x1 - 1.0;
  CHECK(simulation->current_stiffness(diagnostics)[0] == Approx((10.0 + strain * 40.0) * 2.0).epsilon(1e-12));

  SimulationSetup broken = setup;
  broken.strain_stiffness->strain = {0.0, 0.0, 1.0};
  DiagnosticList refused;
  CHECK_FALSE(Simulation::create(broken, refused));
  CHECK(messages(refused) ==
        std::vector<std::string>{"the strain stiffness table needs at least 2 strictly increasing finite strains, one "
                                 "finite non-negative modulus per strain and one non-negative factor per spring"});
}

namespace {

// Issue 11, item 3: stiffness in Pa. A .fzt compiled from such a file was read as kPa (the issue's: E = 8.19 kPa
// from the rules, 8,206 kPa from the table, and a probe force 1000 times too large).
const char* kPascalRules = R"(system tissue_pa "Young's modulus in Pa"
  type sugeno
input HCV "stiffness" in [0, 75] kPa
  any is gauss(mean 40, sd 1000)
input HBV "stiffness" in [0, 75] kPa
  any is gauss(mean 40, sd 1000)
output E "Young's modulus" in [0, 75000] Pa
  model is linear(HCV 500, HBV 430)
rule r1: if HCV is any and HBV is any then E is model
)";

// The table of `rules` over both inputs at max_error (output units), as `fmpc compile --target table` builds it.
LookupTable compiled_table(const std::string& rules, double max_error) {
  const FuzzySystem source = load_system(rules);
  DiagnosticList diagnostics;
  PipelineOptions pipeline;
  const auto compiled = run_pipeline(source, {}, pipeline, diagnostics);
  REQUIRE(compiled);
  TableBuildOptions options;
  options.max_error = max_error;
  options.source_path = "rules.fis";
  const auto table = build_table(source, *compiled, options, diagnostics);
  INFO((diagnostics.empty() ? std::string() : diagnostics.items().front().message));
  REQUIRE(table);
  return *table;
}

std::optional<BuiltScene> build_material_scene(const std::filesystem::path& folder, const std::string& material,
                                               DiagnosticList& diagnostics) {
  const std::string path = (folder / "scene.yaml").string();
  const std::string text = "mesh: {box: {size: [0.02, 0.02, 0.02], cells: [2, 2, 2]}}\nmaterial:\n  " + material +
                           "\n  inputs: {HCV: 9.7, HBV: 7.8}\nfixed: {plane: {point: [0, 0, 0], normal: [0, 0, 1]}}\n"
                           "backend: cpu\n";
  testing::write_text_file(path, text);
  const auto scene = parse_scene(path, text, diagnostics);
  REQUIRE(scene);
  return build_scene(*scene, diagnostics);
}

}  // namespace

TEST_CASE("a rule file in Pa gives the same E as material.rules and as a compiled .fzt", "[scene][units]") {
  testing::ScratchFolder folder("pascal_table");
  testing::write_text_file(folder.path() / "tissue_pa.fis", kPascalRules);
  const LookupTable table = compiled_table(kPascalRules, 10.0);  // 10 Pa
  REQUIRE(table.output_units == std::vector<std::string>{"Pa"});
  REQUIRE(table.axes[0].input_unit == "kPa");
  testing::write_text_file(folder.path() / "tissue_pa.fzt", serialize_fzt(table));

  DiagnosticList from_rules, from_table;
  const auto rules = build_material_scene(folder.path(), "rules: tissue_pa.fis", from_rules);
  const auto tabled = build_material_scene(folder.path(), "table: tissue_pa.fzt", from_table);
  REQUIRE(rules);
  REQUIRE(tabled);
  CHECK(from_rules.empty());
  CHECK(from_table.empty());
  const double expected = evaluate(load_system(kPascalRules), {9.7, 7.8}).outputs[0];  // Pa
  CHECK(expected == Approx(8190).margin(300));  // about the issue's 8.19 kPa
  REQUIRE_FALSE(rules->material->modulus_per_spring.empty());
  for (std::size_t s = 0; s < rules->material->modulus_per_spring.size(); ++s) {
    CHECK(rules->material->modulus_per_spring[s] == Approx(expected).epsilon(1e-12));
    CHECK(std::fabs(tabled->material->modulus_per_spring[s] - expected) <= table.max_error);
  }
}

TEST_CASE("table and rule outputs without a unit are read as kPa with one warning; other units are refused",
          "[scene][units]") {
  testing::ScratchFolder folder("unit_less_table");
  // MATLAB's format: no units anywhere.
  const std::string matlab = R"([System]
Name='tissue'
Type='sugeno'
NumInputs=2
NumOutputs=1
NumRules=1
[Input1]
Name='HCV'
Range=[0 75]
NumMFs=1
MF1='any':'gaussmf',[100 10]
[Input2]
Name='HBV'
Range=[0 75]
NumMFs=1
MF1='any':'gaussmf',[100 10]
[Output1]
Name='E'
Range=[0 75]
NumMFs=1
MF1='model':'linear',[0.5 0.5 0]
[Rules]
1 1, 1 (1) : 1
)";
  testing::write_text_file(folder.path() / "tissue.fis", matlab);
  LookupTable table = compiled_table(matlab, 0.01);
  REQUIRE(table.output_units == std::vector<std::string>{""});
  testing::write_text_file(folder.path() / "tissue.fzt", serialize_fzt(table));
  for (const std::string& material : {std::string("rules: tissue.fis"), std::string("table: tissue.fzt")}) {
    DiagnosticList diagnostics;
    const auto built = build_material_scene(folder.path(), material, diagnostics);
    INFO(material);
    REQUIRE(built);
    REQUIRE(diagnostics.items().size() == 1);
    const Diagnostic& warning = diagnostics.items()[0];
    CHECK(warning.severity == Severity::Warning);
    const std::string field = material.substr(0, material.find(':'));
    CHECK(warning.message == "material." + field + ": output 'E' of " +
                                 (field == "rules" ? "system" : "table") +
                                 " 'tissue' has no unit (MATLAB .fis files carry none); it is read as Young's "
                                 "modulus in kPa");
    CHECK(warning.range.line == 3);  // the scene's `material.rules` / `material.table` line
    CHECK(built->material->modulus_per_spring[0] == Approx((9.7 + 7.8) / 2 * 1000).epsilon(1e-9));
  }
  table.output_units = {"mm"};
  testing::write_text_file(folder.path() / "tissue.fzt", serialize_fzt(table));
  DiagnosticList refused;
  CHECK_FALSE(build_material_scene(folder.path(), "table: tissue.fzt", refused));
  REQUIRE(refused.items().size() == 1);
  CHECK(refused.items()[0].message ==
        "material.table: output 'E' of table 'tissue' is in 'mm'; Young's modulus must be in kPa, Pa or MPa");
  CHECK(refused.items()[0].range.line == 3);
}

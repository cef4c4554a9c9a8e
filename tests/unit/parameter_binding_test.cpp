// material.bind (docs/scenes.md, "Rules for every parameter"): a rule file with several outputs gives each element law
// parameter per element, reproducing the per-element values set directly bit for bit; its checks (the law's
// parameters, units, declared ranges, every element's value); and strain-bound Young's modulus on every law and
// element kind, whose strain is the principal strain (stretch - 1) of largest magnitude.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "compiler/eval/interpreter.h"
#include "compiler/frontend/rule_file_loader.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/fem/fem_model_builder.h"
#include "runtime/integrate/simulation.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "tests/support/bound_material_rules.h"

using namespace fmpc;
using namespace fmpc::sim;
using namespace fmpc::test_rules;

namespace {

struct Folder {
  std::filesystem::path path;
  explicit Folder(const std::string& name) : path(std::filesystem::temp_directory_path() / ("fmpc_bind_" + name)) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~Folder() { std::filesystem::remove_all(path); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path / name) << text;
    return (path / name).string();
  }
};

// The scene `yaml` (written to the folder as scene.yaml) parsed and built; REQUIREs both.
struct Built {
  Scene scene;
  BuiltScene built;
};
Built parse_and_build(const Folder& folder, const std::string& yaml);

std::string all_messages(const DiagnosticList& diagnostics) {
  std::string out;
  for (const Diagnostic& d : diagnostics.items()) out += d.message + "\n";
  return out;
}

Built parse_and_build(const Folder& folder, const std::string& yaml) {
  DiagnosticList diagnostics;
  auto scene = parse_scene(folder.write("scene.yaml", yaml), yaml, diagnostics);
  INFO(all_messages(diagnostics));
  REQUIRE(scene);
  auto built = build_scene(*scene, diagnostics);
  INFO(all_messages(diagnostics));
  REQUIRE(built);
  return {std::move(*scene), std::move(*built)};
}

// `text` written to the folder as tissue.fis (the scenes' rule file) and loaded; REQUIREs no errors.
RuleFile written_rules(const Folder& folder, const char* text) {
  folder.write("tissue.fis", text);
  DiagnosticList diagnostics;
  RuleFile file = load_rule_file("tissue.fis", text, diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  return file;
}

// The messages of the scene `yaml`, which parses but does not build.
std::string build_errors(const Folder& folder, const std::string& yaml) {
  DiagnosticList diagnostics;
  const auto scene = parse_scene(folder.write("scene.yaml", yaml), yaml, diagnostics);
  REQUIRE(scene);
  CHECK_FALSE(build_scene(*scene, diagnostics));
  return all_messages(diagnostics);
}

// Two regions of F (2 below z = 0.01, 8 above) on a 2 x 2 x 2-cell box of 2 cm.
std::string two_region_scene(const std::string& law, const std::string& element, const std::string& extra = "") {
  return "mesh: {box: {size: [0.02, 0.02, 0.02], cells: [2, 2, 2]}}\nmodel: fem\nfem: {law: " + law +
         ", element: " + element +
         "}\nmaterial:\n  rules: tissue.fis\n  inputs:\n    F: {regions: [{box: {min: [0, 0, 0], max: [1, 1, 0.01]}, "
         "value: 2}], default: 8}\n  bind: {youngs_modulus: stiffness, poisson_ratio: nu}\n" +
         extra + "fixed: {box: {min: [-1, -1, -1], max: [1, 1, 0.0001]}}\nloads: {gravity: [0, 0, -9.81]}\nduration: 0.01\n";
}

}  // namespace

TEST_CASE("material.bind: E and nu per element from two outputs equal the values set directly, bit for bit",
          "[scene][bind]") {
  Folder folder("two_outputs");
  const RuleFile rules = written_rules(folder, kTwoOutputRules);
  Interpreter interpreter(rules.systems.front());
  for (const ElementLawRow& law : element_law_rows()) {
    if (law.beside_springs) continue;
    for (const ElementKindRow& element : element_kind_rows()) {
      INFO(law.keyword << " on " << element.keyword << " elements");
      const Built made = parse_and_build(folder, two_region_scene(law.keyword, element.keyword));
      const Scene* scene = &made.scene;
      const BuiltScene* built = &made.built;
      // The same material set directly: the interpreter at each element's region value (kPa -> Pa), through the
      // library's builder with the scene's mass and damping.
      FemModelSpec spec;
      spec.law = law.law;
      spec.element = element.kind;
      spec.mass = scene->mass;
      spec.damping_ratio = scene->damping.ratio;
      spec.rayleigh_stiffness = scene->rayleigh.stiffness;
      spec.length_unit = scene->mesh.unit;
      std::size_t lower = 0;
      for (const Point3& c : tetrahedron_centroids(built->mesh)) {
        const double f = c[2] <= 0.01 ? 2.0 : 8.0;
        lower += f == 2.0 ? 1 : 0;
        const Evaluation evaluation = interpreter.evaluate({f});
        spec.youngs_modulus.push_back(evaluation.outputs[0] * 1000.0);
        spec.poisson_ratio.push_back(evaluation.outputs[1]);
      }
      const std::size_t count = spec.youngs_modulus.size();
      REQUIRE(lower > 0);
      REQUIRE(lower < count);  // both regions hold elements
      CHECK(spec.youngs_modulus[0] == Approx(5000.0).epsilon(1e-12));  // the element at the origin: F = 2
      CHECK(spec.poisson_ratio[0] == Approx(0.32).epsilon(1e-12));
      DiagnosticList direct_diagnostics;
      const auto direct = build_fem_model(built->mesh, spec, direct_diagnostics);
      REQUIRE(direct);
      const ElementTerm& bound = built->setup.elements.terms.front();
      const ElementTerm& expected = direct->elements.terms.front();
      for (int p = 0; p < 2; ++p) {
        REQUIRE(bound.parameter[p].size() == count);
        REQUIRE(expected.parameter[p].size() == count);
        CHECK(std::memcmp(bound.parameter[p].data(), expected.parameter[p].data(), count * sizeof(double)) == 0);
      }
      REQUIRE(bound.stiffness_damping.size() == expected.stiffness_damping.size());
      CHECK(std::memcmp(bound.stiffness_damping.data(), expected.stiffness_damping.data(),
                        bound.stiffness_damping.size() * sizeof(double)) == 0);
      REQUIRE(built->setup.mass.size() == direct->mass.size());
      CHECK(std::memcmp(built->setup.mass.data(), direct->mass.data(), direct->mass.size() * sizeof(double)) == 0);
      CHECK(built->stiffness_description.find("nu = 0.32 to 0.38 from 'tissue' output 'nu'") != std::string::npos);
      // The run takes the per-element parameters (a few steps under gravity: finite, and the block sags).
      SimulationSetup run = built->setup;
      run.step_count = 20;
      DiagnosticList run_diagnostics;
      const SimulationResult result = simulate(run, run_diagnostics);
      CHECK(result.completed);
      double lowest = 0.0;
      for (std::size_t v = 0; v < result.positions.size(); ++v)
        lowest = std::min(lowest, result.positions[v][2] - run.rest_positions[v][2]);
      CHECK(lowest < 0.0);
    }
  }
}

TEST_CASE("strain-bound E: every law on every element kind reads E at the principal strain of largest magnitude",
          "[scene][bind][strain]") {
  // A homogeneous deformation x = F X of the whole mesh: every material point has the same F, so the internal forces
  // of the strain-bound model must equal those of the same model at constant E = E(s), s the principal strain
  // (stretch - 1) of largest magnitude of F. Stretched (s = +0.12) and compressed (s = -0.2, the lateral stretch
  // 1.05 smaller in magnitude), each law and element kind; E(s) is linear, so the table gives it to rounding.
  Folder folder("strain");
  folder.write("stiffening.fis", kStrainStiffeningRules);
  struct Case {
    double stretch[3];
    double strain;
  };
  const Case cases[] = {{{1.12, 0.97, 0.97}, 0.12}, {{0.8, 1.05, 1.05}, -0.2}};
  for (const ElementLawRow& law : element_law_rows()) {
    if (law.beside_springs) continue;
    for (const ElementKindRow& element : element_kind_rows()) {
      INFO(law.keyword << " on " << element.keyword << " elements");
      const std::string yaml = std::string("mesh: {box: {size: [0.02, 0.03, 0.04], cells: [2, 2, 2]}}\nmodel: fem\n") +
                               "fem: {law: " + law.keyword + ", element: " + element.keyword +
                               "}\nmaterial:\n  rules: stiffening.fis\n  inputs: {s: strain}\n  poisson_ratio: 0.4\n";
      const Built made = parse_and_build(folder, yaml);
      const BuiltScene* built = &made.built;
      REQUIRE(built->setup.strain_stiffness);
      // A kind that takes no strain table yet (element_kind_limits) is refused with the registry's reason.
      if (const char* refusal = element_kind_limits(element.kind).strain_table) {
        DiagnosticList refused;
        CHECK(!Simulation::create(built->setup, refused));
        CHECK(render_all(refused, {}).find(refusal) != std::string::npos);
        continue;
      }
      const SimulationSetup& strained = built->setup;
      std::vector<std::int32_t> every(strained.rest_positions.size());
      for (std::size_t v = 0; v < every.size(); ++v) every[v] = static_cast<std::int32_t>(v);
      const std::vector<Point3> still(strained.rest_positions.size(), Point3{0.0, 0.0, 0.0});
      for (const Case& c : cases) {
        INFO("stretches " << c.stretch[0] << ", " << c.stretch[1] << ", " << c.stretch[2]);
        std::vector<Point3> deformed = strained.rest_positions;
        for (Point3& p : deformed)
          for (std::size_t i = 0; i < 3; ++i) p[i] *= c.stretch[i];
        SimulationSetup constant = strained;
        constant.strain_stiffness.reset();
        const double modulus = 10000.0 * (1.0 + 2.0 * c.strain);
        for (double& e : constant.elements.terms.front().parameter[0]) e = modulus;
        const auto with_table = internal_forces(strained, deformed, still, {}, every);
        const auto at_constant = internal_forces(constant, deformed, still, {}, every);
        // The same model at the modulus of the other case's strain differs: the check can fail.
        SimulationSetup other = constant;
        for (double& e : other.elements.terms.front().parameter[0]) e = 10000.0 * (1.0 + 2.0 * (0.12 - 0.2 - c.strain));
        const auto at_other = internal_forces(other, deformed, still, {}, every);
        double largest = 0.0, difference = 0.0, other_difference = 0.0;
        for (std::size_t v = 0; v < every.size(); ++v)
          for (std::size_t i = 0; i < 3; ++i) {
            largest = std::max(largest, std::abs(at_constant[v][i]));
            difference = std::max(difference, std::abs(with_table[v][i] - at_constant[v][i]));
            other_difference = std::max(other_difference, std::abs(at_other[v][i] - at_constant[v][i]));
          }
        REQUIRE(largest > 0.0);
        CHECK(difference <= 1e-12 * largest);
        CHECK(other_difference > 0.1 * largest);
      }
    }
  }
}

TEST_CASE("material.bind: Prony weights from the rules, the same at every element or one per element",
          "[scene][bind][visco]") {
  Folder folder("prony");
  const RuleFile file = written_rules(folder, kPronyWeightRules);
  const auto scene_with = [](const std::string& inputs) {
    return "mesh: {box: {size: [0.02, 0.02, 0.02], cells: [2, 2, 2]}}\nmodel: fem\nmaterial:\n  rules: tissue.fis\n"
           "  inputs: " + inputs + "\n  viscoelastic: {prony: [{time: 1.86}, {time: 51.3}]}\n  bind:\n"
           "    youngs_modulus: stiffness\n    viscoelastic.prony[0].weight: fast\n"
           "    viscoelastic.prony[1].weight: slow\nfixed: {box: {min: [0, 0, 0], max: [1, 1, 0.001]}}\n";
  };
  SECTION("constant inputs: the series' weights are the outputs") {
    const Built made = parse_and_build(folder, scene_with("{F: 4}"));
    const BuiltScene* built = &made.built;
    const Evaluation evaluation = Interpreter(file.systems.front()).evaluate({4.0});
    const std::vector<PronyTerm>& prony = built->setup.elements.terms.front().prony;
    REQUIRE(prony.size() == 2);
    CHECK(prony[0].weight == evaluation.outputs[1]);
    CHECK(prony[1].weight == evaluation.outputs[2]);
    CHECK(prony[0].element_weight.empty());
    CHECK(prony[0].weight == Approx(0.28).epsilon(1e-12));
    CHECK(prony[1].time == 51.3);
  }
  SECTION("inputs per region: each element gets its own weights, the outputs at its centroid") {
    const Built made = parse_and_build(
        folder, scene_with("{F: {regions: [{box: {min: [0, 0, 0], max: [1, 1, 0.01]}, value: 2}], default: 8}}"));
    const SimulationSetup& setup = made.built.setup;
    const std::vector<PronyTerm>& prony = setup.elements.terms.front().prony;
    REQUIRE(prony.size() == 2);
    const Evaluation low = Interpreter(file.systems.front()).evaluate({2.0});
    const Evaluation high = Interpreter(file.systems.front()).evaluate({8.0});
    std::size_t lows = 0;
    for (const PronyTerm& term : prony) REQUIRE(term.element_weight.size() == setup.tetrahedra.size());
    for (std::size_t e = 0; e < setup.tetrahedra.size(); ++e) {
      double z = 0.0;
      for (const std::int32_t v : setup.tetrahedra[e]) z += setup.rest_positions[static_cast<std::size_t>(v)][2] / 4;
      const Evaluation& expected = z < 0.01 ? low : high;
      lows += z < 0.01 ? 1 : 0;
      CHECK(prony[0].element_weight[e] == expected.outputs[1]);
      CHECK(prony[1].element_weight[e] == expected.outputs[2]);
    }
    CHECK(lows == setup.tetrahedra.size() / 2);
    CHECK(prony[0].weight == high.outputs[1]);  // the largest, for messages
    CHECK(made.built.stiffness_description.find("viscoelastic, Prony series (g, tau) (0.24000000000000002 to 0.36 per "
                                                "element, 1.86 s) (0.14 to 0.26 per element, 51.3 s)") !=
          std::string::npos);
  }
}

namespace {

// A 2 cm block of 4 x 2 x 2 cells whose Prony weights follow F, 2 on its half x < 1 cm and 8 on the other, held
// stretched 1% along x from t = 0 (every vertex held: a homogeneous deformation; dt 1 ms), its face at x = `face` the
// probe's (held in place): its reaction force is minus the internal forces there, from the elements of that half alone.
SimulationSetup held_stretch(const Folder& folder, double face) {
  const std::string yaml =
      "mesh: {box: {size: [0.02, 0.02, 0.02], cells: [4, 2, 2]}}\nmodel: fem\nmaterial:\n  rules: tissue.fis\n"
      "  inputs: {F: {regions: [{box: {min: [-1, -1, -1], max: [0.01, 1, 1]}, value: 2}], default: 8}}\n"
      "  viscoelastic: {prony: [{time: 0.02}, {time: 0.2}]}\n"
      "  bind:\n    youngs_modulus: stiffness\n    viscoelastic.prony[0].weight: fast\n"
      "    viscoelastic.prony[1].weight: slow\n";
  SimulationSetup setup = parse_and_build(folder, yaml).built.setup;
  setup.initial_positions = setup.rest_positions;
  for (Point3& p : setup.initial_positions) p[0] *= 1.01;
  setup.fixed_vertices.clear();
  ProbeLoad probe;
  for (std::size_t v = 0; v < setup.rest_positions.size(); ++v) {
    const auto vertex = static_cast<std::int32_t>(v);
    if (std::abs(setup.rest_positions[v][0] - face) < 1e-9)
      probe.vertices.push_back(vertex);
    else
      setup.fixed_vertices.push_back(vertex);
  }
  setup.probe = probe;
  setup.precision = Precision::Double;
  setup.time_step = 1e-3;  // nothing moves: no stable step to derive
  return setup;
}

}  // namespace

TEST_CASE("material.bind: Prony weights per element from a rule output: each element relaxes by its own weights",
          "[scene][bind][visco]") {
  // The block's halves have the series (0.24, 0.02 s), (0.14, 0.2 s) (F = 2) and (0.36, 0.02 s), (0.26, 0.2 s)
  // (F = 8): held, each face's reaction force is G(t) of its own half's series times the instantaneous one, in closed
  // form (Simo's recursion is exact for a strain held), on the CPU engine through the scene's binding.
  Folder folder("prony_relax");
  const RuleFile file = written_rules(folder, kPronyWeightRules);
  for (const double face : {0.0, 0.02}) {
    const Evaluation own = Interpreter(file.systems.front()).evaluate({face < 0.01 ? 2.0 : 8.0});
    const double fast = own.outputs[1], slow = own.outputs[2];
    const auto relaxation = [&](double t) {
      return 1.0 - fast * (1.0 - std::exp(-t / 0.02)) - slow * (1.0 - std::exp(-t / 0.2));
    };
    for (const Integrator integrator : {Integrator::SemiImplicitEuler, Integrator::ImplicitEuler}) {
      INFO("the face at x = " << face << " m, " << to_string(integrator));
      SimulationSetup setup = held_stretch(folder, face);
      setup.integrator = integrator;
      DiagnosticList diagnostics;
      const auto run = Simulation::create(setup, diagnostics);
      INFO(all_messages(diagnostics));
      REQUIRE(run);
      const double dt = run->stability(0).time_step;
      const double instantaneous = run->probe_reading(0, diagnostics).force[0];
      REQUIRE(std::abs(instantaneous) > 0.0);
      double worst = 0.0;
      std::size_t steps = 0;
      while (static_cast<double>(steps) * dt < 0.3) {
        const auto chunk = static_cast<std::size_t>(std::ceil(0.01 / dt));
        REQUIRE(run->advance(chunk, diagnostics));
        steps += chunk;
        const double force = run->probe_reading(0, diagnostics).force[0];
        worst = std::max(worst, std::abs(force / instantaneous - relaxation(static_cast<double>(steps) * dt)));
      }
      INFO("largest |F(t) / F(0) - G(t)| over 0.3 s: " << worst);
      CHECK(worst < 1e-12);
      // The other half's series is far from this one's by then: the test tells them apart.
      const Evaluation other = Interpreter(file.systems.front()).evaluate({face < 0.01 ? 8.0 : 2.0});
      CHECK(std::abs(other.outputs[2] - slow) > 0.1);
    }
  }
}

TEST_CASE("material.bind on springs, and the parameter rows of every law", "[scene][bind]") {
  Folder folder("springs");
  folder.write("tissue.fis", kTwoOutputRules);
  const std::string yaml = "mesh: {box: {size: [0.02, 0.02, 0.02], cells: [1, 1, 1]}}\nmaterial:\n  rules: tissue.fis\n"
                           "  inputs: {F: 4}\n  bind: {youngs_modulus: stiffness}\n";
  CHECK(build_errors(folder, yaml) ==
        "material.bind: binds the parameters of a finite-element law (model: fem); a spring network takes Young's "
        "modulus alone: name its output with 'output'\n");
  // Every law names Young's modulus (the rules' own output) and every parameter its builder reads; the rows' ranges
  // hold their defaults.
  for (const ElementLawRow& law : element_law_rows()) {
    INFO(law.keyword);
    const MaterialParameterRow* youngs = material_parameter(law, "youngs_modulus");
    REQUIRE(youngs != nullptr);
    CHECK_FALSE(in_valid_range(*youngs, 0.0));
    CHECK(in_valid_range(*youngs, 1e-300));
    const MaterialParameterRow* nu = material_parameter(law, "poisson_ratio");
    REQUIRE(nu != nullptr);
    CHECK(in_valid_range(*nu, 0.45));
    CHECK_FALSE(in_valid_range(*nu, 0.5));
    CHECK(si_per_unit(*youngs, "MPa") == 1e6);
    CHECK_FALSE(si_per_unit(*youngs, "%"));
    CHECK(si_per_unit(*nu, "%") == 0.01);
    CHECK_FALSE(si_per_unit(*nu, "kPa"));
    CHECK(material_parameter(law, "shear_modulus") == nullptr);
  }
}

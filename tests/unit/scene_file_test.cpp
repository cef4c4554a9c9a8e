// Scene files: every field parsed, every error message exact and naming the field.
#include <catch2/catch.hpp>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/scene/scene_file.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

struct Parsed {
  std::optional<Scene> scene;
  std::vector<std::string> errors;  // "LINE:COL: message"
  std::vector<std::string> notes;
};

Parsed parse(const std::string& text) {
  DiagnosticList diagnostics;
  Parsed parsed;
  parsed.scene = parse_scene("/scenes/s.yaml", text, diagnostics);
  for (const Diagnostic& d : diagnostics.items()) {
    parsed.errors.push_back(std::to_string(d.range.line) + ":" + std::to_string(d.range.column) + ": " + d.message);
    for (const auto& note : d.notes) parsed.notes.push_back(note);
  }
  return parsed;
}

const std::string kMinimal = "mesh: {box: {size: [1, 1, 1]}}\nmaterial: {youngs_modulus: 10}\n";

// The single error of `text`.
std::string error_of(const std::string& text) {
  const Parsed parsed = parse(text);
  CHECK_FALSE(parsed.scene);
  REQUIRE(parsed.errors.size() == 1);
  return parsed.errors.front();
}

}  // namespace

TEST_CASE("a minimal scene gets the documented defaults", "[scene]") {
  const Parsed parsed = parse(kMinimal);
  REQUIRE(parsed.scene);
  const Scene& s = *parsed.scene;
  CHECK(s.name == "s");
  CHECK(s.mesh.kind == SceneMesh::Kind::Box);
  CHECK(s.mesh.unit == 1.0);
  CHECK(s.material.source == SceneMaterial::Source::YoungsModulus);
  CHECK(s.material.value == 10.0);
  CHECK(s.mass.source == MassSpec::Source::Density);
  CHECK(s.mass.value == 1000.0);
  CHECK(s.damping.rule == DampingSpec::Rule::DampingRatio);
  CHECK(s.damping.ratio == 0.9);
  CHECK(s.integrator == Integrator::SemiImplicitEuler);
  CHECK_FALSE(s.dt);
  CHECK(s.duration == 1.0);
  CHECK(s.backend == SceneBackend::Auto);
  CHECK(s.precision == Precision::Float);
  CHECK(s.outputs.frames == 20);
  CHECK(s.outputs.vtu == VtuFormat::Binary);
  CHECK(s.outputs.samples == 200);
  CHECK_FALSE(s.probe);
  CHECK(s.gravity == Point3{0, 0, 0});
}

TEST_CASE("every scene field is read", "[scene]") {
  const std::string text = R"yaml(name: block
mesh:
  file: meshes/liver.msh
  units: mm
material:
  rules: ../rules/liver.fis
  system: liver
  output: stiffness
  patient: "Ann (F2)"
  inputs:
    HCV: 7.5
    strain: strain
    ALD: {regions: [{box: {min: [0, 0, 0], max: [1, 2, 3]}, value: 9}], default: 4}
  strain_axis: {min: -0.2, max: 0.4, points: 13}
  thickness: 0.002
  flexion_fraction: 0.2
mass: {total: 1.5, thickness: 0.003}
damping: {ratio: 0.5, natural_frequency: 20}
springs: {structural: true, flexion: false}
law: {basafa_farahmand: {k2_over_k1: 100, xc: 0.1, gamma0: 0.5, gamma1: 2}}
fixed:
  indices: [3, 39, 64]
  box: [{min: [0, 0, 0], max: [1, 1, 0.1]}, {min: [2, 2, 2], max: [3, 3, 3]}]
  plane: {point: [0, 0, 0], normal: [0, 1, 0], tolerance: 0.01}
loads:
  gravity: [0, -9.81, 0]
  probe: {ray: {origin: [0, 0, 5], direction: [0, 0, -1]}, radius: 0.5, force: [0, 0, -2], ramp: 0.25}
integrator: rk4
dt: 0.001
duration: 3
backend: cpu
precision: double
threads: 2
outputs: {directory: out/here, frames: 7, vtu: ascii, samples: 50, csv: false, summary: yes, plot: off}
)yaml";
  const Parsed parsed = parse(text);
  INFO((parsed.errors.empty() ? "" : parsed.errors.front()));
  REQUIRE(parsed.scene);
  const Scene& s = *parsed.scene;
  CHECK(s.name == "block");
  CHECK(s.mesh.kind == SceneMesh::Kind::File);
  CHECK(s.mesh.file == "/scenes/meshes/liver.msh");
  CHECK(s.mesh.unit == 0.001);
  CHECK(s.material.source == SceneMaterial::Source::Rules);
  CHECK(s.material.file == "/rules/liver.fis");
  CHECK(s.material.system == "liver");
  CHECK(s.material.output == "stiffness");
  CHECK(s.material.patient == "Ann (F2)");
  REQUIRE(s.material.bindings.size() == 3);
  CHECK(s.material.bindings[0].input == "HCV");
  CHECK(s.material.bindings[0].kind == InputBinding::Kind::Constant);
  CHECK(s.material.bindings[0].value == 7.5);
  CHECK(s.material.bindings[1].kind == InputBinding::Kind::Strain);
  const InputBinding& ald = s.material.bindings[2];
  CHECK(ald.kind == InputBinding::Kind::PerRegion);
  CHECK(ald.has_default);
  CHECK(ald.value == 4.0);
  REQUIRE(ald.regions.size() == 1);
  CHECK(ald.regions[0].box.max == Point3{1, 2, 3});
  CHECK(ald.regions[0].value == 9.0);
  REQUIRE(s.material.strain_axis);
  CHECK(s.material.strain_axis->min == -0.2);
  CHECK(s.material.strain_axis->max == 0.4);
  CHECK(s.material.strain_axis->points == 13);
  CHECK(s.material.thickness == 0.002);
  CHECK(s.material.flexion_fraction == 0.2);
  CHECK(s.mass.source == MassSpec::Source::TotalMass);
  CHECK(s.mass.value == 1.5);
  CHECK(s.mass.thickness == 0.003);
  CHECK(s.damping.rule == DampingSpec::Rule::ThesisNaturalFrequency);
  CHECK(s.damping.ratio == 0.5);
  CHECK(s.damping.natural_frequency == 20.0);
  CHECK(s.triangle_springs.structural);
  CHECK_FALSE(s.triangle_springs.flexion);
  CHECK(s.law.law == kernels::SpringLaw::BasafaFarahmand);
  CHECK(s.law.k2_over_k1 == 100.0);
  CHECK(s.law.xc == 0.1);
  CHECK(s.law.gamma0 == 0.5);
  CHECK(s.law.gamma1 == 2.0);
  CHECK(s.fixed.indices == std::vector<std::int32_t>{3, 39, 64});
  REQUIRE(s.fixed.boxes.size() == 2);
  CHECK(s.fixed.boxes[1].min == Point3{2, 2, 2});
  REQUIRE(s.fixed.planes.size() == 1);
  CHECK(s.fixed.planes[0].normal == Point3{0, 1, 0});
  CHECK(s.fixed.planes[0].tolerance == 0.01);
  CHECK(s.gravity == Point3{0, -9.81, 0});
  REQUIRE(s.probe);
  CHECK(s.probe->by_ray);
  CHECK(s.probe->ray_origin == Point3{0, 0, 5});
  CHECK(s.probe->radius == 0.5);
  CHECK(s.probe->mode == ProbeLoad::Mode::Force);
  CHECK(s.probe->target == Point3{0, 0, -2});
  CHECK(s.probe->ramp == 0.25);
  CHECK(s.integrator == Integrator::RungeKutta4);
  CHECK(s.dt == 0.001);
  CHECK(s.duration == 3.0);
  CHECK(s.backend == SceneBackend::Cpu);
  CHECK(s.precision == Precision::Double);
  CHECK(s.threads == 2);
  CHECK(s.outputs.directory == "out/here");
  CHECK(s.outputs.frames == 7);
  CHECK(s.outputs.vtu == VtuFormat::Ascii);
  CHECK(s.outputs.samples == 50);
  CHECK_FALSE(s.outputs.csv);
  CHECK(s.outputs.summary);
  CHECK_FALSE(s.outputs.plot);
  CHECK(s.range_of("fixed.indices").line == 22);
  CHECK(s.range_of("material.inputs.ALD").line == 13);
}

TEST_CASE("the other spellings: ellipsoid, stiffness laws, damping none, probe by index", "[scene]") {
  const Parsed parsed = parse(R"yaml(mesh: {ellipsoid: {radii: [1, 2, 3], centre: [0, 1, 0], resolution: 3}, units: 0.05}
material: {stiffness_over_length: 4500}
damping: none
law: basafa_farahmand
loads: {probe: {indices: [1, 2], displacement: [0, 0, -0.001]}}
integrator: implicit_euler
dt: auto
)yaml");
  REQUIRE(parsed.scene);
  const Scene& s = *parsed.scene;
  CHECK(s.mesh.kind == SceneMesh::Kind::Ellipsoid);
  CHECK(s.mesh.ellipsoid.radii == Point3{1, 2, 3});
  CHECK(s.mesh.ellipsoid.resolution == 3);
  CHECK(s.mesh.unit == 0.05);
  CHECK(s.material.source == SceneMaterial::Source::StiffnessOverLength);
  CHECK(s.damping.rule == DampingSpec::Rule::Fixed);
  CHECK(s.damping.value == 0.0);
  CHECK(s.law.law == kernels::SpringLaw::BasafaFarahmand);
  REQUIRE(s.probe);
  CHECK(s.probe->indices == std::vector<std::int32_t>{1, 2});
  CHECK(s.probe->mode == ProbeLoad::Mode::Displacement);
  CHECK(s.integrator == Integrator::ImplicitEuler);
  CHECK_FALSE(s.dt);
  CHECK(parse("mesh: {box: {size: [1, 1, 1], cells: [2, 3, 4], min: [1, 1, 1]}}\nmaterial: {stiffness: 5}\n")
            .scene->mesh.box.cells_y == 3);
}

TEST_CASE("scene errors name the field, its position and what is allowed", "[scene]") {
  CHECK(error_of(kMinimal + "integrator: rk5\n") ==
        "3:13: integrator: 'rk5' is not an integrator; use forward_euler, semi_implicit_euler, velocity_verlet, rk4 "
        "or implicit_euler");
  CHECK(error_of(kMinimal + "dt: fast\n") == "3:5: dt: expected 'auto' or a positive time step in seconds, got 'fast'");
  CHECK(error_of(kMinimal + "dt: -1\n") == "3:5: dt: expected 'auto' or a positive time step in seconds, got '-1'");
  CHECK(error_of(kMinimal + "duration: 0\n") == "3:11: duration: expected a positive number of seconds, got 0");
  CHECK(error_of(kMinimal + "backend: gpu\n") == "3:10: backend: 'gpu' is not a backend; use auto, cpu or cuda");
  CHECK(error_of(kMinimal + "precision: half\n") == "3:12: precision: 'half' is not a precision; use float or double");
  CHECK(error_of(kMinimal + "threads: 1.5\n") == "3:10: threads: expected an integer from 0 to 256, got '1.5'");
  CHECK(error_of(kMinimal + "gravity: [0, 0, -9.81]\n") ==
        "3:1: gravity: unknown key; allowed: 'name', 'model', 'mesh', 'material', 'mass', 'damping', 'springs', "
        "'law', 'fem', 'fixed', 'hold', 'loads', 'tools', 'contact', 'integrator', 'dt', 'duration', 'backend', "
        "'precision', 'threads', 'outputs', 'on_inversion' or 'solver'");
  CHECK(error_of("material: {youngs_modulus: 10}\n") ==
        "1:1: mesh: missing; give a mesh file or a generated box or ellipsoid");
  CHECK(error_of("mesh: {box: {size: [1, 1, 1]}}\n") ==
        "1:1: material: missing; give youngs_modulus, stiffness, stiffness_over_length, rules or table");
  CHECK(error_of("mesh: {box: {size: [1, 1]}}\nmaterial: {stiffness: 1}\n") ==
        "1:20: mesh.box.size: expected three numbers [x, y, z] (mesh units), got a list of 2");
  CHECK(error_of("mesh: {box: {size: [1, 0, 1]}}\nmaterial: {stiffness: 1}\n") ==
        "1:20: mesh.box.size: every size must be positive");
  CHECK(error_of("mesh: {box: {size: [1, 1, 1], cells: [1, 0, 1]}}\nmaterial: {stiffness: 1}\n") ==
        "1:42: mesh.box.cells: expected an integer from 1 to 1000, got '0'");
  CHECK(error_of("mesh: {file: a.msh, box: {size: [1, 1, 1]}}\nmaterial: {stiffness: 1}\n") ==
        "1:26: mesh: give only one of 'file', 'box', 'ellipsoid' or 'surface'");
  CHECK(error_of("mesh: {units: m}\nmaterial: {stiffness: 1}\n") == "1:7: mesh: give one of 'file', 'box', 'ellipsoid' or 'surface'");
  CHECK(error_of("mesh: {file: a.msh, units: inch}\nmaterial: {stiffness: 1}\n") ==
        "1:28: mesh.units: 'inch' is not a unit; use m, cm, mm or a positive number of metres per mesh unit");
  CHECK(error_of("mesh: {box: {size: [1, 1, 1]}}\nmaterial: {youngs_modulus: -3}\n") ==
        "2:28: material.youngs_modulus: expected a positive number (kPa), got -3");
  CHECK(error_of("mesh: {box: {size: [1, 1, 1]}}\nmaterial: {stiffness: 1, inputs: {a: 1}}\n") ==
        "2:34: material.inputs: only allowed with 'rules' or 'table'");
  CHECK(error_of("mesh: {box: {size: [1, 1, 1]}}\nmaterial: {rules: r.fis}\n") ==
        "2:11: material.inputs: missing; bind every input of the rules to a constant, regions or strain");
  CHECK(error_of("mesh: {box: {size: [1, 1, 1]}}\nmaterial: {rules: r.fis, inputs: {a: [1]}}\n") ==
        "2:38: material.inputs.a: expected a number, 'strain' or {regions: [...], default: NUMBER}, got a list of 1");
  CHECK(error_of("mesh: {box: {size: [1, 1, 1]}}\nmaterial: {rules: r.fis, inputs: {a: strain, b: strain}}\n") ==
        "2:49: material.inputs.b: only one input can be bound to 'strain'");
  CHECK(error_of("mesh: {box: {size: [1, 1, 1]}}\nmaterial: {rules: r.fis, inputs: {a: 1}, strain_axis: {min: 0}}\n") ==
        "2:55: material.strain_axis: only allowed when an input is bound to 'strain'");
  CHECK(error_of(kMinimal + "mass: {density: 1, total: 2}\n") == "3:27: mass: give only one of 'density' or 'total'");
  CHECK(error_of(kMinimal + "damping: {ratio: -0.5}\n") ==
        "3:18: damping.ratio: expected a non-negative number, got -0.5");
  CHECK(error_of(kMinimal + "damping: lots\n") ==
        "3:10: damping: expected 'none' or a map with 'ratio' (and optionally 'natural_frequency') or 'coefficient', "
        "and/or 'rayleigh'");
  CHECK(error_of(kMinimal + "law: hooke\n") == "3:6: law: 'hooke' is not a spring law; use linear or basafa_farahmand");
  CHECK(error_of(kMinimal + "fixed: {indices: [1, -2]}\n") ==
        "3:22: fixed.indices: expected an integer from 0 to 2147483647, got '-2'");
  CHECK(error_of(kMinimal + "fixed: {box: {min: [1, 0, 0], max: [0, 1, 1]}}\n") ==
        "3:14: fixed.box: 'min' must not exceed 'max' on any axis");
  CHECK(error_of(kMinimal + "fixed: {plane: {point: [0, 0, 0], normal: [0, 0, 0]}}\n") ==
        "3:43: fixed.plane.normal: the normal must not be zero");
  CHECK(error_of(kMinimal + "loads: {probe: {indices: [1], displacement: [0, 0, 1], force: [0, 0, 1]}}\n") ==
        "3:63: loads.probe: give only one of 'displacement' or 'force'");
  CHECK(error_of(kMinimal + "loads: {probe: {displacement: [0, 0, 1]}}\n") ==
        "3:16: loads.probe: give one of 'indices' or 'ray'");
  CHECK(error_of(kMinimal + "loads: {probe: {indices: [1], radius: 1, force: [0, 0, 1]}}\n") ==
        "3:39: loads.probe.radius: only allowed with 'ray'");
  CHECK(error_of(kMinimal + "outputs: {frames: many}\n") ==
        "3:19: outputs.frames: expected an integer from 0 to 100000, got 'many'");
  CHECK(error_of(kMinimal + "outputs: {csv: maybe}\n") == "3:16: outputs.csv: expected true or false, got 'maybe'");
  CHECK(error_of(kMinimal + "outputs: {vtu: text}\n") ==
        "3:16: outputs.vtu: 'text' is not a VTU encoding; use binary or ascii");
  CHECK(error_of("mesh: [1, 2\n") == "2:1: invalid YAML: end of sequence flow not found");
  CHECK(error_of("") == "0:0: a scene file is a YAML map with 'mesh', 'material' and the other keys of docs/scenes.md");
}

TEST_CASE("solver: implicit Euler's linear solver, read and checked", "[scene][implicit]") {
  const std::string implicit = kMinimal + "integrator: implicit_euler\n";
  const Parsed defaults = parse(implicit);
  REQUIRE(defaults.scene);
  CHECK(defaults.scene->solver.method == ImplicitMethod::Automatic);
  CHECK(defaults.scene->solver.tolerance == 1e-10);
  CHECK(defaults.scene->solver.max_iterations == 0);
  CHECK(defaults.scene->solver.contact_rounds == 8);
  const Parsed given =
      parse(implicit + "solver: {method: cg, tolerance: 1e-9, max_iterations: 25, contact_rounds: 1}\n");
  REQUIRE(given.scene);
  CHECK(given.scene->solver.method == ImplicitMethod::ConjugateGradient);
  CHECK(given.scene->solver.tolerance == 1e-9);
  CHECK(given.scene->solver.max_iterations == 25);
  CHECK(given.scene->solver.contact_rounds == 1);
  CHECK(parse(implicit + "solver: {contact_rounds: 8}\n").scene->solver.contact_rounds == 8);
  for (const char* bad : {"0", "9", "-1", "2.5", "two", "[1]"})
    CHECK(error_of(implicit + "solver: {contact_rounds: " + bad + "}\n") ==
          std::string("4:26: solver.contact_rounds: expected an integer from 1 to 8, got ") +
              (bad[0] == '[' ? "a list of 1" : "'" + std::string(bad) + "'"));
  CHECK(parse(implicit + "solver: {method: direct}\n").scene->solver.method == ImplicitMethod::Direct);
  CHECK(error_of(implicit + "solver: {method: lu}\n") ==
        "4:18: solver.method: 'lu' is not a linear solver; use auto, direct or cg");
  CHECK(error_of(implicit + "solver: {tolerance: 0}\n") ==
        "4:21: solver.tolerance: expected a relative residual from 1e-16 (double precision's reach) to 0.5, got 0");
  CHECK(error_of(implicit + "solver: {tolerance: 1e-20}\n") ==
        "4:21: solver.tolerance: expected a relative residual from 1e-16 (double precision's reach) to 0.5, got "
        "1e-20");
  CHECK(error_of(implicit + "solver: {tolerance: tight}\n") ==
        "4:21: solver.tolerance: expected a relative residual from 1e-16 to 0.5, got 'tight'");
  CHECK(error_of(implicit + "solver: {max_iterations: 0}\n") ==
        "4:26: solver.max_iterations: expected an integer from 1 to 1000000, got '0'");
  CHECK(error_of(implicit + "solver: {iterations: 25}\n") ==
        "4:10: solver.iterations: unknown key in solver; allowed: 'method', 'tolerance', 'max_iterations' or "
        "'contact_rounds'");
  CHECK(error_of(implicit + "solver: cg\n") ==
        "4:9: solver: expected a map with 'method', 'tolerance', 'max_iterations' or 'contact_rounds'");
  for (const std::string key : {"max_iterations: 25", "contact_rounds: 1"})
    CHECK(error_of(kMinimal + "solver: {" + key + "}\n") ==
          "3:9: solver: only implicit_euler solves a linear system each step; this scene's integrator is "
          "semi_implicit_euler: remove 'solver' or use integrator: implicit_euler");
}

TEST_CASE("outputs.cohort: a cohort's per-patient frames and pictures only when asked", "[scene]") {
  const Parsed defaults = parse(kMinimal);
  REQUIRE(defaults.scene);
  CHECK_FALSE(defaults.scene->outputs.cohort_frames);
  CHECK_FALSE(defaults.scene->outputs.cohort_plot);
  const Parsed given = parse(kMinimal + "outputs: {cohort: {frames: true, plot: true}}\n");
  REQUIRE(given.scene);
  CHECK(given.scene->outputs.cohort_frames);
  CHECK(given.scene->outputs.cohort_plot);
  CHECK(error_of(kMinimal + "outputs: {cohort: {frames: 25}}\n") ==
        "3:28: outputs.cohort.frames: expected true or false, got '25'");
  CHECK(error_of(kMinimal + "outputs: {cohort: {csv: true}}\n") ==
        "3:20: outputs.cohort.csv: unknown key in outputs.cohort; allowed: 'frames' or 'plot'");
}

TEST_CASE("unknown keys and keywords come with a suggestion", "[scene]") {
  const Parsed parsed = parse(kMinimal + "integrater: rk4\nloads: {probe: {indices: [1], displacment: [0, 0, 1]}}\n");
  CHECK_FALSE(parsed.scene);
  REQUIRE(parsed.errors.size() == 3);
  CHECK(parsed.errors[0].rfind("3:1: integrater: unknown key; allowed:", 0) == 0);
  CHECK(parsed.errors[1] ==
        "4:31: loads.probe.displacment: unknown key in loads.probe; allowed: 'indices', 'ray', 'radius', "
        "'displacement', 'force', 'ramp' or 'cycles'");
  CHECK(parsed.errors[2] == "4:16: loads.probe: give one of 'displacement' or 'force'");
  CHECK(parsed.notes == std::vector<std::string>{"did you mean 'integrator'?", "did you mean 'displacement'?"});
  const Parsed keyword = parse(kMinimal + "integrator: implicit_eular\n");
  CHECK(keyword.notes == std::vector<std::string>{"did you mean 'implicit_euler'?"});
}

TEST_CASE("every shipped scene parses", "[scene]") {
  for (const char* name :
       {"liver_indentation", "sofa_liver_springs", "sofa_liver_fuzzy", "sofa_liver_fem", "strain_stiffening_block",
        "liver_palpation"}) {
    const std::string path = std::string(FMPC_SOURCE_DIR) + "/rulesets/scenes/" + name + ".yaml";
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    DiagnosticList diagnostics;
    INFO(name);
    CHECK(parse_scene(path, text.str(), diagnostics));
    CHECK(diagnostics.empty());
  }
}

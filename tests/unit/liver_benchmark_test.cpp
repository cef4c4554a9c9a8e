// The thesis's experiment (runtime/analysis/liver_benchmark.h): the mass point against closed forms and an
// independent integration, the step's convergence, the refusals, and the numbers of docs/liver_fibrosis.md as a
// regression test. On an organ (organ_step_response.h, `fmpc thesis-benchmark --scene`): the pipeline on a tiny
// meshed block (seconds), with golden similarities, the physics it must keep (a linear response scales as 1 / E),
// and every refusal with its location.
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

#include "compiler/frontend/rule_file_loader.h"
#include "runtime/analysis/liver_benchmark.h"
#include "runtime/analysis/organ_step_response.h"

namespace {

using fmpc::DiagnosticList;
using fmpc::sim::LiverBenchmarkOptions;
using fmpc::sim::MassPointLaw;
using fmpc::sim::simulate_mass_point;

fmpc::RuleFile load_shipped(const std::string& name) {
  std::ifstream in(std::string(FMPC_SOURCE_DIR) + "/rulesets/liver_fibrosis/" + name);
  std::stringstream text;
  text << in.rdbuf();
  DiagnosticList diagnostics;
  fmpc::RuleFile file = fmpc::load_rule_file(name, text.str(), diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(file.systems.size() == 1);
  return file;
}

// rulesets/liver_fibrosis/example_patients.csv, in the controllers' input order HCV, HBV, ALD, CLD, NAFLD.
std::vector<fmpc::sim::LiverPatient> example_patients() {
  std::ifstream in(std::string(FMPC_SOURCE_DIR) + "/rulesets/liver_fibrosis/example_patients.csv");
  std::string line;
  std::getline(in, line);
  REQUIRE(line == "HCV,HBV,ALD,CLD,NAFLD");
  std::vector<fmpc::sim::LiverPatient> patients;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    fmpc::sim::LiverPatient patient{"patient " + std::to_string(patients.size() + 1), {}};
    std::stringstream fields(line);
    std::string field;
    while (std::getline(fields, field, ',')) patient.readings.push_back(std::stod(field));
    REQUIRE(patient.readings.size() == 5);
    patients.push_back(patient);
  }
  return patients;
}

// x'' = (F - F_s(x) - (gamma0 + gamma1 |x|) x') / m by classical RK4 with step h, written apart from the simulator.
std::pair<double, double> basafa_reference(double t_end, double h, double k1, const LiverBenchmarkOptions& o) {
  const double k2 = k1 * o.benchmark.k2 / o.benchmark.k1, xc = o.benchmark.xc;
  const auto acceleration = [&](double x, double v) {
    const double ax = std::abs(x);
    const double spring = ax <= xc ? k1 * x + k2 * x * x * x
                                   : (k1 * xc + k2 * xc * xc * xc + (k1 + 3.0 * k2 * xc * xc) * (ax - xc)) *
                                         (x < 0.0 ? -1.0 : 1.0);
    return (o.force - spring - (o.benchmark.gamma0 + o.benchmark.gamma1 * ax) * v) / o.mass;
  };
  double x = 0.0, v = 0.0;
  const auto steps = static_cast<long>(std::llround(t_end / h));
  for (long i = 0; i < steps; ++i) {
    const double k1x = v, k1v = acceleration(x, v);
    const double k2x = v + h / 2 * k1v, k2v = acceleration(x + h / 2 * k1x, v + h / 2 * k1v);
    const double k3x = v + h / 2 * k2v, k3v = acceleration(x + h / 2 * k2x, v + h / 2 * k2v);
    const double k4x = v + h * k3v, k4v = acceleration(x + h * k3x, v + h * k3v);
    x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
  }
  return {x, v};
}

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

}  // namespace

TEST_CASE("thesis benchmark: the linear mass point follows the closed-form step response", "[thesis]") {
  LiverBenchmarkOptions options;
  for (const double k : {0.05, 9.8, 22.3, 500.0}) {
    DiagnosticList diagnostics;
    const auto response = simulate_mass_point(MassPointLaw::ThesisLinear, k, options, diagnostics);
    REQUIRE(response);
    const double m = options.mass, zeta = options.damping_ratio, f = options.force;
    const double w = std::sqrt(k / m), wd = w * std::sqrt(1.0 - zeta * zeta);
    double worst_x = 0.0, worst_v = 0.0;
    for (std::size_t i = 0; i < response->displacement.time.size(); ++i) {
      const double t = response->displacement.time[i];
      const double decay = std::exp(-zeta * w * t);
      const double x = f / k * (1.0 - decay * (std::cos(wd * t) + zeta / std::sqrt(1.0 - zeta * zeta) * std::sin(wd * t)));
      const double v = f / k * w / std::sqrt(1.0 - zeta * zeta) * decay * std::sin(wd * t);
      worst_x = std::max(worst_x, std::abs(response->displacement.value[i] - x));
      worst_v = std::max(worst_v, std::abs(response->velocity.value[i] - v));
    }
    INFO("k = " << k << " N/m");
    CHECK(response->displacement.time.size() == 1001);
    CHECK(response->displacement.time.back() == Approx(10.0).epsilon(1e-12));
    CHECK(worst_x <= 1e-9 * f / k);  // RK4 at 1 ms: (w h)^4 is below 1e-10 up to k = 500 N/m
    CHECK(worst_v <= 1e-9 * f / k * w);
  }
}

TEST_CASE("thesis benchmark: the Basafa-Farahmand mass point matches an independent RK4", "[thesis]") {
  LiverBenchmarkOptions options;
  for (const double k1 : {0.05, 10.0, 22.9}) {
    DiagnosticList diagnostics;
    const auto response = simulate_mass_point(MassPointLaw::BasafaFarahmand, k1, options, diagnostics);
    REQUIRE(response);
    for (const std::size_t i : {std::size_t{100}, std::size_t{500}, std::size_t{1000}}) {
      const double t = response->displacement.time[i];
      const auto [x, v] = basafa_reference(t, 1e-4, k1, options);
      INFO("K1 = " << k1 << " N, t = " << t << " s");
      CHECK(response->displacement.value[i] == Approx(x).epsilon(1e-8).margin(1e-12));
      CHECK(response->velocity.value[i] == Approx(v).epsilon(1e-6).margin(1e-10));
    }
  }
  // The benchmark's own step response creeps: gamma1 |x| is hundreds of N s/m once it has moved.
  DiagnosticList diagnostics;
  const auto reference = simulate_mass_point(MassPointLaw::BasafaFarahmand, 0.05, options, diagnostics);
  REQUIRE(reference);
  CHECK(reference->displacement.value.back() > 0.05);
  CHECK(reference->displacement.value.back() < 0.2);
}

TEST_CASE("thesis benchmark: refusals", "[thesis]") {
  const auto refused = [](LiverBenchmarkOptions options, double k, const std::string& expected) {
    DiagnosticList diagnostics;
    CHECK_FALSE(simulate_mass_point(MassPointLaw::ThesisLinear, k, options, diagnostics));
    CHECK_THAT(fmpc::render_all(diagnostics, fmpc::SourceFiles{}), Catch::Contains(expected));
  };
  LiverBenchmarkOptions options;
  refused(options, std::nan(""), "stiffness is nan");
  refused(options, 0.0, "positive and finite");
  options.mass = 0.0;
  refused(options, 1.0, "mass is 0");
  options = {};
  options.samples = 1;
  refused(options, 1.0, "samples is 1");
  options = {};
  options.time_step = 1e-9;
  options.duration = 1.0;
  refused(options, 1.0, "more than 100000000");
  options = {};
  options.time_step = 0.5;  // above RK4's limit for k = 500 N/m, m = 1.5 kg
  refused(options, 500.0, "stability limit");

  const fmpc::RuleFile mamdani = load_shipped("mamdani.fis");
  DiagnosticList diagnostics;
  CHECK_FALSE(fmpc::sim::run_liver_benchmark({{"mamdani", &mamdani.systems.front()}}, {{"short", {5.0, 5.0}}}, {}, {},
                                             diagnostics));
  CHECK_THAT(fmpc::render_all(diagnostics, fmpc::SourceFiles{}), Catch::Contains("patient 'short' has 2 readings"));

  // Too many runs x samples is refused before anything runs.
  DiagnosticList big;
  LiverBenchmarkOptions many_samples;
  many_samples.samples = 50'000;
  CHECK_FALSE(fmpc::sim::run_liver_benchmark({}, {}, std::vector<double>(100, 1e4), many_samples, big));
  CHECK_THAT(fmpc::render_all(big, fmpc::SourceFiles{}), Catch::Contains("101 runs of 50000 samples exceed the limit"));

  // A reading outside the input's range is evaluated as given, with a warning naming the patient and the input.
  DiagnosticList warned;
  const auto report = fmpc::sim::run_liver_benchmark({{"mamdani", &mamdani.systems.front()}},
                                                     {{"high", {80.0, 5.0, 5.0, 5.0, 5.0}}}, {}, {}, warned);
  REQUIRE(report);
  CHECK(warned.warning_count() == 1);
  CHECK_THAT(fmpc::render_all(warned, fmpc::SourceFiles{}),
             Catch::Contains("patient 'high': HCV = 80 is outside [0, 75]"));
}

TEST_CASE("thesis benchmark: the numbers of docs/liver_fibrosis.md", "[thesis][heavy]") {
  const fmpc::RuleFile mamdani = load_shipped("mamdani.fis"), sugeno = load_shipped("sugeno.fis"),
                       it2 = load_shipped("it2.fis");
  const std::vector<fmpc::sim::LiverController> controllers = {{"mamdani", &mamdani.systems.front()},
                                                               {"sugeno", &sugeno.systems.front()},
                                                               {"it2", &it2.systems.front()}};
  DiagnosticList diagnostics;
  const auto report = fmpc::sim::run_liver_benchmark(controllers, example_patients(), {}, {}, diagnostics);
  INFO(fmpc::render_all(diagnostics, fmpc::SourceFiles{}));
  REQUIRE(report);
  REQUIRE(report->runs.size() == 12);
  // controller, patient, stiffness (N/m), S displacement and velocity with the benchmark law, then with the thesis's
  // linear mass point. Tolerances: 1e-6 on S (the runs are deterministic; the margin is for libm differences
  // between platforms), 1e-9 relative on the stiffness.
  struct Expected {
    const char* controller;
    const char* patient;
    double stiffness, benchmark_displacement, benchmark_velocity, thesis_displacement, thesis_velocity;
  };
  const Expected expected[] = {
      {"mamdani", "patient 1", 17.96909523, 0.557428862, 0.674042561, 0.682083246, 0.686259841},
      {"mamdani", "patient 2", 19.27493832, 0.540484701, 0.664513189, 0.653506622, 0.683587429},
      {"mamdani", "patient 3", 20.82838002, 0.521542472, 0.653794416, 0.622241426, 0.678183383},
      {"mamdani", "patient 4", 21.50285678, 0.513697187, 0.649328084, 0.609523751, 0.675246000},
      {"sugeno", "patient 1", 9.79192781, 0.692280369, 0.750543208, 0.874475480, 0.627139661},
      {"sugeno", "patient 2", 9.973335536, 0.688577232, 0.748367569, 0.873682815, 0.630601964},
      {"sugeno", "patient 3", 13.25531766, 0.628006386, 0.713620764, 0.802910092, 0.673164711},
      {"sugeno", "patient 4", 17.86967089, 0.558759906, 0.674789441, 0.684349459, 0.686379060},
      {"it2", "patient 1", 17.19710832, 0.567923935, 0.679926805, 0.700024029, 0.686830697},
      {"it2", "patient 2", 17.25328383, 0.567147643, 0.679491893, 0.698691714, 0.686817654},
      {"it2", "patient 3", 17.65051297, 0.561715167, 0.676447021, 0.689390966, 0.686595418},
      {"it2", "patient 4", 17.64632931, 0.561771870, 0.676478816, 0.689487826, 0.686598915},
  };
  for (std::size_t i = 0; i < 12; ++i) {
    const auto& run = report->runs[i];
    const Expected& e = expected[i];
    INFO(run.controller << ", " << run.patient);
    CHECK(run.controller == e.controller);
    CHECK(run.patient == e.patient);
    CHECK(run.stiffness == Approx(e.stiffness).epsilon(1e-9));
    CHECK(run.benchmark_displacement.similarity == Approx(e.benchmark_displacement).margin(1e-6));
    CHECK(run.benchmark_velocity.similarity == Approx(e.benchmark_velocity).margin(1e-6));
    CHECK(run.thesis_displacement.similarity == Approx(e.thesis_displacement).margin(1e-6));
    CHECK(run.thesis_velocity.similarity == Approx(e.thesis_velocity).margin(1e-6));
  }

  // A modulus given as such runs like a controller's output: 10 kPa, as in the docs' sweep table.
  const auto constant = fmpc::sim::run_liver_benchmark({}, {}, {1e4}, {}, diagnostics);
  REQUIRE(constant);
  REQUIRE(constant->runs.size() == 1);
  CHECK(constant->runs[0].controller == "constant");
  CHECK(constant->runs[0].patient == "E = 10 kPa");
  CHECK(constant->runs[0].benchmark_displacement.similarity == Approx(0.688).margin(5e-4));
  CHECK(constant->runs[0].thesis_displacement.similarity == Approx(0.874).margin(5e-4));

  // Halving the step moves no similarity by more than 1e-7: the numbers are the model's, not the integrator's.
  LiverBenchmarkOptions halved;
  halved.time_step = 5e-4;
  const auto fine = fmpc::sim::run_liver_benchmark({controllers[0]}, example_patients(), {}, halved, diagnostics);
  REQUIRE(fine);
  for (std::size_t i = 0; i < fine->runs.size(); ++i) {
    CHECK(fine->runs[i].benchmark_displacement.similarity ==
          Approx(report->runs[i].benchmark_displacement.similarity).margin(1e-7));
    CHECK(fine->runs[i].thesis_velocity.similarity == Approx(report->runs[i].thesis_velocity.similarity).margin(1e-7));
  }
}

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
  const fmpc::RuleFile mamdani = load_shipped("mamdani.fis"), sugeno = load_shipped("sugeno.fis"),
                       it2 = load_shipped("it2.fis");
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

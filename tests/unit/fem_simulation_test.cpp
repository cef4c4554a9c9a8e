// The force models in the simulator: the co-rotational FEM and springs with the volume term, with every integrator
// on the CPU backend, the static solver, holds, inversion counting and its policies, and the resting block of issue 10.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <random>

#include "kernels/integrator_math.h"
#include "kernels/internal_force_math.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/fem/fem_model_builder.h"
#include "runtime/integrate/static_equilibrium.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/scene/spring_model_builder.h"
#include "tests/support/volume_term.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

Mesh box_mesh(Point3 size, int nx, int ny, int nz) {
  DiagnosticList diagnostics;
  BoxSpec spec;
  spec.size = size;
  spec.cells_x = nx;
  spec.cells_y = ny;
  spec.cells_z = nz;
  Mesh mesh = generate_box(spec, diagnostics);
  REQUIRE(!diagnostics.has_errors());
  return mesh;
}

SimulationSetup fem_setup(const Mesh& mesh, double E, double nu, double damping_ratio = 0.0) {
  FemModelSpec spec;
  spec.youngs_modulus = {E};
  spec.poisson_ratio = {nu};
  spec.mass.source = MassSpec::Source::Density;
  spec.mass.value = 1000.0;
  spec.damping_ratio = damping_ratio;
  DiagnosticList diagnostics;
  auto setup = build_fem_model(mesh, spec, diagnostics);
  INFO(render_all(diagnostics, {}));
  REQUIRE(setup);
  return *setup;
}

SimulationSetup spring_setup(const Mesh& mesh, double E, double damping_ratio = 0.0) {
  SpringModelSpec spec;
  spec.stiffness.mapping = StiffnessMapping::VanGelder1998;
  spec.stiffness.value = E;
  spec.mass.source = MassSpec::Source::Density;
  spec.mass.value = 1000.0;
  spec.damping.ratio = damping_ratio;
  DiagnosticList diagnostics;
  auto setup = build_spring_model(mesh, spec, diagnostics);
  REQUIRE(setup);
  setup->tetrahedra = mesh.tetrahedra;
  return *setup;
}

// Springs at the calibrated modulus plus the volume term for (E, nu) (calibrate_volume_term).
SimulationSetup volume_term_setup(const Mesh& mesh, double E, double nu, double damping_ratio = 0.0) {
  DiagnosticList diagnostics;
  const auto unit = calibrate_volume_term(1.0, nu, StiffnessMapping::VanGelder1998, SourceRange{}, diagnostics);
  REQUIRE(unit);
  SimulationSetup setup = spring_setup(mesh, unit->spring_modulus * E, damping_ratio);
  REQUIRE(add_volume_term(setup, unit->bulk_modulus * E, damping_ratio, 0.0, diagnostics));
  return setup;
}

struct Uniaxial {
  double youngs_modulus = 0.0;  // traction / mean axial strain of the top face
  double poisson_ratio = 0.0;   // -(lateral strain of the x = L face) / axial strain
  double sideways_slide = 0.0;  // mean lateral displacement of the top face / its axial displacement
};

// Uniaxial stress on a box: the z = 0, x = 0 and y = 0 faces slide on their planes (each holds its normal axis), the
// top face carries a uniform traction as consistent nodal forces (a third of each boundary triangle's area to each
// corner), the sides are free. Linear static solution.
Uniaxial stretch(SimulationSetup setup, const Mesh& mesh, const Point3& size, double traction) {
  const std::size_t n = mesh.points.size();
  setup.fixed_axes.assign(n, 0);
  setup.external_forces.assign(n, Point3{0.0, 0.0, 0.0});
  const double tolerance = 1e-9;
  for (std::size_t v = 0; v < n; ++v)
    for (int axis = 0; axis < 3; ++axis)
      if (std::abs(mesh.points[v][static_cast<std::size_t>(axis)]) < tolerance)
        setup.fixed_axes[v] = static_cast<std::uint8_t>(setup.fixed_axes[v] | (1u << axis));
  for (const Triangle& t : boundary_triangles(mesh)) {
    bool top = true;
    for (const auto v : t) top = top && std::abs(mesh.points[static_cast<std::size_t>(v)][2] - size[2]) < tolerance;
    if (!top) continue;
    const double area = triangle_area(mesh, t);
    for (const auto v : t) setup.external_forces[static_cast<std::size_t>(v)][2] += traction * area / 3.0;
  }
  StaticOptions options;
  options.linear = true;
  DiagnosticList diagnostics;
  const auto result = static_equilibrium(setup, options, diagnostics);
  INFO(render_all(diagnostics, {}));
  REQUIRE(result);
  double top_z = 0.0, far_x = 0.0, slide_x = 0.0, slide_y = 0.0;
  int top = 0, far = 0;
  for (std::size_t v = 0; v < n; ++v) {
    const Point3& p = mesh.points[v];
    if (std::abs(p[2] - size[2]) < tolerance) {
      top_z += result->positions[v][2] - p[2];
      slide_x += result->positions[v][0] - p[0];
      slide_y += result->positions[v][1] - p[1];
      ++top;
    }
    if (std::abs(p[0] - size[0]) < tolerance) {
      far_x += result->positions[v][0] - p[0];
      ++far;
    }
  }
  Uniaxial out;
  const double axial = top_z / top / size[2];
  out.youngs_modulus = traction / axial;
  out.poisson_ratio = -(far_x / far / size[0]) / axial;
  // The lateral contraction of the top face is symmetric about its centre only for an isotropic response; its mean
  // relative to the contraction expected from nu is the slide.
  const double expected_x = -out.poisson_ratio * axial * size[0] / 2.0,
               expected_y = -out.poisson_ratio * axial * size[1] / 2.0;
  out.sideways_slide = std::hypot(slide_x / top - expected_x, slide_y / top - expected_y) / (top_z / top);
  return out;
}

}  // namespace

TEST_CASE("the corner CSR: slots invert it, and the vertex gather sums each vertex's corners in element order",
          "[fem][sim]") {
  // Shuffled elements and renumbered corners (seeded) so that the CSR is not the generator's order; the gather
  // (kernels::gather_corner_force over forces the element pass wrote at corner_slot) must give the same bits as a
  // plain element-major sum in increasing element order.
  std::mt19937 random(20261124);
  Mesh mesh = box_mesh({0.03, 0.02, 0.05}, 3, 2, 5);
  std::shuffle(mesh.tetrahedra.begin(), mesh.tetrahedra.end(), random);
  for (Tetrahedron& t : mesh.tetrahedra)
    if (random() % 2 == 0) std::swap(t[0], t[1]), std::swap(t[2], t[3]);  // an even permutation keeps the sign
  const SimulationSetup setup = fem_setup(mesh, 5000.0, 0.45, 0.3);
  const ElementGeometry& field = setup.elements.geometry;
  const ElementTerm& term = setup.elements.terms.front();
  using Law = kernels::CorotationalLinear;
  const std::size_t corners = 4 * field.size();
  REQUIRE(field.corner_index.size() == corners);
  REQUIRE(field.corner_slot.size() == corners);
  for (std::size_t k = 0; k < corners; ++k)
    REQUIRE(field.corner_slot[static_cast<std::size_t>(field.corner_index[k])] == static_cast<std::int32_t>(k));
  for (std::size_t v = 0; v < mesh.points.size(); ++v)
    for (auto k = field.corner_offset[v]; k < field.corner_offset[v + 1]; ++k) {
      const auto corner = field.corner_index[static_cast<std::size_t>(k)];
      REQUIRE(mesh.tetrahedra[static_cast<std::size_t>(corner / 4)][static_cast<std::size_t>(corner % 4)] ==
              static_cast<std::int32_t>(v));
      if (k > field.corner_offset[v]) REQUIRE(corner > field.corner_index[static_cast<std::size_t>(k - 1)]);
    }

  // Positions and velocities perturbed from rest (seeded), float as on the GPU.
  std::uniform_real_distribution<double> jitter(-2e-4, 2e-4);
  std::vector<float> x[3], v[3];
  for (const Point3& p : mesh.points)
    for (int axis = 0; axis < 3; ++axis) {
      x[axis].push_back(static_cast<float>(p[static_cast<std::size_t>(axis)] + jitter(random)));
      v[axis].push_back(static_cast<float>(jitter(random) * 100.0));
    }
  std::vector<float> rest_inverse(field.rest_inverse.begin(), field.rest_inverse.end());
  std::vector<float> rest_volume(field.rest_volume.begin(), field.rest_volume.end());
  const std::vector<double>& youngs = term.parameter[Law::kYoungsModulus];
  const std::vector<double>& poisson = term.parameter[Law::kPoissonRatio];
  std::vector<float> modulus(youngs.begin(), youngs.end());
  std::vector<float> ratio(poisson.begin(), poisson.end());
  std::vector<float> damping(term.stiffness_damping.begin(), term.stiffness_damping.end());
  REQUIRE(!damping.empty());
  std::vector<int> element_corners;
  for (const Tetrahedron& t : mesh.tetrahedra) element_corners.insert(element_corners.end(), t.begin(), t.end());
  REQUIRE(term.law == kernels::element_law_index<Law>);
  kernels::ElementTermView<float> view{};
  view.law = term.law;
  view.element = field.kind;
  view.count = static_cast<int>(field.size());
  view.corners = element_corners.data();
  view.corner_slot = field.corner_slot.data();
  view.rest_inverse = rest_inverse.data();
  view.rest_volume = rest_volume.data();
  view.parameter[Law::kYoungsModulus] = modulus.data();
  view.parameter[Law::kPoissonRatio] = ratio.data();
  view.stiffness_damping = damping.data();
  const kernels::StateView<float> state{x[0].data(), x[1].data(), x[2].data(), v[0].data(), v[1].data(), v[2].data()};
  std::vector<kernels::CornerForce<float>> slotted(corners);
  for (int e = 0; e < view.count; ++e)
    kernels::element_node_forces<kernels::LinearTetrahedron, Law, false>(e, view, state, slotted.data());
  const kernels::CornerForceView<float> gather{field.corner_offset.data(), field.corner_index.data(), slotted.data()};

  std::vector<float> sum(3 * mesh.points.size(), 0.0f);
  for (int e = 0; e < view.count; ++e) {
    float xe[4][3], ve[4][3], fe[4][3];
    for (int a = 0; a < 4; ++a)
      for (int axis = 0; axis < 3; ++axis) {
        xe[a][axis] = x[axis][static_cast<std::size_t>(element_corners[static_cast<std::size_t>(4 * e + a)])];
        ve[a][axis] = v[axis][static_cast<std::size_t>(element_corners[static_cast<std::size_t>(4 * e + a)])];
      }
    kernels::LinearTetrahedron::forces<Law>(view, e, xe, ve, fe);
    for (int a = 0; a < 4; ++a)
      for (int axis = 0; axis < 3; ++axis)
        sum[3 * static_cast<std::size_t>(element_corners[static_cast<std::size_t>(4 * e + a)]) +
            static_cast<std::size_t>(axis)] += fe[a][axis];
  }
  float largest = 0.0f;
  for (std::size_t vertex = 0; vertex < mesh.points.size(); ++vertex) {
    float f[3];
    kernels::gather_corner_force(static_cast<int>(vertex), gather, f[0], f[1], f[2]);
    for (std::size_t axis = 0; axis < 3; ++axis) {
      REQUIRE(std::memcmp(&f[axis], &sum[3 * vertex + axis], sizeof(float)) == 0);
      largest = std::max(largest, std::abs(f[axis]));
    }
  }
  REQUIRE(largest > 0.0f);  // the perturbation loads the elements: a zero field would pass vacuously
}

TEST_CASE("co-rotational FEM under uniaxial stress is exact: E and nu come back to rounding", "[fem][sim]") {
  // Linear tetrahedra represent a uniform strain exactly, so the sliding block's response is the material's.
  const Point3 size{0.02, 0.03, 0.05};
  const Mesh mesh = box_mesh(size, 2, 3, 5);
  for (const double nu : {0.0, 0.3, 0.45, 0.499}) {
    const Uniaxial u = stretch(fem_setup(mesh, 5000.0, nu), mesh, size, 10.0);
    INFO("nu = " << nu << ": E_eff / E = " << u.youngs_modulus / 5000.0 << ", nu_eff = " << u.poisson_ratio);
    CHECK(u.youngs_modulus == Approx(5000.0).epsilon(1e-9));
    CHECK(u.poisson_ratio == Approx(nu).margin(1e-9));
    CHECK(u.sideways_slide < 1e-9);
  }
}

TEST_CASE("springs with the volume term: the calibrated Poisson ratio, measured", "[fem][sim][springs]") {
  // The calibration assumes an isotropic spring network (lambda = mu); the mirrored Kuhn lattice is not one, so the
  // measured ratio and modulus differ from the target. These numbers are documented in docs/simulator.md.
  const Point3 size{0.04, 0.04, 0.08};
  const Mesh mesh = box_mesh(size, 4, 4, 8);
  const Uniaxial springs_alone = stretch(spring_setup(mesh, 5000.0), mesh, size, 10.0);
  WARN("springs alone (Van Gelder): E_eff / E = " << springs_alone.youngs_modulus / 5000.0
                                                  << ", nu_eff = " << springs_alone.poisson_ratio);
  CHECK(springs_alone.poisson_ratio == Approx(0.1549).margin(2e-3));
  // Measured (Release, 2026-11-24): nu 0.3 -> 0.2215, 0.4 -> 0.3580, 0.45 -> 0.4269, 0.49 -> 0.4830; E_eff / E
  // 1.336 (alone, and at 0.25 where kappa = 0), 1.362, 1.407, 1.429, 1.447.
  const double measured[] = {0.153152, 0.221526, 0.357964, 0.426876, 0.482998};
  const double targets[] = {0.25, 0.3, 0.4, 0.45, 0.49};
  for (int i = 0; i < 5; ++i) {
    const Uniaxial u = stretch(volume_term_setup(mesh, 5000.0, targets[i]), mesh, size, 10.0);
    WARN("volume term for nu = " << targets[i] << ": E_eff / E = " << u.youngs_modulus / 5000.0
                                 << ", nu_eff = " << u.poisson_ratio);
    CHECK(u.poisson_ratio == Approx(measured[i]).margin(1e-5));
    if (targets[i] >= 0.4) CHECK(std::abs(u.poisson_ratio - targets[i]) < 0.05);
  }
  // Below 1/4 the term would need a negative modulus: refused with the field named.
  DiagnosticList diagnostics;
  SourceRange where{"scene.yaml", 4, 3, 4, 4};
  CHECK_FALSE(calibrate_volume_term(1.0, 0.2, StiffnessMapping::VanGelder1998, where, diagnostics));
  REQUIRE(diagnostics.error_count() == 1);
  CHECK_THAT(diagnostics.items()[0].message, Catch::StartsWith("material.poisson_ratio: 0.2 cannot be reached"));
}

TEST_CASE("every integrator runs every force model and converges at its order", "[fem][sim]") {
  // A block hanging from its top face under gravity, 0.02 s, double precision. Reference: RK4 at h / 16. Each
  // scheme at h and h / 2: error(h) / error(h / 2) = 2^order.
  const Point3 size{0.02, 0.02, 0.04};
  const Mesh mesh = box_mesh(size, 2, 2, 4);
  struct Model {
    const char* name;
    SimulationSetup setup;
  };
  std::vector<Model> models = {{"co-rotational FEM", fem_setup(mesh, 3000.0, 0.4, 0.1)},
                               {"springs + volume term", volume_term_setup(mesh, 3000.0, 0.4, 0.1)}};
  for (Model& model : models) {
    SimulationSetup& setup = model.setup;
    setup.precision = Precision::Double;
    setup.gravity = {0.0, 0.0, -9.81};
    setup.fixed_vertices.clear();
    for (std::size_t v = 0; v < mesh.points.size(); ++v)
      if (std::abs(mesh.points[v][2] - size[2]) < 1e-12) setup.fixed_vertices.push_back(static_cast<std::int32_t>(v));
    DiagnosticList probe;
    const auto report = check_stability(setup, probe);
    REQUIRE(report);
    const double h = 0.25 * report->critical_time_step;
    const double duration = 0.02;
    const auto run = [&](Integrator integrator, double step) {
      SimulationSetup s = setup;
      s.integrator = integrator;
      s.time_step = step;
      s.step_count = static_cast<std::size_t>(std::llround(duration / step));
      DiagnosticList diagnostics;
      const SimulationResult result = simulate(s, diagnostics);
      INFO(render_all(diagnostics, {}));
      REQUIRE(result.completed);
      CHECK(result.inversions.largest_count == 0);
      return result.positions;
    };
    const double h0 = duration / std::ceil(duration / h);
    const std::vector<Point3> reference = run(Integrator::RungeKutta4, h0 / 16);
    const auto error = [&](const std::vector<Point3>& x) {
      double worst = 0.0;
      for (std::size_t v = 0; v < x.size(); ++v) worst = std::max(worst, distance(x[v], reference[v]));
      return worst;
    };
    struct Scheme {
      Integrator integrator;
      double order;
    };
    for (const Scheme scheme : {Scheme{Integrator::SemiImplicitEuler, 1.0}, Scheme{Integrator::VelocityVerlet, 2.0},
                                Scheme{Integrator::RungeKutta4, 4.0}, Scheme{Integrator::ImplicitEuler, 1.0}}) {
      const double coarse = error(run(scheme.integrator, h0)), fine = error(run(scheme.integrator, h0 / 2));
      const double measured = std::log2(coarse / fine);
      WARN(model.name << ", " << to_string(scheme.integrator) << ": errors " << coarse << ", " << fine << " m, order "
                      << measured);
      CHECK(measured == Approx(scheme.order).margin(0.35));
    }
    // Forward Euler has no automatic step without mass damping (docs/simulator.md); with it, it converges at order 1.
    setup.mass_damping = 50.0;
    DiagnosticList euler;
    SimulationSetup with_mass_damping = setup;
    with_mass_damping.integrator = Integrator::ForwardEuler;
    const auto euler_report = check_stability(with_mass_damping, euler);
    REQUIRE(euler_report);
    CHECK(euler_report->critical_time_step > 0.0);
  }
}

TEST_CASE("the force models are bitwise independent of the thread count", "[fem][sim][heavy]") {
  const Mesh mesh = box_mesh({0.05, 0.05, 0.05}, 12, 12, 12);  // 10,368 tetrahedra: enough for 4 workers
  for (const bool fem : {true, false}) {
    SimulationSetup setup = fem ? fem_setup(mesh, 4000.0, 0.45, 0.5) : volume_term_setup(mesh, 4000.0, 0.45, 0.5);
    setup.precision = Precision::Float;
    setup.gravity = {0.0, -9.81, 0.0};
    for (std::size_t v = 0; v < mesh.points.size(); ++v)
      if (mesh.points[v][1] < 1e-12) setup.fixed_vertices.push_back(static_cast<std::int32_t>(v));
    setup.step_count = 60;
    setup.threads = 1;
    DiagnosticList d1, d4;
    const SimulationResult one = simulate(setup, d1);
    setup.threads = 4;
    const SimulationResult four = simulate(setup, d4);
    REQUIRE(one.completed);
    REQUIRE(four.completed);
    INFO((fem ? "FEM" : "springs + volume term"));
    CHECK(std::memcmp(one.positions.data(), four.positions.data(), one.positions.size() * sizeof(Point3)) == 0);
  }
}

TEST_CASE("the static solver: springs and FEM settle where the dynamics settle", "[fem][sim]") {
  const Point3 size{0.03, 0.03, 0.03};
  const Mesh mesh = box_mesh(size, 3, 3, 3);
  for (const bool fem : {true, false}) {
    SimulationSetup setup = fem ? fem_setup(mesh, 2000.0, 0.45, 0.9) : spring_setup(mesh, 2000.0, 0.9);
    setup.precision = Precision::Double;
    setup.gravity = {0.0, 0.0, -9.81};
    for (std::size_t v = 0; v < mesh.points.size(); ++v)
      if (mesh.points[v][2] < 1e-12) setup.fixed_vertices.push_back(static_cast<std::int32_t>(v));
    DiagnosticList diagnostics;
    const auto settled = static_equilibrium(setup, {}, diagnostics);
    INFO(render_all(diagnostics, {}));
    REQUIRE(settled);
    // Newton's method on the co-rotated tangent (the rotation held fixed) converges linearly: 12 steps for the
    // FEM, 29 for the springs (whose sideways stiffness is clamped under compression) at 1e-10 of the load.
    CHECK(settled->iterations <= 40);
    // The reactions carry the weight.
    double reaction = 0.0, weight = 0.0;
    for (std::size_t v = 0; v < mesh.points.size(); ++v) {
      reaction += settled->reactions[v][2];
      weight += setup.mass[v] * 9.81;
    }
    CHECK(reaction == Approx(weight).epsilon(1e-8));
    // Implicit Euler with heavy damping runs to the same state.
    setup.integrator = Integrator::ImplicitEuler;
    setup.mass_damping = 200.0;
    setup.time_step = 0.002;
    setup.step_count = 1500;
    const SimulationResult run = simulate(setup, diagnostics);
    REQUIRE(run.completed);
    double worst = 0.0, sag = 0.0;
    for (std::size_t v = 0; v < mesh.points.size(); ++v) {
      worst = std::max(worst, distance(run.positions[v], settled->positions[v]));
      sag = std::max(sag, distance(settled->positions[v], setup.rest_positions[v]));
    }
    INFO((fem ? "FEM" : "springs") << ": sag " << sag << " m, dynamic - static " << worst << " m");
    CHECK(worst < 1e-3 * sag);
  }
  // No support: an error, not a number.
  SimulationSetup loose = fem_setup(mesh, 2000.0, 0.45);
  loose.gravity = {0.0, 0.0, -9.81};
  DiagnosticList diagnostics;
  CHECK_FALSE(static_equilibrium(loose, {}, diagnostics));
  CHECK_THAT(diagnostics.items().back().message, Catch::Contains("nothing holds the body"));
}

TEST_CASE("inversions are counted, the first step is exact, and on_inversion stops the run", "[fem][sim]") {
  // One tetrahedron of springs, corner 3 thrown at 3 m/s towards the centroid of the opposite face: springs cannot
  // tell it from its mirror image, so it passes through and stays inverted (the co-rotational FEM, below, throws it
  // back; at 5 m/s it goes through the FEM as well).
  Mesh mesh;
  mesh.source = "one tetrahedron";
  mesh.points = {{0, 0, 0}, {0.01, 0, 0}, {0, 0.01, 0}, {0, 0, 0.01}};
  mesh.tetrahedra = {{0, 1, 2, 3}};
  SimulationSetup setup = spring_setup(mesh, 1000.0);
  setup.fixed_vertices = {0, 1, 2};
  const double length = std::sqrt(1.0 / 9 + 1.0 / 9 + 1.0), speed = 3.0;
  setup.initial_velocities = {
      {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {speed / 3 / length, speed / 3 / length, -speed / length}};
  setup.precision = Precision::Double;
  setup.time_step = 1e-5;
  setup.step_count = 1000;
  // The first step at which corner 3 is below the face, stepping the same run one step at a time.
  std::size_t expected = 0;
  {
    DiagnosticList diagnostics;
    auto simulation = Simulation::create(setup, diagnostics);
    REQUIRE(simulation);
    for (std::size_t step = 1; step <= setup.step_count && expected == 0; ++step) {
      simulation->advance(1, diagnostics);
      if (simulation->positions(diagnostics)[3][2] <= 0.0) expected = step;
    }
  }
  REQUIRE(expected > 1);
  REQUIRE(expected % kCheckEvery != 0);  // found by replay, not at a check
  DiagnosticList warned;
  const SimulationResult result = simulate(setup, warned);
  CHECK(result.completed);
  CHECK(result.inversions.first_step == expected);
  CHECK(result.inversions.first_element == 0);
  CHECK(result.inversions.largest_count == 1);
  REQUIRE(warned.warning_count() == 1);
  CHECK(warned.items()[0].code == "inverted-elements");
  CHECK_THAT(
      warned.items()[0].message,
      Catch::StartsWith("tetrahedron 0 (vertices 0, 1, 2, 3) turned inside out at step " + std::to_string(expected)));
  CHECK_THAT(warned.items()[0].message, Catch::Contains("give the springs a volume term"));
  setup.on_inversion = InversionPolicy::Stop;
  DiagnosticList stopped;
  const SimulationResult stop = simulate(setup, stopped);
  CHECK_FALSE(stop.completed);
  CHECK(stop.steps_taken == expected);
  REQUIRE(stopped.error_count() == 1);
  CHECK_THAT(stopped.items()[0].message, Catch::EndsWith("; the scene's on_inversion is stop"));
  // The co-rotational FEM throws the corner back before it passes through.
  SimulationSetup fem = fem_setup(mesh, 1000.0, 0.45);
  fem.fixed_vertices = {0, 1, 2};
  fem.initial_velocities = setup.initial_velocities;
  fem.precision = Precision::Double;
  fem.time_step = 1e-5;
  fem.step_count = 1000;
  DiagnosticList held;
  const SimulationResult kept = simulate(fem, held);
  CHECK(kept.completed);
  CHECK(kept.inversions.largest_count == 0);
  CHECK(kept.positions[3][2] > 0.0);
}

TEST_CASE("resting blocks: the FEM holds a soft block above its base, springs let it fold through",
          "[heavy][fem][sim]") {
  // Issue 10: a 0.1 m cube of 5 kPa tissue and a 2 cm cube of 1 kPa, base fixed, under gravity (semi-implicit Euler,
  // dt auto, damping ratio 0.9), and a 0.1 m cube of 3 kPa, which folds the springs through their base. At 6^3 cells
  // for the test suite's time; docs/simulator.md has the 20^3 runs.
  struct Block {
    double edge, modulus;
    bool springs_fold;
  };
  for (const Block block : {Block{0.1, 5000.0, false}, Block{0.02, 1000.0, false}, Block{0.1, 3000.0, true}}) {
    const Mesh mesh = box_mesh({block.edge, block.edge, block.edge}, 6, 6, 6);
    for (const bool fem : {true, false}) {
      SimulationSetup setup = fem ? fem_setup(mesh, block.modulus, 0.45, 0.9) : spring_setup(mesh, block.modulus, 0.9);
      setup.precision = Precision::Float;
      setup.gravity = {0.0, 0.0, -9.81};
      for (std::size_t v = 0; v < mesh.points.size(); ++v)
        if (mesh.points[v][2] < 1e-12) setup.fixed_vertices.push_back(static_cast<std::int32_t>(v));
      DiagnosticList diagnostics;
      const auto stability = check_stability(setup, diagnostics);
      REQUIRE(stability);
      setup.step_count = static_cast<std::size_t>(std::ceil(1.0 / stability->time_step));
      const SimulationResult result = simulate(setup, diagnostics);
      REQUIRE(result.completed);
      double lowest_top = 1e9;
      for (std::size_t v = 0; v < mesh.points.size(); ++v)
        if (mesh.points[v][2] > block.edge - 1e-12) lowest_top = std::min(lowest_top, result.positions[v][2]);
      INFO((fem ? "FEM" : "springs") << ", " << block.edge << " m at " << block.modulus << " Pa: top face at "
                                     << lowest_top << " m, " << result.inversions.largest_count << " inverted");
      if (fem) {
        CHECK(result.inversions.largest_count == 0);
        CHECK(lowest_top > 0.4 * block.edge);
      } else if (block.springs_fold) {
        CHECK(result.inversions.largest_count > 0);
        CHECK(diagnostics.warning_count() >= 1);
      }
    }
  }
}

TEST_CASE("dt auto never diverges: seeded scenes over damping, modulus, law, model, loads and integrator",
          "[heavy][sim][stability]") {
  // Issue 11: forward Euler's automatic step diverged for damping ratios above 1. Every automatic step must either
  // run bounded or be refused before the run (forward Euler without mass or nodal damping, docs/simulator.md).
  std::mt19937_64 rng(1124);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Mesh mesh = box_mesh({0.02, 0.02, 0.02}, 2, 2, 2);
  const Integrator integrators[] = {Integrator::ForwardEuler, Integrator::SemiImplicitEuler, Integrator::VelocityVerlet,
                                    Integrator::RungeKutta4, Integrator::ImplicitEuler};
  int refused = 0, completed = 0;
  double worst_growth = 0.0;
  for (int n = 0; n < 1000; ++n) {
    const double ratio = n % 10 == 0 ? 0.0 : std::pow(10.0, -2.0 + unit(rng) * std::log10(5000.0));  // 0.01 .. 50
    const double E = std::pow(10.0, 2.0 + unit(rng) * 5.0);                                          // 100 Pa .. 10 MPa
    const int model = n % 3;  // springs, springs + volume term, FEM
    SimulationSetup setup = model == 2   ? fem_setup(mesh, E, 0.45, ratio)
                            : model == 1 ? volume_term_setup(mesh, E, 0.45, ratio)
                                         : spring_setup(mesh, E, ratio);
    setup.integrator = integrators[n % 5];
    setup.precision = n % 4 == 0 ? Precision::Float : Precision::Double;
    if (model == 0 && unit(rng) < 0.5) {
      setup.law = kernels::SpringLaw::BasafaFarahmand;
      setup.nodal_damping_gamma0 = unit(rng) < 0.5 ? 0.0 : 2.0 * unit(rng) * setup.mass.front();
      setup.nodal_damping_gamma1 = unit(rng) < 0.5 ? 0.0 : 1000.0 * unit(rng) * setup.mass.front();
    }
    if (unit(rng) < 0.3) setup.mass_damping = 50.0 * unit(rng);
    for (std::size_t v = 0; v < mesh.points.size(); ++v)
      if (mesh.points[v][2] < 1e-12) setup.fixed_vertices.push_back(static_cast<std::int32_t>(v));
    const int load = static_cast<int>(unit(rng) * 3);
    const std::int32_t top = static_cast<std::int32_t>(mesh.points.size() - 5);  // the top face's centre
    if (load == 0) setup.gravity = {0.0, 0.0, -9.81};
    if (load == 1) setup.probe = ProbeLoad{ProbeLoad::Mode::Displacement, {top}, {0.0, 0.0, -0.002}, 0.05};
    if (load == 2) setup.probe = ProbeLoad{ProbeLoad::Mode::Force, {top}, {0.0, 0.0, -0.02 * E * 4e-4}, 0.05};
    // Implicit Euler is unconditionally stable; its steps (an assembly and a solve each) are the costly ones here.
    setup.step_count = setup.integrator == Integrator::ImplicitEuler ? 60 : 400;
    DiagnosticList diagnostics;
    const SimulationResult result = simulate(setup, diagnostics);
    INFO("case " << n << ": " << to_string(setup.integrator) << ", model " << model << ", ratio " << ratio << ", E "
                 << E << ", law " << static_cast<int>(setup.law) << ", gamma " << setup.nodal_damping_gamma0 << "/"
                 << setup.nodal_damping_gamma1 << ", alpha " << setup.mass_damping << ", load " << load << "\n"
                 << render_all(diagnostics, {}));
    if (!result.completed && result.steps_taken == 0 && !result.non_finite) {
      // Refused before the run: only forward Euler without mass or nodal damping, with the explanation.
      ++refused;
      REQUIRE(setup.integrator == Integrator::ForwardEuler);
      REQUIRE(setup.mass_damping == 0.0);
      REQUIRE(setup.nodal_damping_gamma0 == 0.0);
      REQUIRE_THAT(diagnostics.items().front().message, Catch::Contains("forward Euler has no stable step"));
      continue;
    }
    REQUIRE(result.completed);
    ++completed;
    double largest = 0.0;
    for (std::size_t v = 0; v < mesh.points.size(); ++v)
      largest = std::max(largest, distance(result.positions[v], setup.rest_positions[v]));
    worst_growth = std::max(worst_growth, largest);
    // Bounded: a soft block may collapse under its own weight (100 Pa and 2 cm: rho g L / E = 1.4, reported as
    // inverted elements), but nothing runs away.
    REQUIRE(largest < 0.5);
  }
  WARN("dt auto: " << completed << " runs completed, " << refused << " refused (forward Euler, undamped modes); "
                   << "largest displacement " << worst_growth << " m");
}

// The average nodal pressure tetrahedron (fem: {element: linear_nodal_pressure}; kernels/elements/
// linear_nodal_pressure.h, docs/simulator.md): the patch test (a homogeneous deformation is an equilibrium, and the
// static solver reproduces one prescribed on the boundary), its energy against the linear element's (equal for
// stable neo-Hookean in any homogeneous deformation, for every law at nu = 0, to third order in the strain for the
// co-rotational law), the explicit CPU path (no inversion growth, the same bits for any thread count), implicit
// Euler's system (the nodal term's blocks two elements apart, against the forces' derivative) and its runs settling
// at the static solver's answer. The bending case where linear tetrahedra lock is in tests/unit/validation_test.cpp.
#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "runtime/fem/element_law_registry.h"
#include "runtime/fem/fem_model_builder.h"
#include "runtime/integrate/implicit_system.h"
#include "runtime/integrate/model_tangent.h"
#include "runtime/integrate/simulation.h"
#include "runtime/integrate/static_equilibrium.h"
#include "runtime/mesh/generated_mesh.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

// A 3 x 3 x 3-cell box of 3 cm (a vertex inside, every element on or near the boundary).
Mesh nodal_test_box(int cells) {
  DiagnosticList diagnostics;
  BoxSpec box;
  box.cells_x = box.cells_y = box.cells_z = cells;
  box.size = {0.03, 0.03, 0.03};
  return generate_box(box, diagnostics);
}

SimulationSetup nodal_test_model(const Mesh& mesh, const char* law, const char* element, double nu) {
  DiagnosticList diagnostics;
  FemModelSpec spec;
  spec.law = fem_law_by_keyword(law)->law;
  spec.element = element_kind_by_keyword(element)->kind;
  spec.youngs_modulus = {5000.0};
  spec.poisson_ratio = {nu};
  spec.mass.value = 1000.0;
  auto setup = build_fem_model(mesh, spec, diagnostics);
  INFO(render_all(diagnostics, {}));
  REQUIRE(setup);
  setup->precision = Precision::Double;
  return *setup;
}

// x = A X + b at every vertex.
std::vector<Point3> affine(const std::vector<Point3>& rest, const double A[9]) {
  std::vector<Point3> out(rest.size());
  for (std::size_t v = 0; v < rest.size(); ++v)
    for (std::size_t i = 0; i < 3; ++i)
      out[v][i] = A[3 * i] * rest[v][0] + A[3 * i + 1] * rest[v][1] + A[3 * i + 2] * rest[v][2] + 0.001 * static_cast<double>(i);
  return out;
}

bool on_boundary(const Point3& p) {
  for (std::size_t i = 0; i < 3; ++i)
    if (std::abs(p[i]) < 1e-12 || std::abs(p[i] - 0.03) < 1e-12) return true;
  return false;
}

std::vector<std::int32_t> all_vertices(std::size_t n) {
  std::vector<std::int32_t> out(n);
  for (std::size_t v = 0; v < n; ++v) out[v] = static_cast<std::int32_t>(v);
  return out;
}

// The largest difference between K (3 n square) and -df/dx at rest by central differences of internal_forces.
double largest_difference_from_force_derivative(const SimulationSetup& setup, const Eigen::MatrixXd& K) {
  const std::vector<Point3>& rest = setup.rest_positions;
  const std::size_t n = rest.size();
  const std::vector<Point3> zero(n, Point3{0.0, 0.0, 0.0});
  const double h = 1e-8;
  double worst = 0.0;
  for (std::size_t column = 0; column < 3 * n; ++column) {
    std::vector<Point3> plus = rest, minus = rest;
    plus[column / 3][column % 3] += h;
    minus[column / 3][column % 3] -= h;
    const std::vector<Point3> fp = internal_forces(setup, plus, zero, {}, all_vertices(n));
    const std::vector<Point3> fm = internal_forces(setup, minus, zero, {}, all_vertices(n));
    for (std::size_t row = 0; row < 3 * n; ++row) {
      const double derivative = -(fp[row / 3][row % 3] - fm[row / 3][row % 3]) / (2 * h);
      worst = std::max(worst, std::abs(derivative - K(static_cast<Eigen::Index>(row), static_cast<Eigen::Index>(column))));
    }
  }
  return worst;
}

// Implicit Euler's assembled matrix at h = 1 without damping, less the masses: the stiffness K it holds (dense, 3 n
// square), and its right-hand side at velocities v with a = 0 (-h^2 K v).
Eigen::MatrixXd implicit_stiffness(const SimulationSetup& setup, const std::vector<Point3>& positions,
                                   const std::vector<double>& v, std::vector<double>& rhs) {
  const std::size_t n = positions.size();
  ImplicitSystem system(setup, std::vector<unsigned char>(n, 0));
  WorkerPool pool(2, 1);  // grain 1: the parallel paths even on this small box
  std::vector<double> x(3 * n), a(3 * n, 0.0);
  for (std::size_t vertex = 0; vertex < n; ++vertex)
    for (std::size_t i = 0; i < 3; ++i) x[3 * vertex + i] = positions[vertex][i];
  system.assemble(x, v, a, {}, 1.0, pool, rhs);
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(3 * n), static_cast<Eigen::Index>(3 * n));
  for (std::size_t row = 0; row < n; ++row)
    for (std::size_t k = system.row_offset(row); k < system.row_offset(row + 1); ++k)
      for (std::size_t r = 0; r < 3; ++r)
        for (std::size_t c = 0; c < 3; ++c)
          K(static_cast<Eigen::Index>(3 * row + r), static_cast<Eigen::Index>(3 * static_cast<std::size_t>(system.column(k)) + c)) =
              system.value(k)[3 * r + c] - (static_cast<std::size_t>(system.column(k)) == row && r == c ? setup.mass[row] : 0.0);
  return K;
}

}  // namespace

TEST_CASE("nodal pressure tetrahedra pass the patch test", "[fem][nodal]") {
  const Mesh mesh = nodal_test_box(3);
  // A finite homogeneous deformation (10 % stretch, shear, 6 % volume change): every element has the same F, every
  // node the same theta = J - 1, so the interior nodes' forces cancel as the linear element's do.
  const double A[9] = {1.10, 0.05, -0.02, 0.01, 0.97, 0.04, -0.03, 0.02, 0.99};
  for (const char* law : {"corotational", "stable_neo_hookean"})
    for (const double nu : {0.3, 0.49, 0.4999}) {
      INFO(law << " at nu " << nu);
      const SimulationSetup setup = nodal_test_model(mesh, law, "linear_nodal_pressure", nu);
      const std::vector<Point3> x = affine(setup.rest_positions, A);
      const std::vector<Point3> zero(x.size(), Point3{0.0, 0.0, 0.0});
      const std::vector<Point3> f = internal_forces(setup, x, zero, {}, all_vertices(x.size()));
      double largest = 0.0, interior = 0.0;
      for (std::size_t v = 0; v < x.size(); ++v)
        for (std::size_t i = 0; i < 3; ++i) {
          largest = std::max(largest, std::abs(f[v][i]));
          if (!on_boundary(setup.rest_positions[v])) interior = std::max(interior, std::abs(f[v][i]));
        }
      REQUIRE(largest > 0.0);
      CHECK(interior < 1e-12 * largest);
    }
  // The static solver with the boundary moved affinely (small strain) puts every interior vertex at the affine
  // position.
  const double G[9] = {1.001, 0.0004, -0.0002, 0.0001, 0.9993, 0.0003, -0.0003, 0.0002, 1.0008};
  for (const double nu : {0.3, 0.4999}) {
    INFO("static patch test at nu " << nu);
    SimulationSetup setup = nodal_test_model(mesh, "corotational", "linear_nodal_pressure", nu);
    const std::vector<Point3> target = affine(setup.rest_positions, G);
    setup.initial_positions = setup.rest_positions;
    setup.fixed_axes.assign(setup.rest_positions.size(), 0);
    for (std::size_t v = 0; v < target.size(); ++v)
      if (on_boundary(setup.rest_positions[v])) {
        setup.fixed_axes[v] = 7;
        setup.initial_positions[v] = target[v];
      }
    DiagnosticList diagnostics;
    StaticOptions options;
    options.linear = true;
    const auto result = static_equilibrium(setup, options, diagnostics);
    INFO(render_all(diagnostics, {}));
    REQUIRE(result);
    double error = 0.0;
    for (std::size_t v = 0; v < target.size(); ++v)
      for (std::size_t i = 0; i < 3; ++i) error = std::max(error, std::abs(result->positions[v][i] - target[v][i]));
    CHECK(error < 1e-12);
  }
}

TEST_CASE("nodal pressure tetrahedra: energy and forces against the linear element's", "[fem][nodal]") {
  const Mesh mesh = nodal_test_box(2);
  const double A[9] = {1.20, 0.05, -0.02, 0.01, 0.90, 0.04, -0.03, 0.02, 1.05};
  // Stable neo-Hookean splits exactly (its lambda' (alpha - 1) = mu for every lambda): in a homogeneous deformation
  // the element's energy is the linear element's at any strain.
  for (const double nu : {0.3, 0.499}) {  // linear tetrahedra take up to 0.499
    const SimulationSetup nodal = nodal_test_model(mesh, "stable_neo_hookean", "linear_nodal_pressure", nu);
    const SimulationSetup linear = nodal_test_model(mesh, "stable_neo_hookean", "linear", nu);
    const std::vector<Point3> x = affine(nodal.rest_positions, A);
    CHECK(elastic_energy(nodal, x) == Approx(elastic_energy(linear, x)).epsilon(1e-12));
  }
  // The co-rotational law's volumetric energy is lambda/2 tr(eps)^2 on the linear element, lambda/2 (J - 1)^2 here:
  // equal to second order, so at strain s the energies differ by O(s) relative.
  for (const double strain : {1e-3, 1e-4}) {
    const double B[9] = {1 + strain, 0.5 * strain, 0, 0, 1 - 0.3 * strain, 0.2 * strain, 0, 0, 1 + 0.7 * strain};
    const SimulationSetup nodal = nodal_test_model(mesh, "corotational", "linear_nodal_pressure", 0.45);
    const SimulationSetup linear = nodal_test_model(mesh, "corotational", "linear", 0.45);
    const std::vector<Point3> x = affine(nodal.rest_positions, B);
    const double relative = elastic_energy(nodal, x) / elastic_energy(linear, x) - 1;
    INFO("strain " << strain << ": relative difference " << relative);
    CHECK(std::abs(relative) < 3 * strain);
  }
  // At nu = 0 lambda = 0: no volumetric part, the element is the linear one for any deformation, bit for bit.
  std::mt19937_64 rng(26);
  std::uniform_real_distribution<double> jitter(-0.002, 0.002);
  for (const char* law : {"corotational", "stable_neo_hookean"}) {
    INFO(law);
    const SimulationSetup nodal = nodal_test_model(mesh, law, "linear_nodal_pressure", 0.0);
    const SimulationSetup linear = nodal_test_model(mesh, law, "linear", 0.0);
    std::vector<Point3> x = nodal.rest_positions;
    for (Point3& p : x)
      for (double& c : p) c += jitter(rng);
    const std::vector<Point3> zero(x.size(), Point3{0.0, 0.0, 0.0});
    CHECK(elastic_energy(nodal, x) == elastic_energy(linear, x));
    CHECK(internal_forces(nodal, x, zero, {}, all_vertices(x.size())) ==
          internal_forces(linear, x, zero, {}, all_vertices(x.size())));
  }
}

TEST_CASE("nodal pressure tetrahedra on the CPU engine: a block resting on its base keeps every element positive, "
          "the same bits for any thread count",
          "[fem][nodal][heavy]") {
  // A 2 cm cube of 4^3 cells (E = 1 kPa, nu = 0.4999, stable neo-Hookean) dropped under gravity onto its fixed
  // base, semi-implicit Euler at the automatic step for 0.1 s, float, lightly damped.
  BoxSpec box;
  box.cells_x = box.cells_y = box.cells_z = 4;
  box.size = {0.02, 0.02, 0.02};
  DiagnosticList diagnostics;
  const Mesh mesh = generate_box(box, diagnostics);
  FemModelSpec spec;
  spec.law = fem_law_by_keyword("stable_neo_hookean")->law;
  spec.element = element_kind_by_keyword("linear_nodal_pressure")->kind;
  spec.youngs_modulus = {1000.0};
  spec.poisson_ratio = {0.4999};
  spec.mass.value = 1000.0;
  spec.damping_ratio = 0.1;
  auto setup = build_fem_model(mesh, spec, diagnostics);
  REQUIRE(setup);
  setup->gravity = {0.0, 0.0, -9.81};
  setup->fixed_axes.assign(setup->rest_positions.size(), 0);
  for (std::size_t v = 0; v < setup->rest_positions.size(); ++v)
    if (std::abs(setup->rest_positions[v][2]) < 1e-12) setup->fixed_axes[v] = 7;
  setup->precision = Precision::Float;
  std::vector<std::vector<Point3>> finals;
  for (const unsigned threads : {1u, 2u}) {
    setup->threads = threads;
    auto simulation = Simulation::create(*setup, diagnostics);
    INFO(render_all(diagnostics, {}));
    REQUIRE(simulation);
    const double dt = simulation->stability().time_step;
    const auto steps = static_cast<std::size_t>(std::ceil(0.1 / dt));
    REQUIRE(simulation->advance(steps, diagnostics, 32));
    CHECK(simulation->inversions().largest_count == 0);
    finals.push_back(simulation->positions(diagnostics));
    double sag = 0.0;
    for (std::size_t v = 0; v < finals.back().size(); ++v)
      sag = std::min(sag, finals.back()[v][2] - setup->rest_positions[v][2]);
    INFO("sag " << sag << " m after " << steps << " steps");
    CHECK(sag < -1e-5);  // it moved
    CHECK(sag > -0.01);  // and did not collapse
  }
  CHECK(finals[0] == finals[1]);
}

TEST_CASE("nodal pressure tetrahedra: implicit Euler's block system holds the nodal term two elements apart, "
          "symmetric, the forces' derivative at rest and the static solver's tangent away from it",
          "[fem][nodal][implicit]") {
  const Mesh mesh = nodal_test_box(2);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> jitter(-0.001, 0.001), speed(-0.1, 0.1);
  for (const char* law : {"corotational", "stable_neo_hookean"}) {
    INFO(law);
    const SimulationSetup setup = nodal_test_model(mesh, law, "linear_nodal_pressure", 0.49);
    const std::vector<Point3>& rest = setup.rest_positions;
    const std::size_t n = rest.size();
    std::vector<double> rhs, still(3 * n, 0.0);
    const Eigen::MatrixXd K = implicit_stiffness(setup, rest, still, rhs);
    const double largest = K.cwiseAbs().maxCoeff();
    REQUIRE(largest > 0.0);
    CHECK((K - K.transpose()).cwiseAbs().maxCoeff() < 1e-12 * largest);
    // Vertices sharing no element are coupled where one node's patch holds both (the linear element's pattern has
    // no such block).
    std::vector<std::vector<char>> share(n, std::vector<char>(n, 0));
    for (const Tetrahedron& t : mesh.tetrahedra)
      for (const auto a : t)
        for (const auto b : t) share[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)] = 1;
    std::size_t two_apart = 0;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < n; ++j)
        if (!share[i][j] && K.block<3, 3>(static_cast<Eigen::Index>(3 * i), static_cast<Eigen::Index>(3 * j))
                                    .cwiseAbs()
                                    .maxCoeff() > 1e-9 * largest)
          ++two_apart;
    INFO(two_apart << " blocks couple vertices two elements apart");
    CHECK(two_apart > 0);
    // At rest: central differences of internal_forces.
    CHECK(largest_difference_from_force_derivative(setup, K) < 1e-5 * largest);
    // Deformed and moving: the static solver's tangent (model_tangent, B^T D B from a sparse product) and the
    // right-hand side's -h^2 K v.
    std::vector<Point3> x = rest;
    for (Point3& p : x)
      for (double& c : p) c += jitter(rng);
    std::vector<double> v(3 * n);
    for (double& c : v) c = speed(rng);
    const Eigen::MatrixXd deformed = implicit_stiffness(setup, x, v, rhs);
    const Eigen::MatrixXd expected = Eigen::MatrixXd(model_tangent(setup, x, {}).stiffness);
    CHECK((deformed - expected).cwiseAbs().maxCoeff() < 1e-12 * largest);
    const Eigen::VectorXd Kv = expected * Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(3 * n));
    double rhs_error = 0.0;
    for (std::size_t d = 0; d < 3 * n; ++d)
      rhs_error = std::max(rhs_error, std::abs(rhs[d] + Kv[static_cast<Eigen::Index>(d)]));
    CHECK(rhs_error < 1e-12 * Kv.cwiseAbs().maxCoeff());
  }
}

TEST_CASE("nodal pressure tetrahedra under implicit Euler settle at the static solver's equilibrium, with the direct "
          "solver and the CG alike",
          "[fem][nodal][implicit]") {
  // A 3 cm box of 3^3 cells hanging from its top face under gravity (E = 5 kPa, nu = 0.49, Rayleigh mass damping
  // 50 /s), implicit Euler at 10 ms for 1 s: at rest it is where the forces balance, which the static solver finds
  // with its own Newton iteration on the same tangent. (At nu 0.4999 block-Jacobi CG stops at its cap, twice the
  // unknowns, on a few steps, warned; the direct solver is the one for such a system.)
  const Mesh mesh = nodal_test_box(3);
  SimulationSetup setup = nodal_test_model(mesh, "stable_neo_hookean", "linear_nodal_pressure", 0.49);
  setup.gravity = {0.0, 0.0, -9.81};
  setup.mass_damping = 50.0;
  setup.fixed_axes.assign(setup.rest_positions.size(), 0);
  for (std::size_t v = 0; v < setup.rest_positions.size(); ++v)
    if (std::abs(setup.rest_positions[v][2] - 0.03) < 1e-12) setup.fixed_axes[v] = 7;
  DiagnosticList diagnostics;
  const auto equilibrium = static_equilibrium(setup, StaticOptions{}, diagnostics);
  INFO(render_all(diagnostics, {}));
  REQUIRE(equilibrium);
  double sag = 0.0;
  for (std::size_t v = 0; v < setup.rest_positions.size(); ++v)
    sag = std::max(sag, setup.rest_positions[v][2] - equilibrium->positions[v][2]);
  REQUIRE(sag > 1e-4);
  setup.integrator = Integrator::ImplicitEuler;
  setup.time_step = 0.01;
  for (const ImplicitMethod method : {ImplicitMethod::Direct, ImplicitMethod::ConjugateGradient}) {
    INFO(to_string(method));
    setup.implicit.method = method;
    auto simulation = Simulation::create(setup, diagnostics);
    INFO(render_all(diagnostics, {}));
    REQUIRE(simulation);
    REQUIRE(simulation->advance(100, diagnostics));
    CHECK(simulation->implicit_solver().method == method);
    CHECK(simulation->implicit_solver().capped_steps == 0);
    const std::vector<Point3> x = simulation->positions(diagnostics);
    double difference = 0.0;
    for (std::size_t v = 0; v < x.size(); ++v) difference = std::max(difference, distance(x[v], equilibrium->positions[v]));
    INFO("largest sag " << sag << " m, implicit Euler after 1 s against the static solution: " << difference
                         << " m, at most " << simulation->implicit_solver().iterations_max << " iterations a step");
    CHECK(difference < 1e-8 * sag);
  }
}

TEST_CASE("nodal pressure tetrahedra: the static solver's tangent is the forces' derivative at rest", "[fem][nodal]") {
  // model_tangent's element blocks plus the nodal pass's B^T D B, against central differences of internal_forces on
  // a 2 x 2 x 2-cell box (every vertex's patch differs).
  const Mesh mesh = nodal_test_box(2);
  for (const char* law : {"corotational", "stable_neo_hookean"}) {
    INFO(law);
    const SimulationSetup setup = nodal_test_model(mesh, law, "linear_nodal_pressure", 0.45);
    const Eigen::MatrixXd K = Eigen::MatrixXd(model_tangent(setup, setup.rest_positions, {}).stiffness);
    CHECK(largest_difference_from_force_derivative(setup, K) < 1e-5 * K.cwiseAbs().maxCoeff());
  }
}

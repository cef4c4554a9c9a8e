// Implicit Euler on the CPU (runtime/integrate/implicit_system.h, implicit_solver.h): the block-sparse system against
// the model's tangent assembled by Eigen (model_tangent.h), the direct and the conjugate-gradient solvers against each
// other, warm and cold starts, the same bits for any thread count, and the per-step records with the cap's warning.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <random>

#include "kernels/implicit_math.h"
#include "kernels/integrator_math.h"
#include "runtime/fem/element_terms.h"
#include "runtime/fem/fem_model_builder.h"
#include "runtime/integrate/implicit_system.h"
#include "runtime/integrate/model_tangent.h"
#include "runtime/integrate/stepping_engine.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/scene/spring_model_builder.h"
#include "tests/support/volume_term.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

Mesh implicit_box(int nx, int ny, int nz, double edge) {
  DiagnosticList diagnostics;
  BoxSpec spec;
  spec.size = {edge * nx, edge * ny, edge * nz};
  spec.cells_x = nx;
  spec.cells_y = ny;
  spec.cells_z = nz;
  Mesh mesh = generate_box(spec, diagnostics);
  REQUIRE(!diagnostics.has_errors());
  return mesh;
}

// The co-rotational FEM (E, nu 0.45) with Rayleigh damping, or springs with dashpots and the volume term; the base
// z = 0 fixed, the x = 0 face held along x (a partial hold), gravity, implicit Euler in double.
SimulationSetup implicit_setup(const Mesh& mesh, bool fem, double E, double dt) {
  DiagnosticList diagnostics;
  std::optional<SimulationSetup> setup;
  if (fem) {
    FemModelSpec spec;
    spec.youngs_modulus = {E};
    spec.poisson_ratio = {0.45};
    spec.mass.source = MassSpec::Source::Density;
    spec.mass.value = 1000.0;
    spec.damping_ratio = 0.3;
    spec.rayleigh_stiffness = 0.002;
    setup = build_fem_model(mesh, spec, diagnostics);
  } else {
    SpringModelSpec spec;
    spec.stiffness.mapping = StiffnessMapping::VanGelder1998;
    spec.stiffness.value = E;
    spec.mass.source = MassSpec::Source::Density;
    spec.mass.value = 1000.0;
    spec.damping.ratio = 0.4;
    setup = build_spring_model(mesh, spec, diagnostics);
    REQUIRE(setup);
    setup->tetrahedra = mesh.tetrahedra;
    REQUIRE(add_volume_term(*setup, 2.0 * E, 0.2, 0.0, diagnostics));
  }
  INFO(render_all(diagnostics, {}));
  REQUIRE(setup);
  setup->fixed_axes.assign(mesh.points.size(), 0);
  for (std::size_t v = 0; v < mesh.points.size(); ++v) {
    if (mesh.points[v][2] < 1e-12) setup->fixed_vertices.push_back(static_cast<std::int32_t>(v));
    else if (mesh.points[v][0] < 1e-12) setup->fixed_axes[v] = 1;  // slides on the plane x = 0
  }
  setup->gravity = {0.0, 0.0, -9.81};
  setup->mass_damping = 0.5;
  setup->nodal_damping_gamma0 = 0.01;
  setup->integrator = Integrator::ImplicitEuler;
  setup->precision = Precision::Double;
  setup->time_step = dt;
  setup->refuse_unstable_time_step = false;
  return *setup;
}

std::vector<double> interleaved(const std::vector<Point3>& points) {
  std::vector<double> out;
  for (const Point3& p : points) out.insert(out.end(), p.begin(), p.end());
  return out;
}

bool same_bits(const std::vector<Point3>& a, const std::vector<Point3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Point3)) == 0;
}

double largest_difference(const std::vector<Point3>& a, const std::vector<Point3>& b) {
  double most = 0.0;
  for (std::size_t v = 0; v < a.size(); ++v) most = std::max(most, distance(a[v], b[v]));
  return most;
}

struct ImplicitRun {
  std::vector<Point3> positions, velocities;
  ImplicitSolverReport report;
  std::vector<ImplicitStepRecord> records;
  DiagnosticList diagnostics;
};

ImplicitRun run_implicit(const SimulationSetup& setup, std::size_t steps) {
  ImplicitRun run;
  auto simulation = Simulation::create(setup, run.diagnostics);
  REQUIRE(simulation);
  REQUIRE(simulation->advance(steps, run.diagnostics));
  run.positions = simulation->positions(run.diagnostics);
  run.velocities = simulation->velocities(run.diagnostics);
  run.report = simulation->implicit_solver();
  run.records = simulation->take_implicit_steps();
  return run;
}

}  // namespace

TEST_CASE("implicit Euler's block-sparse system equals the model's tangent assembled by Eigen", "[sim][implicit]") {
  const Mesh mesh = implicit_box(3, 2, 2, 0.01);
  for (const bool fem : {true, false}) {
    INFO((fem ? "co-rotational FEM" : "springs with dashpots and the volume term"));
    const SimulationSetup setup = implicit_setup(mesh, fem, 5000.0, 0.004);
    // A deformed, moving state: every vertex moved and pushed at random (seeded).
    std::mt19937 random(27);
    std::uniform_real_distribution<double> jitter(-1e-3, 1e-3), speed(-0.05, 0.05);
    std::vector<Point3> positions = setup.rest_positions, velocities(positions.size());
    for (std::size_t v = 0; v < positions.size(); ++v)
      for (std::size_t axis = 0; axis < 3; ++axis) {
        positions[v][axis] += jitter(random);
        velocities[v][axis] = speed(random);
      }
    std::vector<double> stiffness = setup.springs.stiffness, acceleration(3 * positions.size());
    for (double& a : acceleration) a = speed(random);
    const std::vector<unsigned char> held = held_axes(setup);
    for (std::size_t d = 0; d < acceleration.size(); ++d)
      if (kernels::axis_fixed(held[d / 3], static_cast<int>(d % 3))) acceleration[d] = 0.0;
    const double h = 0.004;
    ImplicitSystem system(setup, held);
    WorkerPool pool(1);
    std::vector<double> rhs;
    system.assemble(interleaved(positions), interleaved(velocities), acceleration, stiffness, h, pool, rhs);
    if (fem) CHECK(system.colours() > 1);

    // The reference: M' + h D + h^2 K from model_tangent, held rows and columns replaced by the identity.
    const ModelTangent tangent = model_tangent(setup, positions, stiffness);
    const auto n = static_cast<Eigen::Index>(3 * positions.size());
    Eigen::MatrixXd reference = Eigen::MatrixXd(h * h * tangent.stiffness + h * tangent.damping);
    const Eigen::VectorXd v0 = Eigen::Map<const Eigen::VectorXd>(interleaved(velocities).data(), n);
    Eigen::VectorXd reference_rhs = -h * h * (Eigen::MatrixXd(tangent.stiffness) * v0);
    for (std::size_t i = 0; i < positions.size(); ++i) {
      const double diagonal = kernels::implicit_vertex_diagonal(
          setup.mass[i], h, setup.nodal_damping_gamma0, setup.nodal_damping_gamma1,
          distance(positions[i], setup.rest_positions[i]), setup.mass_damping);
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const auto d = static_cast<Eigen::Index>(3 * i + axis);
        reference(d, d) += diagonal;
        reference_rhs[d] += h * setup.mass[i] * acceleration[static_cast<std::size_t>(d)];
      }
    }
    for (Eigen::Index d = 0; d < n; ++d) {
      if (!system.dof_held(static_cast<std::size_t>(d))) continue;
      reference.row(d).setZero();
      reference.col(d).setZero();
      reference(d, d) = 1.0;
      reference_rhs[d] = 0.0;
    }
    Eigen::MatrixXd assembled = Eigen::MatrixXd::Zero(n, n);
    for (std::size_t i = 0; i < system.vertices(); ++i)
      for (std::size_t k = system.row_offset(i); k < system.row_offset(i + 1); ++k)
        for (std::size_t r = 0; r < 3; ++r)
          for (std::size_t c = 0; c < 3; ++c)
            assembled(static_cast<Eigen::Index>(3 * i + r), static_cast<Eigen::Index>(3 * system.column(k) + c)) =
                system.value(k)[3 * r + c];
    const double scale = reference.cwiseAbs().maxCoeff();
    CHECK((assembled - reference).cwiseAbs().maxCoeff() <= 1e-13 * scale);
    const Eigen::VectorXd assembled_rhs = Eigen::Map<const Eigen::VectorXd>(rhs.data(), n);
    CHECK((assembled_rhs - reference_rhs).cwiseAbs().maxCoeff() <= 1e-13 * reference_rhs.cwiseAbs().maxCoeff());
    // The product the CG uses is the matrix's.
    const std::vector<double> p = interleaved(velocities);
    std::vector<double> y(p.size());
    system.multiply(p.data(), y.data(), pool);
    const Eigen::VectorXd expected = assembled * Eigen::Map<const Eigen::VectorXd>(p.data(), n);
    CHECK((Eigen::Map<const Eigen::VectorXd>(y.data(), n) - expected).cwiseAbs().maxCoeff() <=
          1e-13 * expected.cwiseAbs().maxCoeff());
  }
}

TEST_CASE("implicit Euler's direct and CG solvers agree to their tolerance; warm and cold starts too", "[sim][implicit]") {
  const Mesh mesh = implicit_box(3, 3, 3, 0.01);
  for (const bool fem : {true, false}) {
    INFO((fem ? "co-rotational FEM" : "springs with the volume term"));
    SimulationSetup setup = implicit_setup(mesh, fem, 3000.0, 0.01);
    setup.implicit.tolerance = 1e-12;
    setup.implicit.method = ImplicitMethod::Direct;
    const ImplicitRun direct = run_implicit(setup, 30);
    setup.implicit.method = ImplicitMethod::ConjugateGradient;
    const ImplicitRun warm = run_implicit(setup, 30);
    setup.implicit.warm_start = false;
    const ImplicitRun cold = run_implicit(setup, 30);
    CHECK(direct.report.method == ImplicitMethod::Direct);
    CHECK(warm.report.method == ImplicitMethod::ConjugateGradient);
    CHECK(direct.report.iterations_max == 1);  // one solve reaches 1e-12: no refinement
    CHECK(direct.report.residual_max < 1e-12);
    CHECK(warm.report.residual_max < 1e-12);
    CHECK(direct.report.capped_steps == 0);
    CHECK(warm.report.capped_steps == 0);
    CHECK(direct.report.steps == 30);
    CHECK(warm.records.size() == 30);
    double largest = 0.0;
    for (const Point3& p : direct.positions) largest = std::max(largest, distance(p, {0.0, 0.0, 0.0}));
    CHECK(largest_difference(direct.positions, warm.positions) < 1e-10 * largest);
    CHECK(largest_difference(warm.positions, cold.positions) < 1e-10 * largest);
    // The warm start saves iterations over the run.
    CHECK(warm.report.iterations_total < cold.report.iterations_total);
    // The state moved: the comparison is not of two resting blocks.
    CHECK(largest_difference(direct.positions, setup.rest_positions) > 1e-5);
  }
}

TEST_CASE("Automatic takes the cheaper solver by its cost estimate and trial, whatever the system's size",
          "[sim][implicit]") {
  // Soft tissue at 1 ms on 6 x 6 x 4 cells (588 free unknowns): the CG reaches 1e-10 in a dozen iterations, far
  // cheaper than a factorisation, though the system is small (the old rule by size factorised it).
  SimulationSetup soft = implicit_setup(implicit_box(6, 6, 4, 0.01), true, 3000.0, 0.001);
  CHECK(run_implicit(soft, 1).report.method == ImplicitMethod::ConjugateGradient);
  // The same tissue 10,000 times stiffer at 20 ms on 9 x 9 x 5 cells (1,450 free unknowns), stiff against its masses
  // as SOFA's liver is: the CG would need more iterations than a factorisation costs (the old rule: the CG, by size).
  SimulationSetup stiff = implicit_setup(implicit_box(3, 3, 40, 0.01), true, 3e6, 0.02);
  const ImplicitRun direct = run_implicit(stiff, 1);
  CHECK(direct.report.method == ImplicitMethod::Direct);
  // Each choice is what the run would have cost less with: measured by the iterations the CG takes there.
  stiff.implicit.method = ImplicitMethod::ConjugateGradient;
  CHECK(run_implicit(stiff, 1).report.iterations_max > 100);
}

TEST_CASE("the CPU implicit step gives the same bits for 1, 2 and 3 threads", "[sim][implicit][heavy]") {
  // 10 x 10 x 8 cells: 1,089 vertices in 18 chunks of the system, 4,800 tetrahedra in 75 runs over several colours.
  const Mesh mesh = implicit_box(10, 10, 8, 0.005);
  for (const bool fem : {true, false}) {
    INFO((fem ? "co-rotational FEM" : "springs with the volume term"));
    SimulationSetup setup = implicit_setup(mesh, fem, 4000.0, 0.002);
    setup.implicit.method = ImplicitMethod::ConjugateGradient;
    setup.implicit.tolerance = 1e-8;
    setup.threads = 1;
    const ImplicitRun one = run_implicit(setup, 6);
    for (const unsigned threads : {2u, 3u}) {
      setup.threads = threads;
      const ImplicitRun more = run_implicit(setup, 6);
      INFO(threads << " threads");
      CHECK(same_bits(one.positions, more.positions));
      CHECK(same_bits(one.velocities, more.velocities));
      CHECK(more.report.iterations_total == one.report.iterations_total);
      CHECK(more.report.residual_max == one.report.residual_max);
    }
    CHECK(one.report.iterations_min > 1);
  }
}

TEST_CASE("a pool whose waits spin assembles and multiplies the system to a sleeping pool's bits", "[sim][implicit]") {
  // Spinning is automatic only in pools of 4 threads or more with a core each (never on a 2-core CI machine), so the
  // test asks for it: many short runs back to back, as the CG's, each needing every write of the run before it.
  CHECK_FALSE(WorkerPool(2).spins());
  CHECK_FALSE(WorkerPool(8, 0, PoolWait::Sleep).spins());
  WorkerPool sleeping(1), spinning(3, 1, PoolWait::Spin);
  REQUIRE(spinning.spins());
  const SimulationSetup setup = implicit_setup(implicit_box(10, 10, 8, 0.005), true, 4000.0, 0.002);
  const std::vector<unsigned char> held = held_axes(setup);
  ImplicitSystem one(setup, held), other(setup, held);
  std::vector<double> x = interleaved(setup.rest_positions), v(x.size(), 0.0), a(x.size(), 0.0), rhs_one, rhs_other;
  std::mt19937 random(27);
  std::uniform_real_distribution<double> jitter(-1e-4, 1e-4);
  for (int round = 0; round < 20; ++round) {
    for (std::size_t d = 0; d < x.size(); ++d) {
      x[d] += jitter(random);
      v[d] = 100.0 * jitter(random);
      a[d] = kernels::axis_fixed(held[d / 3], static_cast<int>(d % 3)) ? 0.0 : 1e4 * jitter(random);
    }
    one.assemble(x, v, a, setup.springs.stiffness, 0.002, sleeping, rhs_one);
    other.assemble(x, v, a, setup.springs.stiffness, 0.002, spinning, rhs_other);
    std::vector<double> y_one(x.size()), y_other(x.size());
    one.multiply(v.data(), y_one.data(), sleeping);
    other.multiply(v.data(), y_other.data(), spinning);
    INFO("round " << round);
    REQUIRE(std::memcmp(one.value(0), other.value(0), 9 * one.blocks() * sizeof(double)) == 0);
    REQUIRE(std::memcmp(rhs_one.data(), rhs_other.data(), x.size() * sizeof(double)) == 0);
    REQUIRE(std::memcmp(y_one.data(), y_other.data(), x.size() * sizeof(double)) == 0);
  }
}

TEST_CASE("the system from the force pass's linearisations has the bits of one that linearises itself",
          "[sim][implicit]") {
  // cpu_engine.cpp's implicit step keeps each element's linearisation from its force pass
  // (kernels::element_node_forces_linearised; law_unit_test checks those bits) and the assembly reads it.
  const SimulationSetup setup = implicit_setup(implicit_box(6, 5, 4, 0.005), true, 4000.0, 0.002);
  const std::vector<unsigned char> held = held_axes(setup);
  WorkerPool pool(2);
  ImplicitSystem own(setup, held), kept(setup, held);
  std::vector<double> x = interleaved(setup.rest_positions), v(x.size(), 0.0), a(x.size(), 0.0), rhs_own, rhs_kept;
  std::mt19937 random(28);
  std::uniform_real_distribution<double> jitter(-1e-3, 1e-3);
  for (std::size_t d = 0; d < x.size(); ++d) {
    x[d] += jitter(random);
    v[d] = 100.0 * jitter(random);
    a[d] = kernels::axis_fixed(held[d / 3], static_cast<int>(d % 3)) ? 0.0 : 1e4 * jitter(random);
  }
  ElementLinearisations linearisations;
  const ElementGeometry& geometry = setup.elements.geometry;
  REQUIRE(!setup.elements.terms.empty());
  for (std::size_t term = 0; term < setup.elements.terms.size(); ++term) {
    const kernels::ElementTermView<double> view = element_term_view(setup.elements, term, nullptr);
    kernels::visit_element_term(view.element, view.law, [&](auto kind, auto element_law) {
      using Kind = decltype(kind);
      using Law = decltype(element_law);
      if constexpr (kernels::HasForcesAndLinearisation<Kind, Law>::value) {
        using Lin = typename Kind::template Linearisation<Law>;
        constexpr int N = Kind::kNodes;
        linearisations.hold<Lin>(term, geometry.size());
        for (std::size_t e = 0; e < geometry.size(); ++e) {
          double nodes[N][3], forces[N][3];
          for (int c = 0; c < N; ++c)
            for (int i = 0; i < 3; ++i) nodes[c][i] = x[3 * static_cast<std::size_t>(geometry.nodes[N * e + c]) + i];
          Lin lin{};
          Kind::template forces_and_linearisation<Law>(view, static_cast<int>(e), nodes, nullptr, lin, forces);
          linearisations.store(term, e, lin);
        }
        CHECK(linearisations.holds<Lin>(term));
      } else {
        FAIL("the co-rotational FEM's kind and law give their linearisation with the forces");
      }
    });
  }
  own.assemble(x, v, a, setup.springs.stiffness, 0.002, pool, rhs_own);
  kept.assemble(x, v, a, setup.springs.stiffness, 0.002, pool, rhs_kept, &linearisations);
  CHECK(std::memcmp(own.value(0), kept.value(0), 9 * own.blocks() * sizeof(double)) == 0);
  CHECK(std::memcmp(rhs_own.data(), rhs_kept.data(), x.size() * sizeof(double)) == 0);
  // Released, the values are not read: a system assembled elsewhere linearises itself again.
  linearisations.release();
  for (std::size_t d = 0; d < x.size(); ++d) x[d] += jitter(random);
  own.assemble(x, v, a, setup.springs.stiffness, 0.002, pool, rhs_own);
  kept.assemble(x, v, a, setup.springs.stiffness, 0.002, pool, rhs_kept, &linearisations);
  CHECK(std::memcmp(own.value(0), kept.value(0), 9 * own.blocks() * sizeof(double)) == 0);
}

TEST_CASE("implicit steps at the cap are recorded, counted and warned about once", "[sim][implicit]") {
  SimulationSetup setup = implicit_setup(implicit_box(3, 3, 3, 0.01), true, 3000.0, 0.05);
  setup.implicit.method = ImplicitMethod::ConjugateGradient;
  setup.implicit.max_iterations = 2;
  setup.implicit.tolerance = 1e-10;
  DiagnosticList diagnostics;
  auto simulation = Simulation::create(setup, diagnostics);
  REQUIRE(simulation);
  REQUIRE(simulation->advance(5, diagnostics));
  const std::vector<ImplicitStepRecord> first = simulation->take_implicit_steps();
  REQUIRE(simulation->advance(7, diagnostics));
  const std::vector<ImplicitStepRecord> second = simulation->take_implicit_steps();
  CHECK(simulation->take_implicit_steps().empty());
  REQUIRE(first.size() == 5);
  REQUIRE(second.size() == 7);
  CHECK(first.front().step == 1);
  CHECK(second.front().step == 6);
  CHECK(second.back().step == 12);
  for (const auto* records : {&first, &second})
    for (const ImplicitStepRecord& record : *records) {
      CHECK(record.iterations == 2);
      CHECK(record.capped);
      CHECK(record.relative_residual > 1e-10);
    }
  const ImplicitSolverReport report = simulation->implicit_solver();
  CHECK(report.steps == 12);
  CHECK(report.capped_steps == 12);
  CHECK(report.first_capped_step == 1);
  CHECK(report.first_capped_residual == first.front().relative_residual);
  CHECK(report.iterations_total == 24);
  CHECK(report.max_iterations == 2);
  // One warning for the run, at the first step that stopped.
  std::size_t warnings = 0;
  for (const Diagnostic& diagnostic : diagnostics.items()) {
    if (diagnostic.code != "cg-not-converged") continue;
    ++warnings;
    CHECK_THAT(diagnostic.message, Catch::StartsWith("implicit Euler: conjugate gradient stopped at step 1 after 2 "
                                                     "iterations with relative residual "));
  }
  CHECK(warnings == 1);
}

TEST_CASE("the implicit solver log: a checkpoint's restore forgets the steps after it, the warning stays given",
          "[sim][implicit]") {
  ImplicitSolverLog log(ImplicitMethod::ConjugateGradient, 1e-8, 10);
  const auto step = [](std::size_t n, bool capped) { return ImplicitStepRecord{n, capped ? 10 : 3, capped ? 0.1 : 1e-9, capped}; };
  CHECK(!log.record(step(1, false)));
  CHECK(!log.record(step(2, false)));
  CHECK(log.take().size() == 2);
  log.save(2);
  CHECK(log.record(step(3, true)));  // the first capped step: the engine warns
  CHECK(!log.record(step(4, false)));
  CHECK(log.report().steps == 4);
  log.restore();
  CHECK(log.report().steps == 2);
  CHECK(log.report().capped_steps == 0);
  CHECK(log.take().empty());
  CHECK(!log.record(step(3, true)));  // replayed: counted again, not warned again
  CHECK(!log.record(step(4, false)));
  const ImplicitSolverReport report = log.report();
  CHECK(report.steps == 4);
  CHECK(report.capped_steps == 1);
  CHECK(report.first_capped_step == 3);
  CHECK(report.iterations_min == 3);
  CHECK(report.iterations_max == 10);
  CHECK(report.iterations_total == 19);
  CHECK(report.residual_max == 0.1);
  CHECK(report.residual_max_step == 3);
  const std::vector<ImplicitStepRecord> replayed = log.take();
  REQUIRE(replayed.size() == 2);
  CHECK(replayed[0].step == 3);
  CHECK(replayed[1].step == 4);
}

TEST_CASE("a system at rest takes no iterations and still moves with its velocity", "[sim][implicit]") {
  // Two free masses and no force model: the right-hand side is exactly zero, dv = 0, and x moves by h v.
  SimulationSetup setup;
  setup.rest_positions = {{0.0, 0.0, 0.0}, {0.25, 0.0, 0.0}};
  setup.mass = {1.0, 2.0};
  setup.springs.vertex_count = 2;
  setup.springs.adjacency_offset = {0, 0, 0};
  setup.initial_velocities = {{0.5, 0.0, 0.0}, {0.0, -0.25, 0.0}};
  setup.integrator = Integrator::ImplicitEuler;
  setup.precision = Precision::Double;
  setup.time_step = 0.125;
  for (const ImplicitMethod method : {ImplicitMethod::Direct, ImplicitMethod::ConjugateGradient}) {
    setup.implicit.method = method;
    const ImplicitRun run = run_implicit(setup, 4);
    CHECK(run.report.steps == 4);
    CHECK(run.report.iterations_max == 0);
    CHECK(run.report.residual_max == 0.0);
    CHECK(run.positions[0][0] == 0.25);
    CHECK(run.positions[1][1] == -0.125);
    CHECK(run.velocities[0][0] == 0.5);
  }
}

TEST_CASE("the direct solver is refused on CUDA with a clear error", "[sim][implicit]") {
  SimulationSetup setup = implicit_setup(implicit_box(2, 2, 2, 0.01), true, 3000.0, 0.01);
  setup.implicit.method = ImplicitMethod::Direct;
  SimulationOptions options;
  options.backend = Backend::Cuda;
  DiagnosticList diagnostics;
  CHECK(!Simulation::create(setup, diagnostics, options));
  REQUIRE(diagnostics.error_count() == 1);
#if defined(FMPC_RUNTIME_HAVE_CUDA)
  CHECK(diagnostics.items().front().message ==
        "implicit Euler's direct solver runs on the CPU only; use the CPU backend, or the conjugate gradient (method "
        "cg or auto) on CUDA");
#else
  CHECK(diagnostics.items().front().message ==
        "this fmpc was built without CUDA; run the scene with backend cpu or auto");
#endif
}

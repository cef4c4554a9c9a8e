// Implicit Euler's conjugate gradient on the device (issue 27 item 3): the stopping test runs on the device, the
// scene's tolerance and cap are honoured and reported per step as the CPU reports them, the iterations equal those
// of a host reference of the same algorithm (Jacobi-preconditioned CG from x = 0, Eigen's stopping rule) on the
// CPU's assembly of the same system, runs repeat bitwise, and the cooperative launch (one per solve) gives the bits
// of the per-iteration launches, whatever the chunks between the host's reads.
#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "kernels/integrator_math.h"
#include "runtime/fem/fem_model_builder.h"
#include "runtime/gpu/gpu_simulation.h"
#include "runtime/integrate/implicit_system.h"
#include "runtime/integrate/worker_pool.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/scene/spring_model_builder.h"
#include "tests/gpu/cpu_gpu_comparison.h"
#include "tests/gpu/gpu_test_harness.h"

using namespace fmpc;
using namespace fmpc::sim;
using namespace fmpc::gpu_test;

namespace {

// A 0.1 m box of 5 kPa tissue (1060 kg/m^3) of nx x ny x nz cells, springs or co-rotational FEM, hanging at rest
// from its top face under gravity, dt 4 ms: the first step's system is the one at rest, which the host reference
// assembles with the accelerations g (no internal or damping force at rest).
SimulationSetup resting_box(bool fem, int nx, int ny, int nz) {
  DiagnosticList diagnostics;
  BoxSpec box;
  box.cells_x = nx;
  box.cells_y = ny;
  box.cells_z = nz;
  box.size = {0.1, 0.1, 0.1};
  const Mesh mesh = generate_box(box, diagnostics);
  SimulationSetup out;
  if (fem) {
    FemModelSpec spec;
    spec.youngs_modulus = {5000.0};
    spec.poisson_ratio = {0.45};
    spec.mass.value = 1060.0;
    spec.damping_ratio = 0.9;
    if (auto setup = build_fem_model(mesh, spec, diagnostics)) out = *setup;
  } else {
    SpringModelSpec spec;
    spec.stiffness.mapping = StiffnessMapping::VanGelder1998;
    spec.stiffness.value = 5000.0;
    spec.mass.value = 1060.0;
    spec.damping.ratio = 0.9;
    if (auto setup = build_spring_model(mesh, spec, diagnostics)) out = *setup;
  }
  if (diagnostics.has_errors()) note("setup: " + describe(diagnostics));
  for (std::size_t v = 0; v < out.rest_positions.size(); ++v)
    if (out.rest_positions[v][1] > 0.0999) out.fixed_vertices.push_back(static_cast<std::int32_t>(v));
  out.gravity = {0.0, -9.81, 0.0};
  out.precision = Precision::Double;
  out.integrator = Integrator::ImplicitEuler;
  out.time_step = 0.004;
  out.implicit.method = ImplicitMethod::ConjugateGradient;
  return out;
}

struct ReferenceSolve {
  int iterations = 0;
  double relative_residual = 0.0;
  bool capped = false;
};

// The device's algorithm on the host, in plain loops: the first step's system of `setup` (at rest) from the CPU's
// assembly, x = 0, Jacobi preconditioner (A's diagonal), stop when |r|^2 < max(tol^2 |b|^2, DBL_MIN) or at `limit`
// matrix products, each counted.
ReferenceSolve reference_first_step(const SimulationSetup& setup, double tolerance, int limit) {
  const std::vector<unsigned char> held = held_axes(setup);
  const std::size_t n = setup.rest_positions.size(), dofs = 3 * n;
  std::vector<double> x(dofs), v(dofs, 0.0), a(dofs, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t axis = 0; axis < 3; ++axis) {
      x[3 * i + axis] = setup.rest_positions[i][axis];
      if (!kernels::axis_fixed(held[i], static_cast<int>(axis))) a[3 * i + axis] = setup.gravity[axis];
    }
  ImplicitSystem system(setup, held);
  WorkerPool pool(1);
  std::vector<double> b;
  system.assemble(x, v, a, setup.springs.stiffness, *setup.time_step, pool, b);
  std::vector<double> inverse(dofs), r = b, z(dofs), p(dofs), ap(dofs), dv(dofs, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t c = 0; c < 3; ++c) {
      const double d = system.value(system.diagonal_block(i))[3 * c + c];
      inverse[3 * i + c] = d != 0.0 ? 1.0 / d : 1.0;
    }
  const auto dot = [&](const std::vector<double>& f, const std::vector<double>& g) {
    double sum = 0.0;
    for (std::size_t k = 0; k < dofs; ++k) sum += f[k] * g[k];
    return sum;
  };
  for (std::size_t k = 0; k < dofs; ++k) p[k] = z[k] = inverse[k] * r[k];
  const double rhs_norm2 = dot(b, b);
  const double threshold = std::max(tolerance * tolerance * rhs_norm2, DBL_MIN);
  double rz = dot(r, z), residual = rhs_norm2;
  ReferenceSolve out;
  while (residual >= threshold && out.iterations < limit) {
    system.multiply(p.data(), ap.data(), pool);
    const double alpha = rz / dot(p, ap);
    for (std::size_t k = 0; k < dofs; ++k) {
      dv[k] += alpha * p[k];
      r[k] -= alpha * ap[k];
      z[k] = inverse[k] * r[k];
    }
    residual = dot(r, r);
    ++out.iterations;
    if (residual < threshold) break;
    const double rz_next = dot(r, z);
    for (std::size_t k = 0; k < dofs; ++k) p[k] = z[k] + rz_next / rz * p[k];
    rz = rz_next;
  }
  out.relative_residual = std::sqrt(residual / rhs_norm2);
  out.capped = !(residual < threshold);
  return out;
}

struct DeviceRun {
  std::vector<Point3> positions, velocities;
  std::vector<ImplicitStepRecord> records;
  ImplicitSolverReport report;
  DiagnosticList diagnostics;
};

// The run's state and records; none (a failure recorded) where the simulation cannot be created or advanced.
DeviceRun run_on_device(const SimulationSetup& setup, std::size_t steps, std::size_t check_every,
                        const gpu::GpuOptions& options) {
  DeviceRun run;
  const auto simulation = gpu_simulation(setup, run.diagnostics, options);
  if (!simulation || !simulation->advance(steps, run.diagnostics, check_every)) {
    record_failure(__FILE__, __LINE__, "implicit run failed: " + describe(run.diagnostics));
    return run;
  }
  run.positions = simulation->positions(run.diagnostics);
  run.velocities = simulation->velocities(run.diagnostics);
  run.records = simulation->take_implicit_steps();
  run.report = simulation->implicit_solver();
  return run;
}

std::size_t warnings_with_code(const DiagnosticList& diagnostics, const std::string& code) {
  std::size_t count = 0;
  for (const Diagnostic& d : diagnostics.items()) count += d.code == code ? 1 : 0;
  return count;
}

}  // namespace

// Odd sizes (never a multiple of a block), springs and FEM: the first step's iterations equal the host reference's,
// and its residual agrees to rounding (other summation order); tolerance and cap as the scene sets them.
FMPC_GPU_TEST(implicit_cg_matches_host_reference, "implicit Euler: device CG iterations equal a host reference", true) {
  for (const bool fem : {false, true}) {
    for (const auto& [nx, ny, nz] : {std::array<int, 3>{3, 5, 2}, std::array<int, 3>{7, 6, 5}}) {
      for (const auto& [tolerance, limit] :
           {std::pair<double, int>{1e-10, 0}, std::pair<double, int>{1e-4, 0}, std::pair<double, int>{1e-12, 3}}) {
        SimulationSetup setup = resting_box(fem, nx, ny, nz);
        setup.implicit.tolerance = tolerance;
        setup.implicit.max_iterations = limit;
        const ReferenceSolve reference = reference_first_step(setup, tolerance, implicit_iteration_limit(setup));
        for (const CgLaunch& launch : cg_launches()) {
          const DeviceRun run = run_on_device(setup, 1, 1, launch.options);
          FMPC_REQUIRE(run.records.size() == 1);
          const ImplicitStepRecord& step = run.records.front();
          std::ostringstream line;
          line << (fem ? "FEM " : "springs ") << nx << "x" << ny << "x" << nz << ", tol " << tolerance << ", cap "
               << implicit_iteration_limit(setup) << ", " << launch.name << ": device " << step.iterations
               << " iterations, residual " << step.relative_residual << (step.capped ? " (capped)" : "")
               << "; host reference " << reference.iterations << ", " << reference.relative_residual;
          note(line.str());
          FMPC_EXPECT(step.step == 1);
          FMPC_EXPECT(step.iterations == reference.iterations);
          FMPC_EXPECT(step.capped == reference.capped);
          FMPC_EXPECT(std::abs(step.relative_residual - reference.relative_residual) <=
                      1e-2 * reference.relative_residual + 1e-15);
          if (limit == 3) {
            FMPC_EXPECT(step.iterations == 3 && step.capped);
            FMPC_EXPECT(run.report.capped_steps == 1 && run.report.first_capped_step == 1);
            FMPC_EXPECT(warnings_with_code(run.diagnostics, "cg-not-converged") == 1);
          } else {
            FMPC_EXPECT(step.relative_residual < tolerance && !step.capped);
            FMPC_EXPECT(run.report.capped_steps == 0);
            FMPC_EXPECT(warnings_with_code(run.diagnostics, "cg-not-converged") == 0);
          }
          FMPC_EXPECT(run.report.max_iterations == implicit_iteration_limit(setup));
        }
      }
    }
  }
}

// Every step's record over a moving run: a looser tolerance takes fewer iterations and stays below it, a cap stops
// every step there and says so, and the report sums the records.
FMPC_GPU_TEST(implicit_cg_tolerance_and_cap, "implicit Euler: the scene's tolerance and cap on every step", true) {
  SimulationSetup setup = resting_box(true, 5, 3, 4);
  std::vector<int> most;
  for (const double tolerance : {1e-10, 1e-5}) {
    setup.implicit.tolerance = tolerance;
    setup.implicit.max_iterations = 0;
    const DeviceRun run = run_on_device(setup, 40, 10, {});
    FMPC_REQUIRE(run.records.size() == 40);
    int largest = 0;
    for (const ImplicitStepRecord& step : run.records) {
      FMPC_EXPECT(step.relative_residual < tolerance && !step.capped && step.iterations > 0);
      largest = std::max(largest, step.iterations);
    }
    most.push_back(largest);
    FMPC_EXPECT(run.report.iterations_max == largest && run.report.capped_steps == 0);
  }
  note("FEM 5x3x4: at most " + std::to_string(most[0]) + " iterations at 1e-10, " + std::to_string(most[1]) +
       " at 1e-5");
  FMPC_EXPECT(most[1] < most[0]);
  setup.implicit.tolerance = 1e-10;
  setup.implicit.max_iterations = 2;
  const DeviceRun capped = run_on_device(setup, 25, 25, {});
  FMPC_REQUIRE(capped.records.size() == 25);
  for (const ImplicitStepRecord& step : capped.records) FMPC_EXPECT(step.iterations == 2 && step.capped);
  FMPC_EXPECT(capped.report.capped_steps == 25 && capped.report.first_capped_step == 1);
  FMPC_EXPECT(capped.report.residual_max > 1e-10);
  FMPC_EXPECT(warnings_with_code(capped.diagnostics, "cg-not-converged") >= 1);
}

// The one-block solve, the cooperative launch and the per-iteration launches (with their chunks between reads) give
// the same bits, in the state and in every step's record; each reruns bitwise; float and double, springs and FEM,
// with checks that replay nothing and with a check every 7 steps; on 7x6x5 cells (1,008 degrees of freedom: the
// block's threads take two each) and 10x6x5 (1,386: three; its FEM solve is too large for one block's shared memory
// and runs on the grid, its springs in one block).
FMPC_GPU_TEST(implicit_cg_persistent_equals_per_iteration,
              "implicit Euler: one block or one cooperative launch per solve gives the per-iteration launches' bits",
              true) {
  for (const bool fem : {false, true}) {
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      for (const auto& [nx, ny, nz] : {std::array<int, 3>{7, 6, 5}, std::array<int, 3>{10, 6, 5}}) {
        SimulationSetup setup = resting_box(fem, nx, ny, nz);
        setup.precision = precision;
        setup.implicit.tolerance = 1e-8;
        const std::string what = std::string(fem ? "FEM " : "springs ") + std::to_string(nx) + "x" +
                                 std::to_string(ny) + "x" + std::to_string(nz) + ", " + name_of(precision);
        const std::array<CgLaunch, 4> launches = cg_launches();
        const DeviceRun block = run_on_device(setup, 60, 60, launches[0].options);
        const DeviceRun again = run_on_device(setup, 60, 7, launches[0].options);
        FMPC_REQUIRE(block.records.size() == 60);
        FMPC_EXPECT(bitwise_equal(block.positions, again.positions));
        FMPC_EXPECT(bitwise_equal(block.velocities, again.velocities));
        FMPC_EXPECT(same_records(block.records, again.records));
        for (std::size_t k = 1; k < launches.size(); ++k) {
          const DeviceRun other = run_on_device(setup, 60, 60, launches[k].options);
          const bool same = bitwise_equal(block.positions, other.positions) &&
                            bitwise_equal(block.velocities, other.velocities) &&
                            same_records(block.records, other.records);
          note("implicit Euler, " + what + ": one block and " + launches[k].name + " launches " +
               (same ? "bitwise equal" : "DIFFER") + ", at most " + std::to_string(block.report.iterations_max) +
               " iterations per step");
          FMPC_EXPECT(same);
        }
      }
    }
  }
}

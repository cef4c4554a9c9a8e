#include <catch2/catch.hpp>

#if defined(FMPC_RUNTIME_HAVE_CUDA)

#include <cmath>

#include "runtime/gpu/gpu_simulation.h"
#include "runtime/mesh/generated_mesh.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

SimulationSetup hanging_box(Precision precision) {
  DiagnosticList diagnostics;
  BoxSpec spec;
  spec.cells_x = spec.cells_y = spec.cells_z = 4;
  spec.size = {0.1, 0.1, 0.1};
  const Mesh box = generate_box(spec, diagnostics);
  SimulationSetup setup;
  setup.rest_positions = box.points;
  setup.springs = springs_from_tetrahedra(box, diagnostics);
  compute_rest_lengths(setup.springs, box.points, diagnostics);
  StiffnessSpec stiffness;
  stiffness.value = 5000.0;
  assign_stiffness(setup.springs, stiffness, diagnostics);
  MassSpec mass;
  mass.value = 1060.0;
  setup.mass = lumped_masses(box, mass, diagnostics);
  assign_damping(setup.springs, setup.mass, DampingSpec{}, diagnostics);
  for (std::size_t v = 0; v < box.points.size(); ++v) {
    if (box.points[v][1] > 0.0999) setup.fixed_vertices.push_back(static_cast<std::int32_t>(v));
  }
  setup.gravity = {0.0, -9.81, 0.0};
  setup.precision = precision;
  return setup;
}

}  // namespace

TEST_CASE("GPU: a batch of implicit Euler scenes is refused before touching the device", "[sim][gpu]") {
  SimulationSetup setup = hanging_box(Precision::Double);
  setup.integrator = Integrator::ImplicitEuler;
  DiagnosticList diagnostics;
  SimulationOptions cuda;
  cuda.backend = Backend::Cuda;
  CHECK_FALSE(Simulation::create({setup, setup}, cuda, diagnostics));
  CHECK_THAT(diagnostics.items()[0].message, Catch::StartsWith("scene 0: implicit Euler runs one scene at a time"));
}

TEST_CASE("GPU: the fused kernel matches the CPU loop to rounding (float and double)", "[sim][gpu]") {
  std::string device;
  if (!gpu::cuda_device_available(device)) {
    WARN("skipped: " << device);
    return;
  }
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    SimulationSetup setup = hanging_box(precision);
    DiagnosticList diagnostics;
    const auto cpu = Simulation::create(setup, diagnostics);
    SimulationOptions cuda;
    cuda.backend = Backend::Cuda;
    const auto gpu_run = Simulation::create(setup, diagnostics, cuda);
    REQUIRE(cpu);
    REQUIRE(gpu_run);
    REQUIRE(cpu->advance(200, diagnostics));
    REQUIRE(gpu_run->advance(200, diagnostics));
    const auto a = cpu->positions(diagnostics);
    const auto b = gpu_run->positions(diagnostics);
    REQUIRE(a.size() == b.size());
    const double tolerance = precision == Precision::Float ? 1e-6 : 1e-14;
    for (std::size_t v = 0; v < a.size(); ++v) {
      for (std::size_t axis = 0; axis < 3; ++axis) CHECK(b[v][axis] == Approx(a[v][axis]).margin(tolerance));
    }
    CHECK_FALSE(diagnostics.has_errors());
  }
}

#endif

// The force models on the CUDA backend against the CPU loop (the host reference): every fem law of the registry on
// every element kind (kModels), springs with the volume term, Rayleigh mass damping, per-axis holds, inversion
// counting with its exact first step (replay) and on_inversion: stop, quadratic elements' inversion at their
// quadrature points, on odd mesh sizes (never a multiple of the block size), alone and in a batch.
//
// Stated tolerances as for springs (tests/gpu/cpu_gpu_comparison.h): explicit integrators 1e-5 m in float and
// 1e-12 m in double (expected 0: the element pass is the same FMPC_HD code in the same order, --fmad=false);
// implicit Euler to the CG tolerance (1e-5 m float, 1e-9 m double), GPU runs bitwise run to run.
#include <cmath>
#include <cstdint>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "kernels/element_laws.h"
#include "runtime/fem/fem_model_builder.h"
#include "runtime/fem/element_law_registry.h"
#include "tests/support/volume_term.h"
#include "runtime/gpu/gpu_simulation.h"
#include "runtime/integrate/stepping_engine.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/scene/spring_model_builder.h"
#include "tests/gpu/cpu_gpu_comparison.h"
#include "tests/gpu/gpu_test_harness.h"

using namespace fmpc;
using namespace fmpc::sim;
using namespace fmpc::gpu_test;

namespace {

// A model under test: an element law on an element kind (indices in the registries), or springs with the volume
// term (law < 0). Every fem law on every element kind is covered, so that a new row of either registry is compared
// with the CPU and runs under the sanitizers without an edit here; implicit Euler where the registry says the CUDA
// engine runs it (element_kind_limits: runs_implicit_euler).
struct Model {
  int law = -1;
  int element = 0;
  std::string name;
};

std::vector<Model> all_models() {
  std::vector<Model> models;
  for (const ElementLawRow& law : element_law_rows()) {
    if (law.beside_springs) continue;
    for (const ElementKindRow& kind : element_kind_rows())
      models.push_back(Model{law.law, kind.kind, std::string(law.keyword) + " FEM (" + kind.keyword + ")"});
  }
  models.push_back(Model{-1, 0, "springs + volume term"});
  return models;
}

bool runs_implicit_euler(const Model& model) {
  return model.law < 0 || !cuda_refusal(element_kind_limits(model.element), true);
}

const std::string& name_of(const Model& model) { return model.name; }

Mesh box_mesh(int nx, int ny, int nz) {
  DiagnosticList diagnostics;
  BoxSpec box;
  box.cells_x = nx;
  box.cells_y = ny;
  box.cells_z = nz;
  box.size = {0.1, 0.1, 0.1};
  return generate_box(box, diagnostics);
}

// A 0.1 m box of 5 kPa tissue (1060 kg/m^3, nu 0.45, damping ratio 0.9, Rayleigh mass damping 2 /s) hanging from its
// top face under gravity, with seeded random initial velocities so that every vertex moves.
SimulationSetup hanging_box(const Model& model, Precision precision, Integrator integrator, int nx = 3, int ny = 5,
                            int nz = 2, unsigned seed = 1) {
  const Mesh mesh = box_mesh(nx, ny, nz);
  DiagnosticList diagnostics;
  SimulationSetup out;
  if (model.law >= 0) {
    FemModelSpec spec;
    spec.law = model.law;
    spec.element = model.element;
    spec.youngs_modulus = {5000.0};
    spec.poisson_ratio = {0.45};
    spec.mass.value = 1060.0;
    spec.damping_ratio = 0.9;
    if (auto setup = build_fem_model(mesh, spec, diagnostics)) out = *setup;
  } else {
    const auto unit = calibrate_volume_term(1.0, 0.45, StiffnessMapping::VanGelder1998, SourceRange{}, diagnostics);
    SpringModelSpec spec;
    spec.stiffness.mapping = StiffnessMapping::VanGelder1998;
    spec.stiffness.value = unit ? unit->spring_modulus * 5000.0 : 5000.0;
    spec.mass.value = 1060.0;
    spec.damping.ratio = 0.9;
    if (auto setup = build_spring_model(mesh, spec, diagnostics)) out = *setup;
    out.tetrahedra = mesh.tetrahedra;
    if (unit) add_volume_term(out, unit->bulk_modulus * 5000.0, 0.9, 0.0, diagnostics);
  }
  if (diagnostics.has_errors()) note("setup: " + describe(diagnostics));
  out.mass_damping = 2.0;
  for (std::size_t v = 0; v < out.rest_positions.size(); ++v) {
    if (out.rest_positions[v][1] > 0.0999) out.fixed_vertices.push_back(static_cast<std::int32_t>(v));
  }
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> speed(-0.05, 0.05);
  out.initial_velocities.resize(out.rest_positions.size());
  for (Point3& v : out.initial_velocities) v = {speed(random), speed(random), speed(random)};
  out.gravity = {0.0, -9.81, 0.0};
  out.precision = precision;
  out.integrator = integrator;
  return out;
}

// The hanging box whose bottom face slides on its plane (y held, x and z free: SOFA's PartialFixedConstraint) and
// whose x = 0 face holds x only.
SimulationSetup held_box(const Model& model, Precision precision, Integrator integrator) {
  SimulationSetup setup = hanging_box(model, precision, integrator, 4, 3, 3, 7);
  setup.fixed_axes.assign(setup.rest_positions.size(), 0);
  for (std::size_t v = 0; v < setup.rest_positions.size(); ++v) {
    if (setup.rest_positions[v][1] < 1e-6) setup.fixed_axes[v] |= 2;
    if (setup.rest_positions[v][0] < 1e-6) setup.fixed_axes[v] |= 1;
  }
  return setup;
}

// One tetrahedron of springs, corner 3 thrown at 3 m/s towards the centroid of the opposite face: it passes through
// and stays inverted (tests/unit/fem_simulation_test.cpp finds the step by stepping one at a time on the CPU).
SimulationSetup thrown_corner(Precision precision, double speed = 3.0) {
  Mesh mesh;
  mesh.points = {{0, 0, 0}, {0.01, 0, 0}, {0, 0.01, 0}, {0, 0, 0.01}};
  mesh.tetrahedra = {{0, 1, 2, 3}};
  SpringModelSpec spec;
  spec.stiffness.mapping = StiffnessMapping::VanGelder1998;
  spec.stiffness.value = 1000.0;
  spec.mass.value = 1000.0;
  spec.damping.ratio = 0.0;
  DiagnosticList diagnostics;
  auto built = build_spring_model(mesh, spec, diagnostics);
  SimulationSetup setup = built ? *built : SimulationSetup{};
  setup.tetrahedra = mesh.tetrahedra;
  setup.fixed_vertices = {0, 1, 2};
  const double length = std::sqrt(1.0 / 9 + 1.0 / 9 + 1.0);
  setup.initial_velocities = {
      {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {speed / 3 / length, speed / 3 / length, -speed / length}};
  setup.precision = precision;
  setup.time_step = 1e-5;
  return setup;
}

const std::vector<Model> kModels = all_models();

}  // namespace

FMPC_GPU_TEST(force_models_match_cpu, "FEM and springs with the volume term: every integrator matches the CPU", true) {
  for (const Model& model : kModels) {
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      for (const Integrator integrator : kGpuIntegrators) {
        for (const bool held : {false, true}) {
          const SimulationSetup setup =
              held ? held_box(model, precision, integrator) : hanging_box(model, precision, integrator);
          const Difference d = cpu_gpu_difference(setup, 2000, gpu::GpuOptions{});
          std::ostringstream line;
          line << name_of(model) << (held ? " (per-axis holds)" : "") << ", " << to_string(integrator) << ", "
               << name_of(precision) << ": max |GPU - CPU| after 2,000 steps: " << d.positions << " m, "
               << d.velocities << " m/s";
          note(line.str());
          FMPC_EXPECT(d.positions <= position_tolerance(precision));
          FMPC_EXPECT(d.velocities <= velocity_tolerance(precision));
        }
      }
    }
  }
}

FMPC_GPU_TEST(force_models_held_axes, "a held axis stays at rest on the GPU, the free axes move", true) {
  const SimulationSetup setup = held_box(kModels.front(), Precision::Double, Integrator::SemiImplicitEuler);
  DiagnosticList diagnostics;
  const auto run = gpu_simulation(setup, diagnostics);
  FMPC_REQUIRE(run && run->advance(500, diagnostics));
  const auto positions = run->positions(diagnostics);
  double moved_free = 0.0;
  for (std::size_t v = 0; v < positions.size(); ++v) {
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const double moved = std::abs(positions[v][axis] - setup.rest_positions[v][axis]);
      if (setup.fixed_axes[v] & (1u << axis)) {
        FMPC_EXPECT(moved == 0.0);
      } else if (setup.fixed_axes[v] != 0) {
        moved_free = std::max(moved_free, moved);
      }
    }
  }
  FMPC_EXPECT(moved_free > 1e-6);
}

FMPC_GPU_TEST(force_models_implicit, "implicit Euler on the FEM and the volume term: GPU CG agrees with Eigen's", true) {
  for (const Model& model : kModels) {
    if (!runs_implicit_euler(model)) continue;
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      const SimulationSetup setup = hanging_box(model, precision, Integrator::ImplicitEuler);
      check_implicit_against_cpu(setup, name_of(model) + ", " + name_of(precision));
    }
  }
}

FMPC_GPU_TEST(force_models_bitwise,
              "FEM runs are bitwise identical: run to run, graphs, persistent or not, sliced springs or not, any check",
              true) {
  for (const Model& model : kModels) {
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      for (const Integrator integrator : kGpuIntegrators) {
        // 8 x 7 x 6 = 336 vertices and 1,260 tetrahedra: blocks partly idle in both passes.
        const SimulationSetup setup = hanging_box(model, precision, integrator, 7, 6, 5);
        DiagnosticList diagnostics;
        gpu::GpuOptions plain;
        plain.use_graphs = false;
        plain.persistent = false;  // the Euler schemes' default run is persistent: compared with the per-step kernels
        const auto reference = gpu_simulation(setup, diagnostics, plain);
        FMPC_REQUIRE(reference && reference->advance(600, diagnostics, 1));
        const auto expected = reference->positions(diagnostics);
        const auto expected_potential = reference->potential_energy(diagnostics);
        const auto run = gpu_simulation(setup, diagnostics);
        FMPC_REQUIRE(run && run->advance(1, diagnostics) && run->advance(65, diagnostics, 64) &&
                     run->advance(534, diagnostics, 0));
        FMPC_EXPECT(bitwise_equal(run->positions(diagnostics), expected));
        const auto potential = run->potential_energy(diagnostics);
        FMPC_EXPECT(potential && expected_potential && *potential == *expected_potential);
        // One thread per vertex, the springs' records in the sliced layout and in CSR order.
        for (const bool sliced : {true, false}) {
          gpu::GpuOptions one_thread;
          one_thread.persistent = false;
          one_thread.gather_lanes = 1;
          one_thread.sliced_springs = sliced;
          const auto stepped = gpu_simulation(setup, diagnostics, one_thread);
          FMPC_REQUIRE(stepped && stepped->advance(600, diagnostics, 64));
          FMPC_EXPECT(bitwise_equal(stepped->positions(diagnostics), expected));
        }
        if (diagnostics.has_errors()) note(describe(diagnostics));
        FMPC_EXPECT(!diagnostics.has_errors());
      }
    }
  }
}

FMPC_GPU_TEST(force_models_energy, "the elements' potential energy on the GPU equals the CPU's sum", true) {
  for (const Model& model : kModels) {
    const SimulationSetup setup = hanging_box(model, Precision::Double, Integrator::RungeKutta4);
    DiagnosticList diagnostics;
    const auto cpu = sim::Simulation::create(setup, diagnostics);
    const auto device = gpu_simulation(setup, diagnostics);
    FMPC_REQUIRE(cpu && device && cpu->advance(300, diagnostics) && device->advance(300, diagnostics));
    const auto potential = device->potential_energy(diagnostics);
    FMPC_REQUIRE(potential);
    note(name_of(model) + ": potential energy GPU " + std::to_string(*potential) + " J, CPU " +
         std::to_string(*cpu->potential_energy(diagnostics)) + " J");
    FMPC_EXPECT_WITHIN(*potential, *cpu->potential_energy(diagnostics), 1e-10 * std::abs(*cpu->potential_energy(diagnostics)) + 1e-12);
  }
}

FMPC_GPU_TEST(inversions_match_cpu, "inversions: the GPU finds the CPU's first step, element and count; stop stops",
              true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    SimulationSetup setup = thrown_corner(precision);
    DiagnosticList cpu_diagnostics, gpu_diagnostics;
    const auto cpu = sim::Simulation::create(setup, cpu_diagnostics);
    const auto device = gpu_simulation(setup, gpu_diagnostics);
    FMPC_REQUIRE(cpu && device && cpu->advance(1000, cpu_diagnostics) && device->advance(1000, gpu_diagnostics));
    const InversionReport& a = cpu->inversions();
    const InversionReport& b = device->inversions();
    note(std::string("thrown corner, ") + name_of(precision) + ": first inversion at step " +
         std::to_string(a.first_step) + " (CPU), " + std::to_string(b.first_step) + " (GPU)");
    FMPC_EXPECT(a.largest_count == 1);
    FMPC_EXPECT(b.largest_count == a.largest_count);
    FMPC_EXPECT(b.first_step == a.first_step);
    FMPC_EXPECT(b.first_element == a.first_element);
    FMPC_EXPECT(gpu_diagnostics.warning_count() == 1);
    FMPC_EXPECT(!gpu_diagnostics.items().empty() && gpu_diagnostics.items()[0].code == "inverted-elements");
    // The persistent run found the inversion in a chunk with the next one launched ahead, took that one back and
    // replayed from the checkpoint: it goes on with the per-step kernels' bits.
    FMPC_EXPECT(device->launches().persistent);
    gpu::GpuOptions per_step;
    per_step.persistent = false;
    DiagnosticList reference_diagnostics;
    const auto reference = gpu_simulation(setup, reference_diagnostics, per_step);
    FMPC_REQUIRE(reference && reference->advance(1000, reference_diagnostics));
    FMPC_EXPECT(reference->inversions().first_step == b.first_step);
    FMPC_EXPECT(bitwise_equal(device->positions(gpu_diagnostics), reference->positions(reference_diagnostics)));
    FMPC_EXPECT(bitwise_equal(device->velocities(gpu_diagnostics), reference->velocities(reference_diagnostics)));
    setup.on_inversion = InversionPolicy::Stop;
    DiagnosticList stopped;
    const auto stop = gpu_simulation(setup, stopped);
    FMPC_REQUIRE(stop);
    FMPC_EXPECT(!stop->advance(1000, stopped));
    FMPC_EXPECT(stop->steps_taken() == a.first_step);
    FMPC_EXPECT(stopped.error_count() == 1);
  }
  // In a batch, the inversion is the scene's thrown through alone (at 1 m/s the springs throw the corner back).
  std::vector<SimulationSetup> scenes{thrown_corner(Precision::Double, 1.0), thrown_corner(Precision::Double)};
  DiagnosticList diagnostics;
  const auto batch = gpu_batch(scenes, gpu::GpuOptions{}, diagnostics);
  FMPC_REQUIRE(batch && batch->advance(1000, diagnostics));
  FMPC_EXPECT(batch->inversions(0).largest_count == 0);
  FMPC_EXPECT(batch->inversions(1).largest_count == 1);
  DiagnosticList single;
  const auto alone = sim::Simulation::create(scenes[1], single);
  FMPC_REQUIRE(alone && alone->advance(1000, single));
  FMPC_EXPECT(batch->inversions(1).first_step == alone->inversions().first_step);
}

// A quadratic FEM box (2^3 cells) with one edge node moved past its edge's end (1.2 of the way): the elements around
// that edge fold between their corners (tests/unit/quadratic_element_test.cpp), which only the Jacobian at their
// quadrature points shows (kernels::element_inverted).
SimulationSetup folded_quadratic_box(Precision precision) {
  const Mesh mesh = box_mesh(2, 2, 2);
  DiagnosticList diagnostics;
  FemModelSpec spec;
  spec.element = element_kind_by_keyword("quadratic")->kind;
  spec.youngs_modulus = {5000.0};
  spec.poisson_ratio = {0.45};
  spec.mass.value = 1060.0;
  spec.damping_ratio = 0.9;
  SimulationSetup out;
  if (auto setup = build_fem_model(mesh, spec, diagnostics)) out = *setup;
  if (diagnostics.has_errors()) note("setup: " + describe(diagnostics));
  out.initial_positions = out.rest_positions;
  const auto ends = out.elements.geometry.added_vertex_ends.front();
  const Point3& from = out.rest_positions[static_cast<std::size_t>(ends[0])];
  const Point3& to = out.rest_positions[static_cast<std::size_t>(ends[1])];
  for (std::size_t i = 0; i < 3; ++i) out.initial_positions[mesh.points.size()][i] = from[i] + 1.2 * (to[i] - from[i]);
  out.precision = precision;
  return out;
}

FMPC_GPU_TEST(inversions_quadratic_points, "quadratic elements folded between their corners: the GPU counts the CPU's",
              true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    const std::vector<SimulationSetup> scenes = {folded_quadratic_box(precision)};
    DiagnosticList diagnostics;
    const auto stability = check_stability(scenes.front(), diagnostics);
    FMPC_REQUIRE(stability);
    const std::vector<StabilityReport> reports = {*stability};
    const auto cpu = create_cpu_engine(scenes, reports, 1);
    const auto device = gpu::create_engine(scenes, reports, gpu::GpuOptions{}, diagnostics);
    FMPC_REQUIRE(device);
    std::vector<unsigned> cpu_counts, gpu_counts;
    std::vector<int> cpu_firsts, gpu_firsts;
    FMPC_REQUIRE(cpu->count_inverted(cpu_counts, cpu_firsts, diagnostics));
    FMPC_REQUIRE(device->count_inverted(gpu_counts, gpu_firsts, diagnostics));
    note(std::string("folded quadratic box, ") + name_of(precision) + ": " + std::to_string(cpu_counts.front()) +
         " inverted (CPU), " + std::to_string(gpu_counts.front()) + " (GPU)");
    FMPC_EXPECT(cpu_counts.front() > 0u);
    FMPC_EXPECT(gpu_counts == cpu_counts);
    FMPC_EXPECT(gpu_firsts == cpu_firsts);
    // The persistent kernel's own count (its chunk checks) against the CPU's over a short run.
    DiagnosticList cpu_diagnostics, gpu_diagnostics;
    const auto cpu_run = sim::Simulation::create(scenes.front(), cpu_diagnostics);
    const auto gpu_run = gpu_simulation(scenes.front(), gpu_diagnostics);
    FMPC_REQUIRE(cpu_run && gpu_run && cpu_run->advance(200, cpu_diagnostics) && gpu_run->advance(200, gpu_diagnostics));
    FMPC_EXPECT(gpu_run->inversions().largest_count == cpu_run->inversions().largest_count);
    FMPC_EXPECT(gpu_run->inversions().first_element == cpu_run->inversions().first_element);
    FMPC_EXPECT(gpu_run->inversions().first_step == cpu_run->inversions().first_step);
  }
}

// Every element kernel on tiny scenes for compute-sanitizer: forces, energy, inversion counts, implicit products,
// batches of FEM and volume-term scenes.
// The element kernels under compute-sanitizer; explicit and implicit apart, so that bench/run_gpu.sh runs them in
// processes of their own (racecheck instruments every shared access of the cooperative CG: minutes).
void sanitize_force_models(const std::vector<Integrator>& integrators) {
  for (const Model& model : kModels) {
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      for (const Integrator integrator : integrators) {
        if (integrator == Integrator::ImplicitEuler && !runs_implicit_euler(model)) continue;
        SimulationSetup setup = held_box(model, precision, integrator);
        setup.implicit.max_iterations = kSanitizedCgIterations;
        // Implicit Euler's solve in one block (the plan's choice at this size) and also, in float, on the cooperative
        // grid, in double with the per-iteration launches (fused stages, then a launch per kernel).
        gpu::GpuOptions grid, fused, separate;
        grid.cg_single_block = false;
        fused.persistent = false;
        separate.persistent = false;
        separate.cg_fused_stages = false;
        std::vector<gpu::GpuOptions> launches{gpu::GpuOptions{}};
        if (integrator == Integrator::ImplicitEuler) {
          if (precision == Precision::Float) launches.push_back(grid);
          if (precision == Precision::Double) launches.insert(launches.end(), {fused, separate});
        }
        for (const gpu::GpuOptions& options : launches) {
          DiagnosticList diagnostics;
          const auto run = gpu_simulation(setup, diagnostics, options);
          FMPC_REQUIRE(run && run->advance(9, diagnostics, 4));
          FMPC_EXPECT(run->potential_energy(diagnostics).has_value());
          FMPC_EXPECT(run->kinetic_energy(diagnostics).has_value());
          if (diagnostics.has_errors()) note(name_of(model) + ": " + describe(diagnostics));
          FMPC_EXPECT(!diagnostics.has_errors());
        }
      }
    }
  }
}

FMPC_GPU_TEST(sanitizer_force_models, "sanitizer smoke: element, inversion and batch kernels, explicit integrators",
              true) {
  sanitize_force_models({Integrator::ForwardEuler, Integrator::SemiImplicitEuler, Integrator::VelocityVerlet,
                         Integrator::RungeKutta4});
  for (const Model& model : kModels) {
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      std::vector<SimulationSetup> scenes{hanging_box(model, precision, Integrator::VelocityVerlet, 1, 1, 1),
                                          hanging_box(model, precision, Integrator::VelocityVerlet, 2, 3, 1)};
      DiagnosticList diagnostics;
      const auto batch = gpu_batch(scenes, gpu::GpuOptions{}, diagnostics);
      FMPC_REQUIRE(batch && batch->advance(30, diagnostics, 16));
      FMPC_EXPECT(batch->potential_energy(1, diagnostics).has_value());
      if (diagnostics.has_errors()) note(describe(diagnostics));
    }
  }
  // The inversion count and its replay, a run stopped by on_inversion: stop.
  for (const InversionPolicy policy : {InversionPolicy::Warn, InversionPolicy::Stop}) {
    SimulationSetup setup = thrown_corner(Precision::Float);
    setup.on_inversion = policy;
    DiagnosticList diagnostics;
    const auto run = gpu_simulation(setup, diagnostics);
    FMPC_REQUIRE(run);
    FMPC_EXPECT(run->advance(600, diagnostics, 64) == (policy == InversionPolicy::Warn));
    FMPC_EXPECT(run->inversions().largest_count == 1);
  }
}

FMPC_GPU_TEST(sanitizer_implicit_force_models, "sanitizer smoke: implicit element kernels (CG capped)", true) {
  sanitize_force_models({Integrator::ImplicitEuler});
}

// A kind with a nodal pass (kernels::element_kind_has_nodal_pass: the nodal pressure tetrahedra) in a batch of two
// boxes of different sizes (the nodal gather over the concatenated corners' CSR, the vertex and element counts never
// a multiple of the block size): each scene bitwise the CPU's alone, with the per-step kernels (the plan keeps a
// nodal pass off the persistent launches, BatchShape::nodal_pass), and its energy (the nodal field in double from a
// float state) the host's.
FMPC_GPU_TEST(nodal_pass_batch, "nodal pressure elements in a GPU batch: each scene the CPU's alone, bitwise", true) {
  for (const Model& model : kModels) {
    if (model.law < 0 || !kernels::element_kind_has_nodal_pass(model.element)) continue;
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      const std::vector<SimulationSetup> scenes{
          hanging_box(model, precision, Integrator::SemiImplicitEuler, 2, 3, 1, 3),
          hanging_box(model, precision, Integrator::SemiImplicitEuler, 3, 5, 2, 5)};
      DiagnosticList diagnostics;
      const auto batch = gpu_batch(scenes, gpu::GpuOptions{}, diagnostics);
      FMPC_REQUIRE(batch && batch->advance(500, diagnostics, 64));
      FMPC_EXPECT(!batch->launches().persistent);
      for (std::size_t s = 0; s < scenes.size(); ++s) {
        const auto alone = sim::Simulation::create(scenes[s], diagnostics);
        FMPC_REQUIRE(alone && alone->advance(500, diagnostics, 64));
        const double difference = max_difference(batch->positions(s, diagnostics), alone->positions(diagnostics));
        note(name_of(model) + ", " + name_of(precision) + ", scene " + std::to_string(s) +
             " of a batch: max |GPU - CPU| after 500 steps " + std::to_string(difference) + " m");
        FMPC_EXPECT(difference == 0.0);
        const auto energy = batch->potential_energy(s, diagnostics);
        const auto expected = alone->potential_energy(diagnostics);
        FMPC_REQUIRE(energy && expected);
        FMPC_EXPECT_WITHIN(*energy, *expected, 1e-10 * std::abs(*expected) + 1e-12);
      }
      if (diagnostics.has_errors()) note(describe(diagnostics));
      FMPC_EXPECT(!diagnostics.has_errors());
    }
  }
}

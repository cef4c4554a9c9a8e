// The CUDA backend against the CPU loop (the host reference), run to run, with and without graphs, batched and
// alone, with odd mesh sizes (never a multiple of the block size) and NaN/Inf detection.
//
// Stated tolerance (docs/simulator.md): after 10,000 steps of a damped hanging 0.1 m box, every position of the
// GPU run is within 1e-5 m (float) and 1e-12 m (double) of the CPU run. Both sides evaluate the same FMPC_HD
// functions in the same order, and the device code is compiled with --fmad=false, so the expected difference is 0;
// the tests print the measured maximum.
#include "runtime/gpu/gpu_simulation.h"

#include <cuda_runtime_api.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <utility>

#include "runtime/mesh/generated_mesh.h"
#include "runtime/scene/spring_model_builder.h"
#include "tests/gpu/cpu_gpu_comparison.h"
#include "tests/gpu/gpu_test_harness.h"

using namespace fmpc;
using namespace fmpc::sim;
using namespace fmpc::gpu_test;

namespace {

struct BoxScene {
  int cells_x = 3, cells_y = 5, cells_z = 2;
  double young_modulus = 5000.0;  // Pa
  Precision precision = Precision::Double;
  Integrator integrator = Integrator::SemiImplicitEuler;
  unsigned seed = 1;  // initial velocities, uniform in +-0.05 m/s
};

// A 0.1 m box of soft tissue (1060 kg/m^3, Van Gelder stiffness, damping ratio 0.9) hanging from its top face
// under gravity, with seeded random initial velocities so that every vertex moves.
SimulationSetup hanging_box(const BoxScene& scene) {
  DiagnosticList diagnostics;
  BoxSpec box;
  box.cells_x = scene.cells_x;
  box.cells_y = scene.cells_y;
  box.cells_z = scene.cells_z;
  box.size = {0.1, 0.1, 0.1};
  const Mesh mesh = generate_box(box, diagnostics);
  SpringModelSpec model;
  model.stiffness.mapping = StiffnessMapping::VanGelder1998;
  model.stiffness.value = scene.young_modulus;
  model.mass.value = 1060.0;
  auto setup = build_spring_model(mesh, model, diagnostics);
  SimulationSetup out = setup ? *setup : SimulationSetup{};
  for (std::size_t v = 0; v < out.rest_positions.size(); ++v) {
    if (out.rest_positions[v][1] > 0.0999) out.fixed_vertices.push_back(static_cast<std::int32_t>(v));
  }
  std::mt19937 random(scene.seed);
  std::uniform_real_distribution<double> speed(-0.05, 0.05);
  out.initial_velocities.resize(out.rest_positions.size());
  for (Point3& v : out.initial_velocities) v = {speed(random), speed(random), speed(random)};
  out.gravity = {0.0, -9.81, 0.0};
  out.precision = scene.precision;
  out.integrator = scene.integrator;
  out.mass_damping = forward_euler_mass_damping(scene.integrator);
  return out;
}

// One tetrahedron, nothing fixed, falling and spinning: the smallest mesh with springs.
SimulationSetup single_tetrahedron(Precision precision, Integrator integrator) {
  DiagnosticList diagnostics;
  Mesh mesh;
  mesh.points = {{0.0, 0.0, 0.0}, {0.02, 0.0, 0.0}, {0.0, 0.02, 0.0}, {0.0, 0.0, 0.02}};
  mesh.tetrahedra = {{0, 1, 2, 3}};
  SpringModelSpec model;
  model.stiffness.mapping = StiffnessMapping::Uniform;
  model.stiffness.value = 50.0;
  model.mass.value = 1000.0;
  auto setup = build_spring_model(mesh, model, diagnostics);
  SimulationSetup out = setup ? *setup : SimulationSetup{};
  out.initial_velocities = {{0.0, 0.0, 0.0}, {0.0, 0.1, 0.0}, {0.0, 0.0, 0.1}, {0.1, 0.0, 0.0}};
  out.gravity = {0.0, -9.81, 0.0};
  out.precision = precision;
  out.integrator = integrator;
  out.mass_damping = forward_euler_mass_damping(integrator);
  return out;
}

// Basafa-Farahmand springs, nodal damping gamma0 + gamma1 |x - x0|, external forces and an initial displacement:
// every load term of vertex_acceleration.
SimulationSetup nonlinear_box(Precision precision, Integrator integrator) {
  BoxScene scene;
  scene.cells_x = 4;
  scene.cells_y = 3;
  scene.cells_z = 3;
  scene.precision = precision;
  scene.integrator = integrator;
  SimulationSetup setup = hanging_box(scene);
  setup.law = kernels::SpringLaw::BasafaFarahmand;
  setup.nodal_damping_gamma0 = 1e-3;
  setup.nodal_damping_gamma1 = 0.05;
  setup.external_forces.assign(setup.rest_positions.size(), Point3{0.0, 0.0, 0.0});
  setup.initial_positions = setup.rest_positions;
  for (std::size_t v = 0; v < setup.rest_positions.size(); ++v) {
    if (setup.rest_positions[v][1] < 1e-6) {
      setup.external_forces[v] = {0.01, -0.02, 0.005};
      setup.initial_positions[v][0] += 0.002;
    }
  }
  return setup;
}

// The box pressed 5 mm upwards at its free bottom face by a displacement probe (or pulled down by a force probe),
// the load ramping over 0.05 s.
SimulationSetup probed_box(Precision precision, Integrator integrator, ProbeLoad::Mode mode) {
  BoxScene scene;
  scene.precision = precision;
  scene.integrator = integrator;
  SimulationSetup setup = hanging_box(scene);
  ProbeLoad probe;
  probe.mode = mode;
  for (std::size_t v = 0; v < setup.rest_positions.size(); ++v) {
    if (setup.rest_positions[v][1] < 1e-6) probe.vertices.push_back(static_cast<std::int32_t>(v));
  }
  probe.target = mode == ProbeLoad::Mode::Displacement ? Point3{0.0, 0.005, 0.0} : Point3{0.0, -0.5, 0.0};
  probe.ramp_time = 0.05;
  setup.probe = probe;
  return setup;
}

// The box's springs stiffen with strain: E(X) = 4, 5, 9 kPa at X = -0.2, 0, 0.2 (Van Gelder k scales with E).
SimulationSetup strain_table_box(Precision precision, Integrator integrator) {
  BoxScene scene;
  scene.precision = precision;
  scene.integrator = integrator;
  SimulationSetup setup = hanging_box(scene);
  StrainStiffnessTable table;
  table.strain = {-0.2, 0.0, 0.2};
  table.modulus = {4000.0, 5000.0, 9000.0};
  for (const double k : setup.springs.stiffness) table.stiffness_per_modulus.push_back(k / scene.young_modulus);
  setup.strain_stiffness = table;
  return setup;
}

}  // namespace

FMPC_GPU_TEST(single_scene_refused, "implicit Euler and strain tables refuse a batch of several scenes", false) {
  {
    std::vector<SimulationSetup> scenes(2, hanging_box(BoxScene{}));
    for (SimulationSetup& scene : scenes) scene.integrator = Integrator::ImplicitEuler;
    DiagnosticList diagnostics;
    FMPC_EXPECT(!gpu_batch(scenes, gpu::GpuOptions{}, diagnostics));
    FMPC_REQUIRE(diagnostics.error_count() == 1);
    FMPC_EXPECT(diagnostics.items()[0].message.rfind("scene 0: implicit Euler runs one scene at a time", 0) == 0);
  }
  {
    std::vector<SimulationSetup> scenes(2, hanging_box(BoxScene{}));
    scenes[1].strain_stiffness = StrainStiffnessTable{};
    DiagnosticList diagnostics;
    FMPC_EXPECT(!gpu_batch(scenes, gpu::GpuOptions{}, diagnostics));
    FMPC_REQUIRE(diagnostics.error_count() == 1);
    FMPC_EXPECT(diagnostics.items()[0].message.rfind("scene 1: a scene with table-driven stiffness", 0) == 0);
  }
  {
    SimulationSetup setup = hanging_box(BoxScene{});
    setup.probe = ProbeLoad{};  // no vertices: the shared validation names the problem
    DiagnosticList diagnostics;
    FMPC_EXPECT(!gpu_simulation(setup, diagnostics));
    FMPC_EXPECT(first_error(diagnostics) == "the probe has no vertices");
  }
}

FMPC_GPU_TEST(batch_refusals, "a batch refuses no scenes, mixed shared fields and invalid scenes by index", false) {
  const gpu::GpuOptions options;
  {
    DiagnosticList diagnostics;
    FMPC_EXPECT(!gpu_batch({}, options, diagnostics));
    FMPC_EXPECT(diagnostics.error_count() == 1);
  }
  {
    std::vector<SimulationSetup> scenes(3, hanging_box(BoxScene{}));
    scenes[2].gravity = {0.0, 0.0, -9.81};
    DiagnosticList diagnostics;
    FMPC_EXPECT(!gpu_batch(scenes, options, diagnostics));
    FMPC_REQUIRE(diagnostics.error_count() == 1);
    FMPC_EXPECT(diagnostics.items()[0].message ==
                "scene 2 differs from scene 0 in its gravity; the scenes of one "
                "GPU batch share it: run it in another batch");
  }
  {
    std::vector<SimulationSetup> scenes(2, hanging_box(BoxScene{}));
    scenes[1].precision = Precision::Float;
    DiagnosticList diagnostics;
    FMPC_EXPECT(!gpu_batch(scenes, options, diagnostics));
    FMPC_EXPECT(diagnostics.items().at(0).message.find("in its precision") != std::string::npos);
  }
  {
    std::vector<SimulationSetup> scenes(2, hanging_box(BoxScene{}));
    scenes[1].mass.pop_back();
    DiagnosticList diagnostics;
    FMPC_EXPECT(!gpu_batch(scenes, options, diagnostics));
    FMPC_REQUIRE(diagnostics.has_errors());
    FMPC_EXPECT(diagnostics.items()[0].message.rfind("scene 1: masses:", 0) == 0);
  }
}

FMPC_GPU_TEST(cpu_agreement_10000, "every GPU integrator matches the CPU after 10,000 steps (float and double)", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    for (const Integrator integrator : kGpuIntegrators) {
      BoxScene scene;
      scene.precision = precision;
      scene.integrator = integrator;
      const Difference difference = cpu_gpu_difference(hanging_box(scene), 10000, gpu::GpuOptions{});
      std::ostringstream line;
      line << to_string(integrator) << ", " << name_of(precision)
           << ": max |GPU - CPU| after 10,000 steps: " << difference.positions << " m (tolerance "
           << position_tolerance(precision) << "), " << difference.velocities << " m/s (tolerance "
           << velocity_tolerance(precision) << ")";
      note(line.str());
      FMPC_EXPECT(difference.positions <= position_tolerance(precision));
      FMPC_EXPECT(difference.velocities <= velocity_tolerance(precision));
    }
  }
}

FMPC_GPU_TEST(cpu_agreement_loads, "Basafa-Farahmand springs, nodal damping and forces match the CPU", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    for (const Integrator integrator : kGpuIntegrators) {
      const Difference difference = cpu_gpu_difference(nonlinear_box(precision, integrator), 2000, gpu::GpuOptions{});
      std::ostringstream line;
      line << "nonlinear box, " << to_string(integrator) << ", " << name_of(precision)
           << ": max |GPU - CPU| after 2,000 steps: " << difference.positions << " m, " << difference.velocities
           << " m/s";
      note(line.str());
      FMPC_EXPECT(difference.positions <= position_tolerance(precision));
      FMPC_EXPECT(difference.velocities <= velocity_tolerance(precision));
    }
  }
}

FMPC_GPU_TEST(bitwise_reproducible, "runs are bitwise identical: run to run, graphs or not, any check interval", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    for (const Integrator integrator : kGpuIntegrators) {
      BoxScene scene;
      scene.cells_x = 7;  // 8 x 7 x 6 = 336 vertices: two blocks, the second partly idle
      scene.cells_y = 6;
      scene.cells_z = 5;
      scene.precision = precision;
      scene.integrator = integrator;
      const SimulationSetup setup = hanging_box(scene);
      DiagnosticList diagnostics;
      // Reference: no graphs, no persistent launch, a check after every step.
      gpu::GpuOptions plain;
      plain.use_graphs = false;
      plain.persistent = false;
      const auto reference = gpu_simulation(setup, diagnostics, plain);
      FMPC_REQUIRE(reference && reference->advance(1000, diagnostics, 1));
      const auto expected_x = reference->positions(diagnostics);
      const auto expected_v = reference->velocities(diagnostics);
      const auto expected_kinetic = reference->kinetic_energy(diagnostics);
      const auto expected_potential = reference->potential_energy(diagnostics);
      FMPC_REQUIRE(expected_kinetic && expected_potential);
      // Graphs, in uneven pieces: 0, 1, 3 (checked every 2), 65 (every 64), 931 (every 0 = at the end).
      for (int repeat = 0; repeat < 2; ++repeat) {
        const auto run = gpu_simulation(setup, diagnostics);
        FMPC_REQUIRE(run);
        FMPC_REQUIRE(run->advance(0, diagnostics));
        FMPC_REQUIRE(run->advance(1, diagnostics));
        FMPC_REQUIRE(run->advance(3, diagnostics, 2));
        FMPC_REQUIRE(run->advance(65, diagnostics, 64));
        FMPC_REQUIRE(run->advance(931, diagnostics, 0));
        FMPC_EXPECT(run->steps_taken() == 1000);
        FMPC_EXPECT(bitwise_equal(run->positions(diagnostics), expected_x));
        FMPC_EXPECT(bitwise_equal(run->velocities(diagnostics), expected_v));
        const auto kinetic = run->kinetic_energy(diagnostics);
        const auto potential = run->potential_energy(diagnostics);
        FMPC_REQUIRE(kinetic && potential);
        FMPC_EXPECT(std::memcmp(&*kinetic, &*expected_kinetic, sizeof(double)) == 0);
        FMPC_EXPECT(std::memcmp(&*potential, &*expected_potential, sizeof(double)) == 0);
      }
      FMPC_EXPECT(!diagnostics.has_errors());
      if (diagnostics.has_errors()) note(describe(diagnostics));
    }
  }
}

FMPC_GPU_TEST(energy_matches_cpu, "device energy reductions match the CPU's sums", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    for (const SimulationSetup& setup :
         {hanging_box(BoxScene{3, 5, 2, 5000.0, precision}), nonlinear_box(precision, Integrator::RungeKutta4)}) {
      DiagnosticList diagnostics;
      const auto cpu = sim::Simulation::create(setup, diagnostics);
      const auto device = gpu_simulation(setup, diagnostics);
      FMPC_REQUIRE(cpu && device && cpu->advance(300, diagnostics) && device->advance(300, diagnostics));
      const auto kinetic = device->kinetic_energy(diagnostics);
      const auto potential = device->potential_energy(diagnostics);
      FMPC_REQUIRE(kinetic && potential);
      // Same terms in double, summed in another order: relative rounding only.
      FMPC_EXPECT_WITHIN(*kinetic, *cpu->kinetic_energy(diagnostics), 1e-10 * std::abs(*cpu->kinetic_energy(diagnostics)) + 1e-300);
      FMPC_EXPECT_WITHIN(*potential, *cpu->potential_energy(diagnostics), 1e-10 * std::abs(*cpu->potential_energy(diagnostics)) + 1e-12);
      FMPC_EXPECT(*kinetic > 0.0);
      // The elastic part alone (what a scene's time_series.csv reports) against the host's sum on the CPU state.
      const auto elastic = device->elastic_energy(diagnostics);
      FMPC_REQUIRE(elastic.has_value());
      const double host_elastic = sim::elastic_energy(setup, cpu->positions(diagnostics));
      FMPC_EXPECT_WITHIN(*elastic, host_elastic, 1e-10 * std::abs(host_elastic) + 1e-300);
      FMPC_EXPECT(host_elastic > 0.0);
    }
  }
}

FMPC_GPU_TEST(largest_displacement_matches_host,
              "the largest displacement reduced on the device equals the host's on the downloaded state, bitwise",
              true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    std::vector<SimulationSetup> scenes;
    scenes.push_back(single_tetrahedron(precision, Integrator::SemiImplicitEuler));
    scenes.push_back(hanging_box(BoxScene{3, 5, 2, 5000.0, precision, Integrator::SemiImplicitEuler, 3}));
    scenes.push_back(hanging_box(BoxScene{7, 6, 5, 9000.0, precision, Integrator::SemiImplicitEuler, 4}));
    // Initial positions away from rest: the displacement is measured from them, not from the rest shape.
    SimulationSetup moved = hanging_box(BoxScene{5, 3, 4, 3000.0, precision, Integrator::SemiImplicitEuler, 2});
    moved.initial_positions = moved.rest_positions;
    for (std::size_t v = 0; v < moved.initial_positions.size(); ++v)
      moved.initial_positions[v][0] += 1e-4 * static_cast<double>((v * 7919) % 13) / 13.0;
    scenes.push_back(moved);
    for (SimulationSetup& scene : scenes) scene.gravity = {0.0, -9.81, 0.0};
    DiagnosticList diagnostics;
    const auto batch = gpu_batch(scenes, gpu::GpuOptions{}, diagnostics);
    FMPC_REQUIRE(batch && batch->advance(333, diagnostics, 100));
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      const std::vector<Point3> positions = batch->positions(s, diagnostics);
      const std::vector<Point3>& start =
          scenes[s].initial_positions.empty() ? scenes[s].rest_positions : scenes[s].initial_positions;
      double host = 0.0;
      for (std::size_t v = 0; v < positions.size(); ++v) host = std::max(host, distance(positions[v], start[v]));
      const auto device = batch->largest_displacement(s, diagnostics);
      FMPC_REQUIRE(device.has_value());
      FMPC_EXPECT(std::memcmp(&*device, &host, sizeof(double)) == 0);
      FMPC_EXPECT(host > 0.0);
      const auto single = gpu_simulation(scenes[s], diagnostics);
      FMPC_REQUIRE(single && single->advance(333, diagnostics, 100));
      const auto alone = single->largest_displacement(diagnostics);
      FMPC_REQUIRE(alone.has_value());
      FMPC_EXPECT(std::memcmp(&*alone, &host, sizeof(double)) == 0);
    }
  }
}

FMPC_GPU_TEST(batch_equals_single, "a batch of odd-sized scenes gives each scene's single-run bits", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    for (const Integrator integrator : kGpuIntegrators) {
      std::vector<SimulationSetup> scenes;
      scenes.push_back(single_tetrahedron(precision, integrator));
      scenes.push_back(hanging_box(BoxScene{1, 1, 1, 2000.0, precision, integrator, 2}));
      scenes.push_back(hanging_box(BoxScene{3, 5, 2, 5000.0, precision, integrator, 3}));
      scenes.push_back(hanging_box(BoxScene{7, 6, 5, 9000.0, precision, integrator, 4}));
      for (SimulationSetup& scene : scenes) scene.gravity = {0.0, -9.81, 0.0};
      DiagnosticList diagnostics;
      const auto batch = gpu_batch(scenes, gpu::GpuOptions{}, diagnostics);
      FMPC_REQUIRE(batch);
      FMPC_REQUIRE(batch->scene_count() == scenes.size());
      FMPC_REQUIRE(batch->advance(500, diagnostics, 100));
      for (std::size_t s = 0; s < scenes.size(); ++s) {
        const auto single = gpu_simulation(scenes[s], diagnostics);
        FMPC_REQUIRE(single && single->advance(500, diagnostics, 100));
        FMPC_EXPECT(batch->stability(s).time_step == single->stability().time_step);
        FMPC_EXPECT(bitwise_equal(batch->positions(s, diagnostics), single->positions(diagnostics)));
        FMPC_EXPECT(bitwise_equal(batch->velocities(s, diagnostics), single->velocities(diagnostics)));
        const auto batch_energy = batch->kinetic_energy(s, diagnostics);
        const auto single_energy = single->kinetic_energy(diagnostics);
        FMPC_EXPECT(batch_energy && single_energy && *batch_energy == *single_energy);
      }
      // The scenes' own time steps differ (different stiffness and size): the per-scene step array is used.
      FMPC_EXPECT(batch->stability(0).time_step != batch->stability(3).time_step);
      FMPC_EXPECT(batch->positions(scenes.size(), diagnostics).empty());
      FMPC_EXPECT(diagnostics.error_count() == 1);  // the scene index past the end
    }
  }
}

// Whether the device launches thread-block clusters (compute capability 9.0 and newer).
bool clusters_available() {
  int device = 0, major = 0;
  return cudaGetDevice(&device) == cudaSuccess &&
         cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, device) == cudaSuccess && major >= 9;
}

// The persistent launch (GpuOptions::persistent: clusters or a cooperative grid) against the per-step kernels with
// graphs, for forward and semi-implicit Euler: displacement and force probes (probe vertices applied by their own
// threads), a 20^3-cell box (9,261 vertices; grids of 1 and 7 rows per block do not fit it and take more, the last
// block partly idle), a batch of odd sizes with per-scene steps and a batch of the box and small scenes (in
// clusters: clusters of several blocks with windows), in uneven chunks (1, 3 checked every 2, 65 every 64, 931 at the
// end: pieces of 256 steps). Bitwise, probe force included.
FMPC_GPU_TEST(persistent_equals_per_step,
              "persistent launches give the per-step kernels' bits: probes, batches, sizes, block shapes", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    for (const Integrator integrator : {Integrator::ForwardEuler, Integrator::SemiImplicitEuler}) {
      std::vector<std::vector<SimulationSetup>> cases;
      cases.push_back({probed_box(precision, integrator, ProbeLoad::Mode::Displacement)});
      cases.push_back({probed_box(precision, integrator, ProbeLoad::Mode::Force)});
      cases.push_back({hanging_box(BoxScene{20, 20, 20, 5000.0, precision, integrator, 6})});
      cases.push_back({single_tetrahedron(precision, integrator),
                       probed_box(precision, integrator, ProbeLoad::Mode::Displacement),
                       hanging_box(BoxScene{7, 6, 5, 9000.0, precision, integrator, 4})});
      // Clusters of ten blocks: the 20^3 box in one, the two small scenes packed into the next.
      cases.push_back({hanging_box(BoxScene{20, 20, 20, 5000.0, precision, integrator, 7}),
                       probed_box(precision, integrator, ProbeLoad::Mode::Force),
                       hanging_box(BoxScene{7, 6, 5, 9000.0, precision, integrator, 4})});
      for (std::size_t c = 0; c < cases.size(); ++c) {
        const std::vector<SimulationSetup>& scenes = cases[c];
        DiagnosticList diagnostics;
        // Reference: the per-step kernels with one thread per vertex.
        gpu::GpuOptions per_step;
        per_step.persistent = false;
        per_step.gather_lanes = 1;
        const auto reference = gpu_batch(scenes, per_step, diagnostics);
        FMPC_REQUIRE(reference && reference->advance(1000, diagnostics));
        FMPC_EXPECT(!reference->launches().persistent);
        // Persistent in clusters (-1) or on the cooperative grid with `rows` vertices per block (0: automatic; 1: a
        // block per vertex; 7: blocks that split the rows of the boxes; 256: the most), and per step with `lanes`
        // threads per vertex: one, two (several rounds over a vertex's entries), eight, a whole warp.
        struct Launch {
          int rows, lanes;
        };
        for (const Launch launch : {Launch{-1, 0}, Launch{0, 0}, Launch{1, 0}, Launch{7, 0}, Launch{256, 0},
                                    Launch{0, 2}, Launch{0, 8}, Launch{0, 32}}) {
          const bool persistent = launch.lanes == 0;
          const bool clusters = launch.rows < 0;
          gpu::GpuOptions options;
          options.persistent = persistent;
          options.persistent_kind =
              clusters ? gpu::GpuOptions::PersistentKind::Clusters : gpu::GpuOptions::PersistentKind::Grid;
          options.persistent_rows = std::max(launch.rows, 0);
          options.gather_lanes = launch.lanes;
          const auto run = gpu_batch(scenes, options, diagnostics);
          FMPC_REQUIRE(run);
          FMPC_EXPECT(run->launches().persistent == persistent);
          // Every float case fits one cluster of a Hopper GPU (the 20^3 box's double records, 238 KB per block, do
          // not: it stays on the cooperative grid).
          if (clusters && clusters_available() && precision == Precision::Float) FMPC_EXPECT(run->launches().clusters);
          if (persistent && !clusters) FMPC_EXPECT(!run->launches().clusters);
          if (clusters)
            note(std::string(name_of(precision)) + ", case " + std::to_string(c) + ": " +
                 (run->launches().clusters ? "clusters" : "cooperative grid"));
          // 300 steps checked every 64: persistent chunks launched ahead of the previous one's checks.
          FMPC_REQUIRE(run->advance(1, diagnostics) && run->advance(3, diagnostics, 2) &&
                       run->advance(65, diagnostics, 64) && run->advance(300, diagnostics, 64) &&
                       run->advance(631, diagnostics, 0));
          for (std::size_t s = 0; s < scenes.size(); ++s) {
            const bool same = bitwise_equal(run->positions(s, diagnostics), reference->positions(s, diagnostics)) &&
                              bitwise_equal(run->velocities(s, diagnostics), reference->velocities(s, diagnostics));
            const ProbeReading a = run->probe_reading(s, diagnostics), b = reference->probe_reading(s, diagnostics);
            const bool same_probe = std::memcmp(&a.force, &b.force, sizeof a.force) == 0 &&
                                    std::memcmp(&a.displacement, &b.displacement, sizeof a.displacement) == 0;
            if (!same || !same_probe)
              note(std::string(name_of(precision)) + ", " + to_string(integrator) + ", case " + std::to_string(c) +
                   ", scene " + std::to_string(s) + ", rows " + std::to_string(launch.rows) + ", lanes " +
                   std::to_string(launch.lanes) + ": differs from the per-step path");
            FMPC_EXPECT(same && same_probe);
          }
        }
        if (diagnostics.has_errors()) note(describe(diagnostics));
        FMPC_EXPECT(!diagnostics.has_errors());
      }
    }
  }
}

// A check more than 2^20 steps away (advance with check_every 0): the persistent run launches pieces without
// checks up to the last one, each from its own first step, which the probe's ramp (still rising in the last piece)
// reads. Bitwise against the per-step kernels.
FMPC_GPU_TEST(persistent_long_launch, "persistent launches in pieces beyond 2^20 steps give the per-step bits", true) {
  SimulationSetup setup = probed_box(Precision::Float, Integrator::SemiImplicitEuler, ProbeLoad::Mode::Displacement);
  DiagnosticList diagnostics;
  const auto stability = check_stability(setup, diagnostics);
  FMPC_REQUIRE(stability);
  const std::size_t steps = (std::size_t{1} << 20) + 77;
  setup.probe->ramp_time = 1.2 * static_cast<double>(steps) * stability->time_step;
  gpu::GpuOptions per_step;
  per_step.persistent = false;
  const auto reference = gpu_simulation(setup, diagnostics, per_step);
  const auto run = gpu_simulation(setup, diagnostics);
  FMPC_REQUIRE(reference && run && run->launches().persistent);
  FMPC_REQUIRE(reference->advance(steps, diagnostics, 0) && run->advance(steps, diagnostics, 0));
  FMPC_EXPECT(run->steps_taken() == steps);
  FMPC_EXPECT(bitwise_equal(run->positions(diagnostics), reference->positions(diagnostics)));
  FMPC_EXPECT(bitwise_equal(run->velocities(diagnostics), reference->velocities(diagnostics)));
  FMPC_EXPECT(!diagnostics.has_errors());
  if (diagnostics.has_errors()) note(describe(diagnostics));
}

// The sliced layout of the springs (GpuOptions::sliced_springs, kernels::SlicedSpringsView: threads ordered by entry
// count within each block, entries of a warp side by side) against the same kernels reading the CSR order: every
// integrator with one thread per vertex, a batch of odd sizes (blocks and slices partly idle, windows across scene
// boundaries), Basafa-Farahmand springs with every load, and a network without dashpots (no damping records).
// Bitwise, positions, velocities and probe readings.
FMPC_GPU_TEST(sliced_springs_bitwise, "the sliced spring layout gives the CSR order's bits on every integrator", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    for (const Integrator integrator : kGpuIntegrators) {
      SimulationSetup undamped = hanging_box(BoxScene{9, 4, 3, 7000.0, precision, integrator, 3});
      undamped.springs.damping.clear();
      undamped.nodal_damping_gamma0 = 1e-3;
      std::vector<std::vector<SimulationSetup>> cases;
      cases.push_back({single_tetrahedron(precision, integrator),
                       hanging_box(BoxScene{7, 6, 5, 9000.0, precision, integrator, 4}),
                       hanging_box(BoxScene{2, 1, 3, 5000.0, precision, integrator, 5})});
      cases.push_back({nonlinear_box(precision, integrator)});
      cases.push_back({undamped});
      cases.push_back({probed_box(precision, integrator, ProbeLoad::Mode::Force)});
      for (std::size_t c = 0; c < cases.size(); ++c) {
        DiagnosticList diagnostics;
        gpu::GpuOptions csr;
        csr.persistent = false;
        csr.gather_lanes = 1;
        csr.sliced_springs = false;
        const auto reference = gpu_batch(cases[c], csr, diagnostics);
        FMPC_REQUIRE(reference && reference->advance(700, diagnostics, 64));
        // The default window, none (32: each warp keeps its vertices) and a whole block.
        for (const int window : {0, 32, 256}) {
          gpu::GpuOptions sliced = csr;
          sliced.sliced_springs = true;
          sliced.slice_window = window;
          const auto run = gpu_batch(cases[c], sliced, diagnostics);
          FMPC_REQUIRE(run && run->advance(1, diagnostics) && run->advance(699, diagnostics, 64));
          for (std::size_t s = 0; s < cases[c].size(); ++s) {
            const ProbeReading a = run->probe_reading(s, diagnostics), b = reference->probe_reading(s, diagnostics);
            const bool same = bitwise_equal(run->positions(s, diagnostics), reference->positions(s, diagnostics)) &&
                              bitwise_equal(run->velocities(s, diagnostics), reference->velocities(s, diagnostics)) &&
                              std::memcmp(&a.force, &b.force, sizeof a.force) == 0;
            if (!same)
              note(std::string(name_of(precision)) + ", " + to_string(integrator) + ", case " + std::to_string(c) +
                   ", scene " + std::to_string(s) + ", window " + std::to_string(window) +
                   ": the sliced layout differs from the CSR order");
            FMPC_EXPECT(same);
          }
        }
        if (diagnostics.has_errors()) note(describe(diagnostics));
        FMPC_EXPECT(!diagnostics.has_errors());
      }
    }
  }
}

FMPC_GPU_TEST(non_finite_located, "NaN/Inf stops the run naming the exact step, vertex and spring", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    BoxScene scene;
    scene.precision = precision;
    SimulationSetup setup = hanging_box(scene);
    DiagnosticList probe;
    const auto stability = check_stability(setup, probe);
    FMPC_REQUIRE(stability);
    setup.time_step = 40.0 * stability->critical_time_step;
    setup.refuse_unstable_time_step = false;
    DiagnosticList cpu_diagnostics;
    const auto cpu = sim::Simulation::create(setup, cpu_diagnostics);
    FMPC_REQUIRE(cpu);
    FMPC_EXPECT(!cpu->advance(100000, cpu_diagnostics));
    FMPC_REQUIRE(cpu->non_finite());
    for (const std::size_t check_every : {std::size_t{1}, std::size_t{64}, std::size_t{0}}) {
      // The persistent launch on the cooperative grid and in a cluster (its own end-of-chunk check).
      for (const auto kind : {gpu::GpuOptions::PersistentKind::Grid, gpu::GpuOptions::PersistentKind::Clusters}) {
        DiagnosticList diagnostics;
        gpu::GpuOptions options;
        options.persistent_kind = kind;
        const auto run = gpu_simulation(setup, diagnostics, options);
        FMPC_REQUIRE(run);
        FMPC_EXPECT(run->launches().clusters ==
                    (kind == gpu::GpuOptions::PersistentKind::Clusters && clusters_available()));
        FMPC_EXPECT(!run->advance(100000, diagnostics, check_every));
        FMPC_REQUIRE(run->non_finite());
        const NonFiniteReport& report = *run->non_finite();
        std::ostringstream line;
        line << name_of(precision) << (run->launches().clusters ? ", in a cluster" : ", grid") << ", check every "
             << check_every << ": GPU step " << report.step << " vertex " << report.vertex << " spring "
             << report.spring << "; CPU step " << cpu->non_finite()->step << " vertex " << cpu->non_finite()->vertex
             << " spring " << cpu->non_finite()->spring;
        note(line.str());
        FMPC_EXPECT(report.step == cpu->non_finite()->step);
        FMPC_EXPECT(report.vertex == cpu->non_finite()->vertex);
        FMPC_EXPECT(report.spring == cpu->non_finite()->spring);
        FMPC_EXPECT(run->steps_taken() == report.step);
        FMPC_REQUIRE(diagnostics.error_count() == 1);  // besides the warning about the unstable step
        FMPC_EXPECT(first_error(diagnostics)
                        .rfind("the GPU simulation became non-finite at step " + std::to_string(report.step) + " (t = ",
                               0) == 0);
        FMPC_EXPECT(!run->advance(1, diagnostics));  // a failed run stays stopped
      }
    }
  }
}

FMPC_GPU_TEST(non_finite_names_scene, "a NaN in one scene of a batch names that scene", true) {
  std::vector<SimulationSetup> scenes(3, hanging_box(BoxScene{}));
  DiagnosticList probe;
  const auto stability = check_stability(scenes[1], probe);
  FMPC_REQUIRE(stability);
  scenes[1].time_step = 40.0 * stability->critical_time_step;
  scenes[1].refuse_unstable_time_step = false;
  DiagnosticList diagnostics;
  const auto batch = gpu_batch(scenes, gpu::GpuOptions{}, diagnostics);
  FMPC_REQUIRE(batch);
  FMPC_EXPECT(!batch->advance(100000, diagnostics));
  FMPC_REQUIRE(batch->non_finite());
  FMPC_EXPECT(batch->non_finite()->scene == 1);
  FMPC_EXPECT(first_error(diagnostics).find(" in scene 1: vertex ") != std::string::npos);
}

// Small enough for compute-sanitizer (memcheck, racecheck, initcheck, synccheck): every kernel, graphs, a batch,
// energies and a NaN replay.
FMPC_GPU_TEST(sanitizer_smoke, "sanitizer smoke: every kernel on tiny scenes", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    for (const Integrator integrator : kGpuIntegrators) {
      std::vector<SimulationSetup> scenes{single_tetrahedron(precision, integrator),
                                          hanging_box(BoxScene{2, 1, 3, 5000.0, precision, integrator, 5})};
      DiagnosticList diagnostics;
      const auto batch = gpu_batch(scenes, gpu::GpuOptions{}, diagnostics);
      FMPC_REQUIRE(batch && batch->advance(20, diagnostics, 8));
      // The Euler schemes run persistent by default (on the cooperative grid, as these fit it); in clusters (one
      // block per cluster) and their per-step kernels too.
      gpu::GpuOptions in_clusters;
      in_clusters.persistent_kind = gpu::GpuOptions::PersistentKind::Clusters;
      const auto clustered = gpu_batch(scenes, in_clusters, diagnostics);
      FMPC_REQUIRE(clustered && clustered->advance(20, diagnostics, 8));
      // A scene alone of 720 vertices: a cluster of three blocks that copy their windows from each other.
      const std::vector<SimulationSetup> alone{hanging_box(BoxScene{9, 8, 7, 5000.0, precision, integrator, 5})};
      const auto spread = gpu_batch(alone, in_clusters, diagnostics);
      FMPC_REQUIRE(spread && spread->advance(20, diagnostics, 8));
      gpu::GpuOptions per_step;
      per_step.persistent = false;
      const auto stepped = gpu_batch(scenes, per_step, diagnostics);
      FMPC_REQUIRE(stepped && stepped->advance(20, diagnostics, 8));
      // One thread per vertex: the springs' sliced layout in every integrator's kernels.
      per_step.gather_lanes = 1;
      const auto sliced = gpu_batch(scenes, per_step, diagnostics);
      FMPC_REQUIRE(sliced && sliced->advance(20, diagnostics, 8));
      FMPC_EXPECT(batch->kinetic_energy(1, diagnostics).has_value());
      FMPC_EXPECT(batch->potential_energy(1, diagnostics).has_value());
      FMPC_EXPECT(batch->largest_displacement(1, diagnostics).has_value());
      const Difference difference = cpu_gpu_difference(scenes[1], 20, gpu::GpuOptions{});
      FMPC_EXPECT(difference.positions <= position_tolerance(precision));
      if (diagnostics.has_errors()) note(describe(diagnostics));
    }
  }
  SimulationSetup setup = hanging_box(BoxScene{2, 1, 3});
  DiagnosticList probe;
  setup.time_step = 40.0 * check_stability(setup, probe)->critical_time_step;
  setup.refuse_unstable_time_step = false;
  DiagnosticList diagnostics;
  const auto run = gpu_simulation(setup, diagnostics);
  FMPC_REQUIRE(run);
  FMPC_EXPECT(!run->advance(5000, diagnostics, 16));
  FMPC_EXPECT(run->non_finite().has_value());
}

FMPC_GPU_TEST(probe_matches_cpu, "displacement and force probes: GPU equals CPU for every explicit integrator", true) {
  for (const ProbeLoad::Mode mode : {ProbeLoad::Mode::Displacement, ProbeLoad::Mode::Force}) {
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      for (const Integrator integrator : kGpuIntegrators) {
        const SceneDifference d = scene_difference(probed_box(precision, integrator, mode), 3001);
        std::ostringstream line;
        line << (mode == ProbeLoad::Mode::Displacement ? "displacement" : "force") << " probe, "
             << to_string(integrator) << ", " << name_of(precision) << ": max |GPU - CPU| after 3,001 steps "
             << d.state.positions << " m, " << d.state.velocities << " m/s, probe force " << d.probe_force << " N";
        note(line.str());
        FMPC_EXPECT(d.state.positions <= position_tolerance(precision));
        FMPC_EXPECT(d.state.velocities <= velocity_tolerance(precision));
        FMPC_EXPECT(d.probe_force <= (precision == Precision::Float ? 1e-3 : 1e-9));
      }
    }
  }
}

FMPC_GPU_TEST(strain_table_matches_cpu, "table-driven stiffness k(strain): GPU equals CPU, stiffness included", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    for (const Integrator integrator : kGpuIntegrators) {
      const SceneDifference d = scene_difference(strain_table_box(precision, integrator), 2000);
      std::ostringstream line;
      line << "strain table, " << to_string(integrator) << ", " << name_of(precision)
           << ": max |GPU - CPU| after 2,000 steps " << d.state.positions << " m, stiffness " << d.stiffness << " N/m";
      note(line.str());
      FMPC_EXPECT(d.state.positions <= position_tolerance(precision));
      FMPC_EXPECT(d.stiffness <= (precision == Precision::Float ? 1e-2 : 1e-9));
    }
  }
  // Device energy with a strain table: k at the current strain, as the CPU's elastic_energy.
  const SimulationSetup setup = strain_table_box(Precision::Double, Integrator::SemiImplicitEuler);
  DiagnosticList diagnostics;
  const auto cpu = sim::Simulation::create(setup, diagnostics);
  const auto device = gpu_simulation(setup, diagnostics);
  FMPC_REQUIRE(cpu && device && cpu->advance(500, diagnostics) && device->advance(500, diagnostics));
  const auto potential = device->potential_energy(diagnostics);
  FMPC_REQUIRE(potential);
  FMPC_EXPECT_WITHIN(*potential, *cpu->potential_energy(diagnostics), 1e-10 * std::abs(*cpu->potential_energy(diagnostics)) + 1e-12);
}

FMPC_GPU_TEST(undamped_network, "a network without dashpots (no damping array) matches the CPU", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    BoxScene scene;
    scene.precision = precision;
    SimulationSetup setup = hanging_box(scene);
    setup.springs.damping.clear();
    setup.nodal_damping_gamma0 = 1e-3;
    const Difference d = cpu_gpu_difference(setup, 2000, gpu::GpuOptions{});
    note(std::string("undamped springs, ") + name_of(precision) + ": max |GPU - CPU| " + std::to_string(d.positions) +
         " m");
    FMPC_EXPECT(d.positions <= position_tolerance(precision));
  }
}

// Implicit Euler: the same preconditioned CG as Eigen's, summed in another order, so the runs agree to the solver's
// tolerance rather than bitwise; GPU runs are bitwise reproducible.
FMPC_GPU_TEST(implicit_matches_cpu, "implicit Euler: GPU CG agrees with Eigen's, and GPU runs repeat bitwise", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    for (const bool with_probe : {false, true}) {
      SimulationSetup setup = with_probe
                                  ? probed_box(precision, Integrator::ImplicitEuler, ProbeLoad::Mode::Displacement)
                                  : hanging_box(BoxScene{3, 5, 2, 5000.0, precision, Integrator::ImplicitEuler});
      check_implicit_against_cpu(setup, std::string(with_probe ? "with a probe, " : "") + name_of(precision));
    }
  }
}

// The scene features on tiny scenes for compute-sanitizer: probes, a strain table, implicit Euler, no damping.
FMPC_GPU_TEST(sanitizer_scene_features, "sanitizer smoke: probe, strain table and implicit kernels", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    SimulationSetup probed = probed_box(precision, Integrator::SemiImplicitEuler, ProbeLoad::Mode::Force);
    SimulationSetup table = strain_table_box(precision, Integrator::VelocityVerlet);
    SimulationSetup implicit = probed_box(precision, Integrator::ImplicitEuler, ProbeLoad::Mode::Displacement);
    implicit.strain_stiffness = strain_table_box(precision, Integrator::ImplicitEuler).strain_stiffness;
    implicit.springs.damping.clear();
    implicit.implicit.max_iterations = kSanitizedCgIterations;
    // Implicit Euler three times: its solve in one block (the plan's choice for a mesh this small), its conjugate
    // gradient in one cooperative launch per step, then in per-iteration launches.
    gpu::GpuOptions grid, per_iteration;
    grid.cg_single_block = false;
    per_iteration.persistent = false;
    const std::pair<const SimulationSetup*, gpu::GpuOptions> runs[] = {
        {&probed, {}}, {&table, {}}, {&implicit, {}}, {&implicit, grid}, {&implicit, per_iteration}};
    for (const auto& [setup, options] : runs) {
      DiagnosticList diagnostics;
      const auto run = gpu_simulation(*setup, diagnostics, options);
      FMPC_REQUIRE(run && run->advance(12, diagnostics, 5));
      FMPC_EXPECT(run->potential_energy(diagnostics).has_value());
      FMPC_EXPECT(!run->current_stiffness(diagnostics).empty());
      (void)run->probe_reading(diagnostics);
      if (diagnostics.has_errors()) note(describe(diagnostics));
      FMPC_EXPECT(!diagnostics.has_errors());
    }
  }
}

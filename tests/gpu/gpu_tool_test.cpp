// Rigid tools and the material swap on the CUDA backend against the CPU (the host reference): the contact force is one
// FMPC_HD function (kernels/contact_math.h) in both backends' steps, so an explicit integrator's run with a tool
// posed between advances is the CPU's bits (the tolerance of tests/gpu/cpu_gpu_comparison.h, expected 0); implicit
// Euler's contact set and CG agree to the solver's tolerance; a tool's path, the persistent and graph launches, the
// material swapped between two steps and the device pointer to the positions give the same bits as the CPU.
#include <cuda_runtime_api.h>

#include <array>
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/fem/fem_model_builder.h"
#include "runtime/gpu/gpu_simulation.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/scene/spring_model_builder.h"
#include "tests/gpu/cpu_gpu_comparison.h"
#include "tests/gpu/gpu_test_harness.h"

using namespace fmpc;
using namespace fmpc::sim;
using namespace fmpc::gpu_test;

namespace {

// A 2 x 2 x 1 cm block (FEM, or springs), fixed at its base, and a sphere tip and a capsule shaft above the middle of
// its top face; 9 x 7 x 5 cells (or `cells`), so that no launch's blocks are full.
SimulationSetup block_with_tools(bool fem, Precision precision, Integrator integrator,
                                 std::array<int, 3> cells = {9, 7, 5}) {
  DiagnosticList diagnostics;
  BoxSpec box;
  box.size = {0.02, 0.02, 0.01};
  box.cells_x = cells[0];
  box.cells_y = cells[1];
  box.cells_z = cells[2];
  const Mesh mesh = generate_box(box, diagnostics);
  SimulationSetup setup;
  if (fem) {
    FemModelSpec spec;
    spec.youngs_modulus = {10e3};
    spec.poisson_ratio = {0.4};
    spec.mass.value = 1000.0;
    spec.damping_ratio = 0.5;
    if (auto built = build_fem_model(mesh, spec, diagnostics)) setup = *built;
  } else {
    SpringModelSpec spec;
    spec.stiffness.mapping = StiffnessMapping::VanGelder1998;
    spec.stiffness.value = 10e3;
    spec.mass.value = 1000.0;
    spec.damping.ratio = 0.5;
    if (auto built = build_spring_model(mesh, spec, diagnostics)) setup = *built;
    setup.tetrahedra = mesh.tetrahedra;
  }
  if (diagnostics.has_errors()) note("setup: " + describe(diagnostics));
  for (std::size_t v = 0; v < setup.rest_positions.size(); ++v)
    if (setup.rest_positions[v][2] == 0.0) setup.fixed_vertices.push_back(static_cast<std::int32_t>(v));
  setup.precision = precision;
  setup.integrator = integrator;
  setup.mass_damping = 5.0;
  RigidTool tip;
  tip.name = "tip";
  tip.radius = 0.003;
  tip.path = {ToolKeyframe{0.0, ToolPose{{0.0101, 0.0099, 0.0131}, {1.0, 0.0, 0.0, 0.0}}}};
  RigidTool shaft;
  shaft.name = "shaft";
  shaft.shape = RigidTool::Shape::Capsule;
  shaft.radius = 0.001;
  shaft.length = 0.01;
  // Lying along x (a quarter turn about y), just above the surface.
  const double s = std::sqrt(0.5);
  shaft.path = {ToolKeyframe{0.0, ToolPose{{0.004, 0.005, 0.0111}, {s, 0.0, s, 0.0}}}};
  setup.tools = {tip, shaft};
  return setup;
}

ToolPose at(double x, double y, double z, const ToolPose& like) { return ToolPose{{x, y, z}, like.orientation}; }

// Both simulations pressed and dragged by the same poses, one per advance of `steps`; `touched`, where given, counts
// the ticks at whose end each tool touched the tissue (under explicit integrators a penalty-pressed tip bounces, so
// that at a given tick one tool may be out of contact).
bool drive(Simulation& simulation, std::size_t steps, DiagnosticList& diagnostics, int* touched = nullptr) {
  const ToolPose tip = simulation.tool_poses().at(0), shaft = simulation.tool_poses().at(1);
  for (int tick = 1; tick <= 12; ++tick) {
    const double press = 0.0015 * std::min(1.0, tick / 6.0), slide = 0.0004 * tick;
    if (!simulation.set_tool_pose(0, 0, at(tip.position[0] + slide, tip.position[1], tip.position[2] - press, tip),
                                  diagnostics) ||
        !simulation.set_tool_pose(
            0, 1, at(shaft.position[0], shaft.position[1] + slide, shaft.position[2] - press, shaft), diagnostics) ||
        !simulation.advance(steps, diagnostics))
      return false;
    if (touched) {
      const std::vector<ToolReading> readings = simulation.tool_readings(0, diagnostics);
      for (std::size_t t = 0; t < readings.size() && t < 2; ++t) touched[t] += readings[t].contacts > 0 ? 1 : 0;
    }
  }
  return true;
}

double reading_difference(const std::vector<ToolReading>& a, const std::vector<ToolReading>& b) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (std::size_t t = 0; t < a.size(); ++t)
    for (std::size_t i = 0; i < 3; ++i)
      worst = std::max({worst, std::abs(a[t].force[i] - b[t].force[i]), std::abs(a[t].torque[i] - b[t].torque[i])});
  return worst;
}

}  // namespace

FMPC_GPU_TEST(tools_match_cpu, "tools posed between advances: every explicit integrator gives the CPU's bits", true) {
  for (const bool fem : {true, false}) {
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      for (const Integrator integrator : kGpuIntegrators) {
        const SimulationSetup setup = block_with_tools(fem, precision, integrator);
        DiagnosticList diagnostics;
        const auto cpu = Simulation::create(setup, diagnostics);
        const auto device = gpu_simulation(setup, diagnostics);
        FMPC_REQUIRE(cpu && device);
        int touched[2] = {0, 0};
        FMPC_REQUIRE(drive(*cpu, 40, diagnostics, touched) && drive(*device, 40, diagnostics));
        const double positions = max_difference(cpu->positions(diagnostics), device->positions(diagnostics));
        const std::vector<ToolReading> a = cpu->tool_readings(0, diagnostics),
                                       b = device->tool_readings(0, diagnostics);
        const double forces = reading_difference(a, b);
        std::ostringstream line;
        line << (fem ? "FEM" : "springs") << ", " << to_string(integrator) << ", " << name_of(precision)
             << ": max |GPU - CPU| after 12 poses: " << positions << " m; tool forces " << forces << " N; tip "
             << a.at(0).force[2] << " N on " << a.at(0).contacts << " vertices, shaft " << a.at(1).force[2] << " N on "
             << a.at(1).contacts << "; in contact at " << touched[0] << " and " << touched[1] << " of 12 ticks";
        note(line.str());
        FMPC_EXPECT(positions <= position_tolerance(precision));
        FMPC_EXPECT(forces == 0.0 || positions > 0.0);  // the same positions give the same readings
        FMPC_EXPECT(touched[0] > 0 && touched[1] > 0);
        FMPC_EXPECT(!diagnostics.has_errors());
      }
    }
  }
}

FMPC_GPU_TEST(tools_bitwise_launches, "tools: persistent, graph and per-step launches give the same bits, any check",
              true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    const SimulationSetup setup = block_with_tools(false, precision, Integrator::SemiImplicitEuler);
    DiagnosticList diagnostics;
    gpu::GpuOptions plain;
    plain.use_graphs = false;
    plain.persistent = false;
    const auto reference = gpu_simulation(setup, diagnostics, plain);
    FMPC_REQUIRE(reference && drive(*reference, 70, diagnostics));
    const auto expected = reference->positions(diagnostics);
    for (const bool persistent : {true, false}) {
      gpu::GpuOptions options;
      options.persistent = persistent;
      const auto run = gpu_simulation(setup, diagnostics, options);
      FMPC_REQUIRE(run && drive(*run, 70, diagnostics));
      FMPC_EXPECT(bitwise_equal(run->positions(diagnostics), expected));
    }
  }
}

FMPC_GPU_TEST(tools_path, "a tool's path (a pose per step) gives the CPU's bits", true) {
  SimulationSetup setup = block_with_tools(true, Precision::Double, Integrator::SemiImplicitEuler);
  setup.tools[0].path.push_back(ToolKeyframe{0.004, at(0.012, 0.0099, 0.0118, setup.tools[0].path[0].pose)});
  DiagnosticList diagnostics;
  const auto cpu = Simulation::create(setup, diagnostics);
  const auto device = gpu_simulation(setup, diagnostics);
  FMPC_REQUIRE(cpu && device && cpu->advance(700, diagnostics) && device->advance(700, diagnostics));
  const double difference = max_difference(cpu->positions(diagnostics), device->positions(diagnostics));
  note("a tool's path over 700 steps: max |GPU - CPU| " + std::to_string(difference) + " m");
  FMPC_EXPECT(difference == 0.0);
  FMPC_EXPECT(std::memcmp(&cpu->tool_poses()[0], &device->tool_poses()[0], sizeof(ToolPose)) == 0);
}

namespace {

// Implicit Euler with tools on the CPU and on CUDA, driven alike (drive, 5 steps of 1 ms per pose): the largest
// difference of the positions, within the solver's tolerance (the CGs agree to it, not to the bits), noted with the
// steps whose contact set still changed after their last solve on each; both kept for their reports.
struct ImplicitPair {
  std::unique_ptr<Simulation> cpu, device;
  double difference = 0.0;
};

bool implicit_against_cpu(SimulationSetup setup, ImplicitPair& pair, DiagnosticList& diagnostics) {
  setup.time_step = 1e-3;
  pair.cpu = Simulation::create(setup, diagnostics);
  pair.device = gpu_simulation(setup, diagnostics);
  if (!pair.cpu || !pair.device || !drive(*pair.cpu, 5, diagnostics) || !drive(*pair.device, 5, diagnostics))
    return false;
  pair.difference = max_difference(pair.cpu->positions(diagnostics), pair.device->positions(diagnostics));
  const double tolerance = setup.precision == Precision::Float ? 1e-5 : 1e-9;
  std::ostringstream line;
  line << "implicit Euler with tools, contact_rounds " << setup.implicit.contact_rounds << ", "
       << name_of(setup.precision) << ": max |GPU - CPU| " << pair.difference << " m (tolerance " << tolerance
       << "); steps whose set changed after their last solve: CPU "
       << pair.cpu->implicit_solver().contact_unsettled_steps << ", GPU "
       << pair.device->implicit_solver().contact_unsettled_steps << " of " << pair.device->implicit_solver().steps;
  note(line.str());
  FMPC_EXPECT(pair.difference <= tolerance);
  FMPC_EXPECT(!diagnostics.has_errors());
  return true;
}

}  // namespace

FMPC_GPU_TEST(tools_implicit, "implicit Euler with tools: the contact set and the CG agree with the CPU's", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    DiagnosticList diagnostics;
    ImplicitPair pair;
    FMPC_REQUIRE(implicit_against_cpu(block_with_tools(true, precision, Integrator::ImplicitEuler), pair, diagnostics));
  }
}

FMPC_GPU_TEST(tools_implicit_one_round,
              "implicit Euler with tools, contact_rounds 1: one solve per step with the step's first set, as the CPU's",
              true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    SimulationSetup setup = block_with_tools(true, precision, Integrator::ImplicitEuler);
    setup.implicit.contact_rounds = 1;
    DiagnosticList diagnostics;
    ImplicitPair pair;
    FMPC_REQUIRE(implicit_against_cpu(setup, pair, diagnostics));
    // The pressing moves the set within a step (the default solves again): counted on both (the CPU: 25 of 60 steps
    // in either precision), never warned about.
    const ImplicitSolverReport cpu = pair.cpu->implicit_solver(), device = pair.device->implicit_solver();
    FMPC_EXPECT(cpu.contact_unsettled_steps > 0 && device.contact_unsettled_steps > 0);
    FMPC_EXPECT(device.steps == cpu.steps);
    FMPC_EXPECT(diagnostics.warning_count() == 0);
  }
}

// Implicit Euler with tools (the contact rounds: the set predicted from each solve, the vertices re-assembled, the CG
// solved again) in every launch of the solve: the one block (springs on either mesh, FEM on the smaller), the
// cooperative grid, the fused and the separate per-iteration launches give the same bits, in the state, every step's
// record and the tools' readings; every step reaches the tolerance; and later rounds run (the one-round run of the
// same drive leaves steps unsettled; the note gives their iterations per step that needed them).
FMPC_GPU_TEST(tools_implicit_launches_bitwise,
              "implicit Euler with tools: every CG launch gives the same bits through the contact rounds", true) {
  for (const bool fem : {true, false}) {
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      for (const std::array<int, 3> cells : {std::array<int, 3>{9, 7, 5}, std::array<int, 3>{6, 5, 3}}) {
        SimulationSetup setup = block_with_tools(fem, precision, Integrator::ImplicitEuler, cells);
        setup.time_step = 1e-3;
        setup.implicit.tolerance = 1e-8;
        struct Run {
          std::vector<Point3> positions, velocities;
          std::vector<ImplicitStepRecord> records;
          ImplicitSolverReport report;
          std::vector<ToolReading> readings;
        };
        const auto run = [&](const SimulationSetup& scene, const GpuOptions& options, Run& out) {
          DiagnosticList diagnostics;
          const auto device = gpu_simulation(scene, diagnostics, options);
          if (!device || !drive(*device, 5, diagnostics)) return false;
          out = {device->positions(diagnostics), device->velocities(diagnostics), device->take_implicit_steps(),
                 device->implicit_solver(), device->tool_readings(0, diagnostics)};
          if (diagnostics.has_errors()) note(describe(diagnostics));
          return !diagnostics.has_errors();
        };
        const std::array<CgLaunch, 4> launches = cg_launches();
        Run first;
        FMPC_REQUIRE(run(setup, launches[0].options, first));
        const std::string what = std::string(fem ? "FEM " : "springs ") + std::to_string(cells[0]) + "x" +
                                 std::to_string(cells[1]) + "x" + std::to_string(cells[2]) + ", " + name_of(precision);
        for (std::size_t k = 1; k < launches.size(); ++k) {
          Run other;
          FMPC_REQUIRE(run(setup, launches[k].options, other));
          const bool same =
              bitwise_equal(first.positions, other.positions) && bitwise_equal(first.velocities, other.velocities) &&
              same_records(first.records, other.records) && reading_difference(first.readings, other.readings) == 0.0;
          note("implicit Euler with tools, " + what + ": " + launches[0].name + " and " + launches[k].name + " " +
               (same ? "bitwise equal" : "DIFFER"));
          FMPC_EXPECT(same);
        }
        SimulationSetup one_round = setup;
        one_round.implicit.contact_rounds = 1;
        Run single;
        FMPC_REQUIRE(run(one_round, launches[0].options, single));
        const double later =
            static_cast<double>(first.report.iterations_total) - static_cast<double>(single.report.iterations_total);
        std::ostringstream line;
        line << "implicit Euler with tools, " << what << ": a first solve "
             << static_cast<double>(single.report.iterations_total) / static_cast<double>(single.report.steps)
             << " iterations a step; later rounds "
             << later / static_cast<double>(std::max<std::size_t>(1, single.report.contact_unsettled_steps))
             << " a step that needed them (" << single.report.contact_unsettled_steps << " of " << single.report.steps
             << ")";
        note(line.str());
        FMPC_EXPECT(single.report.contact_unsettled_steps > 0);
        FMPC_EXPECT(later > 0.0);
        for (const ImplicitStepRecord& step : first.records) FMPC_EXPECT(step.relative_residual < 1e-8 && !step.capped);
      }
    }
  }
}

FMPC_GPU_TEST(tools_material_swap, "a material swapped between two steps: the GPU takes it as the CPU does", true) {
  for (const Integrator integrator : {Integrator::SemiImplicitEuler, Integrator::ImplicitEuler}) {
    for (const bool fem : {true, false}) {
      SimulationSetup setup = block_with_tools(fem, Precision::Double, integrator);
      setup.time_step = integrator == Integrator::ImplicitEuler ? 1e-3 : 1e-5;
      // The new material: every stiffness and element parameter 0.8 times the old (a softer patient).
      SimulationSetup softer = setup;
      for (double& k : softer.springs.stiffness) k *= 0.8;
      for (double& c : softer.springs.damping) c *= 0.8;
      for (ElementTerm& term : softer.elements.terms)
        term.parameter[0] = std::vector<double>(term.parameter[0].size(), 8e3);
      DiagnosticList diagnostics;
      const auto cpu = Simulation::create(setup, diagnostics);
      const auto device = gpu_simulation(setup, diagnostics);
      FMPC_REQUIRE(cpu && device && drive(*cpu, 20, diagnostics) && drive(*device, 20, diagnostics));
      FMPC_REQUIRE(cpu->replace_material(0, softer, diagnostics) && device->replace_material(0, softer, diagnostics));
      FMPC_REQUIRE(cpu->advance(100, diagnostics) && device->advance(100, diagnostics));
      const double difference = max_difference(cpu->positions(diagnostics), device->positions(diagnostics));
      const double tolerance = integrator == Integrator::ImplicitEuler ? 1e-9 : 1e-12;
      note(std::string(fem ? "FEM" : "springs") + ", " + to_string(integrator) + ": after the swap max |GPU - CPU| " +
           std::to_string(difference) + " m");
      FMPC_EXPECT(difference <= tolerance);
      const std::vector<double> k_cpu = cpu->current_stiffness(diagnostics),
                                k_gpu = device->current_stiffness(diagnostics);
      FMPC_EXPECT(k_cpu.size() == k_gpu.size());
      for (std::size_t s = 0; s < k_cpu.size() && s < k_gpu.size(); ++s) FMPC_EXPECT(k_cpu[s] == k_gpu[s]);
      FMPC_EXPECT(!diagnostics.has_errors());
    }
  }
}

FMPC_GPU_TEST(tools_device_positions, "device_positions points at the state positions() downloads", true) {
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    const SimulationSetup setup = block_with_tools(true, precision, Integrator::SemiImplicitEuler);
    DiagnosticList diagnostics;
    const auto device = gpu_simulation(setup, diagnostics);
    FMPC_REQUIRE(device && drive(*device, 33, diagnostics));
    const auto pointer = device->device_positions(0, diagnostics);
    FMPC_REQUIRE(pointer.has_value());
    FMPC_EXPECT(pointer->count == setup.rest_positions.size());
    FMPC_EXPECT(pointer->double_precision == (precision == Precision::Double));
    const std::size_t bytes = pointer->count * (pointer->double_precision ? sizeof(double) : sizeof(float));
    std::vector<unsigned char> x(bytes), y(bytes), z(bytes);
    FMPC_REQUIRE(cudaMemcpy(x.data(), pointer->x, bytes, cudaMemcpyDeviceToHost) == cudaSuccess &&
                 cudaMemcpy(y.data(), pointer->y, bytes, cudaMemcpyDeviceToHost) == cudaSuccess &&
                 cudaMemcpy(z.data(), pointer->z, bytes, cudaMemcpyDeviceToHost) == cudaSuccess);
    const std::vector<Point3> positions = device->positions(diagnostics);
    bool same = positions.size() == pointer->count;
    for (std::size_t v = 0; same && v < positions.size(); ++v) {
      const auto value = [&](const std::vector<unsigned char>& axis) {
        if (pointer->double_precision) {
          double d;
          std::memcpy(&d, axis.data() + v * sizeof d, sizeof d);
          return d;
        }
        float f;
        std::memcpy(&f, axis.data() + v * sizeof f, sizeof f);
        return static_cast<double>(f);
      };
      same = value(x) == positions[v][0] && value(y) == positions[v][1] && value(z) == positions[v][2];
    }
    FMPC_EXPECT(same);
  }
}

FMPC_GPU_TEST(tools_batch_refused, "a GPU batch of scenes with tools is refused with what to do", false) {
  const SimulationSetup setup = block_with_tools(false, Precision::Float, Integrator::SemiImplicitEuler);
  DiagnosticList diagnostics;
  FMPC_EXPECT(!gpu::batch_accepts({setup, setup}, 1, diagnostics));
  FMPC_EXPECT(
      first_error(diagnostics) ==
      "scene 1: a scene with rigid tools runs on its own on the GPU (its tools' poses are the launch's); run it "
      "as a simulation of its own");
}

// The contact kernels (tool readings, the implicit contact set) under compute-sanitizer: a few poses on each kind of
// tissue, explicit and implicit (CG capped: racecheck instruments every shared access of the cooperative CG); the
// implicit runs also with the per-iteration launches, fused and separate, which the plan (one block for the springs,
// the cooperative grid for FEM) does not take on this mesh.
FMPC_GPU_TEST(sanitizer_tools, "sanitizer smoke: rigid tool contact, explicit and implicit", true) {
  const std::array<CgLaunch, 4> launches = cg_launches();
  for (const bool fem : {true, false}) {
    for (const Integrator integrator : {Integrator::SemiImplicitEuler, Integrator::ImplicitEuler}) {
      SimulationSetup setup = block_with_tools(fem, Precision::Float, integrator);
      if (integrator == Integrator::ImplicitEuler) {
        setup.time_step = 1e-3;
        setup.implicit.max_iterations = kSanitizedCgIterations;
      }
      for (std::size_t k : {0, 2, 3}) {
        if (k > 0 && integrator != Integrator::ImplicitEuler) break;
        DiagnosticList diagnostics;
        const auto run = gpu_simulation(setup, diagnostics, launches[k].options);
        FMPC_REQUIRE(run && drive(*run, 2, diagnostics));
        FMPC_EXPECT(run->tool_readings(0, diagnostics).size() == 2);
        if (diagnostics.has_errors()) note(describe(diagnostics));
        FMPC_EXPECT(!diagnostics.has_errors());
      }
    }
  }
}

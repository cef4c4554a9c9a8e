// The quasi-static press of a scene's first rigid tool (docs/trade.md, "Measured: the liver pressed by a sphere"):
// the scene built with its mesh, law and element changed by the arguments, the tool lowered from its path's first
// pose to its last over `lowering` implicit Euler steps of 1 s (Newton steps of the static problem: h^2 K dominates
// the mass, as tests/support/hertz_contact.h does) and held until its force changes by less than `tolerance` of
// itself. Prints one line: the mesh, the force, the CPU time of the build (meshing included) and of the press, and the
// press's wall time (the figure for backend=cuda, whose host thread waits on the device).
//   fmpc_graded_press_bench SCENE.yaml [size_near=H] [size_far=H] [near_distance=D] [grading=G] [law=KEYWORD]
//       [element=KEYWORD] [refinements=N] [solver=direct|cg] [lowering=4] [tolerance=1e-6] [most_steps=30] [label=TEXT]
//       [keep_surface=0|1] [split_surface=0|1] [stiffness_ratio=R] [backend=cpu|cuda]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "bench/setup/process_clock.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/io/input_file.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"

namespace {

using namespace fmpc;

int fail(const char* what, const DiagnosticList& diagnostics) {
  std::fprintf(stderr, "%s\n", what);
  for (const Diagnostic& d : diagnostics.items())
    if (d.severity == Severity::Error) std::fprintf(stderr, "  %s\n", d.message.c_str());
  return 2;
}

double dot(const sim::Point3& a, const sim::Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: fmpc_graded_press_bench SCENE.yaml [key=value ...]\n");
    return 2;
  }
  DiagnosticList diagnostics;
  const std::string path = argv[1];
  std::string read_error;
  const auto text = sim::read_input_file(path, sim::kMaxSceneFileBytes, "scene file", read_error);
  if (!text) return std::fprintf(stderr, "%s\n", read_error.c_str()), 2;
  auto scene = sim::parse_scene(path, *text, diagnostics);
  if (!scene) return fail("cannot parse the scene", diagnostics);
  unsigned refinements = 0;
  int lowering = 4, most_steps = 30;
  double tolerance = 1e-6;
  std::string label = "scene";
  sim::Backend backend = sim::Backend::Cpu;
  sim::VolumeMeshOptions& meshing = scene->mesh.surface.options;
  for (int i = 2; i < argc; ++i) {
    const std::string argument = argv[i];
    const std::size_t equals = argument.find('=');
    const std::string key = argument.substr(0, equals), value = equals == std::string::npos ? "" : argument.substr(equals + 1);
    if (key == "size_near") {
      meshing.size.size_near = std::atof(value.c_str());
      scene->mesh.surface.size_near_given = true;
    } else if (key == "size_far") {
      meshing.size.size_far = std::atof(value.c_str());
      scene->mesh.surface.size_far_given = true;
    } else if (key == "near_distance") {
      meshing.size.near_distance = std::atof(value.c_str());
    } else if (key == "grading") {
      meshing.size.grading = std::atof(value.c_str());
    } else if (key == "law" || key == "element") {
      scene->model = sim::ForceModel::Elements;
      if (key == "law") {
        const sim::ElementLawRow* row = sim::fem_law_by_keyword(value);
        if (!row) return std::fprintf(stderr, "unknown law %s\n", value.c_str()), 2;
        scene->element_law = row->law;
      } else {
        const sim::ElementKindRow* row = sim::element_kind_by_keyword(value);
        if (!row) return std::fprintf(stderr, "unknown element %s\n", value.c_str()), 2;
        scene->element_kind = row->kind;
      }
    } else if (key == "refinements") {
      refinements = static_cast<unsigned>(std::atoi(value.c_str()));
    } else if (key == "lowering") {
      lowering = std::atoi(value.c_str());
    } else if (key == "tolerance") {
      tolerance = std::atof(value.c_str());
    } else if (key == "most_steps") {
      most_steps = std::atoi(value.c_str());
    } else if (key == "solver") {
      if (value != "direct" && value != "cg") return std::fprintf(stderr, "solver: direct or cg\n"), 2;
      scene->solver.method = value == "direct" ? sim::ImplicitMethod::Direct : sim::ImplicitMethod::ConjugateGradient;
    } else if (key == "keep_surface" || key == "split_surface") {
      if (value != "0" && value != "1") return std::fprintf(stderr, "%s: 0 or 1\n", key.c_str()), 2;
      (key == "keep_surface" ? meshing.keep_surface : meshing.split_surface) = value == "1";
    } else if (key == "backend") {
      if (value != "cpu" && value != "cuda") return std::fprintf(stderr, "backend: cpu or cuda\n"), 2;
      backend = value == "cuda" ? sim::Backend::Cuda : sim::Backend::Cpu;
    } else if (key == "stiffness_ratio") {
      scene->contact_stiffness_ratio = std::atof(value.c_str());
    } else if (key == "label") {
      label = value;
    } else {
      std::fprintf(stderr, "unknown argument %s\n", argument.c_str());
      return 2;
    }
  }
  if (scene->tools.empty() || scene->tools.front().path.empty())
    return std::fprintf(stderr, "the scene has no tool to press\n"), 2;

  const double build_start = bench::cpu_seconds();
  auto built = sim::build_scene(*scene, diagnostics, refinements);
  if (!built) return fail("cannot build the scene", diagnostics);
  const double build_cpu = bench::cpu_seconds() - build_start;

  sim::SimulationSetup setup = built->setup;
  setup.integrator = sim::Integrator::ImplicitEuler;
  setup.precision = sim::Precision::Double;
  setup.time_step = 1.0;
  setup.threads = 1;
  const sim::ToolPose first = setup.tools.front().path.front().pose, last = setup.tools.front().path.back().pose;
  setup.tools.front().path = {sim::ToolKeyframe{0.0, first}};
  const std::size_t vertices = setup.rest_positions.size(), tetrahedra = setup.tetrahedra.size();
  sim::SimulationOptions options;
  options.backend = backend;
  std::vector<sim::SimulationSetup> scenes;
  scenes.push_back(std::move(setup));
  const double press_start = bench::cpu_seconds();
  const auto wall_start = std::chrono::steady_clock::now();
  const auto simulation = sim::Simulation::create(std::move(scenes), options, diagnostics);
  if (!simulation) return fail("cannot create the simulation", diagnostics);
  sim::Point3 direction{};
  for (std::size_t a = 0; a < 3; ++a) direction[a] = last.position[a] - first.position[a];
  const double travel = std::sqrt(dot(direction, direction));
  double force = 0.0, previous = 0.0, change = 0.0;
  std::size_t contacts = 0;
  int steps = 0;
  for (int step = 1; step <= most_steps; ++step) {
    sim::ToolPose pose = first;
    const double along = std::min(1.0, static_cast<double>(step) / lowering);
    for (std::size_t a = 0; a < 3; ++a) pose.position[a] = first.position[a] + along * direction[a];
    if (!simulation->set_tool_pose(0, 0, pose, diagnostics) || !simulation->advance(1, diagnostics))
      return fail("the press failed", diagnostics);
    const sim::ToolReading reading = simulation->tool_readings(0, diagnostics).front();
    force = -dot(reading.force, direction) / travel;  // the tissue pushes back against the travel
    contacts = reading.contacts;
    steps = step;
    change = std::abs(force - previous) / std::max(std::abs(force), 1e-300);
    if (step > lowering && change <= tolerance) break;
    previous = force;
  }
  const double press_cpu = bench::cpu_seconds() - press_start;
  const double press_wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const sim::ImplicitSolverReport solver = simulation->implicit_solver();
  std::printf("%-28s vertices %7zu tetrahedra %8zu force_N %.6g contacts %4zu steps %2d last_change %.1e "
              "build_cpu_s %7.2f press_cpu_s %8.2f press_wall_s %8.2f cg_iterations %llu capped_steps %zu\n",
              label.c_str(), vertices, tetrahedra, force, contacts, steps, change, build_cpu, press_cpu, press_wall,
              static_cast<unsigned long long>(solver.iterations_total), solver.capped_steps);
  return change <= tolerance ? 0 : 1;
}

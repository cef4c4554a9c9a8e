#pragma once
// A rigid sphere pressed into a thick elastic block, against Hertz's F = 4/3 E* sqrt(R) d^1.5 with E* = E / (1 - nu^2)
// (K. L. Johnson, Contact Mechanics, 1985, section 4.2): what tests/unit/rigid_tool_test.cpp checks on a small mesh
// and bench/contact/hertz_bench.cpp converges on finer ones (docs/simulator.md, "Rigid tools").
//
// The block is a quarter (x, y >= 0) of a co-rotational FEM cube of side `extent` contact radii a = sqrt(R d): the
// planes x = 0 and y = 0 hold x and y (symmetry), the base is fixed, and the sphere's centre stays on the x = y = 0
// axis, so the whole block's force is four times the quarter's. Cells grow geometrically by `growth` from `first_cell`
// (a fraction of a) at the contact to the block's far faces, so that a runs over several elements while the block
// stays thick (a layer of thickness H stiffens the contact by about 1 + 1.1 a / H: Dimitriadis et al. 2002). The
// sphere is lowered to depth d over a few implicit Euler steps of 1 s (which are Newton steps of the static problem:
// h^2 K dominates the mass) and held until the force changes by less than 1e-9 of itself.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/fem/fem_model_builder.h"
#include "runtime/integrate/simulation.h"
#include "runtime/mesh/generated_mesh.h"

namespace fmpc::test_support {

struct HertzCase {
  double radius = 0.01;           // R, m
  double depth = 0.0005;          // d, m (d / R = 0.05)
  double youngs_modulus = 10e3;   // Pa
  double poisson_ratio = 0.3;
  double extent = 40.0;           // the block's side, in contact radii
  double first_cell = 0.25;       // the cells' size at the contact, in contact radii
  double growth = 1.3;            // each cell this many times the one before it, away from the contact
  double contact_stiffness_ratio = sim::kDefaultContactStiffnessRatio;
  int element = sim::default_element_kind().kind;  // the element kind (its index in element_kind_rows())
  // The linear solve of each implicit step.
  sim::ImplicitMethod method = sim::ImplicitMethod::Automatic;
  int lowering_steps = 4;
  int most_steps = 60;
};

struct HertzResult {
  bool ok = false;
  std::string error;
  double force = 0.0;  // N, the whole block's
  double hertz = 0.0;  // N
  double relative_error = 0.0;
  int cells = 0;  // per axis
  std::size_t vertices = 0, tetrahedra = 0, contacts = 0;
  int steps = 0;
  double seconds = 0.0;
};

inline double hertz_force(const HertzCase& c) {
  const double effective = c.youngs_modulus / (1.0 - c.poisson_ratio * c.poisson_ratio);
  return 4.0 / 3.0 * effective * std::sqrt(c.radius) * std::pow(c.depth, 1.5);
}

// Grid coordinates 0 = x_0 < x_1 < ... < x_n = length, the first cell `first`, each next `growth` times larger (the
// last one stretched to end at `length`).
inline std::vector<double> graded_coordinates(double length, double first, double growth) {
  std::vector<double> x = {0.0};
  double cell = first;
  while (x.back() + cell < length * (1.0 - 1e-9)) {
    x.push_back(x.back() + cell);
    cell *= growth;
  }
  if (length - x.back() < 0.5 * cell / growth && x.size() > 1) x.pop_back();
  x.push_back(length);
  return x;
}

inline HertzResult run_hertz(const HertzCase& c, sim::Backend backend = sim::Backend::Cpu) {
  HertzResult result;
  const auto start = std::chrono::steady_clock::now();
  const double a = std::sqrt(c.radius * c.depth);
  const double side = c.extent * a;
  const std::vector<double> grid = graded_coordinates(side, c.first_cell * a, c.growth);
  const int n = static_cast<int>(grid.size()) - 1;
  result.cells = n;
  DiagnosticList diagnostics;
  sim::BoxSpec box;
  box.size = {static_cast<double>(n), static_cast<double>(n), static_cast<double>(n)};
  box.cells_x = box.cells_y = box.cells_z = n;
  sim::Mesh mesh = sim::generate_box(box, diagnostics);
  // Each cell maps to a box of the graded grid: affine on each tetrahedron, so every element keeps its orientation.
  // The contact is at the top face's corner x = y = 0, z = side: z runs from the top down.
  for (sim::Point3& p : mesh.points) {
    const auto index = [&](double value) { return static_cast<std::size_t>(std::lround(value)); };
    p = {grid[index(p[0])], grid[index(p[1])], side - grid[static_cast<std::size_t>(n) - index(p[2])]};
  }
  sim::FemModelSpec spec;
  spec.youngs_modulus = {c.youngs_modulus};
  spec.poisson_ratio = {c.poisson_ratio};
  spec.mass.value = 1000.0;
  spec.damping_ratio = 0.0;
  spec.element = c.element;
  auto built = sim::build_fem_model(mesh, spec, diagnostics);
  if (!built) {
    result.error = diagnostics.items().empty() ? "build failed" : diagnostics.items().front().message;
    return result;
  }
  sim::SimulationSetup setup = std::move(*built);
  setup.fixed_axes.assign(setup.rest_positions.size(), 0);
  for (std::size_t v = 0; v < setup.rest_positions.size(); ++v) {
    const sim::Point3& p = setup.rest_positions[v];
    if (p[2] == 0.0) setup.fixed_vertices.push_back(static_cast<std::int32_t>(v));
    if (p[0] == 0.0) setup.fixed_axes[v] |= 1;
    if (p[1] == 0.0) setup.fixed_axes[v] |= 2;
  }
  setup.integrator = sim::Integrator::ImplicitEuler;
  setup.precision = sim::Precision::Double;
  setup.time_step = 1.0;
  setup.contact_stiffness_ratio = c.contact_stiffness_ratio;
  setup.implicit.method = c.method;
  sim::RigidTool sphere;
  sphere.name = "sphere";
  sphere.radius = c.radius;
  sphere.path = {sim::ToolKeyframe{0.0, sim::ToolPose{{0.0, 0.0, side + c.radius + 1e-9}, {1.0, 0.0, 0.0, 0.0}}}};
  setup.tools = {sphere};
  result.vertices = setup.rest_positions.size();
  result.tetrahedra = setup.tetrahedra.size();
  sim::SimulationOptions options;
  options.backend = backend;
  std::vector<sim::SimulationSetup> scenes;
  scenes.push_back(std::move(setup));
  const auto simulation = sim::Simulation::create(std::move(scenes), options, diagnostics);
  if (!simulation) {
    result.error = diagnostics.items().empty() ? "create failed" : diagnostics.items().front().message;
    return result;
  }
  double previous = 0.0;
  for (int step = 1; step <= c.most_steps; ++step) {
    const double lowered = c.depth * std::min(1.0, static_cast<double>(step) / c.lowering_steps);
    if (!simulation->set_tool_pose(0, 0, sim::ToolPose{{0.0, 0.0, side + c.radius - lowered}, {1.0, 0.0, 0.0, 0.0}},
                                   diagnostics) ||
        !simulation->advance(1, diagnostics)) {
      result.error = diagnostics.items().empty() ? "step failed" : diagnostics.items().front().message;
      return result;
    }
    const std::vector<sim::ToolReading> readings = simulation->tool_readings(0, diagnostics);
    result.force = 4.0 * readings.front().force[2];
    result.contacts = readings.front().contacts;
    result.steps = step;
    if (step > c.lowering_steps && std::abs(result.force - previous) <= 1e-9 * std::abs(result.force)) break;
    previous = result.force;
  }
  result.hertz = hertz_force(c);
  result.relative_error = result.force / result.hertz - 1.0;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.ok = true;
  return result;
}

}  // namespace fmpc::test_support

// Rigid tools in contact (kernels/contact_math.h, runtime/integrate/rigid_tools.h, Simulation's tools): the penalty
// force's exact values and its energy, the readings, the paths, the stability bound, the checks of bad input, Hertz
// on a small mesh, the force while sliding across elements, a CPU batch against its scenes alone, and implicit
// Euler's contact rounds (solver.contact_rounds).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>

#include "kernels/contact_math.h"
#include "runtime/fem/fem_model_builder.h"
#include "runtime/integrate/simulation.h"
#include "runtime/mesh/generated_mesh.h"
#include "tests/support/error_messages.h"
#include "tests/support/hertz_contact.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

using fmpc::testing::errors_of;

// A 2 x 2 x 1 cm block of 10 kPa FEM tissue (cells of 2.5 mm), fixed at its base, and a sphere of 3 mm above the
// middle of its top face.
SimulationSetup block_with_sphere(Integrator integrator = Integrator::SemiImplicitEuler, int cells = 8,
                                  const char* element = "linear") {
  DiagnosticList diagnostics;
  BoxSpec box;
  box.size = {0.02, 0.02, 0.01};
  box.cells_x = box.cells_y = cells;
  box.cells_z = cells / 2;
  const Mesh mesh = generate_box(box, diagnostics);
  FemModelSpec spec;
  spec.youngs_modulus = {10e3};
  spec.poisson_ratio = {0.3};
  spec.mass.value = 1000.0;
  spec.damping_ratio = 0.5;
  spec.element = element_kind_by_keyword(element)->kind;
  auto setup = build_fem_model(mesh, spec, diagnostics);
  REQUIRE(setup);
  for (std::size_t v = 0; v < setup->rest_positions.size(); ++v)
    if (setup->rest_positions[v][2] == 0.0) setup->fixed_vertices.push_back(static_cast<std::int32_t>(v));
  setup->integrator = integrator;
  setup->precision = Precision::Double;
  RigidTool sphere;
  sphere.name = "tip";
  sphere.radius = 0.003;
  sphere.path = {ToolKeyframe{0.0, ToolPose{{0.01, 0.01, 0.0131}, {1.0, 0.0, 0.0, 0.0}}}};
  setup->tools = {sphere};
  return *setup;
}

ToolPose at(double x, double y, double z) { return ToolPose{{x, y, z}, {1.0, 0.0, 0.0, 0.0}}; }

// Steps `simulation` to the end of haptic tick `tick` (ticks of 1 ms) at its automatic step.
bool advance_to_tick(Simulation& simulation, int tick, DiagnosticList& diagnostics) {
  const double steps = steps_covering(tick * 1e-3 - simulation.time(), simulation.stability().time_step);
  return simulation.advance(static_cast<std::size_t>(steps), diagnostics);
}

}  // namespace

TEST_CASE("tools: a sphere's and a capsule's penetration and force, exact", "[tools]") {
  const kernels::ToolShape<double> sphere{1.0, 2.0, 3.0, 1.0, 2.0, 3.0, 0.5};
  double nx, ny, nz, depth;
  REQUIRE(kernels::tool_penetration(sphere, 1.0, 2.0, 3.25, nx, ny, nz, depth));
  CHECK(nx == 0.0);
  CHECK(ny == 0.0);
  CHECK(nz == 1.0);
  CHECK(depth == 0.25);
  CHECK_FALSE(kernels::tool_penetration(sphere, 1.0, 2.0, 3.5, nx, ny, nz, depth));  // on the surface: no force
  CHECK_FALSE(kernels::tool_penetration(sphere, 1.0, 2.0, 3.0, nx, ny, nz, depth));  // at the centre: no direction
  // A capsule along x from (0, 0, 0) to (2, 0, 0): beside its axis, and beyond its end (the cap).
  const kernels::ToolShape<double> capsule{0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 1.0};
  REQUIRE(kernels::tool_penetration(capsule, 1.5, 0.0, -0.75, nx, ny, nz, depth));
  CHECK(nx == 0.0);
  CHECK(nz == -1.0);
  CHECK(depth == 0.25);
  REQUIRE(kernels::tool_penetration(capsule, 2.5, 0.0, 0.0, nx, ny, nz, depth));
  CHECK(nx == 1.0);
  CHECK(depth == 0.5);
  const kernels::ContactView<double> contact{&capsule, 1, nullptr, nullptr};
  double f[3] = {1.0, 2.0, 3.0};  // added to
  kernels::add_contact_force(contact, 8.0, 0.0, 1.5, 0.0, -0.75, 0.0, 0.0, 0.0, f[0], f[1], f[2]);
  CHECK(f[0] == 1.0);
  CHECK(f[1] == 2.0);
  CHECK(f[2] == 3.0 - 8.0 * 0.25);
  // Implicit Euler's linear model: inside now, and predicted inside after moving out by less than the depth.
  CHECK(kernels::contact_set(contact, 1.5, 0.0, -0.75, nullptr) == 1u);
  const double out_a_little[3] = {0.0, 0.0, -0.2}, out_beyond[3] = {0.0, 0.0, -0.3}, in_again[3] = {0.0, 0.0, 0.6};
  CHECK(kernels::contact_set(contact, 1.5, 0.0, -0.75, out_a_little) == 1u);
  CHECK(kernels::contact_set(contact, 1.5, 0.0, -0.75, out_beyond) == 0u);
  CHECK(kernels::contact_set(contact, 1.5, 0.0, -1.25, in_again) == 1u);  // outside now, inside after moving
  double block[6], change[3];
  kernels::contact_linear_model(contact, 1u, 8.0, 1.5, 0.0, -0.75, block, change);
  CHECK(block[0] == 0.0);
  CHECK(block[5] == 8.0);
  CHECK(change[2] == 0.0);  // the model's force at x0 is the force f0 holds
  // Outside by 0.25 but active: the model's linear force there is attraction, -8 x 0.25 along the outward -z.
  kernels::contact_linear_model(contact, 1u, 8.0, 1.5, 0.0, -1.25, block, change);
  CHECK(block[5] == 8.0);
  CHECK(change[2] == 8.0 * 0.25);
  // Inside but not active (the solution moves it out): f0's force is taken back.
  kernels::contact_linear_model(contact, 0u, 8.0, 1.5, 0.0, -0.75, block, change);
  CHECK(block[5] == 0.0);
  CHECK(change[2] == 8.0 * 0.25);
}

TEST_CASE("tools: the force is minus the gradient of the penalty energy k d^2 / 2 (seeded)", "[tools]") {
  std::mt19937 random(27);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  int inside = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const kernels::ToolShape<double> tool{coordinate(random),
                                          coordinate(random),
                                          coordinate(random),
                                          coordinate(random),
                                          coordinate(random),
                                          coordinate(random),
                                          0.8};
    const kernels::ContactView<double> contact{&tool, 1, nullptr, nullptr};
    const double p[3] = {coordinate(random), coordinate(random), coordinate(random)};
    const auto energy = [&](const double* x) {
      double nx, ny, nz, depth;
      return kernels::tool_penetration(tool, x[0], x[1], x[2], nx, ny, nz, depth) ? 0.5 * 3.0 * depth * depth : 0.0;
    };
    double f[3] = {0.0, 0.0, 0.0};
    kernels::add_contact_force(contact, 3.0, 0.0, p[0], p[1], p[2], 0.0, 0.0, 0.0, f[0], f[1], f[2]);
    if (f[0] != 0.0 || f[1] != 0.0 || f[2] != 0.0) ++inside;
    for (int axis = 0; axis < 3; ++axis) {
      double plus[3] = {p[0], p[1], p[2]}, minus[3] = {p[0], p[1], p[2]};
      plus[axis] += 1e-6;
      minus[axis] -= 1e-6;
      const double gradient = (energy(plus) - energy(minus)) / 2e-6;
      CHECK(f[axis] == Approx(-gradient).margin(1e-6));
    }
  }
  CHECK(inside > 100);  // the trials cover both sides of the surface
}

TEST_CASE("tools: readings sum -f over the vertices inside, the torque about the tool's origin", "[tools]") {
  RigidTool capsule;
  capsule.shape = RigidTool::Shape::Capsule;
  capsule.radius = 1.0;
  capsule.length = 4.0;
  // The tool's z axis turned onto the world's x axis: a quarter turn about y.
  const double s = std::sqrt(0.5);
  const ToolPose pose{{0.0, 0.0, 0.0}, {s, 0.0, s, 0.0}};
  const kernels::ToolShape<double> shape = tool_shape(capsule, pose);
  CHECK(shape.bx == Approx(4.0));
  CHECK(shape.by == Approx(0.0).margin(1e-15));
  CHECK(shape.bz == Approx(0.0).margin(1e-15));
  // Two vertices 0.5 inside below the axis at x = 1 and x = 3, one outside.
  const std::vector<Point3> positions = {{1.0, 0.0, -0.5}, {3.0, 0.0, -0.5}, {2.0, 0.0, 1.5}};
  const std::vector<ToolReading> readings = read_tools({capsule}, {pose}, {10.0, 10.0, 10.0}, positions);
  REQUIRE(readings.size() == 1);
  const ToolReading& r = readings[0];
  CHECK(r.contacts == 2);
  CHECK(r.deepest == Approx(0.5));
  // Each vertex is pushed down (-z) by 10 x 0.5: the tool is pushed up by 10 in all.
  CHECK(r.force[2] == Approx(10.0));
  CHECK(r.force[0] == Approx(0.0).margin(1e-12));
  // Torque about the origin: sum of x_v x (+5 z) = (1 + 3) x 5 about -y.
  CHECK(r.torque[1] == Approx(-20.0));
  CHECK(r.torque[0] == Approx(0.0).margin(1e-12));
  CHECK(r.torque[2] == Approx(0.0).margin(1e-12));
}

TEST_CASE("tools: a path's poses are linear in position, nlerp in orientation, held at the ends", "[tools]") {
  RigidTool tool;
  tool.radius = 1.0;
  const double s = std::sqrt(0.5);
  tool.path = {ToolKeyframe{1.0, ToolPose{{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0, 0.0}}},
               ToolKeyframe{3.0, ToolPose{{2.0, 4.0, -6.0}, {-s, 0.0, 0.0, -s}}}};  // -q: the shorter way round
  CHECK(tool_pose_at(tool, 0.0).position == Point3{0.0, 0.0, 0.0});
  CHECK(tool_pose_at(tool, 5.0).position == Point3{2.0, 4.0, -6.0});
  const ToolPose middle = tool_pose_at(tool, 2.0);
  CHECK(middle.position == Point3{1.0, 2.0, -3.0});
  // Half way from the identity to a quarter turn about z: an eighth turn, (cos 22.5, 0, 0, sin 22.5).
  CHECK(middle.orientation[0] == Approx(std::cos(M_PI / 8)));
  CHECK(middle.orientation[3] == Approx(std::sin(M_PI / 8)));
}

TEST_CASE("tools: the explicit critical step shrinks by 1 / sqrt(1 + ratio) where a tool can touch", "[tools]") {
  SimulationSetup setup = block_with_sphere();
  DiagnosticList diagnostics;
  SimulationSetup without = setup;
  without.tools.clear();
  const auto with_tools = check_stability(setup, diagnostics);
  const auto plain = check_stability(without, diagnostics);
  REQUIRE(with_tools);
  REQUIRE(plain);
  // The limiting vertex of the block is on its surface: the bound scales exactly.
  CHECK(with_tools->omega_max == Approx(plain->omega_max * std::sqrt(1.0 + kDefaultContactStiffnessRatio)));
  const std::vector<double> k = contact_stiffness(setup);
  const std::vector<unsigned char> surface = surface_vertices(setup);
  const VertexBounds bounds = vertex_bounds(setup);
  std::size_t interior = 0;
  for (std::size_t v = 0; v < k.size(); ++v) {
    if (!surface[v]) {
      CHECK(k[v] == 0.0);
      ++interior;
    } else {
      CHECK(k[v] == kDefaultContactStiffnessRatio * bounds.stiffness[v]);
    }
  }
  CHECK(interior == 7 * 7 * 3);  // the 8 x 8 x 4 cells' inner vertices
}

TEST_CASE("tools: contact damping: its force, its reading, its stability bound, and implicit Euler refuses it",
          "[tools]") {
  // The force: k d - c (v . n) along the outward normal, never below zero.
  const kernels::ToolShape<double> sphere{0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0};
  const kernels::ContactView<double> contact{&sphere, 1, nullptr, nullptr};
  const auto force_z = [&](double c, double vz) {
    double f[3] = {0.0, 0.0, 0.0};
    kernels::add_contact_force(contact, 8.0, c, 0.0, 0.0, 0.75, 0.0, 0.0, vz, f[0], f[1], f[2]);
    CHECK(f[0] == 0.0);
    return f[2];
  };
  CHECK(force_z(0.0, -5.0) == 2.0);           // no damping: the velocity plays no part
  CHECK(force_z(3.0, -0.5) == 2.0 + 1.5);     // moving in (v . n < 0): pushed out harder
  CHECK(force_z(3.0, 0.5) == 2.0 - 1.5);      // moving out: less
  CHECK(force_z(3.0, 1.0) == 0.0);            // never pulls the surface onto the tool
  CHECK(contact_damping_coefficient(0.5, 400.0, 0.01) == Approx(2.0));  // 2 x 0.5 x sqrt(400 x 0.01)

  // The reading sums the damper's force too, from the velocities given.
  SimulationSetup setup = block_with_sphere();
  setup.contact_damping_ratio = 1.0;
  const std::vector<double> k = contact_stiffness(setup);
  const std::vector<double> c = contact_damping(setup, k);
  REQUIRE(c.size() == k.size());
  for (std::size_t v = 0; v < k.size(); ++v) CHECK(c[v] == 2.0 * std::sqrt(k[v] * setup.mass[v]));
  CHECK(contact_damping(block_with_sphere(), k).empty());  // ratio 0: none
  std::vector<Point3> positions = setup.rest_positions, velocities(positions.size(), Point3{0.0, 0.0, 0.0});
  const ToolPose pressed = at(0.01, 0.01, 0.0125);  // 0.5 mm into the top face's middle vertex
  const auto still = read_tools(setup.tools, {pressed}, k, positions, c, velocities);
  for (Point3& v : velocities) v = {0.0, 0.0, -0.01};  // moving down, away from the sphere above
  const auto away = read_tools(setup.tools, {pressed}, k, positions, c, velocities);
  for (Point3& v : velocities) v = {0.0, 0.0, 0.001};  // moving up into the sphere
  const auto into = read_tools(setup.tools, {pressed}, k, positions, c, velocities);
  REQUIRE(still.at(0).contacts > 0);
  CHECK(still[0].force == read_tools(setup.tools, {pressed}, k, positions)[0].force);
  CHECK(into[0].force[2] > still[0].force[2]);  // the tissue pushes the tool up harder
  CHECK(away[0].force[2] < still[0].force[2]);
  CHECK(away[0].force[2] >= 0.0);

  // The stability bound: the damper's rate enters the damping bound, so the explicit step shrinks a little.
  DiagnosticList diagnostics;
  const auto undamped = check_stability(block_with_sphere(), diagnostics);
  const auto damped = check_stability(setup, diagnostics);
  REQUIRE(undamped);
  REQUIRE(damped);
  CHECK(damped->damping_rate_max > undamped->damping_rate_max);
  CHECK(damped->critical_time_step < undamped->critical_time_step);

  // The damped contact in the engine, briefly (the chatter case below runs it long, in the Release suite only).
  {
    DiagnosticList messages;
    auto simulation = Simulation::create(setup, messages);
    REQUIRE(simulation);
    // Ten ticks of 1 ms, the pose reached over the first: the pressed vertices bounce off and come back within them
    // (a wave crosses the 1 cm block in about 3 ms).
    double largest = 0.0;
    for (int tick = 1; tick <= 10; ++tick) {
      REQUIRE(simulation->set_tool_pose(0, 0, pressed, messages));
      REQUIRE(advance_to_tick(*simulation, tick, messages));
      const double force = simulation->tool_readings(0, messages).at(0).force[2];
      REQUIRE(std::isfinite(force));
      largest = std::max(largest, force);
    }
    CHECK(largest > 0.0);
  }

  // Implicit Euler refuses it.
  SimulationSetup implicit = block_with_sphere(Integrator::ImplicitEuler);
  implicit.contact_damping_ratio = 1.0;
  CHECK_FALSE(Simulation::create(implicit, diagnostics));
  CHECK(errors_of(diagnostics).find("contact.damping_ratio: contact damping is for the explicit integrators") == 0);
  diagnostics = DiagnosticList{};
  SimulationSetup negative = block_with_sphere();
  negative.contact_damping_ratio = -1.0;
  CHECK_FALSE(Simulation::create(negative, diagnostics));
  CHECK(errors_of(diagnostics) ==
        "contact.damping_ratio: -1 must be a number from 0 (no contact damping, the default) to 100 (1: critical)");
}

TEST_CASE("tools: contact damping removes the chatter of a held tool's tick-end force", "[tools][heavy]") {
  // The chatter: the sphere pressed 1 mm in over 40 ticks of 1 ms and held, semi-implicit Euler at the automatic
  // step (substeps). Without contact damping the tick-end force jumps from tick to tick as the pressed vertices
  // bounce between the tool and their springs; critically damped they follow the tool.
  const auto mean_jump = [&](double ratio) {
    SimulationSetup run = block_with_sphere();
    run.contact_damping_ratio = ratio;
    DiagnosticList messages;
    auto simulation = Simulation::create(run, messages);
    REQUIRE(simulation);
    double jumps = 0.0, previous = 0.0;
    int counted = 0;
    for (int tick = 1; tick <= 80; ++tick) {
      REQUIRE(simulation->set_tool_pose(0, 0, at(0.01, 0.01, 0.0131 - 0.0011 * std::min(1.0, tick / 40.0)), messages));
      REQUIRE(advance_to_tick(*simulation, tick, messages));
      const double force = simulation->tool_readings(0, messages).at(0).force[2];
      if (tick > 45) {  // held still, in contact
        jumps += std::abs(force - previous);
        ++counted;
      }
      previous = force;
    }
    CHECK(previous > 0.0);
    return jumps / counted;
  };
  const double without = mean_jump(0.0), with = mean_jump(1.0);
  INFO("mean tick-to-tick change of the tick-end force while held: " << without << " N undamped, " << with
                                                                     << " N with contact.damping_ratio 1");
  CHECK(with < 0.2 * without);
}

TEST_CASE("tools: bad input is an error naming the tool, and nothing changes", "[tools]") {
  DiagnosticList diagnostics;
  SECTION("a tool inside the tissue at its start") {
    SimulationSetup setup = block_with_sphere();
    setup.tools[0].path[0].pose.position[2] = 0.012;  // 1 mm into the top face
    CHECK_FALSE(Simulation::create(setup, diagnostics));
    CHECK(errors_of(diagnostics) ==
          "tool 0 'tip' starts inside the tissue: vertex 364 at (0.01, 0.01, 0.01) lies 0.002 m from its axis, within "
          "its radius 0.003 m; start the tool outside the surface and move it in");
  }
  SECTION("a tool buried in the tissue, touching no vertex") {
    SimulationSetup setup = block_with_sphere();
    setup.tools[0].radius = 0.0005;
    setup.tools[0].path[0].pose.position = {0.0112, 0.0112, 0.0062};
    CHECK_FALSE(Simulation::create(setup, diagnostics));
    const std::string text = errors_of(diagnostics);
    CHECK(text.rfind("tool 0 'tip' starts inside the tissue: its axis point (0.0112, 0.0112, 0.0062) lies in "
                     "tetrahedron ",
                     0) == 0);
  }
  SECTION("values") {
    SimulationSetup setup = block_with_sphere();
    RigidTool capsule;
    capsule.shape = RigidTool::Shape::Capsule;
    capsule.radius = std::numeric_limits<double>::quiet_NaN();
    capsule.path = {ToolKeyframe{0.0, at(0.0, 0.0, 1.0)}, ToolKeyframe{0.0, at(0.0, 0.0, 2.0)}};
    capsule.path[1].pose.orientation = {0.0, 0.0, 0.0, 0.0};
    setup.tools.push_back(capsule);
    CHECK_FALSE(Simulation::create(setup, diagnostics));
    CHECK(errors_of(diagnostics) ==
          "tool 1: radius nan m must be finite and greater than 0\n"
          "tool 1: a capsule's length 0 m must be finite and greater than 0 (a sphere has none)\n"
          "tool 1 at path point 1: the pose's orientation (0, 0, 0, 0) is not a rotation; give a quaternion (w, x, y, "
          "z) that is finite and not zero, e.g. (1, 0, 0, 0)");
  }
  SECTION("a NaN pose, a zero quaternion, an unknown tool: the tool stays where it was") {
    const auto simulation = Simulation::create(block_with_sphere(), diagnostics);
    REQUIRE(simulation);
    REQUIRE(simulation->set_tool_pose(0, 0, at(0.01, 0.01, 0.0125), diagnostics));
    REQUIRE(simulation->advance(400, diagnostics));
    const std::vector<ToolReading> before = simulation->tool_readings(0, diagnostics);
    REQUIRE(before.at(0).contacts > 0);
    CHECK_FALSE(simulation->set_tool_pose(0, 0, at(std::nan(""), 0.01, 0.0125), diagnostics));
    ToolPose zero = at(0.01, 0.01, 0.0125);
    zero.orientation = {0.0, 0.0, 0.0, 0.0};
    CHECK_FALSE(simulation->set_tool_pose(0, 0, zero, diagnostics));
    CHECK_FALSE(simulation->set_tool_pose(0, 1, at(0.01, 0.01, 0.0125), diagnostics));
    CHECK(errors_of(diagnostics) ==
          "tool 0 'tip': the pose's position (nan, 0.01, 0.0125) is not finite; give a position in metres\n"
          "tool 0 'tip': the pose's orientation (0, 0, 0, 0) is not a rotation; give a quaternion (w, x, y, z) that "
          "is finite and not zero, e.g. (1, 0, 0, 0)\n"
          "tool 1 does not exist; the scene has 1");
    CHECK(simulation->tool_poses().at(0).position == Point3{0.01, 0.01, 0.0125});
    const std::vector<ToolReading> after = simulation->tool_readings(0, diagnostics);
    CHECK(std::memcmp(&after[0], &before[0], sizeof(ToolReading)) == 0);
    CHECK(simulation->advance(10, diagnostics));  // the run goes on
  }
}

TEST_CASE("tools: a sphere on a thick block against Hertz (a small mesh, converged by the bench)", "[tools][heavy]") {
  // 14 graded cells per axis of the quarter block, a / 2 at the contact growing by 1.25: +4.3% (linear tetrahedra and
  // the coarse far field are stiff, and so is the block's finite thickness, 40 a: bench/contact/hertz_bench.cpp and
  // docs/simulator.md, "Rigid tools", give the convergence).
  test_support::HertzCase hertz;
  hertz.first_cell = 0.5;
  hertz.growth = 1.25;
  const test_support::HertzResult result = test_support::run_hertz(hertz);
  REQUIRE(result.ok);
  std::printf("Hertz: %d cells per axis, %zu vertices, %zu in contact: F = %.6g N against %.6g N (error %+.2f%%)\n",
              result.cells, result.vertices, result.contacts, result.force, result.hertz,
              100.0 * result.relative_error);
  CHECK(result.contacts >= 4);
  CHECK(std::abs(result.relative_error) < 0.05);
}

TEST_CASE("tools: a quadratic element's edge nodes on the surface are contact vertices, those inside are not",
          "[tools]") {
  // On a 6-node face a pressure's consistent load sits on the edge nodes (a third each, none at the corners): a tool
  // touching the corners alone presses the surface at points (Hertz below: -30% before edge nodes could touch).
  const SimulationSetup quadratic = block_with_sphere(Integrator::SemiImplicitEuler, 8, "quadratic");
  const std::size_t corners = 9 * 9 * 5;
  REQUIRE(quadratic.rest_positions.size() > corners);
  const std::vector<unsigned char> surface = surface_vertices(quadratic);
  REQUIRE(surface.size() == quadratic.rest_positions.size());
  const Point3 size{0.02, 0.02, 0.01};
  const auto on_boundary = [&](const Point3& p) {
    for (int axis = 0; axis < 3; ++axis)
      if (p[axis] == 0.0 || p[axis] == size[axis]) return true;
    return false;
  };
  std::size_t edge_nodes_on_surface = 0;
  for (std::size_t v = 0; v < surface.size(); ++v) {
    CAPTURE(v, quadratic.rest_positions[v]);
    CHECK(static_cast<bool>(surface[v]) == on_boundary(quadratic.rest_positions[v]));
    edge_nodes_on_surface += v >= corners && surface[v] ? 1 : 0;
  }
  // The box's surface: 2 (8 x 8 + 8 x 4 + 8 x 4) = 256 squares of two triangles, 512 triangles of three edges, each
  // edge shared by two: 768 edge nodes.
  CHECK(edge_nodes_on_surface == 768);
}

TEST_CASE("tools: a sphere on a thick block of quadratic tetrahedra against Hertz", "[tools][heavy]") {
  // 10-node elements on 10 graded cells per axis, 0.7 a at the contact growing by 1.4 (9,261 vertices;
  // `fmpc_hertz_bench growth=1.4 ratios=4 element=quadratic 0.7`: -0.31%, 8 vertices in contact). The edge nodes under
  // the sphere touch it too: with the corners alone the test above's mesh in quadratic elements was -30.3% with 6 in
  // contact. (That mesh, a / 2 growing by 1.25, is +1.15% with 14 in contact, but its 24,389 vertices took 127 s in the
  // last CI run.)
  test_support::HertzCase hertz;
  hertz.first_cell = 0.7;
  hertz.growth = 1.4;
  hertz.element = element_kind_by_keyword("quadratic")->kind;
  const test_support::HertzResult result = test_support::run_hertz(hertz);
  REQUIRE(result.ok);
  std::printf("Hertz, quadratic: %d cells per axis, %zu vertices, %zu in contact: F = %.6g N against %.6g N (error "
              "%+.2f%%)\n",
              result.cells, result.vertices, result.contacts, result.force, result.hertz,
              100.0 * result.relative_error);
  CHECK(result.contacts > 6);
  CHECK(std::abs(result.relative_error) < 0.05);
}

TEST_CASE("tools: no jump in the force as the sphere slides across elements", "[tools][heavy]") {
  // The sphere (radius 3 mm) pressed 0.8 mm into a block of 1.67 mm cells (a contact radius of about one cell) and
  // slid one cell (the ripple's period) along x in steps of 1/10 of a cell, one implicit step of 1 s (a Newton step of
  // the quasi-static problem) at each: the normal force follows the vertices entering and leaving the contact
  // continuously (each vertex's force grows from zero with its depth), so it ripples with the element period and
  // never jumps.
  const int cells = 12;
  const double cell = 0.02 / cells;
  SimulationSetup setup = block_with_sphere(Integrator::ImplicitEuler, cells);
  setup.time_step = 1.0;
  DiagnosticList diagnostics;
  const auto simulation = Simulation::create(setup, diagnostics);
  REQUIRE(simulation);
  const double depth = 0.0008, top = 0.01, radius = 0.003, start = 0.01 - 1.5 * cell;
  for (int step = 1; step <= 8; ++step) {
    REQUIRE(simulation->set_tool_pose(0, 0, at(start, 0.01, top + radius - depth * std::min(1.0, step / 4.0)),
                                      diagnostics));
    REQUIRE(simulation->advance(1, diagnostics));
  }
  std::vector<double> force;
  for (int step = 0; step <= 10; ++step) {
    REQUIRE(simulation->set_tool_pose(0, 0, at(start + 0.1 * cell * step, 0.01, top + radius - depth), diagnostics));
    REQUIRE(simulation->advance(1, diagnostics));
    force.push_back(simulation->tool_readings(0, diagnostics).at(0).force[2]);
  }
  double low = force[0], high = force[0], mean = 0.0, jump = 0.0;
  for (std::size_t i = 0; i < force.size(); ++i) {
    low = std::min(low, force[i]);
    high = std::max(high, force[i]);
    mean += force[i] / static_cast<double>(force.size());
    if (i > 0) jump = std::max(jump, std::abs(force[i] - force[i - 1]));
  }
  std::printf("sliding: F_z %.6g N mean, ripple %.2f%% (max - min), largest change between steps %.3f%% of the mean\n",
              mean, 100.0 * (high - low) / mean, 100.0 * jump / mean);
  CHECK(mean > 0.0);
  CHECK((high - low) / mean < 0.15);
  // A step of 1/10 of the element period: a continuous ripple changes by at most about 2 pi / 10 of its amplitude.
  CHECK(jump <= 0.7 * (high - low) + 1e-3 * mean);
}

TEST_CASE("tools: a CPU batch of scenes with tools gives each scene's bits alone", "[tools]") {
  SimulationSetup a = block_with_sphere(Integrator::SemiImplicitEuler, 4);
  SimulationSetup b = block_with_sphere(Integrator::SemiImplicitEuler, 6);
  a.tools[0].path.push_back(ToolKeyframe{0.01, at(0.01, 0.01, 0.0121)});
  b.tools[0].path.push_back(ToolKeyframe{0.005, at(0.009, 0.01, 0.0125)});
  DiagnosticList diagnostics;
  SimulationOptions options;
  options.batch_threads = 2;
  const auto batch = Simulation::create({a, b}, options, diagnostics);
  const auto alone_a = Simulation::create(a, diagnostics);
  const auto alone_b = Simulation::create(b, diagnostics);
  REQUIRE(batch);
  REQUIRE(alone_a);
  REQUIRE(alone_b);
  REQUIRE(batch->advance(300, diagnostics));
  REQUIRE(alone_a->advance(300, diagnostics));
  REQUIRE(alone_b->advance(300, diagnostics));
  const std::vector<Point3> pa = batch->positions(0, diagnostics), pb = batch->positions(1, diagnostics);
  const std::vector<Point3> qa = alone_a->positions(diagnostics), qb = alone_b->positions(diagnostics);
  CHECK(std::memcmp(pa.data(), qa.data(), pa.size() * sizeof(Point3)) == 0);
  CHECK(std::memcmp(pb.data(), qb.data(), pb.size() * sizeof(Point3)) == 0);
  CHECK(batch->tool_readings(1, diagnostics).at(0).contacts > 0);
  CHECK(batch->tool_poses(0).at(0).position == Point3{0.01, 0.01, 0.0121});
  CHECK(diagnostics.error_count() == 0);
}

namespace {

// The block (4 cells a side: 75 vertices, cheap under the sanitizers) pressed 1.5 mm by the sphere over 2 poses and
// slid 0.8 mm per pose along x, 2 implicit steps of 20 ms per pose, with `rounds` solves per step at most (the
// default needs up to 3); the direct solver, so that a step's solves are its rounds (one solve reaches the tolerance).
struct RoundsRun {
  std::vector<Point3> positions;
  std::vector<double> force;  // the tool's F_z after each pose's steps (N)
  ImplicitSolverReport report;
  DiagnosticList diagnostics;
};

RoundsRun press_and_slide(int rounds) {
  SimulationSetup setup = block_with_sphere(Integrator::ImplicitEuler, 4);
  setup.time_step = 2e-2;
  setup.implicit.method = ImplicitMethod::Direct;
  setup.implicit.contact_rounds = rounds;
  RoundsRun run;
  const auto simulation = Simulation::create(setup, run.diagnostics);
  REQUIRE(simulation);
  for (int tick = 1; tick <= 6; ++tick) {
    const double press = 0.0015 * std::min(1.0, tick / 2.0), slide = 0.0008 * tick;
    REQUIRE(simulation->set_tool_pose(0, 0, at(0.01 + slide, 0.01, 0.0131 - press), run.diagnostics));
    REQUIRE(simulation->advance(2, run.diagnostics));
    run.force.push_back(simulation->tool_readings(0, run.diagnostics).at(0).force[2]);
  }
  run.positions = simulation->positions(run.diagnostics);
  run.report = simulation->implicit_solver();
  return run;
}

}  // namespace

TEST_CASE("tools: implicit Euler's contact rounds: one solve per step with the set at its start, or up to N",
          "[tools][implicit]") {
  const RoundsRun full = press_and_slide(kernels::kMostContactRounds);
  CHECK(SimulationSetup{}.implicit.contact_rounds == kernels::kMostContactRounds);
  // The default settles every step, some in more than one solve (so that one round differs).
  const int most = full.report.iterations_max;
  CHECK(full.report.contact_unsettled_steps == 0);
  CHECK(full.diagnostics.warning_count() == 0);
  CHECK(most >= 3);
  CHECK(most < kernels::kMostContactRounds);
  // A bound at the most solves a step needed gives the default's bits.
  const RoundsRun same = press_and_slide(most);
  CHECK(std::memcmp(same.positions.data(), full.positions.data(), full.positions.size() * sizeof(Point3)) == 0);
  CHECK(same.report.contact_unsettled_steps == 0);

  // One round: one solve per step with the set at the step's start, the steps whose set then changed counted, no
  // warning (the user chose it); at the end a small step from the default's (measured: 2 of 12 steps unsettled, the
  // positions 1.0e-9 m apart, 8e-7 of the largest displacement; the tool's force 1e-6).
  const RoundsRun once = press_and_slide(1);
  CHECK(once.report.iterations_max == 1);
  CHECK(once.report.iterations_total == once.report.steps);
  CHECK(once.report.contact_unsettled_steps > 0);
  CHECK(once.report.first_contact_unsettled_step > 0);
  CHECK(once.diagnostics.warning_count() == 0);
  double largest = 0.0, difference = 0.0;
  const SimulationSetup rest = block_with_sphere(Integrator::ImplicitEuler, 4);
  for (std::size_t v = 0; v < full.positions.size(); ++v)
    for (std::size_t i = 0; i < 3; ++i) {
      largest = std::max(largest, std::abs(full.positions[v][i] - rest.rest_positions[v][i]));
      difference = std::max(difference, std::abs(once.positions[v][i] - full.positions[v][i]));
    }
  // The force read at the end of a step whose set changed can be far off: a vertex outside the tool at the step's
  // start that the solution moved inside is not pushed back within the step and is read at its full depth (here
  // 2.63 N against 0.0272 N after the second pose, which moves the tool 0.75 mm down and 0.8 mm across in one step);
  // the next step's set takes it in. At the end the two agree closely.
  std::size_t worst = 0;
  for (std::size_t k = 0; k < full.force.size(); ++k)
    if (std::abs(once.force[k] - full.force[k]) > std::abs(once.force[worst] - full.force[worst])) worst = k;
  const double force_difference = std::abs(once.force.back() - full.force.back()) / full.force.back();
  std::printf("contact rounds 1 against %d: %zu of %zu steps unsettled; at the end max |x1 - x8| %.3g m (%.2g of the "
              "largest displacement, %.3g m), tool force %.2g apart (%.6g N); the largest difference in the force "
              "after pose %zu: %.6g N against %.6g N\n",
              kernels::kMostContactRounds, once.report.contact_unsettled_steps, once.report.steps, difference,
              difference / largest, largest, force_difference, full.force.back(), worst + 1, once.force[worst],
              full.force[worst]);
  CHECK(difference > 0.0);
  CHECK(difference < 1e-5 * largest);
  CHECK(force_difference < 1e-5);

  // Two rounds: a step still changing after them is warned about once, naming the bound.
  const RoundsRun two = press_and_slide(2);
  CHECK(two.report.iterations_max == 2);
  CHECK(two.report.contact_unsettled_steps > 0);
  REQUIRE(two.diagnostics.warning_count() == 1);
  const Diagnostic& warning = two.diagnostics.items().front();
  CHECK(warning.code == "contact-not-settled");
  CHECK(warning.message == "implicit Euler: the vertices the tools push still changed after 2 solves "
                           "(solver.contact_rounds) at step " +
                               std::to_string(two.report.first_contact_unsettled_step) +
                               "; the step went on with the last set (a tool moving further than its contact's depth "
                               "in one step): move it less per step or use a smaller dt, or raise "
                               "solver.contact_rounds (at most 8)");

  // Out of range in a setup built in code: an error, no simulation.
  for (const int rounds : {0, kernels::kMostContactRounds + 1, -1}) {
    SimulationSetup setup = block_with_sphere(Integrator::ImplicitEuler, 4);
    setup.implicit.contact_rounds = rounds;
    DiagnosticList diagnostics;
    CHECK_FALSE(Simulation::create(setup, diagnostics));
    CHECK(errors_of(diagnostics) == "implicit Euler's contact rounds (implicit.contact_rounds) must be from 1 to 8, "
                                    "got " + std::to_string(rounds));
  }
}

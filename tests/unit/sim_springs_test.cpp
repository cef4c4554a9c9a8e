#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "kernels/spring_math.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/springs/spring_network.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

Mesh unit_tetrahedron() {
  Mesh mesh;
  mesh.source = "unit";
  mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.tetrahedra = {{0, 1, 2, 3}};
  return mesh;
}

}  // namespace

TEST_CASE("tetrahedron edges: one spring per edge, CSR adjacency in spring order", "[sim]") {
  DiagnosticList diagnostics;
  const Mesh mesh = unit_tetrahedron();
  SpringNetwork net = springs_from_tetrahedra(mesh, diagnostics);
  REQUIRE(net.size() == 6);
  CHECK(net.first == std::vector<std::int32_t>{0, 0, 0, 1, 1, 2});
  CHECK(net.second == std::vector<std::int32_t>{1, 2, 3, 2, 3, 3});
  for (const double measure : net.element_measure) CHECK(measure == Approx(1.0 / 6.0));
  CHECK(net.adjacency_offset == std::vector<std::int32_t>{0, 3, 6, 9, 12});
  CHECK(net.adjacency_spring == std::vector<std::int32_t>{0, 1, 2, 0, 3, 4, 1, 3, 5, 2, 4, 5});
  CHECK(adjacency_neighbours(net) == std::vector<std::int32_t>{1, 2, 3, 0, 2, 3, 0, 1, 3, 0, 1, 2});
  CHECK(adjacency_neighbour(net, 2, 7) == 1);
  REQUIRE(compute_rest_lengths(net, mesh.points, diagnostics));
  CHECK(net.rest_length[0] == 1.0);
  CHECK(net.rest_length[3] == Approx(std::sqrt(2.0)));

  Mesh broken = mesh;
  broken.tetrahedra.push_back({0, 1, 2, 7});
  CHECK(springs_from_tetrahedra(broken, diagnostics).size() == 0);
  CHECK_THAT(diagnostics.items().back().message, Catch::Contains("refers to vertex 7"));
}

TEST_CASE("box springs: edge count of the Kuhn subdivision and Van Gelder's identity", "[sim]") {
  DiagnosticList diagnostics;
  BoxSpec spec;
  spec.cells_x = spec.cells_y = spec.cells_z = 2;
  spec.size = {0.04, 0.04, 0.04};
  const Mesh box = generate_box(spec, diagnostics);
  SpringNetwork net = springs_from_tetrahedra(box, diagnostics);
  // Axis edges 3 n (n+1)^2, face diagonals 3 n^2 (n+1), body diagonals n^3 for n = 2.
  CHECK(net.size() == 54 + 36 + 8);
  REQUIRE(compute_rest_lengths(net, box.points, diagnostics));
  StiffnessSpec stiffness;
  stiffness.mapping = StiffnessMapping::VanGelder1998;
  stiffness.value = 5000.0;  // Pa
  REQUIRE(assign_stiffness(net, stiffness, diagnostics));
  // k l^2 = E sum V_e, and every tetrahedron has 6 edges: sum_s k_s l_s^2 = 6 E V_total.
  double sum = 0.0;
  for (std::size_t s = 0; s < net.size(); ++s) sum += net.stiffness[s] * net.rest_length[s] * net.rest_length[s];
  CHECK(sum == Approx(6.0 * 5000.0 * 0.04 * 0.04 * 0.04).epsilon(1e-12));

  stiffness.mapping = StiffnessMapping::StiffnessOverLength;
  stiffness.value = 4500.0;
  REQUIRE(assign_stiffness(net, stiffness, diagnostics));
  CHECK(net.stiffness[0] == Approx(4500.0 / net.rest_length[0]));
  stiffness.mapping = StiffnessMapping::Uniform;
  stiffness.per_spring.assign(net.size(), 7.0);
  stiffness.per_spring[3] = 9.0;
  REQUIRE(assign_stiffness(net, stiffness, diagnostics));
  CHECK(net.stiffness[3] == 9.0);
  CHECK(net.stiffness[4] == 7.0);
  stiffness.per_spring[2] = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(assign_stiffness(net, stiffness, diagnostics));
  stiffness.per_spring.resize(3);
  CHECK_FALSE(assign_stiffness(net, stiffness, diagnostics));
  CHECK(diagnostics.error_count() == 2);
}

TEST_CASE("thesis triangle springs: structural edges and flexion across shared edges", "[sim]") {
  DiagnosticList diagnostics;
  Mesh quad;
  quad.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  quad.triangles = {{0, 1, 2}, {0, 2, 3}};
  SpringNetwork net = springs_from_triangles(quad, {}, diagnostics);
  REQUIRE(net.size() == 6);
  CHECK(net.kind[5] == SpringKind::Flexion);
  CHECK(net.first[5] == 1);
  CHECK(net.second[5] == 3);                     // opposite the shared edge 0-2
  CHECK(net.element_measure[1] == Approx(1.0));  // edge 0-2 belongs to both triangles (area 0.5 each)
  CHECK(springs_from_triangles(quad, {true, false}, diagnostics).size() == 5);
  CHECK(springs_from_triangles(quad, {false, true}, diagnostics).size() == 1);

  // A closed tetrahedral surface: every opposite pair is already an edge, so no flexion springs.
  Mesh closed;
  closed.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  closed.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  CHECK(springs_from_triangles(closed, {}, diagnostics).size() == 6);

  REQUIRE(compute_rest_lengths(net, quad.points, diagnostics));
  StiffnessSpec stiffness;
  stiffness.value = 1000.0;
  stiffness.thickness = 0.002;
  stiffness.flexion_fraction = 0.5;
  REQUIRE(assign_stiffness(net, stiffness, diagnostics));
  CHECK(net.stiffness[0] == Approx(1000.0 * 0.002 * 0.5 / 1.0));  // edge 0-1: one triangle, area 0.5
  CHECK(net.stiffness[1] == Approx(1000.0 * 0.002 * 1.0 / 2.0));  // diagonal 0-2: two triangles, l^2 = 2
  // Flexion 1-3: half the mean of the structural springs at vertices 1 (0-1, 1-2) and 3 (0-3, 2-3), all 1.0.
  CHECK(net.stiffness[5] == Approx(0.5 * 1.0));
}

TEST_CASE("zero-length springs are refused with the spring and its vertices", "[sim]") {
  DiagnosticList diagnostics;
  Mesh mesh = unit_tetrahedron();
  mesh.points[3] = mesh.points[2];
  SpringNetwork net = springs_from_tetrahedra(mesh, diagnostics);
  CHECK_FALSE(compute_rest_lengths(net, mesh.points, diagnostics));
  REQUIRE(diagnostics.error_count() == 1);
  CHECK_THAT(diagnostics.items()[0].message, Catch::StartsWith("spring 5 between vertices 2 and 3 has rest length 0"));
}

TEST_CASE("lumped masses from density and from a total mass", "[sim]") {
  DiagnosticList diagnostics;
  BoxSpec spec;
  spec.cells_x = 3;
  spec.cells_y = 2;
  spec.cells_z = 1;
  spec.size = {0.3, 0.2, 0.1};
  Mesh box = generate_box(spec, diagnostics);
  MassSpec density;
  density.value = 1060.0;  // kg/m^3
  const auto mass = lumped_masses(box, density, diagnostics);
  double total = 0.0;
  for (const double m : mass) total += m;
  CHECK(total == Approx(1060.0 * 0.006));
  MassSpec total_mass;
  total_mass.source = MassSpec::Source::TotalMass;
  total_mass.value = 1.0;
  const auto scaled = lumped_masses(box, total_mass, diagnostics);
  double scaled_total = 0.0;
  for (const double m : scaled) scaled_total += m;
  CHECK(scaled_total == Approx(1.0));
  CHECK(scaled[0] / scaled[1] == Approx(mass[0] / mass[1]));
  CHECK(diagnostics.empty());

  box.points.push_back({9, 9, 9});  // unreferenced: no mass
  CHECK(lumped_masses(box, density, diagnostics).empty());
  CHECK_THAT(diagnostics.items().back().message, Catch::StartsWith("vertex 24 gets no mass"));
  density.value = -1.0;
  CHECK(lumped_masses(box, density, diagnostics).empty());
}

TEST_CASE("damping: c = 2 zeta sqrt(k mu) and the thesis's gamma = 2 zeta k / w", "[sim]") {
  DiagnosticList diagnostics;
  const Mesh mesh = unit_tetrahedron();
  SpringNetwork net = springs_from_tetrahedra(mesh, diagnostics);
  REQUIRE(compute_rest_lengths(net, mesh.points, diagnostics));
  StiffnessSpec stiffness;
  stiffness.mapping = StiffnessMapping::Uniform;
  stiffness.value = 200.0;
  REQUIRE(assign_stiffness(net, stiffness, diagnostics));
  const std::vector<double> mass = {1.0, 3.0, 1.0, 1.0};
  DampingSpec damping;
  damping.ratio = 0.9;
  REQUIRE(assign_damping(net, mass, damping, diagnostics));
  CHECK(net.damping[0] == Approx(2.0 * 0.9 * std::sqrt(200.0 * 0.75)));  // mu = 1*3/(1+3)
  CHECK(net.damping[5] == Approx(2.0 * 0.9 * std::sqrt(200.0 * 0.5)));
  damping.rule = DampingSpec::Rule::ThesisNaturalFrequency;
  damping.natural_frequency = 20.0;
  REQUIRE(assign_damping(net, mass, damping, diagnostics));
  CHECK(net.damping[2] == Approx(2.0 * 0.9 * 200.0 / 20.0));
  damping.natural_frequency = 0.0;
  CHECK_FALSE(assign_damping(net, mass, damping, diagnostics));
  damping.rule = DampingSpec::Rule::DampingRatio;
  damping.ratio = -1.0;
  CHECK_FALSE(assign_damping(net, mass, damping, diagnostics));
}

TEST_CASE("Basafa-Farahmand spring law: values, continuity at Xc, odd symmetry", "[sim]") {
  using fmpc::kernels::basafa_farahmand_force;
  using fmpc::kernels::basafa_farahmand_slope;
  // The benchmark: K1 = 0.05, K2 = 10, Xc = 0.2.
  CHECK(basafa_farahmand_force(0.1, 0.05, 10.0, 0.2) == Approx(0.005 + 0.01));
  CHECK(basafa_farahmand_force(0.3, 0.05, 10.0, 0.2) == Approx(0.09 + 1.25 * 0.1));  // A + B (X - Xc)
  CHECK(basafa_farahmand_force(-0.3, 0.05, 10.0, 0.2) == Approx(-0.215));
  CHECK(basafa_farahmand_force(0.0, 0.05, 10.0, 0.2) == 0.0);
  const double below = basafa_farahmand_force(0.2, 0.05, 10.0, 0.2);
  const double above = basafa_farahmand_force(0.2 + 1e-12, 0.05, 10.0, 0.2);
  CHECK(above - below == Approx(1.25e-12).margin(1e-15));
  CHECK(basafa_farahmand_slope(0.2, 0.05, 10.0, 0.2) == Approx(1.25));
  CHECK(basafa_farahmand_slope(0.5, 0.05, 10.0, 0.2) == Approx(1.25));
  CHECK(std::isnan(basafa_farahmand_force(std::nan(""), 0.05, 10.0, 0.2)));
  // Seeded property: finite differences of the force match the slope away from Xc.
  for (int i = 0; i < 200; ++i) {
    const double x = -0.6 + 1.2 * static_cast<double>((i * 7919) % 200) / 200.0;
    if (std::abs(std::abs(x) - 0.2) < 1e-3) continue;
    const double h = 1e-6;
    const double numeric =
        (basafa_farahmand_force(x + h, 0.05, 10.0, 0.2) - basafa_farahmand_force(x - h, 0.05, 10.0, 0.2)) / (2 * h);
    CHECK(numeric == Approx(basafa_farahmand_slope(x, 0.05, 10.0, 0.2)).epsilon(1e-6));
  }
}

TEST_CASE("spring force: direction, dashpot, and no NaN for a collapsed spring", "[sim]") {
  fmpc::kernels::SpringLawParameters<double> linear;
  double fx = 0, fy = 0, fz = 0;
  fmpc::kernels::spring_force_on_vertex(2.0, 0.0, 0.0, 0.5, 1.0, 0.0, 1.0, 10.0, 4.0, linear, fx, fy, fz);
  CHECK(fx == Approx(10.0 * 1.0 + 4.0 * 0.5));  // stretched by 1, closing speed 0.5 along the spring
  CHECK(fy == 0.0);
  CHECK(fz == 0.0);
  fmpc::kernels::spring_force_on_vertex(0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 10.0, 4.0, linear, fx, fy, fz);
  CHECK(fx == 0.0);
  CHECK(fy == 0.0);
  float gx = 0, gy = 0, gz = 0;
  fmpc::kernels::SpringLawParameters<float> linear_float;
  fmpc::kernels::spring_force_on_vertex(0.0f, -3.0f, 4.0f, 0.0f, 0.0f, 0.0f, 4.0f, 2.0f, 0.0f, linear_float, gx, gy,
                                        gz);
  CHECK(gy == Approx(-0.6f * 2.0f));
  CHECK(gz == Approx(0.8f * 2.0f));
}

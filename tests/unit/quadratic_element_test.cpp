// Quadratic tetrahedra's inversion check (kernels/elements/quadratic_tetrahedron.h, docs/simulator.md): the Jacobian
// at the four quadrature points, which catches an element folded between its corners while its corner tetrahedron
// stays positive, in the kernel and in the CPU engine's inversion count (tests/gpu/gpu_force_model_test.cpp holds
// the CUDA count against it).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <vector>

#include "kernels/element_laws.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/fem/fem_model_builder.h"
#include "runtime/integrate/stepping_engine.h"
#include "runtime/mesh/generated_mesh.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

using Quadratic = kernels::QuadraticTetrahedron;

// A right tetrahedron of 1 cm with straight edges, its edge node 0-1 (node 4) moved to `fraction` of the way from
// corner 0 to corner 1.
template <typename Real>
void element_with_edge_node_at(double fraction, Real out[Quadratic::kNodes][3]) {
  const double corners[4][3] = {{0, 0, 0}, {0.01, 0, 0}, {0, 0.01, 0}, {0, 0, 0.01}};
  double rest[Quadratic::kNodes][3];
  kernels::element_rest_nodes<Quadratic>(corners, rest);
  rest[4][0] = fraction * 0.01;
  for (int a = 0; a < Quadratic::kNodes; ++a)
    for (int i = 0; i < 3; ++i) out[a][i] = static_cast<Real>(rest[a][i]);
}

}  // namespace

TEST_CASE("quadratic tetrahedra are inverted where the Jacobian at a quadrature point is not positive",
          "[fem][quadratic]") {
  // Moving edge node 0-1 by (f - 1/2) h along the edge changes dx/dL_1 - dx/dL_0 (the Jacobian's column along the
  // edge) by 4 (f - 1/2) h (L_0 - L_1): at the point with L_1 = a = (5 + 3 sqrt 5) / 20, L_0 = b = (5 - sqrt 5) / 20
  // its determinant is 1 - 4 (f - 1/2)(a - b) = 1 - (4 / sqrt 5)(f - 1/2) of the rest's, zero at f = 1/2 + sqrt 5 / 4
  // = 1.0590 (numpy, independently: 0.284 at f = 0.9, -0.252 at f = 1.2); the other points stay positive.
  const double fold = 0.5 + std::sqrt(5.0) / 4.0;
  for (const double fraction : {0.5, 0.75, 0.9, 1.0, 1.05, 1.07, 1.2, 1.5}) {
    INFO("edge node at " << fraction << " of the edge");
    double x[Quadratic::kNodes][3];
    element_with_edge_node_at(fraction, x);
    float xf[Quadratic::kNodes][3];
    element_with_edge_node_at(fraction, xf);
    // Its corner tetrahedron never moves: positive throughout.
    double corners[4][3];
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) corners[a][i] = x[a][i];
    CHECK(kernels::tetrahedron_volume(corners) > 0.0);
    const bool folded = fraction > fold;
    CHECK(Quadratic::inverted(x) == folded);
    CHECK(Quadratic::inverted(xf) == folded);
    // The run-time dispatch the engines call reads the same nodes the same way.
    std::vector<int> nodes(Quadratic::kNodes);
    std::vector<double> px(Quadratic::kNodes), py(Quadratic::kNodes), pz(Quadratic::kNodes);
    for (int a = 0; a < Quadratic::kNodes; ++a) {
      nodes[static_cast<std::size_t>(a)] = Quadratic::kNodes - 1 - a;  // any vertex order
      px[static_cast<std::size_t>(Quadratic::kNodes - 1 - a)] = x[a][0];
      py[static_cast<std::size_t>(Quadratic::kNodes - 1 - a)] = x[a][1];
      pz[static_cast<std::size_t>(Quadratic::kNodes - 1 - a)] = x[a][2];
    }
    CHECK(kernels::element_inverted(element_kind_by_keyword("quadratic")->kind, 0, nodes.data(), px.data(), py.data(),
                                    pz.data()) == folded);
  }
  // A mirrored element (corners 1 and 2 swapped, edge nodes following them) is inverted at every point, and so is a
  // flat one (all nodes in a plane).
  double x[Quadratic::kNodes][3];
  const double mirrored[4][3] = {{0, 0, 0}, {0, 0.01, 0}, {0.01, 0, 0}, {0, 0, 0.01}};
  kernels::element_rest_nodes<Quadratic>(mirrored, x);
  CHECK(Quadratic::inverted(x));
  const double flat[4][3] = {{0, 0, 0}, {0.01, 0, 0}, {0, 0.01, 0}, {0.003, 0.003, 0}};
  kernels::element_rest_nodes<Quadratic>(flat, x);
  CHECK(Quadratic::inverted(x));
}

TEST_CASE("the CPU engine counts a quadratic element folded between its corners as inverted", "[fem][quadratic]") {
  DiagnosticList diagnostics;
  BoxSpec box;
  box.cells_x = box.cells_y = box.cells_z = 2;
  box.size = {0.02, 0.02, 0.02};
  const Mesh mesh = generate_box(box, diagnostics);
  FemModelSpec spec;
  spec.youngs_modulus = {5000.0};
  spec.poisson_ratio = {0.45};
  spec.mass.value = 1000.0;
  spec.element = element_kind_by_keyword("quadratic")->kind;
  auto setup = build_fem_model(mesh, spec, diagnostics);
  REQUIRE(setup);
  const ElementGeometry& geometry = setup->elements.geometry;
  REQUIRE(!geometry.added_vertex_ends.empty());
  // The edge node of the mesh's first edge, moved along its edge toward (0.9) or past (1.2) its second end: every
  // element around that edge folds past f = 1.0590 (the test above), and no other element moves.
  const std::size_t moved = mesh.points.size();
  const auto ends = geometry.added_vertex_ends.front();
  std::vector<int> around;
  const auto N = static_cast<std::size_t>(geometry.nodes_per_element);
  for (std::size_t e = 0; e < geometry.size(); ++e)
    for (std::size_t a = 0; a < N; ++a)
      if (geometry.nodes[N * e + a] == static_cast<std::int32_t>(moved)) around.push_back(static_cast<int>(e));
  REQUIRE(!around.empty());
  for (const double fraction : {0.9, 1.2}) {
    INFO("edge node at " << fraction << " of its edge");
    SimulationSetup scene = *setup;
    scene.initial_positions = scene.rest_positions;
    const Point3& from = scene.rest_positions[static_cast<std::size_t>(ends[0])];
    const Point3& to = scene.rest_positions[static_cast<std::size_t>(ends[1])];
    for (std::size_t i = 0; i < 3; ++i) scene.initial_positions[moved][i] = from[i] + fraction * (to[i] - from[i]);
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      scene.precision = precision;
      const auto stability = check_stability(scene, diagnostics);
      REQUIRE(stability);
      const std::vector<SimulationSetup> scenes = {scene};
      const auto engine = create_cpu_engine(scenes, {*stability}, 1);
      std::vector<unsigned> counts;
      std::vector<int> firsts;
      REQUIRE(engine->count_inverted(counts, firsts, diagnostics));
      CHECK(counts.front() == (fraction > 1.0 ? around.size() : 0u));
      if (fraction > 1.0) CHECK(firsts.front() == around.front());
    }
    // The corner tetrahedra never moved: a count of them would find none.
    for (const Tetrahedron& t : scene.tetrahedra) {
      double x[4][3];
      for (std::size_t a = 0; a < 4; ++a)
        for (std::size_t i = 0; i < 3; ++i) x[a][i] = scene.initial_positions[static_cast<std::size_t>(t[a])][i];
      CHECK(kernels::tetrahedron_volume(x) > 0.0);
    }
  }
  InversionReport report;
  report.first_element = around.front();
  report.first_step = 0;
  report.current_count = around.size();
  const Tetrahedron& t = setup->tetrahedra[static_cast<std::size_t>(around.front())];
  CHECK(inversion_message(*setup, report) ==
        "quadratic element " + std::to_string(around.front()) + " (corners " + std::to_string(t[0]) + ", " +
            std::to_string(t[1]) + ", " + std::to_string(t[2]) + ", " + std::to_string(t[3]) +
            ") turned inside out at the start (" + std::to_string(around.size()) +
            " inverted then); the load is too large for the mesh here: refine it, lower the load, or raise the "
            "stiffness");
}

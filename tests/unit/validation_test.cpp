// Physics checked against physics (issue 10, item 5): analytic solutions (uniaxial block with sliding faces, a
// self-weight column, a slender cantilever, Hayes et al.'s indentation of a bonded layer) and CalculiX (Debian's
// calculix-ccx, test-only) on the same meshes: C3D4 must equal the co-rotational FEM at small strain, C3D10 on a
// fine mesh gives the converged answer every model's error is printed against. docs/validation.md records the
// printed tables. The CalculiX parts skip visibly without ccx.
#include <catch2/catch.hpp>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "runtime/fem/element_law_registry.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/mesh_check.h"
#include "runtime/mesh/mesh_refinement.h"
#include "tests/support/elastic_problem.h"
#include "tests/support/generated_program.h"

using namespace fmpc;
using namespace fmpc::sim;
using namespace fmpc::testing;

namespace {

constexpr ProblemModel kModels[] = {ProblemModel::CorotationalFem, ProblemModel::SpringsVanGelder,
                                    ProblemModel::SpringsLloyd, ProblemModel::SpringsVolumeTerm};

Mesh box(Point3 size, int nx, int ny, int nz) {
  DiagnosticList diagnostics;
  BoxSpec spec;
  spec.size = size;
  spec.cells_x = nx;
  spec.cells_y = ny;
  spec.cells_z = nz;
  return generate_box(spec, diagnostics);
}

bool on(double value, double plane) { return std::abs(value - plane) < 1e-12; }

ElasticProblem problem_on(const Mesh& mesh, double E, double nu, double density) {
  ElasticProblem p;
  p.mesh = mesh;
  p.youngs_modulus = E;
  p.poisson_ratio = nu;
  p.density = density;
  p.held.assign(mesh.points.size(), 0);
  return p;
}

// Mean of one displacement component over the vertices where `select` holds.
template <typename Select>
double mean_displacement(const ElasticProblem& p, const ElasticAnswer& a, int axis, Select select) {
  double sum = 0.0;
  int count = 0;
  for (std::size_t v = 0; v < p.mesh.points.size(); ++v) {
    if (!select(p.mesh.points[v])) continue;
    sum += a.displacement[v][static_cast<std::size_t>(axis)];
    ++count;
  }
  return sum / count;
}

ElasticAnswer fmpc_answer(const ElasticProblem& p, ProblemModel model) {
  std::string error;
  auto answer = solve_with_fmpc(p, model, error);
  INFO(error);
  REQUIRE(answer);
  return *answer;
}

std::optional<ElasticAnswer> calculix_answer(const ElasticProblem& p, bool quadratic, const std::string& tag) {
  if (!calculix_available()) return std::nullopt;
  ScratchFolder folder("ccx_" + tag);
  std::string error;
  auto answer = solve_with_calculix(p, quadratic, folder.path(), error);
  INFO(error);
  REQUIRE(answer);
  return answer;
}

void warn_skip() { WARN("skipped: CalculiX (ccx, Debian's calculix-ccx) is not installed; tools/run installs it"); }

// The relative difference of two displacement fields, by the largest difference over the largest displacement.
double field_difference(const ElasticAnswer& a, const ElasticAnswer& b) {
  double largest = 0.0, difference = 0.0;
  for (std::size_t v = 0; v < a.displacement.size(); ++v) {
    largest = std::max(largest, std::sqrt(a.displacement[v][0] * a.displacement[v][0] +
                                          a.displacement[v][1] * a.displacement[v][1] +
                                          a.displacement[v][2] * a.displacement[v][2]));
    difference = std::max(difference, distance(a.displacement[v], b.displacement[v]));
  }
  return difference / largest;
}

// The cases' problems, shared by their tests and by the table of every law x element kind ("[.element_table]").

// Uniaxial block: 3 x 3 x 6 cm, faces x = 0, y = 0, z = 0 sliding, a traction on the top face.
const Point3 kUniaxialSize{0.03, 0.03, 0.06};
constexpr double kUniaxialModulus = 5000.0, kUniaxialPoissonRatio = 0.45, kUniaxialTraction = 100.0;
ElasticProblem uniaxial_problem() {
  ElasticProblem p = problem_on(box(kUniaxialSize, 3, 3, 6), kUniaxialModulus, kUniaxialPoissonRatio, 1000.0);
  for (std::size_t v = 0; v < p.mesh.points.size(); ++v)
    for (int a = 0; a < 3; ++a)
      if (on(p.mesh.points[v][static_cast<std::size_t>(a)], 0.0)) p.held[v] = static_cast<std::uint8_t>(p.held[v] | (1u << a));
  for (const Triangle& t : boundary_triangles(p.mesh)) {
    bool top = true;
    for (const auto v : t) top = top && on(p.mesh.points[static_cast<std::size_t>(v)][2], kUniaxialSize[2]);
    if (top) p.traction_faces.push_back(t);
  }
  p.traction = {0.0, 0.0, kUniaxialTraction};
  return p;
}

// Self-weight column: a quarter column 2 x 2 x 10 cm (2n x 2n x 5n cells), nu = 0, symmetry planes and base sliding.
constexpr double kColumnModulus = 5000.0, kColumnDensity = 1060.0, kColumnLength = 0.1, kGravity = 9.81;
double column_exact() { return -kColumnDensity * kGravity * kColumnLength * kColumnLength / (2 * kColumnModulus); }
bool column_top(const Point3& x) { return on(x[2], kColumnLength); }
ElasticProblem column_problem(int n) {
  ElasticProblem p = problem_on(box({0.02, 0.02, kColumnLength}, 2 * n, 2 * n, 5 * n), kColumnModulus, 0.0, kColumnDensity);
  p.gravity = {0.0, 0.0, -kGravity};
  for (std::size_t v = 0; v < p.mesh.points.size(); ++v)
    for (int a = 0; a < 3; ++a)
      if (on(p.mesh.points[v][static_cast<std::size_t>(a)], 0.0)) p.held[v] = static_cast<std::uint8_t>(p.held[v] | (1u << a));
  return p;
}

// Slender cantilever: 10 x 1 x 1 cm (10n x n x n cells), E = 1 MPa, nu = 0.45, clamped at x = 0, under gravity.
bool cantilever_tip(const Point3& x) { return on(x[0], 0.1); }
ElasticProblem cantilever_problem(int n) {
  ElasticProblem p = problem_on(box({0.1, 0.01, 0.01}, 10 * n, n, n), 1e6, 0.45, 1060.0);
  p.gravity = {0.0, 0.0, -kGravity};
  for (std::size_t v = 0; v < p.mesh.points.size(); ++v)
    if (on(p.mesh.points[v][0], 0.0)) p.held[v] = 7;
  return p;
}

// Cubes of 10 cm (n^3 cells), E = 5 kPa. Hanging: top face clamped, gravity; the mean displacement of the bottom
// face. Compressed: base clamped, top face clamped and moved down 1 mm; the force on the top face.
constexpr double kCubeEdge = 0.1;
ElasticProblem hanging_cube(int n, double nu) {
  ElasticProblem p = problem_on(box({kCubeEdge, kCubeEdge, kCubeEdge}, n, n, n), 5000.0, nu, 1060.0);
  p.gravity = {0.0, 0.0, -kGravity};
  for (std::size_t v = 0; v < p.mesh.points.size(); ++v)
    if (on(p.mesh.points[v][2], kCubeEdge)) p.held[v] = 7;
  return p;
}
ElasticProblem compressed_cube(int n, double nu) {
  ElasticProblem p = problem_on(box({kCubeEdge, kCubeEdge, kCubeEdge}, n, n, n), 5000.0, nu, 1060.0);
  p.prescribed.assign(p.mesh.points.size(), Point3{0, 0, 0});
  for (std::size_t v = 0; v < p.mesh.points.size(); ++v) {
    if (on(p.mesh.points[v][2], 0.0)) p.held[v] = 7;
    if (on(p.mesh.points[v][2], kCubeEdge)) {
      p.held[v] = 7;
      p.prescribed[v][2] = -0.001;
    }
  }
  return p;
}
bool cube_bottom(const Point3& x) { return on(x[2], 0.0); }
double cube_top_force(const ElasticAnswer& a) {
  double sum = 0.0;
  for (std::size_t v = 0; v < a.nodes.size(); ++v)
    if (on(a.nodes[v][2], kCubeEdge)) sum += a.reaction[v][2];
  return sum;
}

// Hayes et al.'s bonded layer: a flat punch of radius a = 5 mm pressed 0.1 mm into a 10 mm layer (a/h = 0.5) bonded
// to a rigid base. Quarter model (12n x 12n x 4n cells): the punch's axis on the corner x = y = 0, symmetry planes
// slide, the layer 6 a wide, the punch's vertices held in z only (frictionless).
constexpr double kHayesModulus = 5000.0, kHayesPoissonRatio = 0.45, kHayesRadius = 0.005, kHayesHeight = 0.01,
                 kHayesDepth = 1e-4;
struct HayesProblem {
  ElasticProblem problem;
  double effective_radius = 0.0;  // the radius of the discrete punch's footprint
  double expected_force = 0.0;    // Hayes' force at that radius (N)
  // The same for a kind with edge nodes: an edge node is held where both ends of its edge are, and a node's share of
  // the face is its consistent load's (a third of each triangle at its edge nodes, none at its corners).
  double expected_force_edge_nodes = 0.0;
};
HayesProblem hayes_problem(int n) {
  const double a = kHayesRadius, h = kHayesHeight, nu = kHayesPoissonRatio;
  HayesProblem hayes;
  ElasticProblem& p = hayes.problem;
  p = problem_on(box({6 * a, 6 * a, h}, 12 * n, 12 * n, 4 * n), kHayesModulus, nu, 1000.0);
  p.prescribed.assign(p.mesh.points.size(), Point3{0, 0, 0});
  std::vector<bool> punch(p.mesh.points.size(), false);
  for (std::size_t v = 0; v < p.mesh.points.size(); ++v) {
    const Point3& x = p.mesh.points[v];
    if (on(x[0], 0.0)) p.held[v] |= 1;
    if (on(x[1], 0.0)) p.held[v] |= 2;
    if (on(x[2], 0.0)) p.held[v] = 7;
    if (on(x[2], h) && std::hypot(x[0], x[1]) <= a * (1 + 1e-9)) {
      p.held[v] |= 4;
      p.prescribed[v][2] = -kHayesDepth;
      punch[v] = true;
    }
  }
  // The discrete punch is a set of vertices: its footprint is their share of the face (a third of each top
  // triangle's area to each of its vertices), and its force is compared at the radius of equal area.
  double footprint = 0.0, edge_footprint = 0.0;
  for (const Triangle& t : boundary_triangles(p.mesh)) {
    bool top = true;
    for (const auto v : t) top = top && on(p.mesh.points[static_cast<std::size_t>(v)][2], h);
    if (!top) continue;
    for (std::size_t k = 0; k < 3; ++k) {
      const bool held = punch[static_cast<std::size_t>(t[k])];
      if (held) footprint += triangle_area(p.mesh, t) / 3.0;
      if (held && punch[static_cast<std::size_t>(t[(k + 1) % 3])]) edge_footprint += triangle_area(p.mesh, t) / 3.0;
    }
  }
  const auto expected = [&](double area) {
    const double radius = std::sqrt(4 * area / M_PI);
    return 2 * radius * kHayesModulus * kHayesDepth / (1 - nu * nu) * hayes_kappa(radius / h, nu);
  };
  hayes.effective_radius = std::sqrt(4 * footprint / M_PI);
  hayes.expected_force = expected(footprint);
  hayes.expected_force_edge_nodes = expected(edge_footprint);
  return hayes;
}
// The whole punch's force (the quarter's, times 4), from the supports' reactions at its nodes (edge nodes included).
double hayes_punch_force(const ElasticAnswer& answer) {
  double sum = 0.0;
  for (std::size_t v = 0; v < answer.nodes.size(); ++v)
    if (on(answer.nodes[v][2], kHayesHeight) && std::hypot(answer.nodes[v][0], answer.nodes[v][1]) <= kHayesRadius * (1 + 1e-9))
      sum += answer.reaction[v][2];
  return -4 * sum;
}

}  // namespace

TEST_CASE("validation: uniaxial block with sliding faces, u = F L / (E A) and lateral strain -nu axial", "[validation]") {
  const Point3& size = kUniaxialSize;
  const double E = kUniaxialModulus, nu = kUniaxialPoissonRatio, traction = kUniaxialTraction;
  const ElasticProblem p = uniaxial_problem();
  const double axial = traction / E * size[2];      // F L / (E A)
  const double lateral = -nu * traction / E * size[0];
  const auto top = [&](const Point3& x) { return on(x[2], size[2]); };
  const auto side = [&](const Point3& x) { return on(x[0], size[0]); };
  std::ostringstream table;
  for (const ProblemModel model : kModels) {
    const ElasticAnswer a = fmpc_answer(p, model);
    const double u = mean_displacement(p, a, 2, top), w = mean_displacement(p, a, 0, side);
    table << "\n  " << model_name(model) << ": axial " << (u / axial - 1) * 100 << "%, lateral "
          << (w / lateral - 1) * 100 << "%";
    if (model == ProblemModel::CorotationalFem) {
      CHECK(u == Approx(axial).epsilon(1e-9));
      CHECK(w == Approx(lateral).epsilon(1e-9));
    }
  }
  if (const auto c3d4 = calculix_answer(p, false, "uniaxial")) {
    const double u = mean_displacement(p, *c3d4, 2, top);
    table << "\n  CalculiX C3D4: axial " << (u / axial - 1) * 100 << "%";
    CHECK(u == Approx(axial).epsilon(1e-5));
    CHECK(field_difference(*c3d4, fmpc_answer(p, ProblemModel::CorotationalFem)) < 1e-5);
  } else {
    warn_skip();
  }
  WARN("uniaxial block, error against F L / (E A) and -nu x axial strain:" << table.str());
}

TEST_CASE("validation: quadratic tetrahedra equal CalculiX C3D10 on the same mesh", "[validation][quadratic]") {
  // A block clamped at its base, its top moved (shear and compression): no loads, so the answer is the stiffness's
  // alone (C3D10's consistent gravity loads would differ from lumped masses' m g: measured below, not asserted).
  const Point3 size{0.02, 0.02, 0.03};
  std::ostringstream table;
  for (const double nu : {0.3, 0.49, 0.4999}) {
    ElasticProblem p = problem_on(box(size, 2, 2, 3), 5000.0, nu, 1000.0);
    p.prescribed.assign(p.mesh.points.size(), Point3{0, 0, 0});
    for (std::size_t v = 0; v < p.mesh.points.size(); ++v) {
      if (on(p.mesh.points[v][2], 0.0)) p.held[v] = 7;
      if (on(p.mesh.points[v][2], size[2])) {
        p.held[v] = 7;
        p.prescribed[v] = {3e-4, -1e-4 * p.mesh.points[v][0] / size[0], -2e-4};
      }
    }
    const ElasticAnswer quadratic = fmpc_answer(p, ProblemModel::QuadraticFem);
    if (const auto c3d10 = calculix_answer(p, true, "quadratic_" + std::to_string(static_cast<int>(nu * 10000)))) {
      const double difference = field_difference(*c3d10, quadratic);
      table << "\n  nu = " << nu << ": displacements differ by " << difference << " of the largest";
      CHECK(difference < 1e-4);
      // Reactions at every node (corners and edge nodes in the same order on both sides).
      double largest = 0.0, reaction_difference = 0.0;
      REQUIRE(c3d10->reaction.size() == quadratic.reaction.size());
      for (std::size_t v = 0; v < quadratic.reaction.size(); ++v) {
        largest = std::max(largest, distance(c3d10->reaction[v], Point3{0.0, 0.0, 0.0}));
        reaction_difference = std::max(reaction_difference, distance(c3d10->reaction[v], quadratic.reaction[v]));
      }
      CHECK(reaction_difference < 1e-4 * largest);
    } else {
      warn_skip();
    }
  }
  // Under gravity: lumped masses' m g (HRZ: 1/36 of an element's weight at each corner, 4/27 on each edge) against
  // C3D10's consistent body-force loads (-1/20 at each corner, 1/5 on each edge). The two load vectors differ inside
  // each element by a self-equilibrated set of forces, whose effect shrinks as h^2: measured 0.136, 0.035 and 0.0097
  // of the largest displacement on 2 x 2 x 3, 4 x 4 x 6 and 8 x 8 x 12 cells (the last left out here for CI's time).
  std::vector<double> gravity_differences;
  for (const int n : {1, 2}) {
    ElasticProblem hanging = problem_on(box(size, 2 * n, 2 * n, 3 * n), 5000.0, 0.45, 1000.0);
    for (std::size_t v = 0; v < hanging.mesh.points.size(); ++v)
      if (on(hanging.mesh.points[v][2], size[2])) hanging.held[v] = 7;
    hanging.gravity = {0.0, 0.0, -9.81};
    const auto c3d10 = calculix_answer(hanging, true, "quadratic_gravity");
    if (!c3d10) break;
    gravity_differences.push_back(field_difference(*c3d10, fmpc_answer(hanging, ProblemModel::QuadraticFem)));
    table << "\n  hanging block under gravity on " << 2 * n << " x " << 2 * n << " x " << 3 * n
          << " cells, nu = 0.45 (HRZ-lumped m g against consistent loads): " << gravity_differences.back();
  }
  if (gravity_differences.size() == 2) {
    CHECK(gravity_differences[1] < 0.04);
    CHECK(std::log2(gravity_differences[0] / gravity_differences[1]) > 1.8);
  }
  WARN("quadratic tetrahedra against CalculiX C3D10 on the same 2 x 2 x 3-cell mesh:" << table.str());
}

TEST_CASE("validation: self-weight column, rho g L^2 / 2E, converging at second order", "[validation][heavy]") {
  // A quarter column (symmetry planes x = 0 and y = 0 slide) standing on a sliding base: uniaxial stress
  // rho g (L - z), and the top face sinks by rho g L^2 / (2 E). With nu = 0 this is the exact 3-D solution; with
  // nu > 0 the exact field has a term nu rho g (x^2 + y^2) / 2E in u_z that a flat base does not allow, and a
  // boundary layer (Saint-Venant) moves the answer by a few 0.01% (measured below at nu = 0.3).
  const double exact = column_exact();
  std::vector<double> errors;
  std::ostringstream table;
  for (const int n : {1, 2, 4}) {
    const ElasticProblem p = column_problem(n);
    const auto top = column_top;
    const ElasticAnswer fem = fmpc_answer(p, ProblemModel::CorotationalFem);
    const double error = mean_displacement(p, fem, 2, top) / exact - 1;
    errors.push_back(std::abs(error));
    table << "\n  " << 2 * n << " x " << 2 * n << " x " << 5 * n << " cells: co-rotational FEM " << error * 100 << "%";
    if (n == 4) {
      for (const ProblemModel model : kModels) {
        // The volume term cannot lower the springs' nu = 1/4 to this problem's 0.
        if (model == ProblemModel::CorotationalFem || model == ProblemModel::SpringsVolumeTerm) continue;
        table << ", " << model_name(model) << " " << (mean_displacement(p, fmpc_answer(p, model), 2, top) / exact - 1) * 100
              << "%";
      }
    }
    if (const auto c3d4 = calculix_answer(p, false, "column")) {
      CHECK(field_difference(*c3d4, fem) < 1e-5);
    } else if (n == 1) {
      warn_skip();
    }
  }
  const double rate1 = std::log2(errors[0] / errors[1]), rate2 = std::log2(errors[1] / errors[2]);
  WARN("self-weight column, error against rho g L^2 / 2E:" << table.str() << "\n  convergence rates " << rate1 << ", "
                                                          << rate2);
  // At least second order (linear elements' displacements); averaged over a face of nodes they do better (2.5, 2.8).
  CHECK(rate1 > 1.8);
  CHECK(rate2 > 1.8);
  CHECK(errors[2] < 1e-4);
}

TEST_CASE("validation: slender cantilever under gravity against Euler-Bernoulli and converged C3D10",
          "[validation][heavy]") {
  // L = 0.1 m, 1 cm square section, clamped at x = 0, rho g downward. Euler-Bernoulli: tip deflection
  // q L^4 / (8 E I) = 3 rho g L^4 / (2 E h^2); Timoshenko's shear term adds q L^2 / (2 k G A) (k = 5/6), 0.9% here.
  const double E = 1e6, nu = 0.45, rho = 1060.0, g = 9.81, L = 0.1, h = 0.01;
  const double bernoulli = -3 * rho * g * L * L * L * L / (2 * E * h * h);
  const double shear = -rho * g * h * h * L * L / (2 * (5.0 / 6.0) * E / (2 * (1 + nu)) * h * h);
  const auto make = cantilever_problem;
  const auto tip = cantilever_tip;
  std::ostringstream table;
  table << "\n  Euler-Bernoulli " << bernoulli << " m, with Timoshenko's shear term " << bernoulli + shear << " m";
  std::optional<double> converged;
  {
    const ElasticProblem coarse = make(2), fine = make(4);
    const auto c3d10_coarse = calculix_answer(coarse, true, "cantilever10");
    if (const auto c3d10 = calculix_answer(fine, true, "cantilever10")) {
      converged = mean_displacement(fine, *c3d10, 2, tip);
      const double coarser = mean_displacement(coarse, *c3d10_coarse, 2, tip);
      table << "\n  CalculiX C3D10, 40 x 4 x 4 cells: " << *converged << " m ("
            << (*converged / (bernoulli + shear) - 1) * 100 << "% from the beam theories; 20 x 2 x 2 cells "
            << (coarser / *converged - 1) * 100 << "% from it)";
      // The clamped end keeps the section from contracting (nu = 0.45): slightly stiffer than the beam theories.
      CHECK(*converged == Approx(bernoulli + shear).epsilon(0.03));
      // Quadratic elements converge as h^2: 20 x 2 x 2 is 1.5% from 40 x 4 x 4, which is then about 0.4% from the
      // limit.
      CHECK(coarser == Approx(*converged).epsilon(0.02));
    } else {
      warn_skip();
    }
  }
  const double reference = converged.value_or(bernoulli + shear);
  for (const int n : {1, 2, 4}) {
    const ElasticProblem p = make(n);
    table << "\n  " << 10 * n << " x " << n << " x " << n << " cells:";
    for (const ProblemModel model : kModels) {
      const ElasticAnswer a = fmpc_answer(p, model);
      table << " " << model_name(model) << " " << (mean_displacement(p, a, 2, tip) / reference - 1) * 100 << "%;";
      if (model == ProblemModel::CorotationalFem) {
        if (const auto c3d4 = calculix_answer(p, false, "cantilever4")) {
          CHECK(field_difference(*c3d4, a) < 1e-5);
        }
      }
    }
  }
  WARN("cantilever tip deflection, error against the converged answer:" << table.str());
}

TEST_CASE("validation: hanging and compressed cubes against converged C3D10", "[validation][heavy]") {
  if (!calculix_available()) {
    warn_skip();
    return;
  }
  std::ostringstream table;
  for (const double nu : {0.25, 0.45}) {
    const auto hanging = [&](int n) { return hanging_cube(n, nu); };
    const auto compressed = [&](int n) { return compressed_cube(n, nu); };
    const auto bottom = cube_bottom;
    const auto top_force = [&](const ElasticProblem&, const ElasticAnswer& a) { return cube_top_force(a); };
    const ElasticProblem fine_hanging = hanging(8), fine_compressed = compressed(8);
    const auto hanging_c3d10 = calculix_answer(fine_hanging, true, "hanging10");
    const auto compressed_c3d10 = calculix_answer(fine_compressed, true, "compressed10");
    const double hanging_reference = mean_displacement(fine_hanging, *hanging_c3d10, 2, bottom);
    const double compressed_reference = top_force(fine_compressed, *compressed_c3d10);
    table << "\n  nu = " << nu << ": C3D10 8^3 hanging " << hanging_reference << " m, compressed " << compressed_reference
          << " N";
    const ElasticProblem h6 = hanging(6), c6 = compressed(6);
    for (const ProblemModel model : kModels) {
      const ElasticAnswer ha = fmpc_answer(h6, model), ca = fmpc_answer(c6, model);
      table << "\n    6^3 " << model_name(model) << ": hanging " << (mean_displacement(h6, ha, 2, bottom) / hanging_reference - 1) * 100
            << "%, compressed " << (top_force(c6, ca) / compressed_reference - 1) * 100 << "%";
      if (model == ProblemModel::CorotationalFem) {
        const auto h4 = calculix_answer(h6, false, "hanging4");
        const auto c4 = calculix_answer(c6, false, "compressed4");
        CHECK(field_difference(*h4, ha) < 1e-5);
        CHECK(top_force(c6, *c4) == Approx(top_force(c6, ca)).epsilon(1e-5));
        // The FEM on the coarser mesh is within a few percent of the converged answer; linear tetrahedra stiffen
        // (lock) as nu approaches 1/2, most in confined compression (+6.4% at nu = 0.45 here).
        CHECK(std::abs(mean_displacement(h6, ha, 2, bottom) / hanging_reference - 1) < 0.06);
        CHECK(std::abs(top_force(c6, ca) / compressed_reference - 1) < 0.08);
      }
    }
  }
  WARN("cubes, error against C3D10 on 8^3 cells:" << table.str());
}

TEST_CASE("validation: Hayes et al. 1972 indentation of a bonded layer", "[validation][heavy]") {
  // kappa's own checks: the half-space limit (Sneddon) and the thin-layer limit (confined compression).
  CHECK(hayes_kappa(1e-4, 0.3) == Approx(1.0).epsilon(1e-3));
  const double nu_thin = 0.3, M = (1 - nu_thin) / ((1 + nu_thin) * (1 - 2 * nu_thin));
  CHECK(hayes_kappa(8.0, nu_thin) / (M_PI / 2 * 8.0 * (1 - nu_thin * nu_thin) * M) == Approx(1.0).epsilon(0.06));
  // A flat punch of radius a = 5 mm pressed 0.1 mm into a 10 mm layer (a/h = 0.5) bonded to a rigid base. Quarter
  // model: the punch's axis on the corner x = y = 0, symmetry planes slide, the layer 6 a wide, the punch's vertices
  // held in z only (frictionless).
  const double E = kHayesModulus, nu = kHayesPoissonRatio, a = kHayesRadius, h = kHayesHeight, delta = kHayesDepth;
  const double kappa = hayes_kappa(a / h, nu);
  const double expected = 2 * a * E * delta / (1 - nu * nu) * kappa;
  std::ostringstream table;
  table << "\n  kappa(a/h = 0.5, nu = 0.45) = " << kappa << ", P = " << expected << " N";
  for (const int n : {1, 2}) {
    const HayesProblem hayes = hayes_problem(n);
    const ElasticProblem& p = hayes.problem;
    const double a_effective = hayes.effective_radius, expected_here = hayes.expected_force;
    const auto punch_force = hayes_punch_force;
    table << "\n  " << 12 * n << " x " << 12 * n << " x " << 4 * n << " cells (footprint radius " << a_effective * 1000
          << " mm, Hayes P = " << expected_here << " N):";
    for (const ProblemModel model : kModels) {
      const ElasticAnswer answer = fmpc_answer(p, model);
      const double error = punch_force(answer) / expected_here - 1;
      table << " " << model_name(model) << " " << error * 100 << "%;";
      if (model == ProblemModel::CorotationalFem) {
        if (const auto c3d4 = calculix_answer(p, false, "indentation")) {
          CHECK(punch_force(*c3d4) == Approx(punch_force(answer)).epsilon(1e-4));
        } else if (n == 1) {
          warn_skip();
        }
        // Linear tetrahedra are stiff at the punch's edge (the stress is singular there) and at nu = 0.45: within
        // 10% at these meshes (measured: docs/validation.md).
        CHECK(std::abs(error) < 0.10);
      }
    }
  }
  WARN("indentation, error against Hayes et al.:" << table.str());
}

TEST_CASE("validation: nodal pressure tetrahedra do not lock in volume where linear ones do (SOFA's liver, a "
          "cantilever; nu up to 0.4999)",
          "[validation][nodal]") {
  std::ostringstream table;
  // SOFA's liver.msh (596 tetrahedra) under gravity, nodes 3 39 64 held, E = 1 MPa (issue 26's case), each element
  // against the quadratic element on the same mesh (equal to C3D10 there: the test above): the mean displacement
  // magnitude over the vertices. Linear tetrahedra stiffen as nu approaches 1/2 (volumetric locking); the nodal
  // pressure element's answer does not depend on nu. Both keep the linear element's bending error on this coarse
  // mesh (about 60% too stiff at nu 0.3), which only refinement removes.
  DiagnosticList diagnostics;
  auto liver = read_mesh_file(std::string(FMPC_SHARED_DATA_DIR) + "/sofa-liver/liver.msh", diagnostics);
  if (liver) {
    repair_mesh(*liver);
    std::vector<double> nodal_ratio, linear_ratio;
    table << "\n  SOFA's liver, mean |u| over the quadratic element's on the same mesh:";
    for (const double nu : {0.3, 0.49, 0.499, 0.4999}) {
      ElasticProblem p = problem_on(*liver, 1e6, nu, 1000.0);
      p.gravity = {0.0, -9.81, 0.0};
      for (const std::size_t v : {3, 39, 64}) p.held[v] = 7;
      const auto mean = [&](const ElasticAnswer& a) {
        double sum = 0.0;
        for (std::size_t v = 0; v < p.mesh.points.size(); ++v)
          sum += std::sqrt(a.displacement[v][0] * a.displacement[v][0] + a.displacement[v][1] * a.displacement[v][1] +
                           a.displacement[v][2] * a.displacement[v][2]);
        return sum / static_cast<double>(p.mesh.points.size());
      };
      const double quadratic = mean(fmpc_answer(p, ProblemModel::QuadraticFem));
      nodal_ratio.push_back(mean(fmpc_answer(p, ProblemModel::NodalPressureFem)) / quadratic);
      table << "\n    nu " << nu << ": nodal pressure " << nodal_ratio.back();
      // Linear tetrahedra take nu up to 0.499.
      if (nu <= 0.499) {
        linear_ratio.push_back(mean(fmpc_answer(p, ProblemModel::CorotationalFem)) / quadratic);
        table << ", linear " << linear_ratio.back();
      }
    }
    for (const double ratio : nodal_ratio) CHECK(ratio == Approx(nodal_ratio.front()).epsilon(0.1));
    CHECK(linear_ratio[2] < 0.5 * linear_ratio[0]);  // linear tetrahedra lock at 0.499
    CHECK(nodal_ratio[1] > linear_ratio[1] * 1.3);    // nu 0.49
    CHECK(nodal_ratio[2] > linear_ratio[2] * 2.5);    // nu 0.499
  } else {
    WARN("skipped the liver: ../shared/data/sofa-liver/liver.msh is absent");
  }
  // The cantilever above (0.1 m, 1 cm square, clamped at x = 0, gravity) at nu 0.49 and 0.4999 against the quadratic
  // element on 40 x 4 x 4 cells: bending-dominated, so that linear tetrahedra's shear locking (which averaging the
  // pressure leaves) is most of both errors.
  const auto tip = cantilever_tip;
  for (const double nu : {0.49, 0.4999}) {
    const auto make = [&](int n) {
      ElasticProblem p = cantilever_problem(n);
      p.poisson_ratio = nu;
      return p;
    };
    const ElasticProblem fine = make(4), coarse = make(2);
    const double reference = mean_displacement(fine, fmpc_answer(fine, ProblemModel::QuadraticFem), 2, tip);
    table << "\n  cantilever tip at nu " << nu << ": quadratic 40 x 4 x 4 " << reference << " m";
    for (const int n : {2, 4}) {
      const ElasticProblem& p = n == 4 ? fine : coarse;
      ElasticProblem capped = p;
      capped.poisson_ratio = std::min(nu, 0.499);
      const double linear =
          mean_displacement(capped, fmpc_answer(capped, ProblemModel::CorotationalFem), 2, tip) / reference - 1;
      const double nodal =
          mean_displacement(p, fmpc_answer(p, ProblemModel::NodalPressureFem), 2, tip) / reference - 1;
      table << "; " << 10 * n << " x " << n << " x " << n << ": linear" << (nu > 0.499 ? " (nu 0.499) " : " ")
            << linear * 100 << "%, nodal pressure " << nodal * 100 << "%";
      CHECK(std::abs(nodal) < std::abs(linear));
    }
  }
  WARN("nodal pressure tetrahedra against the quadratic element:" << table.str());
}

namespace {

// Every finite-element law x element kind of the registry (runtime/fem/element_law_registry.h): a law or kind added
// there is one more row of the tables below.
struct FemVariant {
  std::string name;  // "law / kind"
  int law = 0, kind = 0;
};
std::vector<FemVariant> fem_variants() {
  std::vector<FemVariant> out;
  for (const std::string& law : fem_law_keywords())
    for (const ElementKindRow& kind : element_kind_rows())
      out.push_back({law + " / " + kind.keyword, fem_law_by_keyword(law)->law, kind.kind});
  return out;
}

ElasticAnswer fem_answer(const ElasticProblem& p, const FemVariant& variant) {
  std::string error;
  auto answer = solve_with_fmpc_fem(p, variant.law, variant.kind, error);
  INFO(variant.name << ": " << error);
  REQUIRE(answer);
  return *answer;
}

}  // namespace

TEST_CASE("validation: every law and element kind is exact for uniform strain", "[validation]") {
  // Linear and quadratic tetrahedra represent a uniform strain exactly, and every law's small-strain tangent is
  // Hooke's: the uniaxial block's answer to rounding.
  const ElasticProblem p = uniaxial_problem();
  const double axial = kUniaxialTraction / kUniaxialModulus * kUniaxialSize[2];
  const double lateral = -kUniaxialPoissonRatio * kUniaxialTraction / kUniaxialModulus * kUniaxialSize[0];
  for (const FemVariant& variant : fem_variants()) {
    const ElasticAnswer a = fem_answer(p, variant);
    INFO(variant.name);
    CHECK(mean_displacement(p, a, 2, [](const Point3& x) { return on(x[2], kUniaxialSize[2]); }) ==
          Approx(axial).epsilon(1e-9));
    CHECK(mean_displacement(p, a, 0, [](const Point3& x) { return on(x[0], kUniaxialSize[0]); }) ==
          Approx(lateral).epsilon(1e-9));
  }
}

TEST_CASE("validation: the analytic and CalculiX cases for every law x element kind (docs/validation.md)",
          "[.element_table]") {
  REQUIRE(calculix_available());
  std::ostringstream out;
  out << std::setprecision(4);
  const auto percent = [](double value) {
    std::ostringstream text;
    text << std::showpos << std::fixed << std::setprecision(std::abs(value) < 1 ? 3 : 1) << value << " %";
    return text.str();
  };
  // The converged references the suite's cases use: C3D10 on the fine meshes.
  const ElasticProblem cantilever_fine = cantilever_problem(4);
  const double cantilever_reference =
      mean_displacement(cantilever_fine, *calculix_answer(cantilever_fine, true, "cantilever10"), 2, cantilever_tip);
  double hanging_reference[2], compressed_reference[2];
  for (int i = 0; i < 2; ++i) {
    const double nu = i == 0 ? 0.25 : 0.45;
    const ElasticProblem hanging = hanging_cube(8, nu), compressed = compressed_cube(8, nu);
    hanging_reference[i] = mean_displacement(hanging, *calculix_answer(hanging, true, "hanging10"), 2, cube_bottom);
    compressed_reference[i] = cube_top_force(*calculix_answer(compressed, true, "compressed10"));
  }
  out << "\n| law / element | column 2x2x5 | column 4x4x10 | cantilever 10x1x1 | cantilever 20x2x2 | cantilever "
         "40x4x4 | hanging cube 6^3, nu 0.25 | compressed, 0.25 | hanging, 0.45 | compressed, 0.45 | Hayes 12x12x4 "
         "|\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|";
  for (const FemVariant& variant : fem_variants()) {
    out << "\n| " << variant.name << " |";
    for (const int n : {1, 2}) {
      const ElasticProblem p = column_problem(n);
      out << " " << percent((mean_displacement(p, fem_answer(p, variant), 2, column_top) / column_exact() - 1) * 100)
          << " |";
    }
    for (const int n : {1, 2, 4}) {
      const ElasticProblem p = cantilever_problem(n);
      out << " "
          << percent((mean_displacement(p, fem_answer(p, variant), 2, cantilever_tip) / cantilever_reference - 1) * 100)
          << " |";
    }
    for (int i = 0; i < 2; ++i) {
      const double nu = i == 0 ? 0.25 : 0.45;
      const ElasticProblem hanging = hanging_cube(6, nu), compressed = compressed_cube(6, nu);
      out << " "
          << percent((mean_displacement(hanging, fem_answer(hanging, variant), 2, cube_bottom) / hanging_reference[i] - 1) *
                     100)
          << " | " << percent((cube_top_force(fem_answer(compressed, variant)) / compressed_reference[i] - 1) * 100)
          << " |";
    }
    const HayesProblem hayes = hayes_problem(1);
    const ElasticAnswer indented = fem_answer(hayes.problem, variant);
    const bool edge_nodes = indented.nodes.size() > hayes.problem.mesh.points.size();
    out << " "
        << percent((hayes_punch_force(indented) / (edge_nodes ? hayes.expected_force_edge_nodes : hayes.expected_force) -
                    1) *
                   100)
        << " |";
  }
  WARN("every law x element kind, error against the analytic answer or converged C3D10:" << out.str());
}

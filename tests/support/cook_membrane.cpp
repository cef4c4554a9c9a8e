#include "tests/support/cook_membrane.h"

#include <cmath>
#include <sstream>
#include <vector>

#include "runtime/mesh/generated_mesh.h"

namespace fmpc::testing {

namespace {

constexpr double kLoad = 1.0;        // the shear's total (N)
constexpr double kEdgeLength = 16.0;  // the right edge, from (48, 44) to (48, 60)

// The unit square's (s, t) on the trapezoid: x = 48 s, y from the bottom edge (44 s) to the top edge (44 + 16 s).
sim::Point3 trapezoid(double s, double t, double z) { return {48.0 * s, 44.0 * s + t * (44.0 - 28.0 * s), z}; }

bool near(double a, double b) { return std::abs(a - b) < 1e-9; }

}  // namespace

CookMembrane cook_membrane(int per_side, double poisson_ratio) {
  DiagnosticList diagnostics;
  sim::BoxSpec box;
  box.cells_x = box.cells_y = per_side;
  box.cells_z = 1;
  sim::Mesh mesh = sim::generate_box(box, diagnostics);
  for (sim::Point3& p : mesh.points) p = trapezoid(p[0], p[1], p[2]);
  mesh.source = "Cook's membrane, " + std::to_string(per_side) + " per side";
  CookMembrane cook;
  ElasticProblem& p = cook.problem;
  p.youngs_modulus = 1.0;
  p.poisson_ratio = poisson_ratio;
  p.density = 1.0;  // no gravity: only the static solver's masses need it
  p.held.assign(mesh.points.size(), 4u);  // plane strain
  for (std::size_t v = 0; v < mesh.points.size(); ++v) {
    const sim::Point3& x = mesh.points[v];
    if (near(x[0], 0.0)) p.held[v] = 7u;
    if (near(x[0], 48.0) && near(x[1], 60.0) && near(x[2], 0.0)) cook.tip = v;
  }
  for (const sim::Triangle& face : sim::boundary_triangles(mesh))
    if (near(mesh.points[static_cast<std::size_t>(face[0])][0], 48.0) &&
        near(mesh.points[static_cast<std::size_t>(face[1])][0], 48.0) &&
        near(mesh.points[static_cast<std::size_t>(face[2])][0], 48.0))
      p.traction_faces.push_back(face);
  p.traction = {0.0, kLoad / kEdgeLength, 0.0};  // per unit area of the 16 x 1 face
  p.mesh = std::move(mesh);
  return cook;
}

std::optional<double> calculix_cook_2d(int per_side, double poisson_ratio, bool plane_stress, bool reduced,
                                       const std::filesystem::path& folder, std::string& error) {
  // Nodes on the (2n + 1)^2 grid of half cells, without the cells' centres (8-node serendipity quadrilaterals).
  const int n = per_side, m = 2 * per_side + 1;
  std::vector<int> id(static_cast<std::size_t>(m * m), 0);
  std::ostringstream deck;
  deck << "*NODE, NSET=Nall\n";
  int count = 0;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) {
      if (i % 2 == 1 && j % 2 == 1) continue;
      id[static_cast<std::size_t>(j * m + i)] = ++count;
      const sim::Point3 x = trapezoid(static_cast<double>(i) / (m - 1), static_cast<double>(j) / (m - 1), 0.0);
      deck << count << ", " << calculix_number(x[0]) << ", " << calculix_number(x[1]) << "\n";
    }
  const auto node = [&](int i, int j) { return id[static_cast<std::size_t>(j * m + i)]; };
  // Corners counter-clockwise, then the mid-edges 1-2, 2-3, 3-4, 4-1 (CalculiX's CPE8 / CPS8 order).
  deck << "*ELEMENT, TYPE=" << (plane_stress ? "CPS8" : "CPE8") << (reduced ? "R" : "") << ", ELSET=Eall\n";
  int element = 0;
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a) {
      const int i = 2 * a, j = 2 * b;
      deck << ++element << ", " << node(i, j) << ", " << node(i + 2, j) << ", " << node(i + 2, j + 2) << ", "
           << node(i, j + 2) << ", " << node(i + 1, j) << ", " << node(i + 2, j + 1) << ", " << node(i + 1, j + 2)
           << ",\n" << node(i, j + 1) << "\n";
    }
  deck << "*MATERIAL, NAME=m\n*ELASTIC\n1.0, " << calculix_number(poisson_ratio)
       << "\n*SOLID SECTION, ELSET=Eall, MATERIAL=m\n1.0\n*STEP\n*STATIC\n*BOUNDARY\n";
  for (int j = 0; j < m; ++j)
    if (node(0, j) != 0) deck << node(0, j) << ", 1, 2\n";
  // Each cell's right edge carries 1 / n of the load: 1/6, 2/3, 1/6 of it at its three nodes.
  deck << "*CLOAD\n";
  std::vector<double> load(static_cast<std::size_t>(m), 0.0);
  for (int b = 0; b < n; ++b) {
    load[static_cast<std::size_t>(2 * b)] += kLoad / n / 6;
    load[static_cast<std::size_t>(2 * b + 1)] += kLoad / n * 2 / 3;
    load[static_cast<std::size_t>(2 * b + 2)] += kLoad / n / 6;
  }
  for (int j = 0; j < m; ++j) deck << node(m - 1, j) << ", 2, " << calculix_number(load[static_cast<std::size_t>(j)]) << "\n";
  deck << "*NODE PRINT, NSET=Nall\nU\n*END STEP\n";
  const auto dat = run_calculix(deck.str(), folder, error);
  if (!dat) return std::nullopt;
  const auto u = read_calculix_block(*dat, "displacements (vx,vy,vz)");
  const auto tip = u.find(node(m - 1, m - 1));
  if (tip == u.end()) {
    error = "ccx's .dat in " + folder.string() + " has no displacement for the top-right corner";
    return std::nullopt;
  }
  return tip->second[1];
}

}  // namespace fmpc::testing

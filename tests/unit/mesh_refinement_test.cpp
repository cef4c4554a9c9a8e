// subdivide_tetrahedra (runtime/mesh/mesh_refinement.h): the properties a convergence study relies on, on generated
// boxes and ellipsoids and on seeded random tetrahedra.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "runtime/mesh/generated_mesh.h"
#include "runtime/mesh/mesh_check.h"
#include "runtime/mesh/mesh_refinement.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

double total_volume(const Mesh& mesh) {
  double sum = 0.0;
  for (const Tetrahedron& t : mesh.tetrahedra) sum += signed_volume(mesh, t);
  return sum;
}

// Every interior face (sorted vertex triple) is shared by exactly two tetrahedra, every boundary face by one, and
// the boundary's area equals the parent's: no hanging vertex, no crack, no overlap along faces.
std::map<std::array<std::int32_t, 3>, int> face_counts(const Mesh& mesh) {
  std::map<std::array<std::int32_t, 3>, int> counts;
  for (const Tetrahedron& t : mesh.tetrahedra) {
    for (int skip = 0; skip < 4; ++skip) {
      std::array<std::int32_t, 3> face{};
      int k = 0;
      for (int i = 0; i < 4; ++i)
        if (i != skip) face[static_cast<std::size_t>(k++)] = t[static_cast<std::size_t>(i)];
      std::sort(face.begin(), face.end());
      ++counts[face];
    }
  }
  return counts;
}

double boundary_area(const Mesh& mesh) {
  double area = 0.0;
  for (const Triangle& t : boundary_triangles(mesh)) area += triangle_area(mesh, t);
  return area;
}

void check_refinement(const Mesh& mesh) {
  const Mesh refined = subdivide_tetrahedra(mesh);
  INFO(mesh.source);
  // V + E vertices, the parent's first and unchanged; 8 tetrahedra per tetrahedron.
  REQUIRE(refined.points.size() == mesh.points.size() + distinct_edge_count(mesh));
  CHECK(std::equal(mesh.points.begin(), mesh.points.end(), refined.points.begin()));
  REQUIRE(refined.tetrahedra.size() == 8 * mesh.tetrahedra.size());
  // Each parent's children: positive volumes summing to the parent's.
  for (std::size_t e = 0; e < mesh.tetrahedra.size(); ++e) {
    const double parent = signed_volume(mesh, mesh.tetrahedra[e]);
    double children = 0.0;
    for (std::size_t c = 0; c < 8; ++c) {
      const double v = signed_volume(refined, refined.tetrahedra[8 * e + c]);
      CHECK(v > 0.0);
      children += v;
    }
    CHECK(children == Approx(parent).epsilon(1e-12));
  }
  CHECK(total_volume(refined) == Approx(total_volume(mesh)).epsilon(1e-12));
  // Conforming: every face is shared by at most two children, and the boundary covers the same area.
  for (const auto& [face, count] : face_counts(refined)) CHECK(count <= 2);
  CHECK(boundary_area(refined) == Approx(boundary_area(mesh)).epsilon(1e-12));
  CHECK(boundary_triangles(refined).size() == 4 * boundary_triangles(mesh).size());
  // The repair finds nothing to change: no duplicate, degenerate, inverted or unused element or vertex.
  Mesh copy = refined;
  const MeshRepairResult repair = repair_mesh(copy);
  for (const MeshFinding& finding : repair.findings) FAIL_CHECK(finding_message(finding));
}

}  // namespace

TEST_CASE("1:8 subdivision keeps the vertices, the volume, the orientation and conformity", "[mesh][refinement]") {
  DiagnosticList diagnostics;
  BoxSpec box;
  box.size = {0.04, 0.03, 0.02};
  box.cells_x = 3, box.cells_y = 2, box.cells_z = 2;
  const Mesh coarse = generate_box(box, diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  check_refinement(coarse);
  check_refinement(subdivide_tetrahedra(coarse));  // twice: the refinement of a refinement
  EllipsoidSpec ellipsoid;
  ellipsoid.radii = {1.0, 0.5, 0.3};
  ellipsoid.resolution = 2;
  check_refinement(generate_ellipsoid(ellipsoid, diagnostics));

  // A single tetrahedron: 4 + 6 vertices, each midpoint exactly between its edge's ends.
  Mesh one;
  one.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  one.tetrahedra = {{0, 1, 2, 3}};
  const Mesh refined = subdivide_tetrahedra(one);
  REQUIRE(refined.points.size() == 10);
  CHECK(refined.points[4] == Point3{0.5, 0, 0});  // edge 0-1, the first in sorted order
  CHECK(refined.points[9] == Point3{0, 0.5, 0.5});  // edge 2-3, the last
  // Volumes 1/48 each: the regular split of a corner tetrahedron gives eight equal volumes.
  for (const Tetrahedron& t : refined.tetrahedra) CHECK(signed_volume(refined, t) == Approx(1.0 / 48.0).epsilon(1e-14));
  // No tetrahedra, no edges: nothing changes.
  CHECK(subdivide_tetrahedra(Mesh{}).points.empty());
}

TEST_CASE("1:8 subdivision of seeded random tetrahedra: volumes, orientation and source lines", "[mesh][refinement]") {
  std::mt19937_64 random(20261124);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Mesh mesh;
    for (int i = 0; i < 4; ++i) mesh.points.push_back({coordinate(random), coordinate(random), coordinate(random)});
    mesh.tetrahedra = {{0, 1, 2, 3}};
    mesh.tetrahedron_lines = {trial + 1};
    const double parent = signed_volume(mesh, mesh.tetrahedra[0]);
    if (std::abs(parent) < 1e-3) continue;  // near-degenerate: the signs of its children are rounding
    // Both orientations: a negative parent gives negative children.
    if (trial % 2 == 1) std::swap(mesh.tetrahedra[0][2], mesh.tetrahedra[0][3]);
    const double signed_parent = signed_volume(mesh, mesh.tetrahedra[0]);
    const Mesh refined = subdivide_tetrahedra(mesh);
    double sum = 0.0;
    for (const Tetrahedron& t : refined.tetrahedra) {
      const double v = signed_volume(refined, t);
      CHECK((v > 0.0) == (signed_parent > 0.0));
      sum += v;
    }
    CHECK(sum == Approx(signed_parent).epsilon(1e-12));
    CHECK(refined.tetrahedron_lines == std::vector<int>(8, trial + 1));
    ++checked;
  }
  CHECK(checked > 1500);
}

TEST_CASE("1:8 subdivision splits triangles into four with the parent's winding", "[mesh][refinement]") {
  Mesh membrane;
  membrane.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  membrane.triangles = {{0, 1, 2}, {0, 2, 3}};
  const Mesh refined = subdivide_tetrahedra(membrane);
  CHECK(refined.points.size() == 4 + 5);  // the shared diagonal gets one midpoint
  REQUIRE(refined.triangles.size() == 8);
  double area = 0.0;
  for (const Triangle& t : refined.triangles) {
    const Point3& a = refined.points[static_cast<std::size_t>(t[0])];
    const Point3& b = refined.points[static_cast<std::size_t>(t[1])];
    const Point3& c = refined.points[static_cast<std::size_t>(t[2])];
    const double normal_z = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    CHECK(normal_z > 0.0);  // counter-clockwise seen from +z, as the parents
    area += triangle_area(refined, t);
  }
  CHECK(area == Approx(1.0).epsilon(1e-14));
}

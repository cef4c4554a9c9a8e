// A kept surface split to the size field (runtime/meshing/surface_split.h): every triangle meets the field, the
// surface stays closed, outward and the same polyhedron (volume and area), the far triangles are untouched, the split
// is deterministic, a selection of surface vertices extends along its edges, the limit is held, and a scene with
// `split_surface` meshes the split surface as its boundary, its fixed face fixed and its probed face picked along
// their length.
#include "runtime/meshing/surface_split.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "runtime/meshing/surface_check.h"
#include "runtime/meshing/volume_mesher.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "tests/support/fmpc_process.h"
#include "tests/support/surface_meshes.h"

using namespace fmpc;
using namespace fmpc::sim;
using fmpc::testing::sorted_faces;
using fmpc::testing::unit_cube_surface;

namespace {

// Fine (0.05) within 0.1 of the top face's centre, graded at 2 to 2 (no split) from the bottom face.
SizeField top_centre_field() {
  SizeField field;
  field.size_far = 2.0;
  field.size_near = 0.05;
  field.near_distance = 0.1;
  field.grading = 2.0;
  field.sources.push_back({{0.5, 0.5, 1.0}, {0.5, 0.5, 1.0}});
  return field;
}

double longest_edge(const Mesh& m, const Triangle& t) {
  const auto& p = m.points;
  return std::max({distance(p[static_cast<std::size_t>(t[0])], p[static_cast<std::size_t>(t[1])]),
                   distance(p[static_cast<std::size_t>(t[1])], p[static_cast<std::size_t>(t[2])]),
                   distance(p[static_cast<std::size_t>(t[2])], p[static_cast<std::size_t>(t[0])])});
}

Point3 centroid(const Mesh& m, const Triangle& t) {
  Point3 c{0, 0, 0};
  for (const auto v : t)
    for (std::size_t a = 0; a < 3; ++a) c[a] += m.points[static_cast<std::size_t>(v)][a] / 3.0;
  return c;
}

}  // namespace

TEST_CASE("a surface split to the field: every triangle meets it, closed, outward, the same polyhedron",
          "[mesher][split]") {
  Mesh surface = unit_cube_surface();
  const SizeField field = top_centre_field();
  DiagnosticList diagnostics;
  const auto split = split_surface_to_size(surface, field, kMaxSurfaceTriangles, diagnostics);
  REQUIRE(split);
  CHECK(diagnostics.empty());
  CHECK(split->triangles_before == 12);
  CHECK(split->triangles_after == surface.triangles.size());
  // A disc of radius 0.1 on the top (area 0.031) in triangles of edges 0.05 (area at most 0.0011) or less.
  CHECK(split->parents.size() >= 30);
  CHECK(surface.points.size() == 8 + split->parents.size());
  CHECK(split->triangles_after == 12 + 2 * split->parents.size());  // each bisection: two triangles for four
  for (const Triangle& t : surface.triangles) {
    CAPTURE(longest_edge(surface, t), size_at(field, centroid(surface, t)));
    CHECK(longest_edge(surface, t) <= size_at(field, centroid(surface, t)));
  }
  // Longest-edge bisection keeps every angle at least half the input's smallest (45 degrees on the cube).
  double smallest = 180.0;
  for (const Triangle& t : surface.triangles)
    for (int k = 0; k < 3; ++k) {
      const Point3& p = surface.points[static_cast<std::size_t>(t[k])];
      const Point3& q = surface.points[static_cast<std::size_t>(t[(k + 1) % 3])];
      const Point3& r = surface.points[static_cast<std::size_t>(t[(k + 2) % 3])];
      const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
      const double cosine = (u[0] * w[0] + u[1] * w[1] + u[2] * w[2]) / (distance(p, q) * distance(p, r));
      smallest = std::min(smallest, std::acos(std::max(-1.0, std::min(1.0, cosine))) * 180.0 / M_PI);
    }
  CAPTURE(smallest);
  CHECK(smallest >= 22.5 - 1e-9);
  // Each added vertex halves its parents' edge, both earlier vertices.
  for (std::size_t k = 0; k < split->parents.size(); ++k) {
    const auto [a, b] = split->parents[k];
    REQUIRE(static_cast<std::size_t>(std::max(a, b)) < 8 + k);
    const Point3& p = surface.points[8 + k];
    for (std::size_t axis = 0; axis < 3; ++axis)
      CHECK(p[axis] ==
            (surface.points[static_cast<std::size_t>(a)][axis] + surface.points[static_cast<std::size_t>(b)][axis]) /
                2.0);
  }
  // Closed (every edge in two triangles, once each way), outward, and the cube's volume and area.
  DiagnosticList check;
  const SurfaceCheck closed = check_closed_surface(surface, check);
  CHECK(closed.closed);
  CHECK_FALSE(closed.inward);
  CHECK(closed.volume == Approx(1.0).epsilon(1e-12));
  double area = 0.0;
  for (const Triangle& t : surface.triangles) area += triangle_area(surface, t);
  CHECK(area == Approx(6.0).epsilon(1e-12));
  // Far from the source the bottom's two triangles are untouched.
  const std::set<Triangle> faces = sorted_faces(surface.triangles);
  CHECK(faces.count({0, 2, 3}) == 1);
  CHECK(faces.count({0, 1, 2}) == 1);
  // The same input gives the same split.
  Mesh again = unit_cube_surface();
  DiagnosticList none;
  REQUIRE(split_surface_to_size(again, field, kMaxSurfaceTriangles, none));
  CHECK(again.points == surface.points);
  CHECK(again.triangles == surface.triangles);
}

TEST_CASE("a selection of surface vertices extends to the midpoints of its edges, and only those", "[mesher][split]") {
  Mesh surface = unit_cube_surface();
  SizeField field;
  field.size_far = field.size_near = 0.3;  // every triangle split
  DiagnosticList diagnostics;
  const auto split = split_surface_to_size(surface, field, kMaxSurfaceTriangles, diagnostics);
  REQUIRE(split);
  std::vector<unsigned char> selected(surface.points.size(), 0);
  for (std::size_t v = 0; v < 4; ++v) selected[v] = 1;  // the bottom face's corners
  split_selection(*split, 8, selected);
  std::size_t bottom = 0;
  for (std::size_t v = 0; v < surface.points.size(); ++v) {
    const bool on_bottom = surface.points[v][2] == 0.0;
    bottom += on_bottom ? 1 : 0;
    CAPTURE(v, surface.points[v][0], surface.points[v][1], surface.points[v][2]);
    CHECK(static_cast<bool>(selected[v]) == on_bottom);
  }
  CHECK(bottom > 4);
}

TEST_CASE("a split past the surface limit is refused before it is made", "[mesher][split]") {
  Mesh surface = unit_cube_surface();
  SizeField field;
  field.size_far = field.size_near = 0.01;
  DiagnosticList diagnostics;
  CHECK_FALSE(split_surface_to_size(surface, field, 5000, diagnostics));
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items().front().message ==
        "splitting the kept surface to the size field needs more than 5000 triangles, the mesher's limit: raise "
        "size_near or size_far, or shrink near_distance");
}

// A unit square ab cd (z = 0) on a pyramid's two tetrahedra (apex below, diagonal bd) and a flat element over it
// whose two upper faces (diagonal ac) are the surface's: removed, the square is bounded across bd, the same area.
TEST_CASE("a flat element on the surface is removed; one with a single face there is kept", "[mesher][split]") {
  Mesh mesh;
  mesh.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, -1}};
  mesh.tetrahedra = {{0, 1, 3, 4}, {1, 2, 3, 4}, {0, 1, 2, 3}};
  for (Tetrahedron& t : mesh.tetrahedra)
    if (signed_volume(mesh, t) < 0.0) std::swap(t[2], t[3]);
  const std::vector<Triangle> surface = {{0, 1, 2}, {0, 2, 3}};
  Mesh one_face = mesh;
  CHECK(remove_flat_surface_tetrahedra(mesh, surface) == 1);
  REQUIRE(mesh.tetrahedra.size() == 2);
  const std::set<Triangle> faces = sorted_faces(boundary_triangles(mesh));
  CHECK(faces.count({0, 1, 3}) == 1);
  CHECK(faces.count({1, 2, 3}) == 1);
  CHECK(remove_flat_surface_tetrahedra(one_face, {{0, 1, 2}}) == 0);
  CHECK(one_face.tetrahedra.size() == 3);
}

TEST_CASE("mesh_volume with split_surface: the split surface is the boundary, its far triangles the input's",
          "[mesher][split]") {
  VolumeMeshOptions options;
  options.size = top_centre_field();
  options.keep_surface = true;
  options.split_surface = true;
  DiagnosticList diagnostics;
  const auto meshed = mesh_volume(unit_cube_surface(), options, diagnostics);
  REQUIRE(meshed);
  REQUIRE(meshed->split);
  Mesh split = unit_cube_surface();
  DiagnosticList none;
  REQUIRE(split_surface_to_size(split, options.size, kMaxSurfaceTriangles, none));
  CHECK(sorted_faces(boundary_triangles(meshed->mesh)) == sorted_faces(split.triangles));
  for (std::size_t v = 0; v < split.points.size(); ++v) CHECK(meshed->mesh.points[v] == split.points[v]);
  CHECK(meshed->quality.volume == Approx(1.0).epsilon(1e-12));
  CHECK(quality_text(*meshed, options)
            .find("its triangles split to the field first (12 -> " + std::to_string(split.triangles.size()) +
                  " triangles") != std::string::npos);
}

TEST_CASE("a split surface: the fixed face stays fixed and the probed face moves along its length; needs keep_surface",
          "[mesher][split][scene]") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "fmpc_surface_split";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "box.obj") << "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nv 0 0 2\nv 4 0 2\nv 4 4 2\nv 0 4 2\n"
                                    "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\n"
                                    "f 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";
  const auto scene_text = [](const std::string& keep) {
    return "mesh:\n  surface: box.obj\n  units: cm\n  size_far: 1.5\n  size_near: 1.5\n" + keep +
           "  split_surface: true\nmodel: corotational_fem\nmaterial: {youngs_modulus: 10}\n"
           "fixed: {indices: [0, 1, 2, 3]}\nloads: {gravity: [0, 0, -9.81], probe: {indices: [4, 5, 6, 7], "
           "displacement: [0, 0, -0.001], ramp: 1}}\ndt: 0.001\nduration: 0.01\n";
  };
  const std::string path = (dir / "scene.yaml").string();
  std::ofstream(path) << scene_text("  keep_surface: true\n");
  DiagnosticList diagnostics;
  const auto scene = parse_scene(path, fmpc::testing::read_file_text(path), diagnostics);
  REQUIRE(scene);
  const auto built = build_scene(*scene, diagnostics);
  REQUIRE(built);
  CHECK_FALSE(diagnostics.has_errors());
  REQUIRE(built->meshing);
  REQUIRE(built->meshing->result.split);
  const std::set<std::int32_t> fixed(built->setup.fixed_vertices.begin(), built->setup.fixed_vertices.end());
  std::size_t on_bottom = 0;
  for (std::size_t v = 0; v < built->mesh.points.size(); ++v) {
    const bool bottom = built->mesh.points[v][2] == 0.0;
    on_bottom += bottom ? 1 : 0;
    CHECK(fixed.count(static_cast<std::int32_t>(v)) == (bottom ? 1u : 0u));
  }
  CHECK(on_bottom > 4);
  // The probe's picked top face moves along its length too.
  REQUIRE(built->setup.probe);
  const std::set<std::int32_t> picked(built->setup.probe->vertices.begin(), built->setup.probe->vertices.end());
  std::size_t on_top = 0;
  for (std::size_t v = 0; v < built->mesh.points.size(); ++v) {
    const bool top = built->mesh.points[v][2] == 2.0;
    on_top += top ? 1 : 0;
    CHECK(picked.count(static_cast<std::int32_t>(v)) == (top ? 1u : 0u));
  }
  CHECK(on_top > 4);

  std::ofstream(path) << scene_text("");
  DiagnosticList refused;
  parse_scene(path, fmpc::testing::read_file_text(path), refused);
  REQUIRE(refused.has_errors());
  CHECK(refused.items().front().message ==
        "mesh.split_surface: splits a kept surface; without keep_surface: true the mesher splits the surface itself: "
        "set keep_surface: true or leave split_surface out");
}

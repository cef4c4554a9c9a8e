// Volume meshes from surfaces (runtime/meshing): the meshed volume against the enclosed one, positive elements,
// quality bounds, boundary faces against the surface, the size field measured, determinism, limits, and the
// surface checks' located errors (the command's exact output is in tests/golden/mesh_*).
#include "runtime/meshing/volume_mesher.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <set>
#include <thread>

#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/mesh_writer.h"
#include "runtime/meshing/tetgen_mesher.h"
#include "tests/support/surface_meshes.h"

using namespace fmpc;
using namespace fmpc::sim;
using fmpc::testing::sorted_faces;
using fmpc::testing::unit_cube_surface;

namespace {

// An icosahedron subdivided `levels` times onto the unit sphere (10 * 4^levels + 2 vertices), faces outward.
Mesh sphere_surface(int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  Mesh sphere;
  sphere.source = "sphere";
  sphere.points = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                   {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  sphere.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  const auto normalise = [](Point3 p) {
    const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return Point3{p[0] / r, p[1] / r, p[2] / r};
  };
  for (Point3& p : sphere.points) p = normalise(p);
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> midpoint;
    const auto middle = [&](std::int32_t a, std::int32_t b) {
      const auto key = std::minmax(a, b);
      const auto found = midpoint.find(key);
      if (found != midpoint.end()) return found->second;
      const Point3& p = sphere.points[static_cast<std::size_t>(a)];
      const Point3& q = sphere.points[static_cast<std::size_t>(b)];
      sphere.points.push_back(normalise({p[0] + q[0], p[1] + q[1], p[2] + q[2]}));
      return midpoint[key] = static_cast<std::int32_t>(sphere.points.size() - 1);
    };
    std::vector<Triangle> finer;
    for (const Triangle& f : sphere.triangles) {
      const std::int32_t ab = middle(f[0], f[1]), bc = middle(f[1], f[2]), ca = middle(f[2], f[0]);
      finer.insert(finer.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    sphere.triangles = std::move(finer);
  }
  return sphere;
}

VolumeMeshOptions uniform(double size) {
  VolumeMeshOptions options;
  options.size.size_far = size;
  options.size.size_near = size;
  return options;
}

std::string messages(const DiagnosticList& diagnostics) {
  std::string text;
  for (const Diagnostic& d : diagnostics.items()) text += d.message + "\n";
  return text;
}

double boundary_area(const Mesh& mesh) {
  double area = 0.0;
  for (const Triangle& f : boundary_triangles(mesh)) area += triangle_area(mesh, f);
  return area;
}

}  // namespace

TEST_CASE("a cube meshed: its volume, positive elements, the quality bounds and its surface as boundary", "[mesher]") {
  for (const bool keep : {true, false}) {
    CAPTURE(keep);
    VolumeMeshOptions options = uniform(0.3);
    options.keep_surface = keep;
    DiagnosticList diagnostics;
    const auto meshed = mesh_volume(unit_cube_surface(), options, diagnostics);
    REQUIRE(meshed);
    // Kept, the cube's 12 triangles are its boundary: TetGen cannot refine inside without crowding them.
    CHECK(messages(diagnostics) ==
          (keep ? std::to_string(meshed->above_size) + " of the " + std::to_string(meshed->mesh.tetrahedra.size()) +
                      " tetrahedra have edges longer than 1.5 times the size field at their centroid: the kept "
                      "surface's triangles are coarser than the field near them\n"
                : std::string()));
    CHECK((meshed->above_size > 0) == keep);
    const Mesh& mesh = meshed->mesh;
    // The elements fill the cube exactly (to rounding): 1e-12 relative.
    CHECK(meshed->quality.volume == Approx(1.0).epsilon(1e-12));
    CHECK(meshed->surface.volume == Approx(1.0).epsilon(1e-15));
    for (const Tetrahedron& t : mesh.tetrahedra) CHECK(signed_volume(mesh, t) > 0.0);
    CHECK(meshed->quality.non_positive == 0);
    // Refinement meets the radius-edge bound away from the surface; the cube's right angles leave none above it.
    CHECK(meshed->quality.above_ratio_bound_inside == 0);
    CHECK(meshed->quality.radius_edge_ratio.max <= options.max_radius_edge_ratio + 1e-9);
    CHECK(meshed->quality.min_dihedral_degrees.min > 5.0);
    if (!keep) {  // free to split the surface, TetGen meets both bounds everywhere on the cube (docs/meshing.md)
      CHECK(meshed->quality.above_ratio_bound == 0);
      CHECK(meshed->quality.below_dihedral_bound == 0);
    }
    // Every element's longest edge within the size (measured at its centroid): boundary faces may exceed it only
    // where the kept surface's own triangles do.
    CHECK(meshed->quality.longest_edge.max <= (keep ? std::sqrt(2.0) : 0.3 * 1.1));
    const std::vector<Triangle> boundary = boundary_triangles(mesh);
    CHECK(boundary_area(mesh) == Approx(6.0).epsilon(1e-12));
    if (keep) {
      // The surface's triangles are the boundary, unchanged, and the surface's vertices keep their indices.
      CHECK(sorted_faces(boundary) == sorted_faces(unit_cube_surface().triangles));
      CHECK(mesh.points.size() > 8);
      for (std::size_t v = 0; v < 8; ++v) CHECK(mesh.points[v] == unit_cube_surface().points[v]);
    } else {
      // Split, but on the surface: every boundary vertex on a face of the cube, every boundary face in one.
      for (const Triangle& f : boundary) {
        bool in_one_face = false;
        for (std::size_t axis = 0; axis < 3; ++axis)
          for (const double side : {0.0, 1.0}) {
            bool all = true;
            for (const auto v : f) all = all && mesh.points[static_cast<std::size_t>(v)][axis] == side;
            in_one_face = in_one_face || all;
          }
        CHECK(in_one_face);
      }
      CHECK(boundary.size() > 12);
    }
  }
}

TEST_CASE("a sphere meshed: the enclosed volume and the boundary area kept", "[mesher]") {
  const Mesh surface = sphere_surface(2);  // 162 vertices, 320 triangles
  REQUIRE(surface.triangles.size() == 320);
  double area = 0.0;
  for (const Triangle& f : surface.triangles) area += triangle_area(surface, f);
  DiagnosticList diagnostics;
  VolumeMeshOptions options = uniform(0.25);
  options.keep_surface = true;  // the surface's edges are 0.25 to 0.32 long
  const auto meshed = mesh_volume(surface, options, diagnostics);
  REQUIRE(meshed);
  CHECK(diagnostics.empty());
  CHECK(meshed->surface.volume == Approx(4.0 / 3.0 * M_PI).epsilon(0.05));  // the polyhedron, inside the sphere
  CHECK(meshed->quality.volume == Approx(meshed->surface.volume).epsilon(1e-12));
  CHECK(boundary_area(meshed->mesh) == Approx(area).epsilon(1e-12));
  CHECK(sorted_faces(boundary_triangles(meshed->mesh)) == sorted_faces(surface.triangles));
  CHECK(meshed->quality.non_positive == 0);
  CHECK(meshed->quality.above_ratio_bound_inside == 0);
  // The estimate before meshing against the count after (docs/meshing.md states the factor): within 2x.
  CHECK(meshed->estimate.tetrahedra > 0.5 * static_cast<double>(meshed->quality.tetrahedra));
  CHECK(meshed->estimate.tetrahedra < 2.0 * static_cast<double>(meshed->quality.tetrahedra));
}

TEST_CASE("the size field: elements near the probe's path are smaller than far from it, measured", "[mesher]") {
  VolumeMeshOptions options;
  options.keep_surface = false;
  options.size.size_far = 0.3;
  options.size.size_near = 0.06;
  options.size.near_distance = 0.1;
  options.size.grading = 0.5;
  // A probe on the top face's centre pushing 0.1 down.
  options.size.sources.push_back({{0.5, 0.5, 1.0}, {0.5, 0.5, 0.9}});
  DiagnosticList diagnostics;
  const auto meshed = mesh_volume(unit_cube_surface(), options, diagnostics);
  REQUIRE(meshed);
  const Mesh& mesh = meshed->mesh;
  double near_sum = 0.0, far_sum = 0.0;
  std::size_t near_count = 0, far_count = 0, within_size = 0;
  for (const Tetrahedron& t : mesh.tetrahedra) {
    Point3 centroid{0, 0, 0};
    for (const auto v : t)
      for (std::size_t a = 0; a < 3; ++a) centroid[a] += mesh.points[static_cast<std::size_t>(v)][a] / 4.0;
    const double d = distance_to_segment(centroid, options.size.sources.front());
    const double longest = element_shape(mesh, t).longest_edge;
    within_size += longest <= size_at(options.size, centroid) * 1.0000001;
    if (d < options.size.near_distance) near_sum += longest, ++near_count;
    if (d > 0.6) far_sum += longest, ++far_count;
  }
  REQUIRE(near_count > 20);
  REQUIRE(far_count > 20);
  const double near_mean = near_sum / static_cast<double>(near_count),
               far_mean = far_sum / static_cast<double>(far_count);
  CAPTURE(near_mean, far_mean, near_count, far_count);
  CHECK(near_mean <= options.size.size_near);
  CHECK(far_mean > 3.0 * near_mean);
  CHECK(far_mean <= options.size.size_far);
  // Every element meets the size at its centroid, as TetGen was asked to.
  CHECK(within_size == mesh.tetrahedra.size());
  // The field itself: h = min(far, near + grading * (d - near_distance)).
  CHECK(size_at(options.size, {0.5, 0.5, 1.0}) == 0.06);
  CHECK(size_at(options.size, {0.5, 0.5, 0.5}) == Approx(0.06 + 0.5 * (0.4 - 0.1)));
  CHECK(size_at(options.size, {0.0, 0.0, 0.0}) == 0.3);
}

TEST_CASE("the same surface and options give the same mesh, bit for bit, and the .msh reads back as written",
          "[mesher]") {
  VolumeMeshOptions options = uniform(0.35);
  options.keep_surface = false;
  options.size.size_near = 0.1;
  options.size.near_distance = 0.1;
  options.size.sources.push_back({{0.2, 0.3, 1.0}, {0.2, 0.3, 1.0}});
  DiagnosticList diagnostics;
  const auto first = mesh_volume(sphere_surface(1), options, diagnostics);
  const auto second = mesh_volume(sphere_surface(1), options, diagnostics);
  REQUIRE(first);
  REQUIRE(second);
  CHECK(first->mesh.points == second->mesh.points);
  CHECK(first->mesh.tetrahedra == second->mesh.tetrahedra);
  // On two threads at once (a cohort builds its patients' scenes so): the same again.
  std::optional<VolumeMesh> on_threads[2];
  std::thread other([&] {
    DiagnosticList ignored;
    on_threads[1] = mesh_volume(sphere_surface(1), options, ignored);
  });
  {
    DiagnosticList ignored;
    on_threads[0] = mesh_volume(sphere_surface(1), options, ignored);
  }
  other.join();
  for (const auto& meshed : on_threads) {
    REQUIRE(meshed);
    CHECK(meshed->mesh.points == first->mesh.points);
    CHECK(meshed->mesh.tetrahedra == first->mesh.tetrahedra);
  }
  const std::string text = gmsh_document(first->mesh);
  CHECK(text == gmsh_document(second->mesh));
  const auto read = read_gmsh(text, "meshed.msh", diagnostics);
  REQUIRE(read);
  CHECK(read->points == first->mesh.points);
  CHECK(read->tetrahedra == first->mesh.tetrahedra);
  CHECK(diagnostics.empty());
}

TEST_CASE("limits: the predicted tetrahedra and the surface's size are refused before meshing", "[mesher]") {
  VolumeMeshOptions options = uniform(0.05);
  options.max_tetrahedra = 1000;
  DiagnosticList diagnostics;
  CHECK_FALSE(mesh_volume(unit_cube_surface(), options, diagnostics));
  // 40 / 0.05^3 = 320,000 by the estimate's factor, over a sampled volume of exactly 1.
  CHECK(messages(diagnostics) ==
        "the size field asks for about 320000 tetrahedra (an estimate from the enclosed volume, 1 mesh units^3, and "
        "the sizes); the limit is 1000: raise size_far or size_near, or shrink near_distance\n");
  Mesh huge;
  huge.source = "huge.stl";
  huge.points.resize(kMaxSurfaceVertices + 1);
  DiagnosticList too_many;
  CHECK_FALSE(mesh_volume(std::move(huge), uniform(1.0), too_many));
  CHECK(messages(too_many) ==
        "the surface has 1000001 vertices and 0 triangles; the mesher takes at most 1000000 "
        "and 2000000: decimate the surface first\n");
  VolumeMeshOptions bad = uniform(0.1);
  bad.size.size_near = 0.2;
  bad.size.grading = 0.0;
  DiagnosticList refused;
  CHECK_FALSE(mesh_volume(unit_cube_surface(), bad, refused));
  CHECK(messages(refused) ==
        "size_near (0.2) must not exceed size_far (0.1)\n"
        "grading must be a positive length (mesh units), got 0\n");
}

TEST_CASE("surface defects are refused with their place, and an inward surface is meshed reversed", "[mesher]") {
  struct Case {
    const char* name;
    Mesh surface;
    std::string expected;
  };
  std::vector<Case> cases;
  {
    Mesh open = unit_cube_surface();
    open.triangles.pop_back();
    cases.push_back({"open", open,
                     "the surface is open at the edge from vertex 3 to vertex 4 (0-based): only triangle 10 (0-based) "
                     "has it; close the hole (every edge of a closed surface is on exactly two triangles)\n"
                     "the surface is open at the edge from vertex 3 to vertex 7 (0-based): only triangle 8 (0-based) "
                     "has it; close the hole (every edge of a closed surface is on exactly two triangles)\n"
                     "the surface is open at the edge from vertex 4 to vertex 7 (0-based): only triangle 3 (0-based) "
                     "has it; close the hole (every edge of a closed surface is on exactly two triangles)\n"});
  }
  {
    Mesh flipped = unit_cube_surface();
    std::swap(flipped.triangles[5][1], flipped.triangles[5][2]);
    cases.push_back({"flipped", flipped,
                     "triangle 5 (0-based) is flipped: it runs an edge the same way as its neighbour triangle 10 "
                     "(0-based) (triangles oriented against the rest of their part: 1 of 12); reverse its vertex "
                     "order\n"});
  }
  {
    Mesh unused = unit_cube_surface();
    unused.points.push_back({5, 5, 5});
    unused.triangles.push_back({0, 0, 1});
    cases.push_back({"unused and degenerate", unused,
                     "vertex 8 (0-based) belongs to no triangle; remove it (a surface to mesh has only the vertices "
                     "of its triangles)\ntriangle 12 (0-based) repeats a vertex (0, 0, 1); remove it\n"});
  }
  for (Case& c : cases) {
    CAPTURE(c.name);
    DiagnosticList diagnostics;
    CHECK_FALSE(mesh_volume(c.surface, uniform(0.5), diagnostics));
    CHECK(messages(diagnostics) == c.expected);
  }
  Mesh inward = unit_cube_surface();
  reverse_triangles(inward);
  DiagnosticList diagnostics;
  const auto meshed = mesh_volume(inward, uniform(0.5), diagnostics);
  REQUIRE(meshed);
  CHECK(messages(diagnostics) ==
        "the surface's triangles are oriented inwards (enclosed volume 1 with the normals "
        "reversed); meshed as if reversed\n");
  CHECK(meshed->quality.volume == Approx(1.0).epsilon(1e-12));
}

TEST_CASE("a self-intersecting surface is refused, or smoothed on request and then meshed", "[mesher]") {
  // A sphere with one vertex pushed through the opposite side: its cone of triangles pierces the surface there.
  Mesh folded = sphere_surface(1);
  const std::size_t tip = 0;
  const Point3 p = folded.points[tip];
  folded.points[tip] = {-1.3 * p[0], -1.3 * p[1], -1.3 * p[2]};
  DiagnosticList refused;
  CHECK_FALSE(mesh_volume(folded, uniform(0.5), refused));
  REQUIRE(refused.has_errors());
  CHECK_THAT(refused.items().front().message, Catch::Contains("intersects another part of the surface ("));
  VolumeMeshOptions smooth = uniform(0.5);
  smooth.smooth_intersections = true;
  DiagnosticList diagnostics;
  const auto meshed = mesh_volume(folded, smooth, diagnostics);
  REQUIRE(meshed);
  REQUIRE(meshed->untangling);
  CHECK(meshed->untangling->moved_vertices >= 1);
  CHECK(meshed->untangling->largest_move > 1.0);
  CHECK_THAT(messages(diagnostics), Catch::Contains("smoothing moved"));
  CHECK(meshed->quality.volume == Approx(meshed->surface.volume).epsilon(1e-9));
}

TEST_CASE("TetGen's own errors come back as diagnostics, not as a crash", "[mesher]") {
  // Two overlapping cubes: mesh_volume refuses them before TetGen runs (self-intersections); given to TetGen directly
  // they make it stop with its error 3, whose path in Debian's TetGen 1.5.0 freed memory twice until fmpc replaced
  // terminatetetgen (tetgen_termination.cpp).
  Mesh two = unit_cube_surface();
  const Mesh cube = unit_cube_surface();
  for (const Point3& p : cube.points) two.points.push_back({p[0] + 0.5, p[1] + 0.25, p[2] + 0.25});
  for (const Triangle& t : cube.triangles) two.triangles.push_back({t[0] + 8, t[1] + 8, t[2] + 8});
  DiagnosticList diagnostics;
  CHECK_FALSE(tetgen_tetrahedralize(two, uniform(0.5), 1000, diagnostics));
  CHECK(messages(diagnostics) ==
        "TetGen found the surface intersecting itself; fix the surface (fmpc checks that it is closed, manifold and "
        "oriented, but not that it is free of self-intersections)\n");
}

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

#include "runtime/mesh/generated_mesh.h"
#include "runtime/mesh/mesh_check.h"
#include "runtime/mesh/mesh_reader.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

const std::string kSofa = std::string(FMPC_SHARED_DATA_DIR) + "/sofa-liver/";

bool have_sofa_data() {
  std::ifstream probe(kSofa + "liver.msh");
  return static_cast<bool>(probe);
}

std::string temporary_file(const std::string& name, const std::string& contents) {
  const std::string path = std::string("/tmp/fmpc_sim_test_") + name;
  std::ofstream out(path, std::ios::binary);
  out << contents;
  return path;
}

std::string first_error(const DiagnosticList& diagnostics) {
  for (const auto& d : diagnostics.items()) {
    if (d.severity == Severity::Error) return d.message;
  }
  return "";
}

int first_error_line(const DiagnosticList& diagnostics) {
  for (const auto& d : diagnostics.items()) {
    if (d.severity == Severity::Error) return d.range.line;
  }
  return -1;
}

double total_volume(const Mesh& mesh) {
  double volume = 0.0;
  for (const auto& t : mesh.tetrahedra) volume += signed_volume(mesh, t);
  return volume;
}

const char* const kTetGmsh2 =
    "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
    "$Nodes\n4\n10 0 0 0\n20 1 0 0\n30 0 1 0\n40 0 0 1\n$EndNodes\n"
    "$Elements\n3\n1 15 2 0 1 10\n2 2 2 0 1 10 20 30\n3 4 2 0 1 10 20 30 40\n$EndElements\n";

const char* const kTetGmsh4 =
    "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
    "$Entities\n0 0 0 1\n1 0 0 0 1 1 1 0 0\n$EndEntities\n"
    "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n"
    "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n";

}  // namespace

TEST_CASE("SOFA liver meshes load with the published counts", "[sim]") {
  if (!have_sofa_data()) {
    WARN("skipped: " << kSofa << " is absent (../shared/data is needed for the SOFA meshes)");
    return;
  }
  struct Expected {
    const char* file;
    std::size_t points, tetrahedra, triangles;
  };
  const Expected cases[] = {{"liver.msh", 181, 596, 0},          {"liver2.msh", 507, 1493, 860},
                            {"liver.obj", 181, 0, 274},          {"liver2.obj", 1170, 0, 2336},
                            {"liver-smooth.obj", 2194, 0, 4384}, {"liver.vtk", 5008, 0, 10000}};
  for (const Expected& e : cases) {
    CAPTURE(e.file);
    DiagnosticList diagnostics;
    const auto mesh = read_mesh_file(kSofa + e.file, diagnostics);
    REQUIRE(mesh);
    CHECK_FALSE(diagnostics.has_errors());
    CHECK(mesh->points.size() == e.points);
    CHECK(mesh->tetrahedra.size() == e.tetrahedra);
    CHECK(mesh->triangles.size() == e.triangles);
    if (e.tetrahedra > 0) {
      CHECK(mesh->tetrahedron_lines.size() == e.tetrahedra);
      CHECK(total_volume(*mesh) != 0.0);
    }
  }
  DiagnosticList diagnostics;
  const auto liver = read_mesh_file(kSofa + "liver.msh", diagnostics);
  REQUIRE(liver);
  CHECK(liver->points[0] == Point3{-0.979259, 2.23512, 2.61245});
  CHECK(liver->tetrahedra[0] == Tetrahedron{127, 140, 137, 141});  // "1 4 1 1 4 128 141 138 142", 1-based tags
  CHECK(liver->tetrahedron_lines[0] == 187);
  const auto vtk = read_mesh_file(kSofa + "liver.vtk", diagnostics);
  REQUIRE(vtk);
  for (const auto& p : vtk->points) CHECK(std::isfinite(p[0] + p[1] + p[2]));
  for (const auto& t : vtk->triangles) {
    for (const auto v : t) CHECK((v >= 0 && v < 5008));
  }
  // liver.msh is clean; liver.obj lists 42 vertices that no face uses (SOFA's file: it is not closed).
  CHECK(check_mesh(*liver).empty());
  const auto obj_findings = check_mesh(*read_mesh_file(kSofa + "liver.obj", diagnostics));
  CHECK(obj_findings.size() == 42);
  for (const auto& f : obj_findings) CHECK(f.kind == MeshFindingKind::UnreferencedVertex);
  // The surface meshes are usable after repair (their findings are data, not output).
  Mesh surface = *read_mesh_file(kSofa + "liver2.obj", diagnostics);
  const auto repair = repair_mesh(surface);
  CHECK(check_mesh(surface).empty());
  CHECK(repair.new_vertex_index.size() == 1170);
}

TEST_CASE("Gmsh v2 and v4.1 ASCII files give the same tetrahedron", "[sim]") {
  DiagnosticList diagnostics;
  const auto v2 = read_gmsh(kTetGmsh2, "tet2.msh", diagnostics);
  const auto v4 = read_gmsh(kTetGmsh4, "tet4.msh", diagnostics);
  REQUIRE(v2);
  REQUIRE(v4);
  CHECK(diagnostics.empty());
  CHECK(v2->points == v4->points);
  CHECK(v2->tetrahedra == std::vector<Tetrahedron>{{0, 1, 2, 3}});
  CHECK(v4->tetrahedra == std::vector<Tetrahedron>{{0, 1, 2, 3}});
  CHECK(v2->triangles == std::vector<Triangle>{{0, 1, 2}});
  CHECK(v2->tetrahedron_lines == std::vector<int>{15});
  CHECK(v2->triangle_lines == std::vector<int>{14});
  CHECK(signed_volume(*v2, v2->tetrahedra[0]) == Approx(1.0 / 6.0));
}

TEST_CASE("Gmsh v1 hexahedra are skipped with a warning", "[sim]") {
  DiagnosticList diagnostics;
  const auto mesh = read_gmsh(
      "$NOD\n8\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 0 0 1\n6 1 0 1\n7 1 1 1\n8 0 1 1\n$ENDNOD\n"
      "$ELM\n2\n1 5 1 1 8 1 2 3 4 5 6 7 8\n2 4 1 1 4 1 2 4 5\n$ENDELM\n",
      "hex.msh", diagnostics);
  REQUIRE(mesh);
  CHECK(mesh->tetrahedra.size() == 1);
  REQUIRE(diagnostics.warning_count() == 1);
  CHECK(diagnostics.items()[0].message ==
        "1 elements of Gmsh type 5 were ignored; only tetrahedra (4) and triangles (2) are simulated");
}

TEST_CASE("broken Gmsh files are errors that name file:line and what to do", "[sim]") {
  struct Broken {
    const char* name;
    const char* text;
    int line;
    const char* message_part;
  };
  const Broken cases[] = {
      {"truncated", "$NOD\n3\n1 0 0 0\n2 1 0 0\n", 5, "truncated"},
      {"bad-number", "$NOD\n2\n1 0 0 0\n2 1.2.3 0 0\n$ENDNOD\n", 4, "found '1.2.3'"},
      {"nan-coordinate", "$NOD\n1\n1 nan 0 0\n$ENDNOD\n", 3, "not a finite number"},
      {"missing-node", "$NOD\n1\n1 0 0 0\n$ENDNOD\n$ELM\n1\n1 4 1 1 4 1 2 3 4\n$ENDELM\n", 7, "refers to node 2"},
      {"duplicate-node", "$NOD\n2\n1 0 0 0\n1 1 0 0\n$ENDNOD\n", 4, "appears twice"},
      {"wrong-count", "$NOD\n1\n1 0 0 0\n$ENDNOD\n$ELM\n1\n1 4 1 1 3 1 1 1\n$ENDELM\n", 7, "lists 3 nodes"},
      {"binary", "$MeshFormat\n2.2 1 8\n$EndMeshFormat\n", 2, "binary .msh files are not supported"},
      {"version3", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n", 2, "version 3.0 is not supported"},
      {"not-gmsh", "hello\n", 1, "not a Gmsh ASCII mesh"},
      {"short-element",
       "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
       "$EndNodes\n$Elements\n1\n1 4 0 1 2 3\n4\n$EndElements\n",
       13, "continues past its line"},
  };
  for (const Broken& b : cases) {
    CAPTURE(b.name);
    const std::string path = temporary_file(std::string(b.name) + ".msh", b.text);
    DiagnosticList diagnostics;
    CHECK_FALSE(read_mesh_file(path, diagnostics));
    REQUIRE(diagnostics.has_errors());
    CHECK(diagnostics.items()[0].range.file == path);
    CHECK(first_error_line(diagnostics) == b.line);
    CHECK_THAT(first_error(diagnostics), Catch::Contains(b.message_part));
  }
}

TEST_CASE("OBJ faces: corner formats, negative indices and polygons", "[sim]") {
  DiagnosticList diagnostics;
  const auto mesh = read_obj(
      "# square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\nvn 0 0 1\nvt 0 0\n"
      "f 1/1/1 2//1 3/2\nf -4 -2 -1\ng group\nf 1 2 3 4\n",
      "square.obj", diagnostics);
  REQUIRE(mesh);
  CHECK(diagnostics.empty());
  CHECK(mesh->points.size() == 4);
  CHECK(mesh->triangles == std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}, {0, 1, 2}, {0, 2, 3}});
  CHECK(mesh->triangle_lines == std::vector<int>{8, 9, 11, 11});
}

TEST_CASE("broken OBJ and VTK files are errors with file:line", "[sim]") {
  struct Broken {
    const char* name;
    std::string text;
    int line;
    const char* message_part;
  };
  const Broken cases[] = {
      {"missing.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n", 3, "refers to vertex 3 but the file has 2"},
      {"two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", 3, "at least three vertices"},
      {"zero.obj", "v 0 0 0\nf 0 1 1\n", 2, "is not a vertex number"},
      {"short-v.obj", "v 0 0\n", 1, "three finite coordinates"},
      {"header.vtk", "hello\n", 1, "not a legacy VTK file"},
      {"v5.vtk", "# vtk DataFile Version 5.1\nt\nASCII\nDATASET POLYDATA\n", 1, "version 5"},
      {"encoding.vtk", "# vtk DataFile Version 3.0\nt\nTEXT\n", 3, "ASCII or BINARY"},
      {"cell-range.vtk",
       "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 "
       "5\n",
       8, "refers to point 5"},
      {"binary-short.vtk",
       std::string("# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\nPOINTS 2 float\n") + std::string(12, '\0'),
       5, "truncated"},
      {"types.vtk",
       "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0 1 0 0 0 1 0 0 0 1\n"
       "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 2\n10 10\n",
       9, "one entry per cell"},
  };
  for (const Broken& b : cases) {
    CAPTURE(b.name);
    const std::string path = temporary_file(b.name, b.text);
    DiagnosticList diagnostics;
    CHECK_FALSE(read_mesh_file(path, diagnostics));
    REQUIRE(diagnostics.has_errors());
    CHECK(diagnostics.items()[0].range.file == path);
    CHECK(first_error_line(diagnostics) == b.line);
    CHECK_THAT(first_error(diagnostics), Catch::Contains(b.message_part));
  }
  DiagnosticList diagnostics;
  CHECK_FALSE(read_mesh_file("/tmp/fmpc_sim_test_does_not_exist.msh", diagnostics));
  CHECK_THAT(first_error(diagnostics), Catch::Contains("cannot read"));
  CHECK_FALSE(read_mesh_file(temporary_file("mesh.step", "solid"), diagnostics));
  CHECK_THAT(diagnostics.items().back().message, Catch::Contains("unknown mesh format"));
}

TEST_CASE("legacy VTK: ASCII unstructured grid and big-endian binary polydata", "[sim]") {
  DiagnosticList diagnostics;
  const auto grid = read_vtk(
      "# vtk DataFile Version 3.0\ngrid\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0 1 0 0 0 1 0 0 0 1\n"
      "METADATA\nINFORMATION 1\nNAME L2_NORM_RANGE LOCATION vtkDataArray\nDATA 2 0 1.73205\n\n"
      "CELLS 3 12\n4 0 1 2 3\n3 0 1 2\n2 0 3\nCELL_TYPES 3\n10\n5\n3\nPOINT_DATA 4\nSCALARS s float\n",
      "grid.vtk", diagnostics);
  REQUIRE(grid);
  CHECK(grid->tetrahedra == std::vector<Tetrahedron>{{0, 1, 2, 3}});
  CHECK(grid->triangles == std::vector<Triangle>{{0, 1, 2}});
  CHECK(diagnostics.warning_count() == 1);  // the line cell

  // POINTS 3 float + POLYGONS 1 4 in big-endian binary, as liver.vtk is written.
  std::string binary = "# vtk DataFile Version 3.0\nbin\nBINARY\nDATASET POLYDATA\nPOINTS 3 float\n";
  const auto put32 = [&](std::uint32_t bits) {
    for (int shift = 24; shift >= 0; shift -= 8) binary.push_back(static_cast<char>((bits >> shift) & 0xffu));
  };
  const float coordinates[9] = {0.0f, 0.0f, 0.0f, 2.5f, 0.0f, 0.0f, 0.0f, -1.0f, 10.0f};
  for (const float c : coordinates) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &c, sizeof bits);
    put32(bits);
  }
  binary += "\nPOLYGONS 1 4\n";
  for (const std::uint32_t v : {3u, 0u, 1u, 2u}) put32(v);
  binary += "\n";
  DiagnosticList binary_diagnostics;
  const auto poly = read_vtk(binary, "bin.vtk", binary_diagnostics);
  REQUIRE(poly);
  CHECK(binary_diagnostics.empty());
  CHECK(poly->points == std::vector<Point3>{{0, 0, 0}, {2.5, 0, 0}, {0, -1, 10}});
  CHECK(poly->triangles == std::vector<Triangle>{{0, 1, 2}});
}

TEST_CASE("generated boxes: counts, positive volumes, exact total volume", "[sim]") {
  for (int n : {1, 2, 5}) {
    DiagnosticList diagnostics;
    BoxSpec spec;
    spec.cells_x = n;
    spec.cells_y = n + 1;
    spec.cells_z = 2;
    spec.size = {0.2, 0.3, 0.1};
    const Mesh box = generate_box(spec, diagnostics);
    CHECK(diagnostics.empty());
    CHECK(box.points.size() == static_cast<std::size_t>((n + 1) * (n + 2) * 3));
    CHECK(box.tetrahedra.size() == static_cast<std::size_t>(6 * n * (n + 1) * 2));
    for (const auto& t : box.tetrahedra) CHECK(signed_volume(box, t) > 0.0);
    CHECK(total_volume(box) == Approx(0.2 * 0.3 * 0.1).epsilon(1e-12));
    CHECK(check_mesh(box).empty());
    // A conforming mesh: every interior face is shared by exactly two tetrahedra, so the boundary of the box is
    // 2 triangles per boundary square.
    const std::size_t squares = 2 * (static_cast<std::size_t>(n * (n + 1)) + static_cast<std::size_t>(n * 2) +
                                     static_cast<std::size_t>((n + 1) * 2));
    CHECK(boundary_triangles(box).size() == 2 * squares);
  }
  DiagnosticList diagnostics;
  BoxSpec bad;
  bad.cells_x = 0;
  CHECK(generate_box(bad, diagnostics).points.empty());
  bad.cells_x = 1;
  bad.size = {1.0, std::nan(""), 1.0};
  CHECK(generate_box(bad, diagnostics).points.empty());
  CHECK(diagnostics.error_count() == 2);
}

TEST_CASE("generated boxes with even cell counts have every corner at an end of its cell's Kuhn diagonal", "[sim]") {
  // Then each face of a corner cell that lies on the box's boundary belongs to a tetrahedron whose fourth vertex is
  // the cell's interior corner, never a vertex on the box's edge. The other phase of the mirroring puts that apex on
  // the edge: on a clamped base the corner's first-layer vertex sinks through the base plane and the three-clamped
  // tetrahedron under it inverts, at 80^3 cells of bench/scenes/resting_block_snh.yaml where this phase keeps
  // J >= 0.33 (docs/validation.md, "Does the 120^3 block fold?").
  // Four, two and six cells (an odd count would leave the corners on its far side off the diagonal).
  const BoxSpec spec{{0.0, 0.0, 0.0}, {0.4, 0.2, 0.6}, 4, 2, 6};
  DiagnosticList diagnostics;
  const Mesh box = generate_box(spec, diagnostics);
  REQUIRE(diagnostics.empty());
  for (int corner = 0; corner < 8; ++corner) {
    const Point3 at{corner & 1 ? 0.4 : 0.0, corner & 2 ? 0.2 : 0.0, corner & 4 ? 0.6 : 0.0};
    std::int32_t vertex = -1;
    for (std::size_t v = 0; v < box.points.size(); ++v)
      if (std::abs(box.points[v][0] - at[0]) + std::abs(box.points[v][1] - at[1]) + std::abs(box.points[v][2] - at[2]) <
          1e-12)
        vertex = static_cast<std::int32_t>(v);
    REQUIRE(vertex >= 0);
    int containing = 0;
    for (const Tetrahedron& t : box.tetrahedra)
      containing += std::count(t.begin(), t.end(), vertex) > 0 ? 1 : 0;
    INFO("corner " << corner);
    CHECK(containing == 6);
  }
}

TEST_CASE("generated ellipsoids converge to the ellipsoid volume", "[sim]") {
  const double exact = 4.0 / 3.0 * M_PI * 0.1 * 0.2 * 0.15;
  double previous_error = 1.0;
  for (int resolution : {1, 2, 4, 8}) {
    DiagnosticList diagnostics;
    EllipsoidSpec spec;
    spec.radii = {0.1, 0.2, 0.15};
    spec.resolution = resolution;
    const Mesh mesh = generate_ellipsoid(spec, diagnostics);
    CHECK(diagnostics.empty());
    for (const auto& t : mesh.tetrahedra) REQUIRE(signed_volume(mesh, t) > 0.0);
    const double error = std::abs(total_volume(mesh) - exact) / exact;
    CHECK(error < previous_error);
    previous_error = error;
  }
  CHECK(previous_error < 0.02);
}

TEST_CASE("mesh findings list every defect with its index, and repair fixes them", "[sim]") {
  Mesh mesh;
  mesh.source = "defects";
  mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {1, 0, 0}, {5, 5, 5}};
  mesh.tetrahedra = {
      {0, 1, 2, 3},  // good
      {0, 2, 1, 4},  // inverted
      {0, 1, 2, 3},  // duplicate of 0
      {0, 1, 1, 3},  // repeated vertex
      {0, 5, 2, 3},  // uses vertex 5, a duplicate of vertex 1: becomes a duplicate of 0 after merging
      {0, 1, 2, 9},  // out of range
  };
  mesh.tetrahedron_lines = {10, 11, 12, 13, 14, 15};
  const auto findings = check_mesh(mesh);
  std::vector<std::pair<MeshFindingKind, std::size_t>> seen;
  for (const auto& f : findings) seen.emplace_back(f.kind, f.index);
  const std::vector<std::pair<MeshFindingKind, std::size_t>> expected = {
      {MeshFindingKind::IndexOutOfRange, 5},      {MeshFindingKind::InvertedTetrahedron, 1},
      {MeshFindingKind::DuplicateTetrahedron, 2}, {MeshFindingKind::DegenerateTetrahedron, 3},
      {MeshFindingKind::DuplicateVertex, 5},      {MeshFindingKind::UnreferencedVertex, 6}};
  CHECK(seen == expected);
  CHECK(findings[2].other == 0);
  CHECK(findings[2].line == 12);
  CHECK(findings[4].other == 1);
  CHECK(finding_message(findings[1]) == "element 1 (line 11) is inverted (volume -0.166667)");

  const auto repair = repair_mesh(mesh);
  CHECK(check_mesh(mesh).empty());
  CHECK(mesh.tetrahedra.size() == 2);
  CHECK(mesh.points.size() == 5);
  CHECK(repair.new_vertex_index == std::vector<std::int32_t>{0, 1, 2, 3, 4, 1, -1});
  for (const auto& t : mesh.tetrahedra) CHECK(signed_volume(mesh, t) > 0.0);
  CHECK(mesh.tetrahedron_lines == std::vector<int>{10, 11});
  for (const auto& f : repair.findings) CHECK(f.repaired);
  CHECK(repair.findings.size() == 7);  // the six above plus element 4, a duplicate once vertex 5 is merged
}

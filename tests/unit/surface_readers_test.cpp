// Surface files for the mesher: the unit cube written in every format the mesher takes (OBJ, STL ASCII and binary,
// legacy VTK polydata ASCII and binary, PLY ASCII and binary little-endian) reads back as the same closed surface;
// broken files are errors with their place.
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstring>
#include <fstream>

#include "runtime/mesh/mesh_reader.h"
#include "runtime/meshing/surface_check.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

const double kCubePoints[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                  {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
const int kCubeFaces[12][3] = {{0, 3, 2}, {0, 2, 1}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                               {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};

std::string write_surface_file(const std::string& name, const std::string& contents) {
  const std::string path = "/tmp/fmpc_surface_test_" + name;
  std::ofstream out(path, std::ios::binary);
  out << contents;
  return path;
}

template <typename T>
void append_little_endian(std::string& out, T value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(reinterpret_cast<const char*>(bytes), sizeof(T));  // x86-64 and arm64 are little-endian
}

template <typename T>
void append_big_endian(std::string& out, T value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  for (std::size_t i = sizeof(T); i-- > 0;) out.push_back(static_cast<char>(bytes[i]));
}

std::string ascii_points(const char* prefix) {
  std::string text;
  for (const auto& p : kCubePoints)
    text +=
        prefix + std::to_string(int(p[0])) + " " + std::to_string(int(p[1])) + " " + std::to_string(int(p[2])) + "\n";
  return text;
}

std::string ascii_faces(const char* face_prefix, int face_offset) {
  std::string text;
  for (const auto& f : kCubeFaces)
    text += face_prefix + std::to_string(f[0] + face_offset) + " " + std::to_string(f[1] + face_offset) + " " +
            std::to_string(f[2] + face_offset) + "\n";
  return text;
}

std::string ascii_stl() {
  std::string text = "solid cube\n";
  for (const auto& f : kCubeFaces) {
    text += "  facet normal 0 0 0\n    outer loop\n";
    for (const int v : f)
      text += "      vertex " + std::to_string(kCubePoints[v][0]) + " " + std::to_string(kCubePoints[v][1]) + " " +
              std::to_string(kCubePoints[v][2]) + "\n";
    text += "    endloop\n  endfacet\n";
  }
  return text + "endsolid cube\n";
}

std::string binary_stl() {
  std::string bytes = "solid but binary";  // a header that starts like ASCII: the size decides
  bytes.resize(80, ' ');
  append_little_endian<std::uint32_t>(bytes, 12);
  for (const auto& f : kCubeFaces) {
    for (int k = 0; k < 3; ++k) append_little_endian<float>(bytes, 0.0f);
    for (const int v : f)
      for (int a = 0; a < 3; ++a) append_little_endian<float>(bytes, static_cast<float>(kCubePoints[v][a]));
    append_little_endian<std::uint16_t>(bytes, 0);
  }
  return bytes;
}

std::string binary_vtk() {
  std::string bytes = "# vtk DataFile Version 3.0\ncube\nBINARY\nDATASET POLYDATA\nPOINTS 8 float\n";
  for (const auto& p : kCubePoints)
    for (int a = 0; a < 3; ++a) append_big_endian<float>(bytes, static_cast<float>(p[a]));
  bytes += "\nPOLYGONS 12 48\n";
  for (const auto& f : kCubeFaces) {
    append_big_endian<std::int32_t>(bytes, 3);
    for (const int v : f) append_big_endian<std::int32_t>(bytes, v);
  }
  return bytes + "\n";
}

std::string binary_ply() {
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\ncomment made by fmpc's tests\nelement vertex 8\nproperty float x\n"
      "property float y\nproperty float z\nproperty uchar red\nelement face 12\n"
      "property list uchar int vertex_indices\nend_header\n";
  for (const auto& p : kCubePoints) {
    for (int a = 0; a < 3; ++a) append_little_endian<float>(bytes, static_cast<float>(p[a]));
    bytes.push_back('\x7f');
  }
  for (const auto& f : kCubeFaces) {
    bytes.push_back('\3');
    for (const int v : f) append_little_endian<std::int32_t>(bytes, v);
  }
  return bytes;
}

}  // namespace

TEST_CASE("the cube in every surface format reads back as the same closed surface", "[mesher]") {
  const std::string ply_header =
      "ply\nformat ascii 1.0\nelement vertex 8\nproperty double x\nproperty double y\nproperty double z\n"
      "element face 12\nproperty list uchar int vertex_index\nend_header\n";
  const std::pair<std::string, std::string> files[] = {
      {"cube.obj", "# cube\n" + ascii_points("v ") + ascii_faces("f ", 1)},
      {"cube_ascii.stl", ascii_stl()},
      {"cube_binary.stl", binary_stl()},
      {"cube_ascii.vtk", "# vtk DataFile Version 3.0\ncube\nASCII\nDATASET POLYDATA\nPOINTS 8 float\n" +
                             ascii_points("") + "POLYGONS 12 48\n" + ascii_faces("3 ", 0)},
      {"cube_binary.vtk", binary_vtk()},
      {"cube_ascii.ply", ply_header + ascii_points("") + ascii_faces("3 ", 0)},
      {"cube_binary.ply", binary_ply()},
  };
  for (const auto& [name, contents] : files) {
    CAPTURE(name);
    DiagnosticList diagnostics;
    const auto surface = read_mesh_file(write_surface_file(name, contents), diagnostics);
    REQUIRE(surface);
    CHECK(diagnostics.empty());
    REQUIRE(surface->points.size() == 8);
    REQUIRE(surface->triangles.size() == 12);
    // STL numbers corners by first appearance; the rest keep the file's numbering.
    for (std::size_t t = 0; t < 12; ++t)
      for (std::size_t k = 0; k < 3; ++k)
        CHECK(surface->points[static_cast<std::size_t>(surface->triangles[t][k])] ==
              Point3{kCubePoints[kCubeFaces[t][k]][0], kCubePoints[kCubeFaces[t][k]][1],
                     kCubePoints[kCubeFaces[t][k]][2]});
    const SurfaceCheck check = check_closed_surface(*surface, diagnostics);
    CHECK(check.closed);
    CHECK_FALSE(check.inward);
    CHECK(check.volume == Approx(1.0).epsilon(1e-15));
    CHECK(check.area == Approx(6.0).epsilon(1e-15));
  }
}

TEST_CASE("broken STL and PLY files are errors with their place", "[mesher]") {
  struct Broken {
    const char* name;
    std::string contents;
    int line;
    std::string message;
  };
  const Broken cases[] = {
      {"short.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n", 6,
       "expected 'vertex', found 'endloop'; an ASCII STL facet is 'facet normal nx ny nz / outer loop / vertex x y z "
       "(three times) / endloop / endfacet'"},
      {"unended.stl", "solid x\n", 2, "the file ends without 'endsolid'; it is truncated: export it again"},
      {"truncated.stl", std::string(84, '\0').replace(80, 1, "\x02") + std::string(50, '\0'), 0,
       "this is neither an ASCII STL file (starting with 'solid') nor a binary one (84 + 50 x triangles bytes): it has "
       "134 bytes, while a binary STL with the 2 triangles its header claims has 184; the file is truncated or not "
       "STL: export it again"},
      {"big_endian.ply", "ply\nformat binary_big_endian 1.0\nend_header\n", 2,
       "PLY format 'binary_big_endian' is not supported; write ascii or binary_little_endian"},
      {"no_z.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n", 3,
       "the vertex element needs properties x, y and z; fix the header"},
      {"face_range.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\n"
       "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
       13, "face 0 refers to vertex 3 but the file has 3 vertices (0-based); fix the face"},
      // Beyond any integer's range (fuzz_surface: converted before it was checked, undefined behaviour).
      {"face_huge.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\n"
       "property list uchar double vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1e308 2\n",
       13, "face 0 refers to vertex 1e+308 but the file has 3 vertices (0-based); fix the face"},
      {"count.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 1000000\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n",
       3,
       "element 'vertex' claims 1000000 items but the file has only 0 bytes left; the file is truncated or the "
       "count is wrong"},
  };
  for (const Broken& b : cases) {
    CAPTURE(b.name);
    const std::string path = write_surface_file(b.name, b.contents);
    DiagnosticList diagnostics;
    CHECK_FALSE(read_mesh_file(path, diagnostics));
    REQUIRE(diagnostics.has_errors());
    CHECK(diagnostics.items().front().range.file == path);
    CHECK(diagnostics.items().front().range.line == b.line);
    CHECK(diagnostics.items().front().message == b.message);
  }
}

TEST_CASE("SOFA's surfaces: liver.vtk (binary polydata, mm, oriented inwards) and liver-smooth.obj are closed",
          "[mesher]") {
  const std::string folder = std::string(FMPC_SHARED_DATA_DIR) + "/sofa-liver/";
  for (const auto& [name, inward] : {std::pair<const char*, bool>{"liver.vtk", true}, {"liver-smooth.obj", false}}) {
    CAPTURE(name);
    DiagnosticList diagnostics;
    const auto surface = read_mesh_file(folder + name, diagnostics);
    if (!surface) {
      WARN("skipped: " << folder << name << " is absent (../shared/data)");
      continue;
    }
    const SurfaceCheck check = check_closed_surface(*surface, diagnostics);
    CHECK(diagnostics.empty());
    CHECK(check.closed);
    CHECK(check.inward == inward);
    CHECK((check.volume < 0.0) == inward);  // liver.vtk encloses 1.48 litres (in mm^3) with its normals reversed
  }
}

#include <cmath>
#include <cstring>
#include <map>
#include <vector>

#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/text_cursor.h"

namespace fmpc::sim {

namespace {

// A binary STL is an 80-byte header, a little-endian uint32 triangle count, then 50 bytes per triangle: the normal
// and three vertices as 12 little-endian float32, and a uint16 attribute (3D Systems, "StereoLithography Interface
// Specification", 1989).
constexpr std::size_t kStlHeaderBytes = 84;
constexpr std::size_t kStlTriangleBytes = 50;

std::uint32_t load_little_endian_u32(const char* bytes) {
  std::uint32_t value = 0;
  for (std::size_t i = 0; i < 4; ++i)
    value |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i])) << (8 * i);
  return value;
}

float load_little_endian_float(const char* bytes) {
  const std::uint32_t raw = load_little_endian_u32(bytes);
  float value = 0.0f;
  std::memcpy(&value, &raw, sizeof value);
  return value;
}

// STL stores every triangle with its own three corners: corners with the same coordinates (bit for bit) become one
// vertex, numbered in the order they first appear, so that edges are shared and the surface can be checked closed.
class VertexWelder {
 public:
  explicit VertexWelder(Mesh& mesh) : mesh_(mesh) {}
  std::int32_t add(const Point3& p) {
    const auto [it, inserted] = index_.emplace(p, static_cast<std::int32_t>(mesh_.points.size()));
    if (inserted) mesh_.points.push_back(p);
    return it->second;
  }

 private:
  Mesh& mesh_;
  std::map<Point3, std::int32_t> index_;
};

std::optional<Mesh> read_binary_stl(std::string_view bytes, const std::string& file, std::size_t count,
                                    DiagnosticList& diagnostics) {
  Mesh mesh;
  mesh.source = file;
  mesh.triangles.reserve(count);  // the file's size was checked to hold exactly `count` triangles
  VertexWelder welder(mesh);
  for (std::size_t t = 0; t < count; ++t) {
    const char* record = bytes.data() + kStlHeaderBytes + kStlTriangleBytes * t;
    Triangle triangle{};
    for (std::size_t corner = 0; corner < 3; ++corner) {
      Point3 p{};
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const float value = load_little_endian_float(record + 12 + 12 * corner + 4 * axis);
        if (!std::isfinite(value)) {
          diagnostics.error(SourceRange{file, 0, 0, 0, 0}, "binary STL triangle " + std::to_string(t) +
                                                               " (0-based) has a coordinate that is not a "
                                                               "finite number; fix the surface");
          return std::nullopt;
        }
        p[axis] = static_cast<double>(value);
      }
      triangle[corner] = welder.add(p);
    }
    mesh.triangles.push_back(triangle);
  }
  return mesh;
}

std::optional<Mesh> read_ascii_stl(std::string_view text, const std::string& file, DiagnosticList& diagnostics) {
  TextCursor cursor(text, file);
  Mesh mesh;
  mesh.source = file;
  VertexWelder welder(mesh);
  const auto expect = [&](std::string_view keyword) {
    const std::string_view token = cursor.next_token();
    if (token == keyword) return true;
    diagnostics.error(cursor.range_here(), "expected '" + std::string(keyword) + "', found '" +
                                               std::string(token.substr(0, 40)) +
                                               "'; an ASCII STL facet is 'facet normal nx ny nz / outer loop / vertex "
                                               "x y z (three times) / endloop / endfacet'");
    return false;
  };
  if (cursor.next_token() != "solid") {
    diagnostics.error(cursor.range_here(), "an ASCII STL file starts with 'solid'; check the file");
    return std::nullopt;
  }
  cursor.skip_line();  // the solid's name
  bool ended = false;
  while (!cursor.at_end()) {
    const std::string_view keyword = cursor.next_token();
    if (keyword == "endsolid") {
      ended = true;
      break;
    }
    if (keyword != "facet") {
      diagnostics.error(cursor.range_here(), "expected 'facet' or 'endsolid', found '" +
                                                 std::string(keyword.substr(0, 40)) + "'; fix the file");
      return std::nullopt;
    }
    const int line = cursor.token_line();
    cursor.skip_line();  // normal nx ny nz: fmpc orients by the corners' order, as the standard says it must agree
    if (!expect("outer") || !expect("loop")) return std::nullopt;
    Triangle triangle{};
    for (std::size_t corner = 0; corner < 3; ++corner) {
      if (!expect("vertex")) return std::nullopt;
      Point3 p{};
      for (double& coordinate : p) {
        const auto value = cursor.read_real(diagnostics, "a vertex coordinate");
        if (!value) return std::nullopt;
        if (!std::isfinite(*value)) {
          diagnostics.error(cursor.range_here(), "a vertex coordinate is not a finite number; fix the facet");
          return std::nullopt;
        }
        coordinate = *value;
      }
      triangle[corner] = welder.add(p);
    }
    if (!expect("endloop") || !expect("endfacet")) return std::nullopt;
    mesh.triangles.push_back(triangle);
    mesh.triangle_lines.push_back(line);
  }
  if (!ended) {
    diagnostics.error(SourceRange{file, cursor.line(), 1, 0, 0},
                      "the file ends without 'endsolid'; it is truncated: export it again");
    return std::nullopt;
  }
  return mesh;
}

}  // namespace

std::optional<Mesh> read_stl(std::string_view bytes, const std::string& file, DiagnosticList& diagnostics) {
  // Binary files may also begin with "solid" (some exporters write it into the header): the size decides first.
  if (bytes.size() >= kStlHeaderBytes) {
    const std::size_t count = load_little_endian_u32(bytes.data() + 80);
    if (bytes.size() == kStlHeaderBytes + kStlTriangleBytes * count)
      return read_binary_stl(bytes, file, count, diagnostics);
  }
  if (bytes.substr(0, 5) == "solid") return read_ascii_stl(bytes, file, diagnostics);
  std::string detail = " it has " + std::to_string(bytes.size()) + " bytes";
  if (bytes.size() >= kStlHeaderBytes)
    detail += ", while a binary STL with the " + std::to_string(load_little_endian_u32(bytes.data() + 80)) +
              " triangles its header claims has " +
              std::to_string(kStlHeaderBytes + kStlTriangleBytes * load_little_endian_u32(bytes.data() + 80));
  diagnostics.error(SourceRange{file, 0, 0, 0, 0},
                    "this is neither an ASCII STL file (starting with 'solid') nor a binary one (84 + 50 x triangles "
                    "bytes):" +
                        detail + "; the file is truncated or not STL: export it again");
  return std::nullopt;
}

}  // namespace fmpc::sim

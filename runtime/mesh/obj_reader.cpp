#include <cmath>
#include <vector>

#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/text_cursor.h"

namespace fmpc::sim {

namespace {

// The vertex index of an OBJ face corner "v", "v/vt", "v//vn" or "v/vt/vn"; negative counts back from the last
// vertex read so far (OBJ specification, "Referencing vertex data").
bool obj_vertex_index(std::string_view corner, std::size_t vertices_so_far, std::int64_t& index) {
  const std::string_view first = corner.substr(0, corner.find('/'));
  std::int64_t value = 0;
  if (!parse_integer(first, value) || value == 0) return false;
  index = value > 0 ? value - 1 : static_cast<std::int64_t>(vertices_so_far) + value;
  return true;
}

}  // namespace

std::optional<Mesh> read_obj(std::string_view text, const std::string& file, DiagnosticList& diagnostics) {
  TextCursor cursor(text, file);
  Mesh mesh;
  mesh.source = file;
  // Faces are checked once every vertex is known (a face may come before its vertices). They are kept flat, one
  // corner array for all faces, so that memory stays a small multiple of the file size.
  std::vector<std::int64_t> corners;
  std::vector<std::size_t> face_start;
  std::vector<int> face_line;
  const auto face_range = [&](std::size_t face) {
    SourceRange range;
    range.file = file;
    range.line = face_line[face];
    range.column = 1;
    return range;
  };
  while (!cursor.at_end()) {
    const std::string_view keyword = cursor.next_token();
    if (keyword == "v") {
      Point3 p{};
      for (double& coordinate : p) {
        const auto token = cursor.next_token_on_line();
        double value = 0.0;
        if (!token || !parse_real(*token, value) || !std::isfinite(value)) {
          diagnostics.error(cursor.range_here(), "a 'v' record needs three finite coordinates" +
                                                     (token ? ", found '" + std::string(token->substr(0, 40)) + "'"
                                                            : std::string(", the line ends early")) +
                                                     "; fix the vertex");
          return std::nullopt;
        }
        coordinate = value;
      }
      mesh.points.push_back(p);
      cursor.skip_line();  // an optional w weight
    } else if (keyword == "f") {
      const SourceRange range = cursor.range_here();
      const std::size_t first = corners.size();
      while (const auto corner = cursor.next_token_on_line()) {
        std::int64_t index = 0;
        if (!obj_vertex_index(*corner, mesh.points.size(), index)) {
          diagnostics.error(cursor.range_here(),
                            "face corner '" + std::string(corner->substr(0, 40)) +
                                "' is not a vertex number (1-based, or negative to count back); fix the face");
          return std::nullopt;
        }
        corners.push_back(index);
      }
      if (corners.size() - first < 3) {
        diagnostics.error(range, "a face needs at least three vertices, this one has " +
                                     std::to_string(corners.size() - first) +
                                     "; remove it or add the missing vertices");
        return std::nullopt;
      }
      face_start.push_back(first);
      face_line.push_back(range.line);
    } else {
      cursor.skip_line();  // vn, vt, g, o, s, usemtl, mtllib, l, comments: nothing to simulate
    }
  }
  face_start.push_back(corners.size());
  for (std::size_t face = 0; face + 1 < face_start.size(); ++face) {
    const std::size_t begin = face_start[face], end = face_start[face + 1];
    for (std::size_t c = begin; c < end; ++c) {
      const std::int64_t index = corners[c];
      if (index < 0 || index >= static_cast<std::int64_t>(mesh.points.size())) {
        diagnostics.error(face_range(face), "the face refers to vertex " + std::to_string(index + 1) +
                                                " but the file has " + std::to_string(mesh.points.size()) +
                                                " vertices; fix the face");
        return std::nullopt;
      }
    }
    for (std::size_t c = begin + 1; c + 1 < end; ++c) {
      mesh.triangles.push_back({static_cast<std::int32_t>(corners[begin]), static_cast<std::int32_t>(corners[c]),
                                static_cast<std::int32_t>(corners[c + 1])});
      mesh.triangle_lines.push_back(face_line[face]);
    }
  }
  return mesh;
}

}  // namespace fmpc::sim

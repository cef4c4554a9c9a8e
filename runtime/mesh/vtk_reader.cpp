#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <utility>
#include <vector>

#include "runtime/io/input_file.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/text_cursor.h"

namespace fmpc::sim {

namespace {

constexpr std::int64_t kVtkTriangle = 5;
constexpr std::int64_t kVtkTetra = 10;

// Legacy VTK binary data is big-endian (VTK User's Guide, "Simple Legacy Formats").
template <typename Unsigned>
Unsigned load_big_endian(const char* bytes) {
  Unsigned value = 0;
  for (std::size_t i = 0; i < sizeof(Unsigned); ++i) {
    value = static_cast<Unsigned>((value << 8) | static_cast<Unsigned>(static_cast<unsigned char>(bytes[i])));
  }
  return value;
}

class VtkParser {
 public:
  VtkParser(std::string_view bytes, const std::string& file, DiagnosticList& diagnostics)
      : cursor_(bytes, file), diagnostics_(diagnostics) {
    mesh_.source = file;
  }
  std::optional<Mesh> parse();

 private:
  bool read_reals(std::size_t count, std::string_view type, std::vector<double>& out);
  bool read_integers(std::size_t count, std::vector<std::int64_t>& out);
  std::optional<std::size_t> read_count(std::string_view what);
  bool read_points();
  bool read_cell_list(std::string_view keyword, std::vector<std::int64_t>& connectivity, std::size_t& cells, int& line);
  bool add_cells(const std::vector<std::int64_t>& list, std::size_t cells, int line,
                 const std::vector<std::int64_t>* types);
  void error(const std::string& message) { diagnostics_.error(cursor_.range_here(), message); }

  TextCursor cursor_;
  DiagnosticList& diagnostics_;
  Mesh mesh_;
  bool binary_ = false;
};

std::optional<std::size_t> VtkParser::read_count(std::string_view what) {
  const auto value = cursor_.read_integer(diagnostics_, what);
  if (!value) return std::nullopt;
  if (*value < 0 || *value > (std::int64_t{1} << 31)) {
    error(std::string(what) + " " + std::to_string(*value) + " is out of range; fix the count");
    return std::nullopt;
  }
  return static_cast<std::size_t>(*value);
}

bool VtkParser::read_reals(std::size_t count, std::string_view type, std::vector<double>& out) {
  out.clear();
  if (!binary_) {
    // The count is the file's claim: reserve only what the bytes left can hold (two per value, "0 "), so that
    // `POINTS 2147483648` over one line fails at the end of the text, where it is truncated, having allocated little.
    out.reserve(std::min(count, cursor_.remaining() / 2));
    for (std::size_t i = 0; i < count; ++i) {
      const auto value = cursor_.read_real(diagnostics_, "a point coordinate");
      if (!value) return false;
      out.push_back(*value);
    }
    return true;
  }
  const std::size_t width = type == "double" ? 8 : 4;
  cursor_.skip_line();  // binary data starts on the line after the keyword
  if (cursor_.remaining() < count * width) {
    error("the binary point data needs " + std::to_string(count * width) + " bytes but only " +
          std::to_string(cursor_.remaining()) + " remain; the file is truncated: export it again");
    return false;
  }
  out.resize(count);  // checked against the bytes left just above
  const char* bytes = cursor_.data_here();
  for (std::size_t i = 0; i < count; ++i) {
    if (width == 8) {
      const std::uint64_t raw = load_big_endian<std::uint64_t>(bytes + 8 * i);
      std::memcpy(&out[i], &raw, sizeof raw);
    } else {
      const std::uint32_t raw = load_big_endian<std::uint32_t>(bytes + 4 * i);
      float value = 0.0f;
      std::memcpy(&value, &raw, sizeof raw);
      out[i] = static_cast<double>(value);
    }
    if (!std::isfinite(out[i])) {
      error("binary point coordinate " + std::to_string(i) + " is not a finite number; fix the points");
      return false;
    }
  }
  cursor_.advance_bytes(count * width);
  return true;
}

bool VtkParser::read_integers(std::size_t count, std::vector<std::int64_t>& out) {
  out.clear();
  if (!binary_) {
    out.reserve(std::min(count, cursor_.remaining() / 2));  // as in read_reals
    for (std::size_t i = 0; i < count; ++i) {
      const auto value = cursor_.read_integer(diagnostics_, "a cell entry");
      if (!value) return false;
      out.push_back(*value);
    }
    return true;
  }
  cursor_.skip_line();
  if (cursor_.remaining() < count * 4) {
    error("the binary cell data needs " + std::to_string(count * 4) + " bytes but only " +
          std::to_string(cursor_.remaining()) + " remain; the file is truncated: export it again");
    return false;
  }
  out.resize(count);  // checked against the bytes left just above
  const char* bytes = cursor_.data_here();
  for (std::size_t i = 0; i < count; ++i) {
    out[i] = static_cast<std::int32_t>(load_big_endian<std::uint32_t>(bytes + 4 * i));
  }
  cursor_.advance_bytes(count * 4);
  return true;
}

bool VtkParser::read_points() {
  const auto count = read_count("the point count");
  if (!count) return false;
  const std::string_view type = cursor_.next_token();
  if (type != "float" && type != "double") {
    error("point data type '" + std::string(type) + "' is not supported; write the points as float or double");
    return false;
  }
  std::vector<double> values;
  if (!read_reals(*count * 3, type, values)) return false;
  mesh_.points.resize(*count);
  for (std::size_t i = 0; i < *count; ++i) mesh_.points[i] = {values[3 * i], values[3 * i + 1], values[3 * i + 2]};
  return true;
}

bool VtkParser::read_cell_list(std::string_view keyword, std::vector<std::int64_t>& connectivity, std::size_t& cells,
                               int& line) {
  line = cursor_.token_line();
  const auto count = read_count("the " + std::string(keyword) + " count");
  if (!count) return false;
  const auto size = read_count("the " + std::string(keyword) + " list size");
  if (!size) return false;
  cells = *count;
  return read_integers(*size, connectivity);
}

bool VtkParser::add_cells(const std::vector<std::int64_t>& list, std::size_t cells, int line,
                          const std::vector<std::int64_t>* types) {
  std::size_t at = 0;
  std::size_t ignored = 0;
  for (std::size_t cell = 0; cell < cells; ++cell) {
    if (at >= list.size()) {
      error("the cell list ends after " + std::to_string(cell) + " of " + std::to_string(cells) +
            " cells; the list size is wrong: fix the header or re-export");
      return false;
    }
    const std::int64_t n = list[at];
    if (n < 0 || at + 1 + static_cast<std::size_t>(n) > list.size()) {
      error("cell " + std::to_string(cell) + " claims " + std::to_string(n) +
            " points, past the end of the list; fix the cell list");
      return false;
    }
    for (std::int64_t k = 0; k < n; ++k) {
      const std::int64_t index = list[at + 1 + static_cast<std::size_t>(k)];
      if (index < 0 || index >= static_cast<std::int64_t>(mesh_.points.size())) {
        error("cell " + std::to_string(cell) + " refers to point " + std::to_string(index) + " but there are " +
              std::to_string(mesh_.points.size()) + " points (0-based); fix the cell");
        return false;
      }
    }
    const auto point = [&](std::int64_t k) {
      return static_cast<std::int32_t>(list[at + 1 + static_cast<std::size_t>(k)]);
    };
    const std::int64_t type = types ? (*types)[cell] : (n >= 3 ? kVtkTriangle : 0);
    if (type == kVtkTetra && n == 4) {
      mesh_.tetrahedra.push_back({point(0), point(1), point(2), point(3)});
      mesh_.tetrahedron_lines.push_back(line);
    } else if ((type == kVtkTriangle && n == 3) || (!types && n >= 3)) {
      for (std::int64_t k = 1; k + 1 < n; ++k) {  // polygons are fanned into triangles
        mesh_.triangles.push_back({point(0), point(k), point(k + 1)});
        mesh_.triangle_lines.push_back(line);
      }
    } else {
      ++ignored;
    }
    at += 1 + static_cast<std::size_t>(n);
  }
  if (ignored > 0) {
    SourceRange range = cursor_.range_here();
    range.line = line;
    diagnostics_.warning(range, "mesh-ignored-elements",
                         std::to_string(ignored) + " cells that are neither tetrahedra nor triangles were ignored");
  }
  return true;
}

std::optional<Mesh> VtkParser::parse() {
  const std::string_view header = cursor_.rest_of_line();
  if (header.substr(0, 22) != "# vtk DataFile Version") {
    diagnostics_.error(
        SourceRange{cursor_.file(), 1, 1, 0, 0},
        "this is not a legacy VTK file: the first line must be '# vtk DataFile Version x.x'; check the file");
    return std::nullopt;
  }
  const std::string_view version = header.substr(22);
  if (version.find("5.") != std::string_view::npos) {
    diagnostics_.error(SourceRange{cursor_.file(), 1, 1, 0, 0},
                       "legacy VTK version 5 (OFFSETS/CONNECTIVITY) is not supported; write version 4.2 or older "
                       "(vtkDataWriter::SetFileVersion(42))");
    return std::nullopt;
  }
  cursor_.skip_line();  // title
  const std::string_view encoding = cursor_.next_token();
  if (encoding == "BINARY") {
    binary_ = true;
  } else if (encoding != "ASCII") {
    error("line 3 must be ASCII or BINARY, found '" + std::string(encoding.substr(0, 40)) + "'; fix the header");
    return std::nullopt;
  }
  if (cursor_.next_token() != "DATASET") {
    error("expected 'DATASET POLYDATA' or 'DATASET UNSTRUCTURED_GRID'; fix the header");
    return std::nullopt;
  }
  const std::string dataset(cursor_.next_token());
  if (dataset != "POLYDATA" && dataset != "UNSTRUCTURED_GRID") {
    error("dataset '" + dataset + "' is not supported; write POLYDATA or UNSTRUCTURED_GRID");
    return std::nullopt;
  }
  bool saw_points = false;
  std::vector<std::int64_t> cells_list;
  std::size_t cell_count = 0;
  int cells_line = 0;
  bool have_cells = false;
  while (!cursor_.at_end()) {
    const std::string keyword(cursor_.next_token());
    if (keyword == "POINTS") {
      if (!read_points()) return std::nullopt;
      saw_points = true;
    } else if (keyword == "METADATA") {
      // VTK 9 writes METADATA blocks (array information) that end at an empty line.
      cursor_.skip_line();
      while (!cursor_.at_end_of_text() && !cursor_.rest_of_line().empty()) {
      }
    } else if (keyword == "POINT_DATA" || keyword == "CELL_DATA" || keyword == "FIELD") {
      break;  // attributes: nothing the simulator uses
    } else if (!saw_points) {
      error("'" + keyword.substr(0, 40) + "' comes before POINTS; put the points first");
      return std::nullopt;
    } else if (dataset == "POLYDATA" &&
               (keyword == "POLYGONS" || keyword == "VERTICES" || keyword == "LINES" || keyword == "TRIANGLE_STRIPS")) {
      std::vector<std::int64_t> list;
      std::size_t count = 0;
      int line = 0;
      if (!read_cell_list(keyword, list, count, line)) return std::nullopt;
      if (keyword == "POLYGONS" && !add_cells(list, count, line, nullptr)) return std::nullopt;
      if (keyword == "TRIANGLE_STRIPS") {
        SourceRange range = cursor_.range_here();
        range.line = line;
        diagnostics_.warning(range, "mesh-ignored-elements", "TRIANGLE_STRIPS were ignored; write them as POLYGONS");
      }
    } else if (dataset == "UNSTRUCTURED_GRID" && keyword == "CELLS") {
      if (!read_cell_list(keyword, cells_list, cell_count, cells_line)) return std::nullopt;
      have_cells = true;
    } else if (dataset == "UNSTRUCTURED_GRID" && keyword == "CELL_TYPES") {
      const auto count = read_count("the cell type count");
      if (!count) return std::nullopt;
      if (!have_cells || *count != cell_count) {
        error("CELL_TYPES must follow CELLS and have one entry per cell (" + std::to_string(cell_count) +
              "); fix the counts");
        return std::nullopt;
      }
      std::vector<std::int64_t> types;
      if (!read_integers(*count, types)) return std::nullopt;
      if (!add_cells(cells_list, cell_count, cells_line, &types)) return std::nullopt;
      have_cells = false;
    } else {
      error("unexpected keyword '" + keyword.substr(0, 40) + "' in a " + dataset + " dataset; fix the file");
      return std::nullopt;
    }
  }
  if (!saw_points) {
    diagnostics_.error(SourceRange{cursor_.file(), 0, 0, 0, 0},
                       "the file has no POINTS; export the mesh with its points");
    return std::nullopt;
  }
  if (have_cells) {
    error("CELLS without CELL_TYPES; add the CELL_TYPES section");
    return std::nullopt;
  }
  return std::move(mesh_);
}

bool ends_with(const std::string& text, const std::string& suffix) {
  if (text.size() < suffix.size()) return false;
  for (std::size_t i = 0; i < suffix.size(); ++i) {
    const char c = text[text.size() - suffix.size() + i];
    if (static_cast<char>(std::tolower(static_cast<unsigned char>(c))) != suffix[i]) return false;
  }
  return true;
}

}  // namespace

std::optional<Mesh> read_vtk(std::string_view bytes, const std::string& file, DiagnosticList& diagnostics) {
  VtkParser parser(bytes, file, diagnostics);
  return parser.parse();
}

std::optional<Mesh> read_mesh_file(const std::string& path, DiagnosticList& diagnostics, std::string* contents) {
  SourceRange range;
  range.file = path;
  using Reader = std::optional<Mesh> (*)(std::string_view, const std::string&, DiagnosticList&);
  const std::pair<const char*, Reader> readers[] = {
      {".msh", read_gmsh}, {".obj", read_obj}, {".vtk", read_vtk}, {".stl", read_stl}, {".ply", read_ply}};
  Reader reader = nullptr;
  for (const auto& [extension, candidate] : readers)
    if (ends_with(path, extension)) reader = candidate;
  if (reader == nullptr) {
    diagnostics.error(range, "unknown mesh format; use a .msh (Gmsh), .obj, .vtk (legacy VTK), .stl or .ply file");
    return std::nullopt;
  }
  std::string error;
  std::optional<std::string> read = read_input_file(path, kMaxMeshFileBytes, "mesh file", error);
  if (!read) {
    diagnostics.error(range, error);
    return std::nullopt;
  }
  auto mesh = reader(*read, path, diagnostics);
  if (contents != nullptr) *contents = std::move(*read);
  return mesh;
}

}  // namespace fmpc::sim

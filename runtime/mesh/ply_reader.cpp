#include <cmath>
#include <cstring>
#include <vector>

#include "diagnostics/number_format.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/text_cursor.h"

namespace fmpc::sim {

namespace {

// The PLY polygon format (G. Turk, "The PLY Polygon File Format", 1994): a text header listing elements and their
// properties, then the elements in ASCII or binary. Only `vertex` (x, y, z) and `face` (a vertex_indices or
// vertex_index list) matter here; other elements and properties are read past.
enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

std::optional<PlyType> ply_type(std::string_view name) {
  if (name == "char" || name == "int8") return PlyType::Int8;
  if (name == "uchar" || name == "uint8") return PlyType::UInt8;
  if (name == "short" || name == "int16") return PlyType::Int16;
  if (name == "ushort" || name == "uint16") return PlyType::UInt16;
  if (name == "int" || name == "int32") return PlyType::Int32;
  if (name == "uint" || name == "uint32") return PlyType::UInt32;
  if (name == "float" || name == "float32") return PlyType::Float32;
  if (name == "double" || name == "float64") return PlyType::Float64;
  return std::nullopt;
}

std::size_t type_bytes(PlyType type) {
  switch (type) {
    case PlyType::Int8:
    case PlyType::UInt8:
      return 1;
    case PlyType::Int16:
    case PlyType::UInt16:
      return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32:
      return 4;
    case PlyType::Float64:
      return 8;
  }
  return 1;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  int line = 0;
  std::vector<PlyProperty> properties;
};

class PlyParser {
 public:
  PlyParser(std::string_view bytes, const std::string& file, DiagnosticList& diagnostics)
      : cursor_(bytes, file), diagnostics_(diagnostics) {
    mesh_.source = file;
  }
  std::optional<Mesh> parse();

 private:
  bool parse_header();
  bool read_value(PlyType type, double& value);
  bool read_element(const PlyElement& element);
  void error(const std::string& message) { diagnostics_.error(cursor_.range_here(), message); }
  void error_at(int line, const std::string& message) {
    diagnostics_.error(SourceRange{cursor_.file(), line, line > 0 ? 1 : 0, 0, 0}, message);
  }

  TextCursor cursor_;
  DiagnosticList& diagnostics_;
  Mesh mesh_;
  bool binary_ = false;
  std::vector<PlyElement> elements_;
};

bool PlyParser::parse_header() {
  if (cursor_.next_token() != "ply") {
    error_at(1, "this is not a PLY file: the first line must be 'ply'; check the file");
    return false;
  }
  bool have_format = false;
  while (true) {
    if (cursor_.at_end()) {
      error_at(cursor_.line(), "the header ends without 'end_header'; the file is truncated: export it again");
      return false;
    }
    const std::string_view keyword = cursor_.next_token();
    if (keyword == "end_header") {
      if (!have_format) {
        error("the header has no 'format' line; add 'format ascii 1.0' or 'format binary_little_endian 1.0'");
        return false;
      }
      // Binary data starts right after the header's newline.
      if (binary_) cursor_.skip_line();
      return true;
    }
    if (keyword == "comment" || keyword == "obj_info") {
      cursor_.skip_line();
    } else if (keyword == "format") {
      const std::string_view format = cursor_.next_token();
      if (format == "binary_little_endian") {
        binary_ = true;
      } else if (format != "ascii") {
        error("PLY format '" + std::string(format.substr(0, 40)) +
              "' is not supported; write ascii or binary_little_endian");
        return false;
      }
      cursor_.skip_line();  // the version
      have_format = true;
    } else if (keyword == "element") {
      PlyElement element;
      element.line = cursor_.token_line();
      element.name = std::string(cursor_.next_token().substr(0, 64));
      const auto count = cursor_.read_integer(diagnostics_, "the element count");
      if (!count) return false;
      if (*count < 0 || *count > (std::int64_t{1} << 31)) {
        error("element count " + std::to_string(*count) + " is out of range; fix the header");
        return false;
      }
      element.count = static_cast<std::size_t>(*count);
      elements_.push_back(std::move(element));
    } else if (keyword == "property") {
      if (elements_.empty()) {
        error("a 'property' line comes before any 'element'; fix the header");
        return false;
      }
      PlyProperty property;
      std::string_view type_name = cursor_.next_token();
      if (type_name == "list") {
        property.is_list = true;
        const std::string_view count_type = cursor_.next_token();
        const auto counted = ply_type(count_type);
        if (!counted || *counted == PlyType::Float32 || *counted == PlyType::Float64) {
          error("list count type '" + std::string(count_type.substr(0, 40)) +
                "' is not an integer type; fix the "
                "header");
          return false;
        }
        property.count_type = *counted;
        type_name = cursor_.next_token();
      }
      const auto type = ply_type(type_name);
      if (!type) {
        error("property type '" + std::string(type_name.substr(0, 40)) +
              "' is not a PLY type (char uchar short ushort int uint float double, or int8 ... float64)");
        return false;
      }
      property.type = *type;
      property.name = std::string(cursor_.next_token().substr(0, 64));
      elements_.back().properties.push_back(property);
    } else {
      error("unexpected header keyword '" + std::string(keyword.substr(0, 40)) + "'; fix the header");
      return false;
    }
  }
}

bool PlyParser::read_value(PlyType type, double& value) {
  if (!binary_) {
    const auto read = cursor_.read_real(diagnostics_, "a PLY value");
    if (!read) return false;
    value = *read;
    return true;
  }
  const std::size_t width = type_bytes(type);
  if (cursor_.remaining() < width) {
    error_at(0, "the binary data ends early; the file is truncated: export it again");
    return false;
  }
  unsigned char raw[8] = {};
  std::memcpy(raw, cursor_.data_here(), width);
  cursor_.advance_bytes(width);
  std::uint64_t bits = 0;
  for (std::size_t i = 0; i < width; ++i) bits |= static_cast<std::uint64_t>(raw[i]) << (8 * i);
  switch (type) {
    case PlyType::UInt8:
    case PlyType::UInt16:
    case PlyType::UInt32:
      value = static_cast<double>(bits);
      break;
    case PlyType::Int8:
      value = static_cast<std::int8_t>(bits);
      break;
    case PlyType::Int16:
      value = static_cast<std::int16_t>(bits);
      break;
    case PlyType::Int32:
      value = static_cast<std::int32_t>(bits);
      break;
    case PlyType::Float32: {
      const auto narrow = static_cast<std::uint32_t>(bits);
      float f = 0.0f;
      std::memcpy(&f, &narrow, sizeof f);
      value = static_cast<double>(f);
      break;
    }
    case PlyType::Float64:
      std::memcpy(&value, &bits, sizeof value);
      break;
  }
  return true;
}

bool PlyParser::read_element(const PlyElement& element) {
  const bool vertex = element.name == "vertex";
  const bool face = element.name == "face";
  int axis_of[3] = {-1, -1, -1};
  int indices_property = -1;
  for (std::size_t p = 0; p < element.properties.size(); ++p) {
    const PlyProperty& property = element.properties[p];
    if (vertex && !property.is_list && property.name.size() == 1 && property.name[0] >= 'x' && property.name[0] <= 'z')
      axis_of[property.name[0] - 'x'] = static_cast<int>(p);
    if (face && property.is_list && (property.name == "vertex_indices" || property.name == "vertex_index"))
      indices_property = static_cast<int>(p);
  }
  if (vertex && (axis_of[0] < 0 || axis_of[1] < 0 || axis_of[2] < 0)) {
    error_at(element.line, "the vertex element needs properties x, y and z; fix the header");
    return false;
  }
  if (face && indices_property < 0) {
    error_at(element.line,
             "the face element needs a list property 'vertex_indices' (or 'vertex_index'); fix the "
             "header");
    return false;
  }
  // Every element takes at least one byte (binary) or two (ASCII "0 "): a count the rest of the file cannot hold is
  // refused before anything is reserved for it.
  const std::size_t least = binary_ ? 1 : 2;
  if (element.count > cursor_.remaining() / least) {
    error_at(element.line, "element '" + element.name + "' claims " + std::to_string(element.count) +
                               " items but the file has only " + std::to_string(cursor_.remaining()) +
                               " bytes left; the file is truncated or the count is wrong");
    return false;
  }
  if (vertex) mesh_.points.reserve(element.count);
  std::vector<std::int64_t> polygon;
  for (std::size_t item = 0; item < element.count; ++item) {
    Point3 p{};
    int line = 0;  // the item's line (ASCII), known once its first value is read
    const auto note_line = [&] {
      if (!binary_ && line == 0) line = cursor_.token_line();
    };
    for (std::size_t k = 0; k < element.properties.size(); ++k) {
      const PlyProperty& property = element.properties[k];
      double value = 0.0;
      if (!property.is_list) {
        if (!read_value(property.type, value)) return false;
        note_line();
        for (std::size_t axis = 0; axis < 3; ++axis)
          if (vertex && axis_of[axis] == static_cast<int>(k)) p[axis] = value;
        continue;
      }
      if (!read_value(property.count_type, value)) return false;
      note_line();
      if (!(value >= 0.0 && value <= 1000.0) || value != std::floor(value)) {
        error_at(line, element.name + " " + std::to_string(item) + ": list length " + format_number(value) +
                           " is not a count from 0 to 1000; fix the file");
        return false;
      }
      const auto length = static_cast<std::size_t>(value);
      polygon.clear();
      for (std::size_t i = 0; i < length; ++i) {
        if (!read_value(property.type, value)) return false;
        // Checked before the conversion: a value outside int64's range (1e308) is undefined behaviour to convert.
        if (value != std::floor(value) || value < 0.0 || value >= static_cast<double>(mesh_.points.size())) {
          error_at(line, "face " + std::to_string(item) + " refers to vertex " + format_number(value) +
                             " but the file has " + std::to_string(mesh_.points.size()) +
                             " vertices (0-based); fix the face");
          return false;
        }
        polygon.push_back(static_cast<std::int64_t>(value));
      }
      if (!face || static_cast<int>(k) != indices_property) continue;
      if (length < 3) {
        error_at(line, "face " + std::to_string(item) + " has " + std::to_string(length) +
                           " vertices; a face needs at least three");
        return false;
      }
      for (std::size_t c = 1; c + 1 < length; ++c) {  // polygons are fanned into triangles
        mesh_.triangles.push_back({static_cast<std::int32_t>(polygon[0]), static_cast<std::int32_t>(polygon[c]),
                                   static_cast<std::int32_t>(polygon[c + 1])});
        mesh_.triangle_lines.push_back(line);
      }
    }
    if (vertex) {
      if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) {
        error_at(line, "vertex " + std::to_string(item) + " has a coordinate that is not a finite number; fix it");
        return false;
      }
      mesh_.points.push_back(p);
    }
  }
  return true;
}

std::optional<Mesh> PlyParser::parse() {
  if (!parse_header()) return std::nullopt;
  bool have_vertices = false;
  for (const PlyElement& element : elements_) {
    if (element.name == "face" && !have_vertices) {
      error_at(element.line, "the face element comes before the vertex element; put the vertices first");
      return std::nullopt;
    }
    if (!read_element(element)) return std::nullopt;
    have_vertices = have_vertices || element.name == "vertex";
  }
  if (!have_vertices) {
    error_at(0, "the file has no vertex element; export the surface with its vertices");
    return std::nullopt;
  }
  return std::move(mesh_);
}

}  // namespace

std::optional<Mesh> read_ply(std::string_view bytes, const std::string& file, DiagnosticList& diagnostics) {
  PlyParser parser(bytes, file, diagnostics);
  return parser.parse();
}

}  // namespace fmpc::sim

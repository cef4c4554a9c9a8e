#include <algorithm>
#include <cstdint>
#include <unordered_map>

#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/text_cursor.h"

namespace fmpc::sim {

namespace {

constexpr std::int64_t kGmshTriangle = 2;
constexpr std::int64_t kGmshTetrahedron = 4;
constexpr std::int64_t kGmshPoint = 15;
constexpr std::int64_t kGmshLine = 1;
// The fewest bytes a node record can take ("1 0 0 0\n"): what the reader reserves for a node count.
constexpr std::size_t kMinNodeBytes = 8;

// Nodes per element for the Gmsh element types (gmsh reference manual, "MSH file format", element types 1-31).
int gmsh_node_count(std::int64_t type) {
  switch (type) {
    case 1:
      return 2;
    case 2:
      return 3;
    case 3:
      return 4;
    case 4:
      return 4;
    case 5:
      return 8;
    case 6:
      return 6;
    case 7:
      return 5;
    case 8:
      return 3;
    case 9:
      return 6;
    case 10:
      return 9;
    case 11:
      return 10;
    case 12:
      return 27;
    case 13:
      return 18;
    case 14:
      return 14;
    case 15:
      return 1;
    case 16:
      return 8;
    case 17:
      return 20;
    case 18:
      return 15;
    case 19:
      return 13;
    default:
      return -1;
  }
}

class GmshParser {
 public:
  GmshParser(std::string_view text, const std::string& file, DiagnosticList& diagnostics)
      : cursor_(text, file), diagnostics_(diagnostics) {
    mesh_.source = file;
  }

  std::optional<Mesh> parse();

 private:
  bool parse_nodes_v1_v2(std::string_view end_marker);
  bool parse_elements_v1_v2(bool version1, std::string_view end_marker);
  bool parse_nodes_v4();
  bool parse_elements_v4();
  bool skip_section(std::string_view end_marker);
  bool expect(std::string_view marker);
  bool add_element(std::int64_t type, const std::int64_t* tags, int count, int line, std::int64_t element_id);
  std::optional<std::int32_t> node_index(std::int64_t tag, std::int64_t element_id);
  void warn_ignored_types();

  TextCursor cursor_;
  DiagnosticList& diagnostics_;
  Mesh mesh_;
  std::unordered_map<std::int64_t, std::int32_t> index_of_tag_;
  std::unordered_map<std::int64_t, std::size_t> ignored_types_;
  bool saw_nodes_ = false;
};

bool GmshParser::expect(std::string_view marker) {
  const std::string_view token = cursor_.next_token();
  if (token == marker) return true;
  diagnostics_.error(cursor_.range_here(), "expected '" + std::string(marker) + "' but found '" +
                                               std::string(token.substr(0, 40)) +
                                               "'; the section is incomplete: check the counts or re-export the mesh");
  return false;
}

bool GmshParser::skip_section(std::string_view end_marker) {
  while (!cursor_.at_end()) {
    if (cursor_.next_token() == end_marker) return true;
  }
  diagnostics_.error(cursor_.range_here(),
                     "the file ends before '" + std::string(end_marker) + "'; the file is truncated: export it again");
  return false;
}

std::optional<std::int32_t> GmshParser::node_index(std::int64_t tag, std::int64_t element_id) {
  const auto it = index_of_tag_.find(tag);
  if (it != index_of_tag_.end()) return it->second;
  diagnostics_.error(cursor_.range_here(),
                     "element " + std::to_string(element_id) + " refers to node " + std::to_string(tag) +
                         ", which is not in the node section; add the node or remove the element");
  return std::nullopt;
}

bool GmshParser::add_element(std::int64_t type, const std::int64_t* tags, int count, int line,
                             std::int64_t element_id) {
  if (type != kGmshTriangle && type != kGmshTetrahedron) {
    if (type != kGmshPoint && type != kGmshLine) ++ignored_types_[type];
    return true;
  }
  std::int32_t indices[4] = {0, 0, 0, 0};
  for (int i = 0; i < count; ++i) {
    const auto index = node_index(tags[i], element_id);
    if (!index) return false;
    indices[i] = *index;
  }
  if (type == kGmshTetrahedron) {
    mesh_.tetrahedra.push_back({indices[0], indices[1], indices[2], indices[3]});
    mesh_.tetrahedron_lines.push_back(line);
  } else {
    mesh_.triangles.push_back({indices[0], indices[1], indices[2]});
    mesh_.triangle_lines.push_back(line);
  }
  return true;
}

bool GmshParser::parse_nodes_v1_v2(std::string_view end_marker) {
  const auto count = cursor_.read_integer(diagnostics_, "the node count");
  if (!count) return false;
  if (*count < 0) {
    diagnostics_.error(cursor_.range_here(), "node count " + std::to_string(*count) + " is negative; fix the count");
    return false;
  }
  // The count is the file's claim: reserve only what the bytes left can hold, so that `$Nodes` claiming 2^30 over
  // five lines fails where the text ends (truncated), having allocated little.
  mesh_.points.reserve(std::min(static_cast<std::size_t>(*count), cursor_.remaining() / kMinNodeBytes));
  for (std::int64_t i = 0; i < *count; ++i) {
    const auto tag = cursor_.read_integer(diagnostics_, "a node number");
    if (!tag) return false;
    Point3 p{};
    for (double& coordinate : p) {
      const auto value = cursor_.read_real(diagnostics_, "a node coordinate");
      if (!value) return false;
      coordinate = *value;
    }
    const auto [it, inserted] = index_of_tag_.emplace(*tag, static_cast<std::int32_t>(mesh_.points.size()));
    (void)it;
    if (!inserted) {
      diagnostics_.error(cursor_.range_here(),
                         "node number " + std::to_string(*tag) + " appears twice; give every node its own number");
      return false;
    }
    mesh_.points.push_back(p);
  }
  saw_nodes_ = true;
  return expect(end_marker);
}

bool GmshParser::parse_elements_v1_v2(bool version1, std::string_view end_marker) {
  if (!saw_nodes_) {
    diagnostics_.error(cursor_.range_here(), "the element section comes before the node section; put the nodes first");
    return false;
  }
  const auto count = cursor_.read_integer(diagnostics_, "the element count");
  if (!count) return false;
  if (*count < 0) {
    diagnostics_.error(cursor_.range_here(), "element count " + std::to_string(*count) + " is negative; fix the count");
    return false;
  }
  for (std::int64_t i = 0; i < *count; ++i) {
    const auto id = cursor_.read_integer(diagnostics_, "an element number");
    if (!id) return false;
    const int line = cursor_.token_line();
    const auto type = cursor_.read_integer(diagnostics_, "an element type");
    if (!type) return false;
    const int expected_nodes = gmsh_node_count(*type);
    if (expected_nodes < 0) {
      diagnostics_.error(cursor_.range_here(), "element " + std::to_string(*id) + " has unknown type " +
                                                   std::to_string(*type) +
                                                   "; only Gmsh types 1-19 are known: re-export with linear elements");
      return false;
    }
    int node_count = expected_nodes;
    if (version1) {
      // v1: elm-number elm-type reg-phys reg-elem number-of-nodes node-list
      for (int skip = 0; skip < 2; ++skip) {
        if (!cursor_.read_integer(diagnostics_, "a region number")) return false;
      }
      const auto listed = cursor_.read_integer(diagnostics_, "the number of nodes");
      if (!listed) return false;
      if (*listed != expected_nodes) {
        diagnostics_.error(cursor_.range_here(), "element " + std::to_string(*id) + " of type " +
                                                     std::to_string(*type) + " lists " + std::to_string(*listed) +
                                                     " nodes but that type has " + std::to_string(expected_nodes) +
                                                     "; fix the node count");
        return false;
      }
    } else {
      // v2: elm-number elm-type number-of-tags <tags> node-number-list
      const auto tag_count = cursor_.read_integer(diagnostics_, "the number of tags");
      if (!tag_count) return false;
      if (*tag_count < 0 || *tag_count > 64) {
        diagnostics_.error(cursor_.range_here(), "element " + std::to_string(*id) + " has " +
                                                     std::to_string(*tag_count) +
                                                     " tags; expected 0-64: fix the count");
        return false;
      }
      for (std::int64_t skip = 0; skip < *tag_count; ++skip) {
        if (!cursor_.read_integer(diagnostics_, "an element tag")) return false;
      }
    }
    std::int64_t tags[27] = {};
    for (int n = 0; n < node_count; ++n) {
      const auto tag = cursor_.read_integer(diagnostics_, "a node number of element " + std::to_string(*id));
      if (!tag) return false;
      tags[n] = *tag;
    }
    if (cursor_.token_line() != line) {
      SourceRange range = cursor_.range_here();
      range.line = line;
      range.column = 1;
      diagnostics_.error(range, "element " + std::to_string(*id) + " continues past its line; " +
                                    "an element has too few nodes or a count is wrong: fix the record");
      return false;
    }
    if (!add_element(*type, tags, node_count, line, *id)) return false;
  }
  return expect(end_marker);
}

bool GmshParser::parse_nodes_v4() {
  // v4.1: numEntityBlocks numNodes minNodeTag maxNodeTag; per block: entityDim entityTag parametric numNodesInBlock,
  // then the block's tags, then their coordinates (x y z, plus u [v [w]] when parametric).
  const auto blocks = cursor_.read_integer(diagnostics_, "the number of node blocks");
  if (!blocks || !cursor_.read_integer(diagnostics_, "the node count") ||
      !cursor_.read_integer(diagnostics_, "the smallest node tag") ||
      !cursor_.read_integer(diagnostics_, "the largest node tag")) {
    return false;
  }
  for (std::int64_t b = 0; b < *blocks; ++b) {
    const auto dim = cursor_.read_integer(diagnostics_, "the entity dimension");
    if (!dim || !cursor_.read_integer(diagnostics_, "the entity tag")) return false;
    const auto parametric = cursor_.read_integer(diagnostics_, "the parametric flag");
    const auto count =
        parametric ? cursor_.read_integer(diagnostics_, "the number of nodes in the block") : std::nullopt;
    if (!count) return false;
    if (*count < 0) {
      diagnostics_.error(cursor_.range_here(),
                         "node block size " + std::to_string(*count) + " is negative; fix the count");
      return false;
    }
    const std::size_t first = mesh_.points.size();
    for (std::int64_t i = 0; i < *count; ++i) {
      const auto tag = cursor_.read_integer(diagnostics_, "a node tag");
      if (!tag) return false;
      if (!index_of_tag_.emplace(*tag, static_cast<std::int32_t>(mesh_.points.size())).second) {
        diagnostics_.error(cursor_.range_here(),
                           "node tag " + std::to_string(*tag) + " appears twice; give every node its own tag");
        return false;
      }
      mesh_.points.push_back({0.0, 0.0, 0.0});
    }
    const int parametric_values = *parametric != 0 ? static_cast<int>(*dim) : 0;
    for (std::int64_t i = 0; i < *count; ++i) {
      Point3& p = mesh_.points[first + static_cast<std::size_t>(i)];
      for (double& coordinate : p) {
        const auto value = cursor_.read_real(diagnostics_, "a node coordinate");
        if (!value) return false;
        coordinate = *value;
      }
      for (int skip = 0; skip < parametric_values; ++skip) {
        if (!cursor_.read_real(diagnostics_, "a parametric coordinate")) return false;
      }
    }
  }
  saw_nodes_ = true;
  return expect("$EndNodes");
}

bool GmshParser::parse_elements_v4() {
  if (!saw_nodes_) {
    diagnostics_.error(cursor_.range_here(), "the element section comes before the node section; put the nodes first");
    return false;
  }
  const auto blocks = cursor_.read_integer(diagnostics_, "the number of element blocks");
  if (!blocks || !cursor_.read_integer(diagnostics_, "the element count") ||
      !cursor_.read_integer(diagnostics_, "the smallest element tag") ||
      !cursor_.read_integer(diagnostics_, "the largest element tag")) {
    return false;
  }
  for (std::int64_t b = 0; b < *blocks; ++b) {
    if (!cursor_.read_integer(diagnostics_, "the entity dimension") ||
        !cursor_.read_integer(diagnostics_, "the entity tag")) {
      return false;
    }
    const auto type = cursor_.read_integer(diagnostics_, "the element type");
    if (!type) return false;
    const int node_count = gmsh_node_count(*type);
    if (node_count < 0) {
      diagnostics_.error(cursor_.range_here(), "element block of unknown type " + std::to_string(*type) +
                                                   "; only Gmsh types 1-19 are known: re-export with linear elements");
      return false;
    }
    const auto count = cursor_.read_integer(diagnostics_, "the number of elements in the block");
    if (!count) return false;
    for (std::int64_t i = 0; i < *count; ++i) {
      const auto id = cursor_.read_integer(diagnostics_, "an element tag");
      if (!id) return false;
      const int line = cursor_.token_line();
      std::int64_t tags[27] = {};
      for (int n = 0; n < node_count; ++n) {
        const auto tag = cursor_.read_integer(diagnostics_, "a node tag of element " + std::to_string(*id));
        if (!tag) return false;
        tags[n] = *tag;
      }
      if (!add_element(*type, tags, node_count, line, *id)) return false;
    }
  }
  return expect("$EndElements");
}

void GmshParser::warn_ignored_types() {
  for (const auto& [type, count] : ignored_types_) {
    SourceRange range;
    range.file = mesh_.source;
    diagnostics_.warning(range, "mesh-ignored-elements",
                         std::to_string(count) + " elements of Gmsh type " + std::to_string(type) +
                             " were ignored; only tetrahedra (4) and triangles (2) are simulated");
  }
}

std::optional<Mesh> GmshParser::parse() {
  const std::string_view first = cursor_.next_token();
  int major_version = 0;
  if (first == "$NOD") {
    major_version = 1;
    if (!parse_nodes_v1_v2("$ENDNOD")) return std::nullopt;
    if (!expect("$ELM") || !parse_elements_v1_v2(true, "$ENDELM")) return std::nullopt;
  } else if (first == "$MeshFormat") {
    const auto version_token = cursor_.next_token();
    const int version_line = cursor_.token_line();
    double version = 0.0;
    if (!parse_real(version_token, version)) {
      diagnostics_.error(cursor_.range_here(), "expected the format version after $MeshFormat but found '" +
                                                   std::string(version_token) + "'; fix the header");
      return std::nullopt;
    }
    const auto file_type = cursor_.read_integer(diagnostics_, "the file type (0 for ASCII)");
    if (!file_type) return std::nullopt;
    if (*file_type != 0) {
      diagnostics_.error(cursor_.range_here(),
                         "binary .msh files are not supported; save the mesh as ASCII "
                         "(gmsh -save -format msh41 or msh22 with Mesh.Binary=0)");
      return std::nullopt;
    }
    if (!cursor_.read_integer(diagnostics_, "the data size")) return std::nullopt;
    if (version >= 2.0 && version < 3.0) {
      major_version = 2;
    } else if (version >= 4.1 && version < 5.0) {
      major_version = 4;
    } else {
      SourceRange range = cursor_.range_here();
      range.line = version_line;
      diagnostics_.error(range,
                         "Gmsh format version " + std::string(version_token) +
                             " is not supported; save the mesh as version 2.2 or 4.1 ASCII (gmsh -format msh22)");
      return std::nullopt;
    }
    if (!expect("$EndMeshFormat")) return std::nullopt;
    bool saw_elements = false;
    while (!cursor_.at_end()) {
      const std::string_view section = cursor_.next_token();
      if (section == "$Nodes") {
        if (!(major_version == 4 ? parse_nodes_v4() : parse_nodes_v1_v2("$EndNodes"))) return std::nullopt;
      } else if (section == "$Elements") {
        if (!(major_version == 4 ? parse_elements_v4() : parse_elements_v1_v2(false, "$EndElements")))
          return std::nullopt;
        saw_elements = true;
      } else if (section.size() > 1 && section[0] == '$' && section.substr(0, 4) != "$End") {
        if (!skip_section("$End" + std::string(section.substr(1)))) return std::nullopt;
      } else {
        diagnostics_.error(cursor_.range_here(), "expected a section such as $Nodes or $Elements but found '" +
                                                     std::string(section.substr(0, 40)) + "'; fix the file");
        return std::nullopt;
      }
    }
    if (!saw_nodes_ || !saw_elements) {
      SourceRange range;
      range.file = mesh_.source;
      diagnostics_.error(range, std::string("the mesh has no ") + (saw_nodes_ ? "$Elements" : "$Nodes") +
                                    " section; export the mesh with its nodes and elements");
      return std::nullopt;
    }
  } else {
    diagnostics_.error(cursor_.range_here(), "this is not a Gmsh ASCII mesh: it starts with '" +
                                                 std::string(first.substr(0, 40)) +
                                                 "' instead of $MeshFormat or $NOD; check the file");
    return std::nullopt;
  }
  (void)major_version;
  warn_ignored_types();
  return std::move(mesh_);
}

}  // namespace

std::optional<Mesh> read_gmsh(std::string_view text, const std::string& file, DiagnosticList& diagnostics) {
  GmshParser parser(text, file, diagnostics);
  return parser.parse();
}

}  // namespace fmpc::sim

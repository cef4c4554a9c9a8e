// VTU frames: the binary layout (appended raw data, vtkZLibDataCompressor blocks behind UInt64 headers) decoded back
// by a small reader written from VTK's description of the format, to the same numbers; ASCII frames; errors.
#include <zlib.h>

#include <catch2/catch.hpp>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <regex>
#include <string>
#include <vector>

#include "runtime/integrate/worker_pool.h"
#include "runtime/io/vtk_xml.h"
#include "runtime/mesh/generated_mesh.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

std::uint64_t read_u64(const std::string& text, std::size_t at) {
  REQUIRE(at + 8 <= text.size());
  std::uint64_t value = 0;
  for (int i = 7; i >= 0; --i) value = (value << 8) | static_cast<unsigned char>(text[at + static_cast<std::size_t>(i)]);
  return value;
}

struct DecodedArray {
  std::string type, name, format;
  int components = 1;
  std::string raw;           // the array's bytes, inflated
  std::uint64_t blocks = 0;  // compressed: the header's words
  std::uint64_t block_size = 0, last_block = 0;
  std::size_t start = 0, end = 0;  // where its appended bytes begin and end (from the appended data's start)
};

struct DecodedFile {
  std::string head;  // everything before <AppendedData>
  bool compressed = false;
  std::vector<DecodedArray> arrays;  // in the order of the DataArray elements
};

std::string attribute(const std::string& element, const std::string& name) {
  const std::regex pattern("\\b" + name + "=\"([^\"]*)\"");
  std::smatch match;
  return std::regex_search(element, match, pattern) ? match[1].str() : "";
}

// A reader of VTK's appended raw layout: each DataArray's offset counts from the byte after "_"; with the zlib
// compressor, an array is [blocks][block size][last partial size or 0][compressed sizes...] then the blocks, each
// a zlib stream of block size bytes (the last one of `last` bytes when last != 0); without it, [size] then bytes.
DecodedFile decode(const std::string& file) {
  DecodedFile decoded;
  const std::string opening = "  <AppendedData encoding=\"raw\">\n   _";
  const std::size_t start = file.find(opening);
  REQUIRE(start != std::string::npos);
  decoded.head = file.substr(0, start);
  decoded.compressed = decoded.head.find("compressor=\"vtkZLibDataCompressor\"") != std::string::npos;
  const std::size_t base = start + opening.size();
  const std::string closing = "\n  </AppendedData>\n</VTKFile>\n";
  REQUIRE(file.size() >= base + closing.size());
  CHECK(file.compare(file.size() - closing.size(), closing.size(), closing) == 0);
  const std::regex element("<DataArray([^>]*)/>");
  for (auto it = std::sregex_iterator(decoded.head.begin(), decoded.head.end(), element); it != std::sregex_iterator();
       ++it) {
    const std::string attributes = (*it)[1].str();
    DecodedArray array;
    array.type = attribute(attributes, "type");
    array.name = attribute(attributes, "Name");
    array.format = attribute(attributes, "format");
    const std::string components = attribute(attributes, "NumberOfComponents");
    array.components = components.empty() ? 1 : std::stoi(components);
    array.start = std::stoull(attribute(attributes, "offset"));
    std::size_t at = base + array.start;
    if (decoded.compressed) {
      array.blocks = read_u64(file, at);
      array.block_size = read_u64(file, at + 8);
      array.last_block = read_u64(file, at + 16);
      std::vector<std::uint64_t> sizes;
      for (std::uint64_t b = 0; b < array.blocks; ++b) sizes.push_back(read_u64(file, at + 24 + 8 * b));
      at += 24 + 8 * array.blocks;
      for (std::uint64_t b = 0; b < array.blocks; ++b) {
        const bool partial = b + 1 == array.blocks && array.last_block != 0;
        uLongf length = static_cast<uLongf>(partial ? array.last_block : array.block_size);
        std::string block(length, '\0');
        REQUIRE(uncompress(reinterpret_cast<Bytef*>(&block[0]), &length,
                           reinterpret_cast<const Bytef*>(file.data() + at), static_cast<uLong>(sizes[b])) == Z_OK);
        CHECK(length == (partial ? array.last_block : array.block_size));
        array.raw += block;
        at += sizes[b];
      }
    } else {
      const std::uint64_t size = read_u64(file, at);
      array.raw = file.substr(at + 8, size);
      at += 8 + size;
    }
    array.end = at - base;
    decoded.arrays.push_back(array);
  }
  // The arrays tile the appended data: each starts where the previous one ended, the last ends at its close.
  for (std::size_t i = 0; i + 1 < decoded.arrays.size(); ++i) CHECK(decoded.arrays[i + 1].start == decoded.arrays[i].end);
  if (!decoded.arrays.empty()) CHECK(decoded.arrays.front().start == 0);
  if (!decoded.arrays.empty()) CHECK(base + decoded.arrays.back().end == file.size() - closing.size());
  return decoded;
}

template <class T>
std::vector<T> values_of(const DecodedArray& array) {
  REQUIRE(array.raw.size() % sizeof(T) == 0);
  std::vector<T> values(array.raw.size() / sizeof(T));
  for (std::size_t i = 0; i < values.size(); ++i) {
    unsigned char bytes[sizeof(T)];
    for (std::size_t b = 0; b < sizeof(T); ++b) bytes[b] = static_cast<unsigned char>(array.raw[i * sizeof(T) + b]);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    std::reverse(bytes, bytes + sizeof(T));
#endif
    std::memcpy(&values[i], bytes, sizeof(T));
  }
  return values;
}

const DecodedArray& named(const DecodedFile& file, const std::string& name) {
  for (const DecodedArray& array : file.arrays)
    if (array.name == name) return array;
  FAIL("no array " << name);
  return file.arrays.front();
}

struct Frame {
  Mesh mesh;
  std::vector<Point3> displacement, velocity;
  std::vector<double> stress;
  std::vector<float> temperature;
  std::vector<std::uint8_t> inverted;
};

Frame random_frame(int cells_x, int cells_y, int cells_z, unsigned seed) {
  Frame frame;
  DiagnosticList diagnostics;
  BoxSpec spec;
  spec.cells_x = cells_x;
  spec.cells_y = cells_y;
  spec.cells_z = cells_z;
  frame.mesh = generate_box(spec, diagnostics);
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (std::size_t v = 0; v < frame.mesh.points.size(); ++v) {
    frame.displacement.push_back({uniform(random) * 1e-3, uniform(random), 1e-300 * uniform(random)});
    frame.velocity.push_back({uniform(random), uniform(random), uniform(random)});
    frame.temperature.push_back(static_cast<float>(uniform(random)));
  }
  for (std::size_t c = 0; c < frame.mesh.tetrahedra.size(); ++c) {
    frame.stress.push_back(uniform(random) * 1e4);
    frame.inverted.push_back(static_cast<std::uint8_t>(random() % 2));
  }
  return frame;
}

std::string write(const Frame& frame, const VtuOptions& options) {
  DiagnosticList diagnostics;
  const auto cells = encode_vtu_cells(frame.mesh, options, diagnostics);
  REQUIRE(cells);
  const auto document =
      vtu_document(frame.mesh.points, *cells,
                   {vtu_vectors("displacement", frame.displacement),
                    vtu_vectors("velocity", frame.velocity, VtuType::Float32),
                    vtu_scalars("temperature", frame.temperature)},
                   {vtu_scalars("von_mises", frame.stress), vtu_flags("inverted", frame.inverted)}, options, diagnostics);
  INFO((diagnostics.items().empty() ? std::string() : diagnostics.items().front().message));
  REQUIRE(document);
  return *document;
}

void check_round_trip(const Frame& frame, const DecodedFile& file) {
  const Mesh& mesh = frame.mesh;
  const std::vector<double> points = values_of<double>(named(file, ""));
  REQUIRE(points.size() == 3 * mesh.points.size());
  for (std::size_t v = 0; v < mesh.points.size(); ++v)
    for (std::size_t c = 0; c < 3; ++c) CHECK(points[3 * v + c] == mesh.points[v][c]);
  const std::vector<double> displacement = values_of<double>(named(file, "displacement"));
  const std::vector<float> velocity = values_of<float>(named(file, "velocity"));
  const std::vector<float> temperature = values_of<float>(named(file, "temperature"));
  REQUIRE(displacement.size() == 3 * mesh.points.size());
  REQUIRE(velocity.size() == 3 * mesh.points.size());
  for (std::size_t v = 0; v < mesh.points.size(); ++v) {
    CHECK(temperature[v] == frame.temperature[v]);
    for (std::size_t c = 0; c < 3; ++c) {
      CHECK(displacement[3 * v + c] == frame.displacement[v][c]);
      CHECK(velocity[3 * v + c] == static_cast<float>(frame.velocity[v][c]));
    }
  }
  CHECK(values_of<double>(named(file, "von_mises")) == frame.stress);
  CHECK(values_of<std::uint8_t>(named(file, "inverted")) == frame.inverted);
  const std::vector<std::int32_t> connectivity = values_of<std::int32_t>(named(file, "connectivity"));
  const std::vector<std::int32_t> offsets = values_of<std::int32_t>(named(file, "offsets"));
  const std::vector<std::uint8_t> types = values_of<std::uint8_t>(named(file, "types"));
  REQUIRE(connectivity.size() == 4 * mesh.tetrahedra.size());
  REQUIRE(offsets.size() == mesh.tetrahedra.size());
  for (std::size_t c = 0; c < mesh.tetrahedra.size(); ++c) {
    for (std::size_t k = 0; k < 4; ++k) CHECK(connectivity[4 * c + k] == mesh.tetrahedra[c][k]);
    CHECK(offsets[c] == static_cast<std::int32_t>(4 * (c + 1)));
    CHECK(types[c] == 10);
  }
  CHECK(named(file, "velocity").type == "Float32");
  CHECK(named(file, "velocity").components == 3);
  CHECK(named(file, "inverted").type == "UInt8");
  CHECK(named(file, "connectivity").type == "Int32");
}

}  // namespace

TEST_CASE("binary VTU frames decode back to the same numbers (zlib blocks, UInt64 headers)", "[vtu]") {
  // 9x7x6 cells: 560 points (13,440 bytes of Float64 positions: one partial block), 2,268 tetrahedra (36,288 bytes
  // of connectivity: a full block and a partial one).
  const Frame frame = random_frame(9, 7, 6, 1);
  const std::string file = write(frame, VtuOptions{});
  const DecodedFile decoded = decode(file);
  CHECK(decoded.compressed);
  CHECK(decoded.head.find("header_type=\"UInt64\"") != std::string::npos);
  CHECK(decoded.head.find("<PointData Scalars=\"temperature\" Vectors=\"displacement\">") != std::string::npos);
  CHECK(decoded.head.find("<CellData Scalars=\"von_mises\">") != std::string::npos);
  CHECK(decoded.arrays.size() == 9);
  check_round_trip(frame, decoded);
  const DecodedArray& connectivity = named(decoded, "connectivity");
  CHECK(connectivity.blocks == 2);
  CHECK(connectivity.block_size == 32768);
  CHECK(connectivity.last_block == 2268 * 16 - 32768);
  CHECK(named(decoded, "").blocks == 1);
  CHECK(named(decoded, "").last_block == 560 * 24);

  // The same file for any thread count; every level decodes to the same numbers; level 0 is uncompressed.
  for (const int level : {0, 1, 6, 9}) {
    CAPTURE(level);
    VtuOptions options;
    options.compression_level = level;
    WorkerPool one(1), four(4, 1);
    options.pool = &one;
    const std::string on_one = write(frame, options);
    options.pool = &four;
    CHECK(write(frame, options) == on_one);
    const DecodedFile again = decode(on_one);
    CHECK(again.compressed == (level > 0));
    check_round_trip(frame, again);
  }
}

TEST_CASE("binary VTU blocks: a full last block is written as last size 0; empty arrays have no blocks", "[vtu]") {
  Mesh mesh;
  for (int i = 0; i < 4096; ++i) mesh.points.push_back({double(i), 0.5 * i, -1.0 * i});  // 98,304 bytes: 3 blocks
  mesh.tetrahedra = {{0, 1, 2, 3}};
  std::vector<double> scalars(4096);  // 32,768 bytes: exactly one block
  for (std::size_t i = 0; i < scalars.size(); ++i) scalars[i] = 1.0 / static_cast<double>(i + 1);
  DiagnosticList diagnostics;
  const auto cells = encode_vtu_cells(mesh, VtuOptions{}, diagnostics);
  REQUIRE(cells);
  const auto file = vtu_document(mesh.points, *cells, {vtu_scalars("s", scalars)}, {}, VtuOptions{}, diagnostics);
  REQUIRE(file);
  const DecodedFile decoded = decode(*file);
  CHECK(named(decoded, "s").blocks == 1);
  CHECK(named(decoded, "s").last_block == 0);
  CHECK(values_of<double>(named(decoded, "s")) == scalars);
  CHECK(named(decoded, "").blocks == 3);
  CHECK(named(decoded, "").last_block == 0);

  Mesh empty;
  const auto no_cells = encode_vtu_cells(empty, VtuOptions{}, diagnostics);
  REQUIRE(no_cells);
  const auto nothing = vtu_document(empty.points, *no_cells, {}, {}, VtuOptions{}, diagnostics);
  REQUIRE(nothing);
  const DecodedFile decoded_nothing = decode(*nothing);
  REQUIRE(decoded_nothing.arrays.size() == 4);
  for (const DecodedArray& array : decoded_nothing.arrays) {
    CHECK(array.blocks == 0);
    CHECK(array.block_size == 32768);
    CHECK(array.last_block == 0);
    CHECK(array.raw.empty());
  }
}

TEST_CASE("ASCII VTU frames: the layout, numbers that read back exactly, cell data", "[vtu]") {
  Mesh mesh;
  mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0.1}};
  mesh.tetrahedra = {{0, 1, 2, 3}};
  const std::vector<Point3> displacement = {{0.1, 0, -1e-300}, {0, 0, 0}, {0, 0, 0}, {1, 2, 3}};
  const std::vector<double> stress = {0.30000000000000004};
  const std::vector<std::uint8_t> inverted = {1};
  VtuOptions options;
  options.format = VtuFormat::Ascii;
  DiagnosticList diagnostics;
  const auto cells = encode_vtu_cells(mesh, options, diagnostics);
  REQUIRE(cells);
  const auto file = vtu_document(mesh.points, *cells, {vtu_vectors("displacement", displacement, VtuType::Float32)},
                                 {vtu_scalars("von_mises", stress), vtu_flags("inverted", inverted)}, options,
                                 diagnostics);
  REQUIRE(file);
  CHECK(*file ==
        "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
        "  <UnstructuredGrid>\n"
        "    <Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n"
        "      <PointData Vectors=\"displacement\">\n"
        "        <DataArray type=\"Float32\" Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\">\n"
        "          0.10000000149011612 0 0\n"
        "          0 0 0\n"
        "          0 0 0\n"
        "          1 2 3\n"
        "        </DataArray>\n"
        "      </PointData>\n"
        "      <CellData Scalars=\"von_mises\">\n"
        "        <DataArray type=\"Float64\" Name=\"von_mises\" format=\"ascii\">\n"
        "          0.30000000000000004\n"
        "        </DataArray>\n"
        "        <DataArray type=\"UInt8\" Name=\"inverted\" format=\"ascii\">\n"
        "          1\n"
        "        </DataArray>\n"
        "      </CellData>\n"
        "      <Points>\n"
        "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n"
        "          0 0 0\n"
        "          1 0 0\n"
        "          0 1 0\n"
        "          0 0 0.1\n"
        "        </DataArray>\n"
        "      </Points>\n"
        "      <Cells>\n"
        "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">\n"
        "          0 1 2 3\n"
        "        </DataArray>\n"
        "        <DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n"
        "          4\n"
        "        </DataArray>\n"
        "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n"
        "          10\n"
        "        </DataArray>\n"
        "      </Cells>\n"
        "    </Piece>\n"
        "  </UnstructuredGrid>\n"
        "</VTKFile>\n");
  // ASCII and binary frames of the same data carry the same numbers, for any thread count.
  const Frame frame = random_frame(4, 3, 5, 7);
  VtuOptions ascii_one = options;
  WorkerPool one(1), three(3, 1);
  ascii_one.pool = &one;
  VtuOptions ascii_three = options;
  ascii_three.pool = &three;
  CHECK(write(frame, ascii_one) == write(frame, ascii_three));
}

TEST_CASE("VTU cells of a given type and node count: a quadratic tetrahedron is type 24 with its ten nodes", "[vtu]") {
  const std::int32_t nodes[10] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
  VtuOptions options;
  options.format = VtuFormat::Ascii;
  DiagnosticList diagnostics;
  const auto cells = encode_vtu_cells(nodes, 1, 10, 24, "quadratic.msh", options, diagnostics);
  REQUIRE(cells);
  std::vector<Point3> points(10, Point3{0, 0, 0});
  const auto file = vtu_document(points, *cells, {}, {}, options, diagnostics);
  REQUIRE(file);
  CHECK(file->find("          0 1 2 3 4 5 6 7 8 9\n") != std::string::npos);
  CHECK(file->find("<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n          10\n") !=
        std::string::npos);
  CHECK(file->find("<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n          24\n") !=
        std::string::npos);
}

TEST_CASE("VTU frame errors name the array and what to give", "[vtu]") {
  Mesh mesh;
  mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.tetrahedra = {{0, 1, 2, 3}};
  DiagnosticList diagnostics;
  const auto cells = encode_vtu_cells(mesh, VtuOptions{}, diagnostics);
  REQUIRE(cells);
  const std::vector<Point3> three(3);
  const std::vector<double> four(4), one(1);
  const auto error_of = [&](const std::vector<VtuArray>& points, const std::vector<VtuArray>& cell,
                            const VtuOptions& options = VtuOptions{}) {
    DiagnosticList errors;
    CHECK_FALSE(vtu_document(mesh.points, *cells, points, cell, options, errors));
    REQUIRE(errors.has_errors());
    return errors.items().front().message;
  };
  CHECK(error_of({vtu_vectors("u", three)}, {}) == "VTU frame: point data array 'u' has 3 tuples for 4 points");
  CHECK(error_of({}, {vtu_scalars("s", four)}) == "VTU frame: cell data array 's' has 4 tuples for 1 cells");
  VtuArray two = vtu_scalars("pair", four);
  two.components = 2;
  CHECK(error_of({two}, {}) == "VTU frame: point data array 'pair' has 2 components; give 1 (scalars) or 3 (vectors)");
  CHECK(error_of({vtu_scalars("s", four), vtu_scalars("s", four)}, {}) ==
        "VTU frame: point data array 's' appears twice; give each array its own name");
  CHECK(error_of({}, {vtu_scalars("flag", one, VtuType::UInt8)}) ==
        "VTU frame: cell data array 'flag' is written as UInt8 and must read from bytes (vtu_flags)");
  CHECK(error_of({vtu_scalars("", four)}, {}) == "VTU frame: point data array 0 has no name");
  VtuOptions ascii;
  ascii.format = VtuFormat::Ascii;
  CHECK(error_of({}, {}, ascii) ==
        "VTU frame: the cells were encoded for another format or compression level; encode them with the frame's "
        "options");
  VtuOptions bad_level;
  bad_level.compression_level = 12;
  CHECK_FALSE(encode_vtu_cells(mesh, bad_level, diagnostics));
  CHECK(diagnostics.items().back().message == "VTU frame: compression level 12 is not a zlib level; give 0 (none) to 9");
}

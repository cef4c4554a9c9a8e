#include "runtime/io/vtk_xml.h"

#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <limits>
#include <sstream>

#include "diagnostics/number_format.h"
#include "runtime/integrate/worker_pool.h"

namespace fmpc::sim {

namespace {

// vtkXMLWriter's default BlockSize: every word size written (1, 4, 8) divides it, so no value straddles two blocks.
constexpr std::size_t kBlockSize = 32768;

std::string xml_escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// Stores `value` little-endian (byte_order="LittleEndian") at `to`.
template <class T>
void put(T value, unsigned char* to) {
  std::memcpy(to, &value, sizeof value);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  std::reverse(to, to + sizeof value);
#endif
}

const char* type_name(VtuType type) {
  switch (type) {
    case VtuType::Float32: return "Float32";
    case VtuType::Float64: return "Float64";
    case VtuType::UInt8: return "UInt8";
  }
  return "?";
}

std::size_t word_size(VtuType type) {
  switch (type) {
    case VtuType::Float32: return 4;
    case VtuType::Float64: return 8;
    case VtuType::UInt8: return 1;
  }
  return 1;
}

// Writes the words [first, last) of an array (byte offsets first * word .. last * word) little-endian at `to`.
using WordWriter = std::function<void(std::size_t first, std::size_t last, unsigned char* to)>;
// Appends the text of line `line` of an ASCII array to `to`.
using LineWriter = std::function<void(std::size_t line, std::string& to)>;

template <class Out, class In>
void convert_words(const In* values, std::size_t first, std::size_t last, unsigned char* to) {
  for (std::size_t w = first; w < last; ++w) put(static_cast<Out>(values[w]), to + (w - first) * sizeof(Out));
}

template <class In>
WordWriter words_of(const In* values, VtuType type) {
  switch (type) {
    case VtuType::Float32:
      return [values](std::size_t first, std::size_t last, unsigned char* to) {
        convert_words<float>(values, first, last, to);
      };
    case VtuType::Float64:
      return [values](std::size_t first, std::size_t last, unsigned char* to) {
        convert_words<double>(values, first, last, to);
      };
    case VtuType::UInt8:
      break;
  }
  return [values](std::size_t first, std::size_t last, unsigned char* to) {
    convert_words<std::uint8_t>(values, first, last, to);
  };
}

// The text of one value as written: the shortest text that reads back as the value of the written type.
template <class In>
void append_value(In value, VtuType type, std::string& to) {
  switch (type) {
    case VtuType::Float32:
      to += format_number(static_cast<double>(static_cast<float>(value)));
      return;
    case VtuType::Float64:
      to += format_number(static_cast<double>(value));
      return;
    case VtuType::UInt8:
      to += std::to_string(static_cast<unsigned>(value));
      return;
  }
}

template <class In>
LineWriter lines_of(const In* values, int components, VtuType type) {
  return [values, components, type](std::size_t line, std::string& to) {
    to += "         ";
    for (int c = 0; c < components; ++c) {
      to += ' ';
      append_value(values[line * static_cast<std::size_t>(components) + static_cast<std::size_t>(c)], type, to);
    }
    to += '\n';
  };
}

void append_words(std::string& out, std::uint64_t word) {
  unsigned char bytes[8];
  put(word, bytes);
  out.append(reinterpret_cast<const char*>(bytes), 8);
}

// Appends an array of `size` bytes in VTK's appended layout: without compression a UInt64 byte count and the
// bytes; with it the vtkZLibDataCompressor header (blocks, block size, last partial block size or 0, compressed
// sizes) and the blocks, each a zlib stream of its own (deflate, 15-bit window: what VTK's uncompress reads),
// compressed in parallel. Floating-point arrays are deflated with Huffman coding alone (Z_HUFFMAN_ONLY): their
// mantissas give LZ77 almost no matches, and on a sagging box's positions the full level-1 search took 2.5 times as
// long for a 5% smaller block (0.865 against 0.918 of the raw size); integers (connectivity) use the level's full
// deflate, which shrinks them about 11 times.
bool append_binary(std::string& out, std::size_t size, const WordWriter& write, std::size_t word, bool floating,
                   int level, WorkerPool& pool) {
  if (level == 0) {
    append_words(out, size);
    const std::size_t at = out.size();
    out.resize(at + size);
    auto* base = reinterpret_cast<unsigned char*>(&out[at]);
    pool.run((size + kBlockSize - 1) / kBlockSize, [&](std::size_t first, std::size_t last) {
      for (std::size_t b = first; b < last; ++b) {
        const std::size_t begin = b * kBlockSize, end = std::min(size, begin + kBlockSize);
        write(begin / word, end / word, base + begin);
      }
    }, 8);
    return true;
  }
  const std::size_t last_block = size % kBlockSize;
  const std::size_t blocks = size / kBlockSize + (last_block ? 1 : 0);
  std::vector<std::uint64_t> compressed(blocks);
  const unsigned parts = pool.parts(blocks, 8);
  std::vector<std::string> pieces(parts);
  std::vector<char> failed(parts, 0);
  pool.run_parts(blocks, [&](unsigned part, std::size_t first, std::size_t last) {
    if (first == last) return;
    z_stream stream{};
    if (deflateInit2(&stream, level, Z_DEFLATED, 15, 8, floating ? Z_HUFFMAN_ONLY : Z_DEFAULT_STRATEGY) != Z_OK) {
      failed[part] = 1;
      return;
    }
    const uLong bound = deflateBound(&stream, static_cast<uLong>(kBlockSize));
    std::vector<unsigned char> raw(kBlockSize), packed(bound);
    std::string& piece = pieces[part];
    piece.reserve((last - first) * kBlockSize);  // address space only: no regrowth, pages touched as written
    if (piece.capacity() >= kHugePageAdviceBytes) advise_huge_pages(piece.data(), piece.capacity());
    for (std::size_t b = first; b < last && !failed[part]; ++b) {
      const std::size_t begin = b * kBlockSize, end = std::min(size, begin + kBlockSize);
      write(begin / word, end / word, raw.data());
      stream.next_in = raw.data();
      stream.avail_in = static_cast<uInt>(end - begin);
      stream.next_out = packed.data();
      stream.avail_out = static_cast<uInt>(bound);
      if (deflate(&stream, Z_FINISH) != Z_STREAM_END) failed[part] = 1;
      piece.append(reinterpret_cast<const char*>(packed.data()), stream.total_out);
      compressed[b] = stream.total_out;
      if (deflateReset(&stream) != Z_OK) failed[part] = 1;
    }
    deflateEnd(&stream);
  }, 8);
  if (std::find(failed.begin(), failed.end(), 1) != failed.end()) return false;
  append_words(out, blocks);
  append_words(out, kBlockSize);
  append_words(out, last_block);
  for (const std::uint64_t length : compressed) append_words(out, length);
  for (std::string& piece : pieces) {
    out += piece;
    std::string().swap(piece);
  }
  return true;
}

void append_ascii(std::string& out, std::size_t lines, const LineWriter& line, WorkerPool& pool) {
  std::vector<std::string> pieces(pool.parts(lines, 4096));
  pool.run_parts(lines, [&](unsigned part, std::size_t first, std::size_t last) {
    for (std::size_t l = first; l < last; ++l) line(l, pieces[part]);
  }, 4096);
  for (const std::string& piece : pieces) out += piece;
}


std::string element_attributes(const char* type, const std::string& name, int components) {
  std::string text = std::string(" type=\"") + type + "\"";
  if (!name.empty()) text += " Name=\"" + xml_escape(name) + "\"";
  if (components != 1) text += " NumberOfComponents=\"" + std::to_string(components) + "\"";
  return text;
}

// Appends an array's body to `out`: its ASCII lines, or its appended bytes.
bool encode(std::string& out, const VtuOptions& options, std::size_t words, std::size_t word, bool floating,
            std::size_t lines, const WordWriter& write, const LineWriter& line, WorkerPool& pool) {
  if (options.format == VtuFormat::Ascii) {
    append_ascii(out, lines, line, pool);
    return true;
  }
  return append_binary(out, words * word, write, word, floating, options.compression_level, pool);
}

// The first vector (3 components) and scalar (1 component) arrays, as the PointData/CellData attributes that make
// them the active ones in ParaView.
std::string active_attributes(const std::vector<VtuArray>& arrays) {
  std::string text;
  const auto first = [&](int components) {
    return std::find_if(arrays.begin(), arrays.end(), [&](const VtuArray& a) { return a.components == components; });
  };
  if (auto scalars = first(1); scalars != arrays.end()) text += " Scalars=\"" + xml_escape(scalars->name) + "\"";
  if (auto vectors = first(3); vectors != arrays.end()) text += " Vectors=\"" + xml_escape(vectors->name) + "\"";
  return text;
}

bool check_arrays(const std::vector<VtuArray>& arrays, std::size_t tuples, const char* where,
                  DiagnosticList& diagnostics) {
  SourceRange range;
  for (std::size_t i = 0; i < arrays.size(); ++i) {
    const VtuArray& a = arrays[i];
    const std::string name = std::string(where) + " array '" + a.name + "'";
    const int sources = (a.doubles ? 1 : 0) + (a.floats ? 1 : 0) + (a.bytes ? 1 : 0);
    std::string problem;
    if (a.name.empty())
      problem = std::string(where) + " array " + std::to_string(i) + " has no name";
    else if (a.components != 1 && a.components != 3)
      problem = name + " has " + std::to_string(a.components) + " components; give 1 (scalars) or 3 (vectors)";
    else if (a.tuples != tuples)
      problem = name + " has " + std::to_string(a.tuples) + " tuples for " + std::to_string(tuples) +
                (std::string(where) == "point data" ? " points" : " cells");
    else if (sources != 1 && tuples > 0)
      problem = name + " must read from exactly one of doubles, floats and bytes";
    else if (a.type == VtuType::UInt8 && !a.bytes && tuples > 0)
      problem = name + " is written as UInt8 and must read from bytes (vtu_flags)";
    else if (std::any_of(arrays.begin(), arrays.begin() + static_cast<std::ptrdiff_t>(i),
                         [&](const VtuArray& earlier) { return earlier.name == a.name; }))
      problem = name + " appears twice; give each array its own name";
    if (!problem.empty()) {
      diagnostics.error(range, "VTU frame: " + problem);
      return false;
    }
  }
  return true;
}

std::string data_attributes(const VtuArray& a) { return element_attributes(type_name(a.type), a.name, a.components); }

bool encode_data(std::string& out, const VtuArray& a, const VtuOptions& options, WorkerPool& pool) {
  const std::size_t words = a.tuples * static_cast<std::size_t>(a.components);
  const std::size_t word = word_size(a.type);
  const bool floating = a.type != VtuType::UInt8;
  if (a.doubles)
    return encode(out, options, words, word, floating, a.tuples, words_of(a.doubles, a.type),
                  lines_of(a.doubles, a.components, a.type), pool);
  if (a.floats)
    return encode(out, options, words, word, floating, a.tuples, words_of(a.floats, a.type),
                  lines_of(a.floats, a.components, a.type), pool);
  return encode(out, options, words, word, floating, a.tuples, words_of(a.bytes, a.type),
                lines_of(a.bytes, a.components, a.type), pool);
}

}  // namespace

const char* to_string(VtuFormat format) { return format == VtuFormat::Ascii ? "ascii" : "binary"; }

namespace {

VtuArray array_of(std::string name, int components, std::size_t tuples, VtuType type) {
  VtuArray array;
  array.name = std::move(name);
  array.components = components;
  array.tuples = tuples;
  array.type = type;
  return array;
}

}  // namespace

VtuArray vtu_vectors(std::string name, const std::vector<Point3>& values, VtuType type) {
  VtuArray array = array_of(std::move(name), 3, values.size(), type);
  array.doubles = values.empty() ? nullptr : values[0].data();  // std::array<double, 3> holds no padding
  return array;
}

VtuArray vtu_scalars(std::string name, const std::vector<double>& values, VtuType type) {
  VtuArray array = array_of(std::move(name), 1, values.size(), type);
  array.doubles = values.data();
  return array;
}

VtuArray vtu_scalars(std::string name, const std::vector<float>& values, VtuType type) {
  VtuArray array = array_of(std::move(name), 1, values.size(), type);
  array.floats = values.data();
  return array;
}

VtuArray vtu_flags(std::string name, const std::vector<std::uint8_t>& values) {
  VtuArray array = array_of(std::move(name), 1, values.size(), VtuType::UInt8);
  array.bytes = values.data();
  return array;
}

std::optional<VtuCells> encode_vtu_cells(const Mesh& mesh, const VtuOptions& options, DiagnosticList& diagnostics) {
  const bool tetrahedra = !mesh.tetrahedra.empty();
  const std::size_t count = tetrahedra ? mesh.tetrahedra.size() : mesh.triangles.size();
  const std::int32_t* corner = tetrahedra ? mesh.tetrahedra.empty() ? nullptr : mesh.tetrahedra[0].data()
                                          : mesh.triangles.empty() ? nullptr : mesh.triangles[0].data();
  // VTK_TETRA, VTK_TRIANGLE
  return encode_vtu_cells(corner, count, tetrahedra ? 4 : 3, tetrahedra ? 10 : 5, mesh.source, options, diagnostics);
}

std::optional<VtuCells> encode_vtu_cells(const std::int32_t* corner, std::size_t count, std::size_t corners,
                                         std::uint8_t type, const std::string& source, const VtuOptions& options,
                                         DiagnosticList& diagnostics) {
  SourceRange range;
  range.file = source;
  if (options.format == VtuFormat::Binary && (options.compression_level < 0 || options.compression_level > 9)) {
    diagnostics.error(range, "VTU frame: compression level " + std::to_string(options.compression_level) +
                                 " is not a zlib level; give 0 (none) to 9");
    return std::nullopt;
  }
  constexpr auto int32_max = static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());
  if (count > int32_max) {
    diagnostics.error(range, "VTU frame: " + std::to_string(count) + " cells, more than a frame can hold (2^31 - 1)");
    return std::nullopt;
  }
  PoolLease lease(options.pool, 0, count);
  WorkerPool& pool = lease.pool();
  VtuCells cells;
  cells.count_ = count;
  cells.format_ = options.format;
  cells.compression_level_ = options.compression_level;
  cells.arrays_.resize(3);
  bool ok = true;
  VtuCells::Encoded connectivity{element_attributes("Int32", "connectivity", 1), {}};
  ok = ok && encode(connectivity.body, options, count * corners, 4, false, count,
                    [corner](std::size_t first, std::size_t last, unsigned char* to) {
                      for (std::size_t w = first; w < last; ++w) put(corner[w], to + 4 * (w - first));
                    },
                    [corner, corners](std::size_t cell, std::string& to) {
                      to += "         ";
                      for (std::size_t k = 0; k < corners; ++k) {
                        to += ' ';
                        to += std::to_string(corner[cell * corners + k]);
                      }
                      to += '\n';
                    },
                    pool);
  const bool wide = count * corners > int32_max;
  VtuCells::Encoded offsets{element_attributes(wide ? "Int64" : "Int32", "offsets", 1), {}};
  ok = ok && encode(offsets.body, options, count, wide ? 8 : 4, false, count,
                    [corners, wide](std::size_t first, std::size_t last, unsigned char* to) {
                      for (std::size_t c = first; c < last; ++c) {
                        const std::size_t end = (c + 1) * corners;
                        if (wide)
                          put(static_cast<std::int64_t>(end), to + 8 * (c - first));
                        else
                          put(static_cast<std::int32_t>(end), to + 4 * (c - first));
                      }
                    },
                    [corners](std::size_t cell, std::string& to) {
                      to += "          " + std::to_string((cell + 1) * corners) + "\n";
                    },
                    pool);
  VtuCells::Encoded types{element_attributes("UInt8", "types", 1), {}};
  ok = ok && encode(types.body, options, count, 1, false, count,
                    [type](std::size_t first, std::size_t last, unsigned char* to) {
                      std::memset(to, type, last - first);
                    },
                    [type](std::size_t, std::string& to) { to += "          " + std::to_string(type) + "\n"; }, pool);
  if (!ok) {
    diagnostics.error(range, "VTU frame: zlib could not compress the cells (out of memory?)");
    return std::nullopt;
  }
  cells.arrays_[0] = std::move(connectivity);
  cells.arrays_[1] = std::move(offsets);
  cells.arrays_[2] = std::move(types);
  return cells;
}

std::optional<std::string> vtu_document(const std::vector<Point3>& points, const VtuCells& cells,
                                        const std::vector<VtuArray>& point_data,
                                        const std::vector<VtuArray>& cell_data, const VtuOptions& options,
                                        DiagnosticList& diagnostics) {
  SourceRange range;
  if (cells.format_ != options.format ||
      (options.format == VtuFormat::Binary && cells.compression_level_ != options.compression_level)) {
    diagnostics.error(range, "VTU frame: the cells were encoded for another format or compression level; encode "
                             "them with the frame's options");
    return std::nullopt;
  }
  if (options.point_type == VtuType::UInt8) {
    diagnostics.error(range, "VTU frame: points are written as Float32 or Float64");
    return std::nullopt;
  }
  if (!check_arrays(point_data, points.size(), "point data", diagnostics) ||
      !check_arrays(cell_data, cells.size(), "cell data", diagnostics))
    return std::nullopt;
  PoolLease lease(options.pool, 0, points.size() + cells.size());
  WorkerPool& pool = lease.pool();
  const bool binary = options.format == VtuFormat::Binary;

  // Every array in the order of the file: point data, cell data, points, then the cells (encoded already).
  std::vector<const VtuArray*> data;
  for (const VtuArray& a : point_data) data.push_back(&a);
  for (const VtuArray& a : cell_data) data.push_back(&a);
  const VtuArray positions = vtu_vectors("", points, options.point_type);
  data.push_back(&positions);
  std::size_t estimate = 4096 + 256 * (data.size() + cells.arrays_.size());  // the XML, and at most the raw bytes
  for (const VtuArray* a : data)
    estimate += a->tuples * static_cast<std::size_t>(a->components) * (binary ? word_size(a->type) : 26);
  for (const VtuCells::Encoded& array : cells.arrays_) estimate += array.body.size();
  std::string document;
  document.reserve(estimate);
  if (document.capacity() >= kHugePageAdviceBytes) advise_huge_pages(document.data(), document.capacity());

  // The XML; an ASCII array's lines go inline, a binary array gets an offset field padded to be filled in once the
  // bodies are placed in the appended data, after the XML.
  std::vector<std::size_t> offset_fields;
  bool ok = true;
  const auto data_array = [&](const std::string& element, const VtuArray* a, const std::string* encoded) {
    document += "        <DataArray";
    document += element;
    if (binary) {
      document += " format=\"appended\"";
      offset_fields.push_back(document.size());
      document += std::string(32, ' ');
      document += "/>\n";
      return;
    }
    document += " format=\"ascii\">\n";
    if (a)
      ok = ok && encode_data(document, *a, options, pool);
    else
      document += *encoded;
    document += "        </DataArray>\n";
  };
  document += "<?xml version=\"1.0\"?>\n";
  document += "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\"";
  if (binary && options.compression_level > 0) document += " compressor=\"vtkZLibDataCompressor\"";
  document += ">\n  <UnstructuredGrid>\n";
  document += "    <Piece NumberOfPoints=\"" + std::to_string(points.size()) + "\" NumberOfCells=\"" +
              std::to_string(cells.size()) + "\">\n";
  document += "      <PointData" + active_attributes(point_data) + ">\n";
  for (const VtuArray& a : point_data) data_array(data_attributes(a), &a, nullptr);
  document += "      </PointData>\n";
  if (!cell_data.empty()) {
    document += "      <CellData" + active_attributes(cell_data) + ">\n";
    for (const VtuArray& a : cell_data) data_array(data_attributes(a), &a, nullptr);
    document += "      </CellData>\n";
  }
  document += "      <Points>\n";
  data_array(data_attributes(positions), &positions, nullptr);
  document += "      </Points>\n      <Cells>\n";
  for (const VtuCells::Encoded& array : cells.arrays_) data_array(array.element, nullptr, &array.body);
  document += "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n";
  if (binary) {
    document += "  <AppendedData encoding=\"raw\">\n   _";
    const std::size_t base = document.size();
    for (std::size_t i = 0; i < offset_fields.size() && ok; ++i) {
      const std::string field = " offset=\"" + std::to_string(document.size() - base) + "\"";
      document.replace(offset_fields[i], field.size(), field);
      if (i < data.size())
        ok = encode_data(document, *data[i], options, pool);
      else
        document += cells.arrays_[i - data.size()].body;
    }
    document += "\n  </AppendedData>\n";
  }
  document += "</VTKFile>\n";
  if (!ok) {
    diagnostics.error(range, "VTU frame: zlib could not compress an array (out of memory?)");
    return std::nullopt;
  }
  return document;
}

std::string pvd_document(const std::vector<PvdFrame>& frames) {
  std::ostringstream out;
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
      << "  <Collection>\n";
  for (const PvdFrame& frame : frames)
    out << "    <DataSet timestep=\"" << format_number(frame.time) << "\" group=\"\" part=\"0\" file=\""
        << xml_escape(frame.file) << "\"/>\n";
  out << "  </Collection>\n"
      << "</VTKFile>\n";
  return out.str();
}

}  // namespace fmpc::sim

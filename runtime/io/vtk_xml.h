#pragma once
// VTK XML files for ParaView: one UnstructuredGrid (.vtu) per frame and a .pvd collection that lists the frames with
// their times (VTK file formats, "XML File Formats": UnstructuredGrid and Collection).
//
// Frames are binary by default, laid out as VTK's own vtkXMLWriter writes them in appended mode with raw encoding:
// every DataArray is `format="appended" offset="N"`, N counting bytes from the one after the `_` that opens
// <AppendedData encoding="raw">. With compression (compressor="vtkZLibDataCompressor"), an array is cut into blocks
// of 32768 bytes, each compressed by zlib on its own, behind a header of UInt64 words (header_type="UInt64"): the
// number of blocks, the block size, the size of the last block when it is partial (0 when it is full), then the
// compressed size of every block. Without compression the header is one UInt64, the array's size in bytes. The
// blocks are independent, so they are compressed in parallel and the file is the same for any thread count.
// ASCII on request (every number the shortest text that reads back exactly).
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

class WorkerPool;  // runtime/integrate/worker_pool.h

enum class VtuFormat { Binary, Ascii };
const char* to_string(VtuFormat format);  // "binary", "ascii"

// The type an array is written as (the DataArray's `type`).
enum class VtuType { Float32, Float64, UInt8 };

// A point or cell data array, borrowed from the caller for the call: `tuples` tuples of `components` numbers (1: a
// scalar, 3: a vector), read from exactly one of `doubles`, `floats` and `bytes`, written as `type`.
struct VtuArray {
  std::string name;
  int components = 1;
  std::size_t tuples = 0;
  const double* doubles = nullptr;
  const float* floats = nullptr;
  const std::uint8_t* bytes = nullptr;
  VtuType type = VtuType::Float64;
};
VtuArray vtu_vectors(std::string name, const std::vector<Point3>& values, VtuType type = VtuType::Float64);
VtuArray vtu_scalars(std::string name, const std::vector<double>& values, VtuType type = VtuType::Float64);
VtuArray vtu_scalars(std::string name, const std::vector<float>& values, VtuType type = VtuType::Float32);
// One byte per tuple, written as UInt8 (e.g. 1 for an inverted tetrahedron).
VtuArray vtu_flags(std::string name, const std::vector<std::uint8_t>& values);

struct VtuOptions {
  VtuFormat format = VtuFormat::Binary;
  // zlib level: 1 (fastest, the default: a frame is written many times per run) to 9; 0 writes the arrays
  // uncompressed (no compressor attribute).
  int compression_level = 1;
  VtuType point_type = VtuType::Float64;  // the positions' type
  // Compresses (or formats) the blocks in parallel; null: a pool of its own for large frames.
  WorkerPool* pool = nullptr;
};

// The cells of a frame, the same in every frame of a run: tetrahedra as VTK_TETRA (10) or, without them, triangles
// as VTK_TRIANGLE (5), with their connectivity (Int32), offsets (Int32, Int64 past 2^31 - 1) and types (UInt8),
// encoded once and copied into each frame.
class VtuCells {
 public:
  std::size_t size() const { return count_; }

 private:
  friend std::optional<VtuCells> encode_vtu_cells(const std::int32_t* nodes, std::size_t count,
                                                  std::size_t nodes_per_cell, std::uint8_t type,
                                                  const std::string& source, const VtuOptions& options,
                                                  DiagnosticList& diagnostics);
  friend std::optional<std::string> vtu_document(const std::vector<Point3>& points, const VtuCells& cells,
                                                 const std::vector<VtuArray>& point_data,
                                                 const std::vector<VtuArray>& cell_data, const VtuOptions& options,
                                                 DiagnosticList& diagnostics);
  struct Encoded {
    std::string element;  // the DataArray's attributes after `<DataArray`
    std::string body;     // ASCII lines, or the appended bytes (header and blocks)
  };
  std::size_t count_ = 0;
  VtuFormat format_ = VtuFormat::Binary;
  int compression_level_ = 1;
  std::vector<Encoded> arrays_;  // connectivity, offsets, types
};

// Encodes the cells for frames written with `options` (the same format and compression level); an error when the
// mesh has more than 2^31 - 1 cells or zlib fails.
std::optional<VtuCells> encode_vtu_cells(const Mesh& cells, const VtuOptions& options, DiagnosticList& diagnostics);
// `count` cells of VTK type `type` (e.g. 24, VTK_QUADRATIC_TETRA), `nodes_per_cell` point indices each from `nodes`
// (cell-major, in VTK's node order); `source` names the mesh in errors.
std::optional<VtuCells> encode_vtu_cells(const std::int32_t* nodes, std::size_t count, std::size_t nodes_per_cell,
                                         std::uint8_t type, const std::string& source, const VtuOptions& options,
                                         DiagnosticList& diagnostics);

// A frame: the points (m) with point data, the cells with cell data. Errors (nullopt) name the array: a tuple count
// other than the points' (point data) or the cells' (cell data), components other than 1 or 3, no values or two
// sources, cells encoded for another format or level, and zlib failures.
std::optional<std::string> vtu_document(const std::vector<Point3>& points, const VtuCells& cells,
                                        const std::vector<VtuArray>& point_data,
                                        const std::vector<VtuArray>& cell_data, const VtuOptions& options,
                                        DiagnosticList& diagnostics);

struct PvdFrame {
  double time = 0.0;  // s
  std::string file;   // relative to the .pvd
};
std::string pvd_document(const std::vector<PvdFrame>& frames);

}  // namespace fmpc::sim

// VTU frame benchmark: seconds to encode and write one frame of a generated box (positions, displacement and
// velocity per point) binary (appended, zlib level 1 by default) and, with --ascii, as ASCII text.
//
//   fmpc_frame_bench [--cells N] [--threads T] [--level L] [--ascii] [--dir DIR]
//
// --cells   box of N^3 cells (default 215: 216^3 = 10,077,696 vertices, 59,617,500 tetrahedra)
// --dir     where the frames are written (default /tmp); the files are removed afterwards
//
// The cells (connectivity, offsets, types) are the same in every frame of a run and are encoded once; the table
// shows that once-per-run cost apart from the per-frame one (vtu_document) and the write to disk.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <string>
#include <thread>

#include "bench/setup/process_clock.h"
#include "runtime/integrate/worker_pool.h"
#include "runtime/io/atomic_file.h"
#include "runtime/io/vtk_xml.h"
#include "runtime/mesh/generated_mesh.h"

using namespace fmpc;
using namespace fmpc::sim;
using fmpc::bench::cpu_seconds;
using fmpc::bench::seconds_since;

namespace {

struct Timing {
  double cells = 0, document = 0, write = 0;
  double document_cpu = 0;
  std::size_t bytes = 0;
};

bool time_frame(const Mesh& mesh, const std::vector<Point3>& positions, const std::vector<Point3>& displacement,
                const std::vector<Point3>& velocity, const VtuOptions& options, const std::string& path,
                Timing& timing) {
  DiagnosticList diagnostics;
  auto start = std::chrono::steady_clock::now();
  const auto cells = encode_vtu_cells(mesh, options, diagnostics);
  timing.cells = seconds_since(start);
  if (!cells) return false;
  start = std::chrono::steady_clock::now();
  const double cpu = cpu_seconds();
  const auto document = vtu_document(positions, *cells,
                                     {vtu_vectors("displacement", displacement), vtu_vectors("velocity", velocity)},
                                     {}, options, diagnostics);
  timing.document = seconds_since(start);
  timing.document_cpu = cpu_seconds() - cpu;
  if (!document) return false;
  timing.bytes = document->size();
  start = std::chrono::steady_clock::now();
  const bool written = write_file_atomically(path, *document, diagnostics);
  timing.write = seconds_since(start);
  std::filesystem::remove(path);
  return written;
}

}  // namespace

int main(int argc, char** argv) {
  int cells = 215;
  unsigned threads = 0;
  int level = 1;
  bool ascii = false;
  std::string dir = "/tmp";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (arg == "--cells") {
      cells = std::atoi(value().c_str());
    } else if (arg == "--threads") {
      threads = static_cast<unsigned>(std::atoi(value().c_str()));
    } else if (arg == "--level") {
      level = std::atoi(value().c_str());
    } else if (arg == "--ascii") {
      ascii = true;
    } else if (arg == "--dir") {
      dir = value();
    } else {
      std::fprintf(stderr, "usage: fmpc_frame_bench [--cells N] [--threads T] [--level L] [--ascii] [--dir DIR]\n");
      return 2;
    }
  }
  if (cells < 1 || cells > 1000) {
    std::fprintf(stderr, "fmpc_frame_bench: --cells must be 1 to 1000\n");
    return 2;
  }
  DiagnosticList diagnostics;
  BoxSpec box;
  box.cells_x = box.cells_y = box.cells_z = cells;
  box.size = {0.1, 0.1, 0.1};
  const Mesh mesh = generate_box(box, diagnostics);
  // A smooth sag under gravity and a velocity field like a frame's in the middle of a run.
  std::vector<Point3> positions(mesh.points.size()), displacement(mesh.points.size()), velocity(mesh.points.size());
  for (std::size_t v = 0; v < mesh.points.size(); ++v) {
    const Point3& p = mesh.points[v];
    const double sag = -0.004 * (1.0 - p[1] / 0.1) * std::sin(31.4 * p[0]) * std::cos(27.0 * p[2]);
    displacement[v] = {0.1 * sag, sag, -0.05 * sag};
    velocity[v] = {0.3 * sag, 2.0 * sag * std::cos(40.0 * p[1]), 0.0};
    for (std::size_t a = 0; a < 3; ++a) positions[v][a] = p[a] + displacement[v][a];
  }
  const unsigned used = threads > 0 ? threads : std::max(1u, std::thread::hardware_concurrency());
  WorkerPool pool(used);
  std::printf("| frame | vertices | tetrahedra | threads | cells (once per run) s | frame s | frame CPU s | write s | MB "
              "| MB/s |\n| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  const auto row = [&](const char* what, const VtuOptions& options) {
    Timing timing;
    const std::string path = dir + "/fmpc_frame_bench.vtu";
    if (!time_frame(mesh, positions, displacement, velocity, options, path, timing)) {
      std::printf("| %s | failed |\n", what);
      return false;
    }
    const double megabytes = static_cast<double>(timing.bytes) / 1e6;
    std::printf("| %s | %zu | %zu | %u | %.2f | %.2f | %.2f | %.2f | %.0f | %.0f |\n", what, mesh.points.size(),
                mesh.tetrahedra.size(), used, timing.cells, timing.document, timing.document_cpu, timing.write,
                megabytes, megabytes / (timing.document + timing.write));
    std::fflush(stdout);
    return true;
  };
  VtuOptions binary;
  binary.compression_level = level;
  binary.pool = &pool;
  bool ok = row(level == 0 ? "binary, uncompressed" : ("binary, zlib level " + std::to_string(level)).c_str(), binary);
  if (ascii) {
    VtuOptions text;
    text.format = VtuFormat::Ascii;
    text.pool = &pool;
    ok = row("ascii", text) && ok;
  }
  return ok ? 0 : 1;
}

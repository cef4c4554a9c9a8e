// libFuzzer target for one mesh reader (runtime/mesh/mesh_reader.h), chosen at build time by
// FMPC_FUZZ_MESH_READER (read_gmsh, read_obj, read_vtk, read_stl_or_ply) and FMPC_FUZZ_MESH_FILE; what it read
// then goes through the checks and repair every mesh from a file goes through (runtime/mesh/mesh_check.h), and its
// triangles through the closed-surface check a surface to mesh goes through (runtime/meshing/surface_check.h; TetGen
// itself is not fuzzed here: it is not fmpc's code and is not instrumented).
#include <cstdint>
#include <string_view>

#include "runtime/mesh/mesh_check.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/meshing/surface_check.h"

namespace fmpc::sim {

// fuzz_surface: the two formats only surfaces come in, one target (one smoke run in CI): PLY when the input starts
// with "ply", STL (ASCII or binary) otherwise.
[[maybe_unused]] static std::optional<Mesh> read_stl_or_ply(std::string_view bytes, const std::string& file,
                                                            DiagnosticList& diagnostics) {
  return bytes.substr(0, 3) == "ply" ? read_ply(bytes, file, diagnostics) : read_stl(bytes, file, diagnostics);
}

}  // namespace fmpc::sim

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  fmpc::DiagnosticList diagnostics;
  if (auto mesh = fmpc::sim::FMPC_FUZZ_MESH_READER(text, FMPC_FUZZ_MESH_FILE, diagnostics)) {
    if (mesh->tetrahedra.empty()) (void)fmpc::sim::check_closed_surface(*mesh, diagnostics);
    (void)fmpc::sim::check_mesh(*mesh);
    (void)fmpc::sim::repair_mesh(*mesh);
  }
  return 0;
}
